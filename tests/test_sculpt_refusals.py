"""Honest refusals and the bound on an edit, the same for every sculpt solver (issue 36, points 2
and 3): a band narrower than one edge length, a stroke whose moving part lies only in the rim
margin, a stroke within the never-worse tolerance that would end farther, an edit that would
change heights by more than 60% of the peak."""

import numpy as np
import pytest
from sculpt_helpers import isophote_stroke, stroke_moving_only_in_the_margin

from sketchforge.errors import NothingToDoError, SculptError
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool import sculpt
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.pipeline import MAX_CHANGE
from sketchforge_isophote_tool.testing import LIGHT, inflated
from sketchforge_strips.solver import STRIPS

SOLVERS = [None, STRIPS]
PICK = [0.2, 0.1]


@pytest.fixture(scope="module")
def ellipse():
    return inflated("ellipse", 0.04)


@pytest.mark.parametrize("solver", SOLVERS, ids=["gauss_newton", "strips"])
def test_a_band_narrower_than_one_edge_length_is_refused(ellipse, solver):
    ld = layer_data(ellipse, LIGHT, LAMBERTIAN)
    stroke, _, _ = isophote_stroke(ellipse, PICK, offset=0.1)
    with pytest.raises(SculptError, match=r"narrower than one edge length.*widen it to at least") as info:
        sculpt(ellipse, LIGHT, PICK, 0.9 * ld.h, stroke, solver=solver)
    assert "\n" not in str(info.value)
    # One edge length is enough to be heard.
    r = sculpt(ellipse, LIGHT, PICK, 1.5 * ld.h, isophote_stroke(ellipse, PICK, offset=0.5 * ld.h)[0], solver=solver)
    assert r.after <= r.before


@pytest.mark.parametrize("solver", SOLVERS, ids=["gauss_newton", "strips"])
def test_a_stroke_moving_only_in_the_rim_margin_gets_the_rim_margin_message_and_changes_nothing(ellipse, solver):
    stroke, ld = stroke_moving_only_in_the_margin(ellipse, PICK, 1.5)
    with pytest.raises(SculptError, match="rim margin.*draw it further inside"):
        sculpt(ellipse, LIGHT, PICK, 0.3, stroke, solver=solver)


@pytest.mark.parametrize("solver", SOLVERS, ids=["gauss_newton", "strips"])
def test_a_stroke_within_the_tolerance_never_ends_farther(solver):
    """Strokes 0.05-0.2 edge lengths off the isophote, on a fresh layer and on one edited three
    times (where the first release applied a change of 24% of the peak that left the isophote
    farther): each is refused as already on the isophote, or ends no farther from it."""
    mesh = inflated("ellipse", 0.04)
    layers = [mesh]
    for off in (0.08, -0.06, 0.1):
        st, _, _ = isophote_stroke(layers[-1], [0.1, -0.05], offset=off)
        layers.append(sculpt(layers[-1], LIGHT, [0.1, -0.05], 0.3, st, solver=solver).mesh)
    outcomes = []
    for layer in (layers[0], layers[-1]):
        h = layer_data(layer, LIGHT, LAMBERTIAN).h
        for frac in (0.05, 0.12, 0.2):
            st, _, _ = isophote_stroke(layer, PICK, offset=frac * h)
            try:
                r = sculpt(layer, LIGHT, PICK, 0.3, st, solver=solver)
            except NothingToDoError as exc:
                assert "already" in str(exc)
                outcomes.append("refused")
                continue
            assert r.after <= r.before, (frac, r.before / h, r.after / h)
            outcomes.append("applied")
    assert len(outcomes) == 6


def test_an_edit_over_60_percent_of_the_peak_is_scaled_down_and_says_so(ellipse):
    from sketchforge.plugin_api import SculptSolver
    from sketchforge_isophote_tool.gauss_newton import check_params, solve

    st, _, _ = isophote_stroke(ellipse, PICK, 0.1)
    peak = ellipse.V[:, 2].max()
    # The built-in answer plus a lump of 120% of the peak far from the stroke.
    lump = 1.2 * peak * np.exp(-np.sum((ellipse.V[:, :2] - [-0.5, -0.2]) ** 2, axis=1) / 0.02)

    def with_lump(problem, params):
        return solve(problem, params).dz + lump

    huge = SculptSolver("huge", with_lump, check_params)
    r = sculpt(ellipse, LIGHT, PICK, 0.3, st, solver=huge)
    assert np.abs(r.mesh.V[:, 2] - ellipse.V[:, 2]).max() <= MAX_CHANGE * peak * (1 + 1e-9)
    assert r.bounded_from == pytest.approx(1.2, abs=0.02)  # the lump, and the edit's own change
    assert r.fraction == pytest.approx(MAX_CHANGE / r.bounded_from) and r.after < r.before
    assert f"would have changed heights by {r.bounded_from:.0%} of the peak, at most 60%" in r.describe()
    k = 1.0
    # Scaled down and still pointing the wrong way: refused, with the figure.
    wrong = SculptSolver("wrong", lambda problem, params: lump - k * solve(problem, params).dz, check_params)
    with pytest.raises(SculptError, match=r"would change heights by 1\d\d% of the peak; at most 60% is applied"):
        sculpt(ellipse, LIGHT, PICK, 0.3, st, solver=wrong)
