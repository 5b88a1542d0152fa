"""The ``strips`` solver on shapes nobody here chose (issue 29, point 3): a reduced, seeded subset
of the corpus (the full one, both solvers side by side: benchmarks/bench_sculpt_corpus.py)."""

import numpy as np
import pytest

from sketchforge_isophote_tool.corpus import SHAPES, corpus_layers, draw_edits, refusal_reason, run_edit
from sketchforge_isophote_tool.testing import LIGHT
from sketchforge_strips.solver import STRIPS

INVALID = {"stroke outside the band", "stroke in the rim margin"}


@pytest.fixture(scope="module")
def outcomes():
    out = []
    for shape, _, mesh, rng in corpus_layers(SHAPES, per_shape=2, seed=29):
        out.extend(run_edit(mesh, LIGHT, e, STRIPS) for e in draw_edits(shape, mesh, rng, LIGHT, 3))
    return out


def test_no_strips_edit_crashes_or_ends_farther_from_the_stroke(outcomes):
    assert len(outcomes) == len(SHAPES) * 2 * 3
    assert not [o for o in outcomes if o.status == "crash"]
    ok = [o for o in outcomes if o.status == "ok"]
    assert all(o.after <= max(o.before, 0.25) for o in ok)
    refused = [o for o in outcomes if o.status == "refused"]
    assert all("\n" not in o.reason and len(o.reason) < 300 for o in refused)


def test_strips_edits_land_where_drawn(outcomes):
    valid = [o for o in outcomes if not (o.status == "refused" and refusal_reason(o.reason) in INVALID)]
    ok = [o for o in valid if o.status == "ok"]
    assert len(ok) >= 0.8 * len(valid)
    # The full corpus lands 100% of applied edits (2 x 320, two seeds); of ~20 here allow one
    # miss plus 5%: a fall to 80% (4 misses expected) fails.
    misses = [(o.shape, o.kind, o.before, o.after) for o in ok if not o.lands]
    assert len(misses) <= 1 + int(0.05 * len(ok)), misses
    assert np.median([o.after for o in ok]) < 0.5
    assert sum(o.shape == "thin" for o in ok) >= 2  # thin limbs are editable


@pytest.mark.parametrize("shape, seed", [("star", 36), ("thin", 36), ("concave", 6)])
def test_a_chain_of_strips_edits_keeps_the_surface_free_of_creases_and_folds(shape, seed):
    """Issue 36, point 1, on a seeded chain of 6 accepted edits (the benchmark runs 12 chains of
    10): interior creases (dihedral angle, shading jump) within 2.5x the fresh layer's, no new
    fold near the rim, and a stroke on the isophote afterwards changes heights by < 1%. The
    "C" of seed 6 is finely meshed (its fresh edges meet at 11° at most): under the former fixed
    30° bound its chain ended at 2.68x the fresh dihedral angle and 3.0x the shading jump."""
    from sketchforge.errors import SketchforgeError
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool import sculpt
    from sketchforge_isophote_tool.corpus import chain_measures, random_edit
    from sketchforge_isophote_tool.layerdata import layer_data

    _, _, fresh, rng = next(corpus_layers((shape,), per_shape=1, seed=seed))
    mesh, done, tries = fresh, 0, 0
    while done < 6 and tries < 40:
        tries += 1
        e = random_edit(shape, layer_data(mesh, LIGHT, LAMBERTIAN), rng, kind="shift")
        if e is None:
            continue
        try:
            mesh = sculpt(mesh, LIGHT, e.pick, e.band, e.stroke, solver=STRIPS, reference=fresh).mesh
        except SketchforgeError:
            continue
        done += 1
    assert done == 6
    m = chain_measures(fresh, mesh, LIGHT)
    assert m["dihedral"] <= 2.5 * m["dihedral_fresh"], m
    assert m["jump"] <= 2.5 * m["jump_fresh"], m
    assert m["folds"] == 0, m
