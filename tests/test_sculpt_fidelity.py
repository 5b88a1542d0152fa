"""Fidelity of the isophote edit and the thesis' observations (ch. 5), on inflated layers.

Light (1/√2, 1/√2, 0), band 0.3, strokes = the picked isophote offset by ±0.1 (4 edge lengths).
"""

import numpy as np
import pytest
import shapely
from sculpt_helpers import fidelity, isophote_stroke

from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool import sculpt
from sketchforge_isophote_tool.fidelity import isophote_lines
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.testing import LIGHT, inflated

CASES = [("ellipse", [0.2, 0.1]), ("pillow", [0.2, 0.1]), ("m", [-0.2, 0.35]), ("m", [0.3, 0.45])]


@pytest.mark.parametrize("offset", [0.1, -0.1])
@pytest.mark.parametrize("shape,pick", CASES)
def test_new_isophote_follows_the_stroke(shape, pick, offset):
    mesh = inflated(shape, 0.03)
    st, c, iso = isophote_stroke(mesh, pick, offset)
    r = sculpt(mesh, LIGHT, pick, 0.3, st)
    before, after, h = fidelity(r)
    assert before > 3 * h
    assert after <= max(2 * h, 0.3 * before)
    assert abs(after - r.after) < 1e-9 and abs(before - r.before) < 1e-9  # the pipeline's own check agrees
    # No new c-isophote piece away from the stroke: new isophote points far from every old
    # c-isophote lie near the stroke.
    ld0, ld1 = layer_data(mesh, LIGHT, LAMBERTIAN), layer_data(r.mesh, LIGHT, LAMBERTIAN)
    old, new = isophote_lines(ld0.planar, ld0.E, c), isophote_lines(ld1.planar, ld1.E, c)
    P = shapely.get_coordinates(new)
    moved = shapely.distance(shapely.points(P), old) > 3 * h
    near_stroke = shapely.distance(shapely.points(P), r.stroke) < 0.3 + 2 * h
    assert not (moved & ~near_stroke).any()


def test_changed_region_grows_with_the_band():
    mesh = inflated("ellipse", 0.03)
    st, _, _ = isophote_stroke(mesh, [0.2, 0.1], 0.05)
    counts = [sculpt(mesh, LIGHT, [0.2, 0.1], band, st).changed.sum() for band in (0.15, 0.3, 0.45)]
    assert counts[0] < counts[1] < counts[2]


def test_same_edit_at_two_resolutions_agrees():
    fine, coarse = inflated("ellipse", 0.025), inflated("ellipse", 0.04)
    st, _, _ = isophote_stroke(coarse, [0.2, 0.1], 0.1)
    rf = sculpt(fine, LIGHT, [0.2, 0.1], 0.3, st)
    rc = sculpt(coarse, LIGHT, [0.2, 0.1], 0.3, st)
    ldc = layer_data(rc.mesh, LIGHT, LAMBERTIAN)
    V = fine.V
    inside = rf.changed & (ldc.locator.locate(V[:, :2])[0] >= 0)
    zc = ldc.locator.interpolate(ldc.z, V[inside, :2])
    peak = fine.V[:, 2].max()
    assert inside.sum() > 50
    assert np.abs(rf.mesh.V[inside, 2] - zc).max() <= 0.05 * peak
    # and both land where drawn
    for r in (rf, rc):
        before, after, h = fidelity(r)
        assert after <= max(2 * h, 0.3 * before)


def test_what_the_app_draws_after_an_edit():
    """The landed isophote (white in the app) runs along the stroke, and the characteristics
    pass through the stroke in the direction -∇R (the strips' base direction, thesis 3.1.2)."""
    from sketchforge_isophote_tool.layerdata import vertex_shading

    mesh = inflated("ellipse", 0.03)
    st, _, _ = isophote_stroke(mesh, [0.2, 0.1], 0.1)
    r = sculpt(mesh, LIGHT, [0.2, 0.1], 0.3, st)
    landed = np.concatenate(r.new_isophotes())
    P = np.asarray(shapely.segmentize(r.stroke, 0.5 * r.h).coords)
    assert shapely.distance(shapely.points(P), shapely.MultiPoint(landed)).mean() < 2 * r.h
    lines = r.characteristics(n=9)
    assert len(lines) == 9
    _, Rp, Rq = vertex_shading(r.layer.planar, r.layer.z, LIGHT, r.layer.model)
    for line in lines:
        assert shapely.distance(shapely.LineString(line), r.stroke) < 1e-9  # through the stroke
        k = int(np.argmin(shapely.distance(shapely.points(line), r.stroke)))
        k = min(max(k, 1), len(line) - 2)
        tangent = line[k + 1] - line[k - 1]
        flow = -r.layer.locator.interpolate(np.column_stack([Rp, Rq]), line[k][None])[0]
        cos = abs(tangent @ flow) / (np.linalg.norm(tangent) * np.linalg.norm(flow))
        assert cos > 0.98, cos
