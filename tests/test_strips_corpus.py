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
