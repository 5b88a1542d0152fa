"""What a sculpt reports besides its mesh (the shading change it aimed at, the time of each
stage) and the edges of its options: 1..50 Gauss–Newton steps, a rim margin of 0."""

from __future__ import annotations

import time

import numpy as np
import pytest
from sculpt_helpers import isophote_stroke

from sketchforge.errors import ParameterError
from sketchforge_isophote_tool import sculpt
from sketchforge_isophote_tool.testing import LIGHT, inflated

PICK = [0.2, 0.1]


def _edit(**params):
    mesh = inflated("ellipse", 0.04)
    stroke, _, _ = isophote_stroke(mesh, PICK, offset=0.04)
    t0 = time.perf_counter()
    r = sculpt(mesh, LIGHT, PICK, 0.3, stroke, params=params or None)
    return r, time.perf_counter() - t0


def test_a_sculpt_reports_its_shading_change_and_the_time_of_each_stage():
    r, wall = _edit()
    assert r.dE.shape == (len(r.mesh.V),) and np.abs(r.dE).max() > 0.01
    assert not r.dE[r.mesh.boundary].any()  # the outline's shading is not asked to change
    stages = ("stroke", "zones", "shading", "check", "total")
    assert set(stages) <= set(r.timings)
    for stage in stages:
        assert 0.0 <= r.timings[stage] <= wall, stage
    assert r.timings["total"] >= max(r.timings[s] for s in stages[:-1])


@pytest.mark.parametrize("steps, ok", [(1, True), (50, True), (0, False), (51, False)])
def test_the_steps_option_takes_1_to_50(steps, ok):
    if ok:
        r, _ = _edit(steps=steps)
        assert r.options["steps"] == steps and r.changed.any()
        return
    with pytest.raises(ParameterError) as err:
        _edit(steps=steps)
    assert str(err.value) == f"sculpt solver 'gauss_newton': 'steps' must be an integer in 1..50, got {steps}"


def test_a_rim_margin_of_zero_weighs_the_whole_stroke_fully():
    r0, _ = _edit(rim_margin=0.0)
    r, _ = _edit()
    assert r0.changed.any() and r0.after < r0.before
    assert r0.options["rim_margin"] == 0.0 and not np.array_equal(r0.mesh.V, r.mesh.V)
