"""The inflate plugin's registration (entry point ``inflate``): the ``poisson`` inflater."""

from __future__ import annotations

from sketchforge.plugin_api import Inflater, hookimpl

from sketchforge_inflate.inflate import inflate_stroke, validate_params

#: Bumped when the same stroke and parameters would inflate differently.
VERSION = "1"


def inflate(points, closed, params, holes):
    return inflate_stroke(points, closed, params, holes=holes)


POISSON = Inflater(
    "poisson",
    inflate,
    check_params=validate_params,
    version=VERSION,
    description="thesis 3.2/4.2: -L u = 4M with u = 0 on every rim, z = inflation·sqrt(u), then faired",
)


@hookimpl
def sketchforge_inflaters():
    return [POISSON]
