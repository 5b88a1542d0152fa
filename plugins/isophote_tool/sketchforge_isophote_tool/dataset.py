"""The isophote tool's material for ``sketchforge dataset``: drawn outlines with holes (the
sculpt corpus' blobs and stars, :func:`.corpus.random_outline`) and random isophote edits
(the corpus' shifts, bumps, loops and run-on strokes, :func:`.corpus.random_edit`) as
``sculpt_isophote`` journal entries."""

from __future__ import annotations

from typing import Any

import numpy as np

from sketchforge.plugin_api import DatasetGenerator, SketchforgeError

#: Edge length of the random shapes (the app's default resolution).
RESOLUTION = 0.03


def holes_journal(rng: np.random.Generator) -> list[dict]:
    """A drawn outline (a blob or a star) with 1-3 elliptic holes, each at least 3 edge lengths
    from the outline and from the other holes; refused (SketchforgeError) when none fits."""
    import shapely

    from .corpus import random_outline

    outline = random_outline(str(rng.choice(["blob", "star"])), rng, n=240)
    inner = shapely.Polygon(outline).buffer(-3 * RESOLUTION)
    wanted = int(rng.integers(1, 4))
    holes: list[Any] = []
    x0, y0, x1, y1 = inner.bounds
    t = np.linspace(0.0, 2.0 * np.pi, 32, endpoint=False)
    for _ in range(60):
        if len(holes) == wanted:
            break
        a = rng.uniform(0.08, 0.22)
        b = a * rng.uniform(0.55, 1.0)
        turn = rng.uniform(0.0, np.pi)
        c = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
        ring = np.column_stack([a * np.cos(t), b * np.sin(t)]) @ np.array(
            [[np.cos(turn), np.sin(turn)], [-np.sin(turn), np.cos(turn)]]) + c
        hole = shapely.Polygon(ring)
        if inner.contains(hole) and all(hole.distance(h) > 3 * RESOLUTION for h in holes):
            holes.append(hole)
    if not holes:
        raise SketchforgeError("no hole fits in this outline")
    return [
        {"command": "add_layer", "id": "shape", "name": "Shape"},
        {"command": "set_contour", "layer": "shape", "points": np.round(outline, 4).tolist(), "closed": True,
         "holes": [np.round(np.asarray(h.exterior.coords)[:-1], 4).tolist() for h in holes]},
        {"command": "set_inflate_params", "layer": "shape",
         "params": {"resolution": RESOLUTION, "inflation": float(np.round(rng.uniform(0.7, 1.3), 3)), "smoothing": 0.5}},
    ]


def isophote_edit(doc, layer: str, model_name: str, rng: np.random.Generator) -> dict | None:
    """A random isophote edit of layer ``layer`` under the document's light and the model
    ``model_name``: a ``sculpt_isophote`` entry, or None when the corpus found no isophote to
    redraw there."""
    from .corpus import random_edit
    from .layerdata import layer_data

    mesh = doc.layer(layer).mesh
    ld = layer_data(mesh, doc.light.direction, doc.host.reflectance_models[model_name])
    edit = random_edit("sample", ld, rng)
    if edit is None:
        return None
    entry = {"command": "sculpt_isophote", "layer": layer, "pick": [float(v) for v in edit.pick],
             "band": float(edit.band), "stroke": np.asarray(edit.stroke, dtype=np.float64).tolist()}
    if model_name != "lambertian":
        entry["model"] = model_name
    return entry


HOLES = DatasetGenerator("holes", "shape", holes_journal, "a drawn blob or star with 1-3 elliptic holes")
ISOPHOTE_EDIT = DatasetGenerator("isophote", "edit", isophote_edit,
                                 "a piece of an isophote moved sideways or bent, possibly with a loop or running "
                                 "past the band (the sculpt corpus' kinds)")
