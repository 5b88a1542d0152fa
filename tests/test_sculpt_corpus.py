"""Isophote edits on shapes nobody here chose (issue 16, points 3 and 4).

A reduced, seeded subset of the corpus in ``sketchforge_isophote_tool.corpus`` (the full set
runs in ``benchmarks/bench_sculpt_corpus.py``): random blobs, stars, thin limbs 0.2–0.3 wide
and letter shapes with deep concavities; strokes = the isophote shifted or bumped by 1–5 edge
lengths, with a small loop, or partly outside the band.
"""

import numpy as np
import pytest

from sketchforge_isophote_tool.corpus import SHAPES, corpus_layers, refusal_reason, run_edits
from sketchforge_isophote_tool.testing import LIGHT

#: Refusals for strokes that ask for nothing the edit promises (no part inside the band, or
#: all of it in the rim margin): not valid edits in the issue's sense.
INVALID = {"stroke outside the band", "stroke in the rim margin"}


@pytest.fixture(scope="module")
def outcomes():
    out = []
    for shape, _, mesh, rng in corpus_layers(SHAPES, per_shape=4, seed=16):
        out.extend(run_edits(shape, mesh, rng, LIGHT, edits=4))
    return out


def test_no_edit_crashes(outcomes):
    crashes = [o for o in outcomes if o.status == "crash"]
    assert not crashes, crashes
    assert len(outcomes) == len(SHAPES) * 4 * 4


def test_isophotes_land_where_drawn_on_95_percent_of_valid_edits(outcomes):
    valid = [o for o in outcomes if not (o.status == "refused" and refusal_reason(o.reason) in INVALID)]
    landed = [o for o in valid if o.lands]
    assert len(valid) >= 0.75 * len(outcomes)
    # ~55 valid edits measure a rate to a few percent: the full corpus
    # (benchmarks/bench_sculpt_corpus.py, 2 seeds x 320 edits) lands 97.8% and moves 97%,
    # where 4 misses in 55 still happen on about 1 seed in 12. Allow 5% of the sample plus 2
    # (4 here): a true rate of 97% then fails on ~3% of seeds, a regression to 85% (8 misses
    # expected) on most. The benchmark holds the 95% figure itself.
    allowed = int(0.05 * len(valid)) + 2
    assert len(valid) - len(landed) <= allowed, [(o.shape, o.kind, o.move, o.before, o.after, o.reason) for o in valid if not o.lands]
    # ...and moved there: the isophote beside the stroke runs along it too (a pit whose little
    # loop touches the stroke while the old isophote stays would pass the first check only)
    moved = [o for o in valid if o.moved]
    assert len(valid) - len(moved) <= allowed, [(o.shape, o.kind, o.before, o.after, o.beside) for o in landed if not o.moved]
    # thin limbs are editable (point 4), not only refused
    assert sum(o.status == "ok" and o.shape == "thin" for o in outcomes) >= 4


def test_no_edit_ends_farther_from_the_stroke(outcomes):
    ok = [o for o in outcomes if o.status == "ok"]
    # 0.25 edge lengths: below what first-order vertex normals resolve (pipeline.RESOLUTION_EDGES)
    assert all(o.after <= max(o.before, 0.25) for o in ok)
    assert np.median([o.after for o in ok]) < 1.0


def test_refusals_are_one_line_and_say_what_to_do(outcomes):
    for o in outcomes:
        if o.status == "refused":
            assert "\n" not in o.reason and len(o.reason) < 300
            assert "draw" in o.reason or "nothing to change" in o.reason
