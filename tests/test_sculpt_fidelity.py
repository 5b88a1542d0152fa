"""Fidelity of the isophote edit and the thesis' observations (ch. 5), on inflated layers.

Light (1/√2, 1/√2, 0), band 0.3, strokes = the picked isophote offset by ±0.1.
"""

import numpy as np
import pytest
import shapely

from sculpt_helpers import fidelity, isophote_stroke
from sketchforge.geometry.isophotes import isophotes
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool import sculpt
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.testing import LIGHT, inflated

CASES = [("ellipse", [0.2, 0.1]), ("pillow", [0.2, 0.1]), ("m", [-0.2, 0.35]), ("m", [0.3, 0.45])]


@pytest.mark.parametrize("offset", [0.1, -0.1])
@pytest.mark.parametrize("shape,pick", CASES)
def test_new_isophote_follows_the_stroke(shape, pick, offset):
    mesh = inflated(shape, 0.03)
    st, c, iso = isophote_stroke(mesh, pick, offset)
    r = sculpt(mesh, LIGHT, pick, 0.3, st)
    before, after, h, lines = fidelity(r)
    assert before > 0.08
    assert after <= max(2 * h, 0.3 * before)
    # No new c-isophote piece away from the stroke: new isophote points far from every old
    # c-isophote lie near the stroke.
    ld0 = layer_data(mesh, LIGHT, LAMBERTIAN)
    old = shapely.MultiLineString([L for L in isophotes(ld0.V2, mesh.F, ld0.E, c)[0] if len(L) > 1])
    P = np.concatenate(lines)
    pts = shapely.points(P)
    moved = shapely.distance(pts, old) > 3 * h
    near_stroke = shapely.distance(pts, r.stroke) < 0.3 + 2 * h
    assert not (moved & ~near_stroke).any()


def _M_area(mesh, pick, offset, band=0.3):
    st, c, _ = isophote_stroke(mesh, pick, offset)
    r = sculpt(mesh, LIGHT, pick, band, st)
    return r.regions.M.area, r.c


def test_impacted_region_larger_for_c_zero():
    mesh = inflated("ellipse", 0.03)
    a0, c0 = _M_area(mesh, [-0.3, -0.1], 0.05)  # in shadow: the terminator, c = 0
    a1, c1 = _M_area(mesh, [0.3, 0.2], 0.05)
    assert c0 == 0.0 and c1 > 0.2
    assert a0 > a1


def test_impacted_region_grows_with_the_band():
    mesh = inflated("ellipse", 0.03)
    areas = [_M_area(mesh, [0.2, 0.1], 0.05, band)[0] for band in (0.15, 0.3, 0.45)]
    assert areas[0] < areas[1] < areas[2]


def test_same_edit_at_two_resolutions_agrees():
    fine, coarse = inflated("ellipse", 0.025), inflated("ellipse", 0.04)
    st, _, _ = isophote_stroke(coarse, [0.2, 0.1], 0.1)
    rf = sculpt(fine, LIGHT, [0.2, 0.1], 0.3, st)
    rc = sculpt(coarse, LIGHT, [0.2, 0.1], 0.3, st)
    ldc = layer_data(rc.mesh, LIGHT, LAMBERTIAN)
    # compare on the fine vertices inside both impacted regions, away from the rim
    V = fine.V
    inside = shapely.contains_xy(rf.regions.M.intersection(rc.regions.M), V[:, 0], V[:, 1])
    zc = ldc.locator.interpolate(ldc.z, V[inside, :2])
    peak = fine.V[:, 2].max()
    assert inside.sum() > 50
    assert np.abs(rf.mesh.V[inside, 2] - zc).max() <= 0.05 * peak
