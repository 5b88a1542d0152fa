"""Random documents for shape-from-shading data: a shape, isophote edits, a light, a model.

Every random choice of sample ``index`` under seed ``K`` comes from streams seeded by
``(K, index, attempt)`` alone (one stream per kind of choice: shape, edits, light, model), so a
sample is the same whichever worker makes it and whatever else runs, and changing how one kind
of choice is drawn (the light, once it may leave the plane) changes nothing else.

The shapes and edits are those of the project's test corpora, made by the built-in plugins:
random creatures (``sketchforge_assemble.testing.random_creature``: a body, head, limbs and an
eye), or a drawn outline (``sketchforge_isophote_tool.corpus.random_outline``: a blob or a star)
with 1-3 elliptic holes; edits are the isophote corpus' (``random_edit``: a piece of an isophote
moved sideways or bent, possibly with a loop or running past the band), applied as
``sculpt_isophote`` journal entries, so the document is an ordinary one. An attempt whose shape
cannot be built or assembled is drawn again with the next attempt number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from sketchforge.errors import SketchforgeError

#: Edge length of the random shapes (the app's default resolution).
RESOLUTION = 0.03
#: Attempts at one sample before it is reported as failed.
MAX_ATTEMPTS = 8
#: Tries at each edit (a random edit may be refused: a stroke in the rim margin, no isophote).
EDIT_TRIES = 4
#: Stream numbers of the kinds of random choice.
_SHAPE, _EDITS, _LIGHT, _MODEL = range(4)


def draw_light(rng: np.random.Generator) -> np.ndarray:
    """A random direction towards the light, uniform over those a document can hold.

    The light lies on the hemisphere facing the viewer (z >= 0), as a document's light may
    (issue 35); uniform there means z uniform in [0, 1] (Archimedes) and the azimuth uniform.

    Returns
    -------
    (3,) float64
        A unit vector (x, y, z), z >= 0; its x, y are unit to rounding when z = 0, so a
        document keeps them bit for bit.
    """
    azimuth = rng.uniform(0.0, 2.0 * math.pi)
    height = rng.uniform(0.0, 1.0)
    z = height
    r = math.sqrt(1.0 - z * z)
    return np.array([r * math.cos(azimuth), r * math.sin(azimuth), z])


def streams(seed: int, index: int, attempt: int) -> list[np.random.Generator]:
    """The four random streams (shape, edits, light, model) of one attempt at one sample."""
    children = np.random.SeedSequence([int(seed), int(index), int(attempt)]).spawn(4)
    return [np.random.default_rng(c) for c in children]


def creature_journal(rng: np.random.Generator) -> list[dict]:
    """A random creature's journal (the assemble plugin's corpus generator)."""
    from sketchforge_assemble.testing import random_creature

    try:
        return random_creature(int(rng.integers(0, 2**62)), resolution=RESOLUTION)["journal"]
    except ValueError as exc:  # the few seeds whose head cannot be placed
        raise SketchforgeError(str(exc)) from None


def holes_journal(rng: np.random.Generator) -> list[dict]:
    """A drawn outline (a blob or a star) with 1-3 elliptic holes, each at least 3 edge lengths
    from the outline and from the other holes; refused (SketchforgeError) when none fits."""
    import shapely
    from sketchforge_isophote_tool.corpus import random_outline

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


def add_edits(doc, rng: np.random.Generator, model_name: str, count: int) -> int:
    """Apply up to ``count`` random isophote edits (the isophote corpus' kinds) to random layers
    of ``doc`` (larger layers more often) under the document's light and ``model_name``;
    returns how many were applied. A refused edit is drawn again, at most
    :data:`EDIT_TRIES` times per edit."""
    from sketchforge_isophote_tool.corpus import random_edit
    from sketchforge_isophote_tool.layerdata import layer_data

    model = doc.host.reflectance_models[model_name]
    applied = 0
    for _ in range(count):
        for _ in range(EDIT_TRIES):
            layers = [layer for layer in doc.layers if layer.mesh is not None]
            weights = np.array([layer.mesh.n_vertices for layer in layers], dtype=np.float64)
            layer = layers[int(rng.choice(len(layers), p=weights / weights.sum()))]
            ld = layer_data(layer.mesh, doc.light.direction, model)
            edit = random_edit("sample", ld, rng)
            if edit is None:
                continue
            entry = {"command": "sculpt_isophote", "layer": layer.id, "pick": [float(v) for v in edit.pick],
                     "band": float(edit.band), "stroke": np.asarray(edit.stroke, dtype=np.float64).tolist()}
            if model_name != "lambertian":
                entry["model"] = model_name
            try:
                doc.execute(entry)
            except SketchforgeError:
                continue
            applied += 1
            break
    return applied


@dataclass(frozen=True)
class Sample:
    """A random document and what the sample records about it."""

    doc: Any
    kind: str
    model: str
    light: np.ndarray
    edits: int
    holes: int
    attempt: int


def make_sample(seed: int, index: int, host=None) -> Sample:
    """Sample ``index`` of seed ``seed``: its document, replayed and assembled.

    Raises
    ------
    SketchforgeError
        When :data:`MAX_ATTEMPTS` attempts all fail (the last one's reason), or when the
        plugins that make the shapes are not installed.
    """
    from sketchforge.document import Document, Light
    from sketchforge.plugins.manager import default_host

    host = default_host() if host is None else host
    for plugin in ("assemble", "isophote_tool"):
        if plugin not in host.plugin_names():
            raise SketchforgeError(
                f"sketchforge dataset needs the {plugin!r} plugin (its random shapes and edits); it is not installed"
            )
    models = sorted(host.reflectance_models)
    last = ""
    for attempt in range(MAX_ATTEMPTS):
        shape_rng, edit_rng, light_rng, model_rng = streams(seed, index, attempt)
        light = draw_light(light_rng)
        model = models[int(model_rng.integers(len(models)))]
        kind = "creature" if shape_rng.random() < 0.5 else "holes"
        try:
            journal = creature_journal(shape_rng) if kind == "creature" else holes_journal(shape_rng)
            doc = Document(host=host, light=Light.from_vector(light))
            if not np.array_equal(doc.light.direction, light):
                raise RuntimeError(f"a document cannot hold the light {light.tolist()}")
            for entry in journal:
                doc.execute(entry)
            edits = add_edits(doc, edit_rng, model, int(edit_rng.integers(1, 4)))
            doc.export_mesh()  # assembled now: a shape that cannot be is drawn again
        except SketchforgeError as exc:
            last = str(exc)
            continue
        holes = sum(len(layer.holes) for layer in doc.layers)
        return Sample(doc, kind, model, light, edits, holes, attempt)
    raise SketchforgeError(f"sample {index}: no valid shape in {MAX_ATTEMPTS} attempts (the last: {last})")
