"""The inflate plugin's registration (entry point ``inflate``): the ``poisson`` inflater."""

from __future__ import annotations

from sketchforge.plugin_api import MAX_COORDINATE, Inflater, declare_params, hookimpl, number
from sketchforge_inflate.inflate import DEFAULT_PARAMS, inflate_stroke, validate_params

#: Bumped when the same stroke and parameters would inflate differently.
VERSION = "2"  # 2: narrow parts meshed finer (inflate.edge_length_for)


def inflate(points, closed, params, holes):
    return inflate_stroke(points, closed, params, holes=holes)


#: The parameters as the app's form shows them: the ranges ``validate_params`` checks (its own
#: messages), the largest values being the drawing's coordinate range.
FORM = {
    "resolution": number("resolution", 0.0, MAX_COORDINATE, lo_open=True),
    "inflation": number("inflation", 0.0, MAX_COORDINATE),
    "smoothing": number("smoothing", 0.0, 1.0, hi_open=True),
}
HELP = {
    "resolution": "Target triangle edge length, drawing units (smaller: finer, slower); parts narrower than 4 edges are meshed finer",
    "inflation": "Height scale: 1 turns a disk of radius R into a hemisphere of height R",
    "smoothing": "Fairing weight α in [0, 1): 0 keeps the inflation's steep rim, more rounds it",
}

POISSON = Inflater(
    "poisson",
    inflate,
    check_params=declare_params(validate_params, DEFAULT_PARAMS, FORM, HELP),
    version=VERSION,
    description="thesis 3.2/4.2: -L u = 4M with u = 0 on every rim, z = inflation·sqrt(u), then faired",
)


@hookimpl
def sketchforge_inflaters():
    return [POISSON]
