"""Random documents for shape-from-shading data: a shape, isophote edits, a light, a model.

Every random choice of sample ``index`` under seed ``K`` comes from streams seeded by
``(K, index, attempt)`` alone (one stream per kind of choice: shape, edits, light, model), so a
sample is the same whichever worker makes it and whatever else runs, and changing how one kind
of choice is drawn (the light, once it may leave the plane) changes nothing else.

The shapes and edits come from the installed plugins, through the hook
``sketchforge_dataset_generators`` (the core knows no shape of its own): a shape generator
returns the journal entries of a sample's layers, an edit generator one journal entry that
edits a layer, so the document is an ordinary one. Built in: random creatures (``creature``,
plugin ``assemble``: a body, head, limbs and an eye), drawn outlines with 1-3 elliptic holes
(``holes``, plugin ``isophote_tool``) and isophote edits (``isophote``, plugin
``isophote_tool``: a piece of an isophote moved sideways or bent, possibly with a loop or
running past the band). Generators are taken in name order, so a sample depends on the seed
and on which are installed (the manifest lists them). An attempt whose shape cannot be built
or assembled is drawn again with the next attempt number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from sketchforge.errors import SketchforgeError

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


def add_edits(doc, generators: list, rng: np.random.Generator, model_name: str, count: int) -> int:
    """Apply up to ``count`` random edits from the edit ``generators`` (dataset generators of
    kind "edit", sorted by name) to random layers of ``doc`` (larger layers more often) under
    the document's light and ``model_name``; returns how many were applied. A refused edit
    (or a generator that finds nothing) is drawn again, at most :data:`EDIT_TRIES` times per
    edit. With several generators each try draws one first."""
    applied = 0
    if not generators:
        return 0
    for _ in range(count):
        for _ in range(EDIT_TRIES):
            gen = generators[int(rng.integers(len(generators)))] if len(generators) > 1 else generators[0]
            layers = [layer for layer in doc.layers if layer.mesh is not None]
            weights = np.array([layer.mesh.n_vertices for layer in layers], dtype=np.float64)
            layer = layers[int(rng.choice(len(layers), p=weights / weights.sum()))]
            entry = gen.make(doc, layer.id, model_name, rng)
            if entry is None:
                continue
            try:
                doc.execute(entry)
            except SketchforgeError:
                continue
            applied += 1
            break
    return applied


def generators(host) -> tuple[list, list]:
    """(shape generators, edit generators) installed on ``host``, each sorted by name."""
    gens = sorted(host.dataset_generators.values(), key=lambda g: g.name)
    return [g for g in gens if g.kind == "shape"], [g for g in gens if g.kind == "edit"]


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
    shapes, edits = generators(host)
    if not shapes:
        raise SketchforgeError(
            "sketchforge dataset needs a plugin that draws random shapes (a dataset generator of kind 'shape', "
            "such as the built-in 'assemble' and 'isophote_tool' plugins'); none is installed"
        )
    models = sorted(host.reflectance_models)
    last = ""
    for attempt in range(MAX_ATTEMPTS):
        shape_rng, edit_rng, light_rng, model_rng = streams(seed, index, attempt)
        light = draw_light(light_rng)
        model = models[int(model_rng.integers(len(models)))]
        shape = shapes[min(int(shape_rng.random() * len(shapes)), len(shapes) - 1)]
        kind = shape.name
        try:
            journal = shape.make(shape_rng)
            doc = Document(host=host, light=Light.from_vector(light))
            if not np.array_equal(doc.light.direction, light):
                raise RuntimeError(f"a document cannot hold the light {light.tolist()}")
            for entry in journal:
                doc.execute(entry)
            edits_applied = add_edits(doc, edits, edit_rng, model, int(edit_rng.integers(1, 4)))
            doc.export_mesh()  # assembled now: a shape that cannot be is drawn again
        except SketchforgeError as exc:
            last = str(exc)
            continue
        holes = sum(len(layer.holes) for layer in doc.layers)
        return Sample(doc, kind, model, light, edits_applied, holes, attempt)
    raise SketchforgeError(f"sample {index}: no valid shape in {MAX_ATTEMPTS} attempts (the last: {last})")
