"""The sculpt's fidelity measures, checked on layouts whose answer is known by hand.

``fidelity.py`` is what the pipeline uses to refuse an edit that would end farther from the
stroke than it started, and what the sculpt tests and the corpus benchmark report. A wrong
measure would let a failing sculpt pass, so each function is checked here against distances
worked out on straight lines, where every distance is exact.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import shapely
import shapely.affinity

from sketchforge.geometry.locate import locate
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool.fidelity import beside_distance, honoured_samples, isophote_lines, mean_distance
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.testing import LIGHT, inflated

STROKE = shapely.LineString([(0.0, 0.0), (10.0, 0.0)])


def _line(*xy):
    return shapely.MultiLineString([list(xy)])


# --- beside_distance ----------------------------------------------------------------------------


@pytest.mark.parametrize("offset", [0.05, 0.3, 0.9])
def test_an_isophote_parallel_to_the_stroke_is_beside_it_at_its_offset(offset):
    lines = _line((-5.0, offset), (15.0, offset))
    assert beside_distance(lines, STROKE, radius=1.0, h=0.1) == pytest.approx(offset, rel=1e-12)


def test_isophote_points_farther_than_the_radius_do_not_count():
    lines = _line((2.0, 0.5), (8.0, 0.5))
    assert beside_distance(lines, STROKE, radius=0.49, h=0.1) == 0.0
    assert beside_distance(lines, STROKE, radius=0.51, h=0.1) == pytest.approx(0.5, rel=1e-12)
    # Only the near half of a tilted line counts: d runs from 0.2 to 0.8 along it.
    tilted = _line((2.0, 0.2), (8.0, 0.8))
    assert beside_distance(tilted, STROKE, radius=0.5, h=0.01) == pytest.approx(0.35, abs=2e-3)


def test_no_isophote_or_none_near_gives_zero():
    assert beside_distance(shapely.MultiLineString(), STROKE, radius=1.0, h=0.1) == 0.0
    # (also for a stroke running past the origin: "no isophote" has no point anywhere)
    through_origin = shapely.LineString([(-5.0, 0.1), (5.0, 0.1)])
    assert beside_distance(shapely.MultiLineString(), through_origin, radius=1.0, h=0.1) == 0.0
    assert beside_distance(_line((0.0, 3.0), (10.0, 3.0)), STROKE, radius=1.0, h=0.1) == 0.0


def test_points_whose_nearest_stroke_point_is_an_end_are_not_beside_it():
    # Past either end, the nearest stroke point is the end itself: a new little loop there
    # must not count as the isophote having moved onto the stroke.
    bent = shapely.LineString([(0.0, 0.0), (5.0, 0.0), (10.0, 0.0)])  # its ends are x = 0 and 10
    for x in (10.3, -0.3):
        across = _line((x, -1.0), (x, 1.0))
        assert beside_distance(across, STROKE, radius=1.0, h=0.1) == 0.0
        assert beside_distance(across, bent, radius=1.0, h=0.1) == 0.0
    # Next to the start, within 2h of the end's distance: left out; with a finer h: beside.
    near_start = _line((0.1, 0.3), (0.3, 0.3))
    assert beside_distance(near_start, STROKE, radius=1.0, h=0.1) == 0.0
    assert beside_distance(near_start, STROKE, radius=1.0, h=0.01) == pytest.approx(0.3, rel=1e-12)
    # The margin is 2h: at x in [0.42, 0.5] the end is 0.52-0.58 away, more than d + 2h = 0.5.
    just_past = _line((0.42, 0.3), (0.5, 0.3))
    assert beside_distance(just_past, STROKE, radius=1.0, h=0.1) == pytest.approx(0.3, rel=1e-12)


def test_every_end_of_a_multi_part_stroke_is_an_end():
    stroke = shapely.MultiLineString([[(0.0, 0.0), (4.0, 0.0)], [(6.0, 0.0), (10.0, 0.0)]])
    # Across the gap, each point's nearest stroke point is an inner end (x = 4 or x = 6).
    gap = _line((4.5, -0.6), (4.5, 0.6), (5.5, 0.6), (5.5, -0.6))
    assert beside_distance(gap, stroke, radius=1.0, h=0.05) == 0.0
    # Along the parts, the offset.
    along = shapely.MultiLineString([[(1.0, 0.25), (3.0, 0.25)], [(7.0, 0.25), (9.0, 0.25)]])
    assert beside_distance(along, stroke, radius=1.0, h=0.05) == pytest.approx(0.25, rel=1e-12)


def test_the_mean_is_over_the_length_of_the_isophote_not_its_vertices():
    # Two pieces of equal length at 0.2 and 0.6, the first one with 20 times the vertices: the
    # mean must weigh them by length (0.4), not by vertex count (0.22).
    dense = [(2.0 + 0.05 * i, 0.2) for i in range(41)]
    lines = shapely.MultiLineString([dense, [(6.0, 0.6), (8.0, 0.6)]])
    assert beside_distance(lines, STROKE, radius=1.0, h=0.004) == pytest.approx(0.4, abs=0.01)


def test_the_isophote_is_sampled_every_quarter_edge_length():
    # A tilted isophote, d running from 0.2 to 0.8 along it; the part within 0.5 counts. Its
    # exact mean is 0.35; samples every h/4 = 0.1 come within 0.005 of it (every h would not).
    tilted = _line((2.0, 0.2), (8.0, 0.8))
    assert beside_distance(tilted, STROKE, radius=0.5, h=0.4) == pytest.approx(0.35, abs=0.005)


def test_beside_distance_scales_with_the_drawing():
    lines = _line((1.0, 0.1), (4.0, 0.35), (9.0, 0.2))
    d1 = beside_distance(lines, STROKE, radius=0.5, h=0.05)
    k = 3.0
    scaled = shapely.affinity.scale(lines, k, k, origin=(0, 0))
    dk = beside_distance(scaled, shapely.affinity.scale(STROKE, k, k, origin=(0, 0)), radius=0.5 * k, h=0.05 * k)
    assert d1 > 0.1 and dk == pytest.approx(k * d1, rel=1e-9)


# --- mean_distance ------------------------------------------------------------------------------


def test_mean_distance_is_the_mean_of_point_distances_and_inf_without_a_target():
    P = np.array([[1.0, 0.5], [2.0, -1.5], [3.0, 0.0]])
    assert mean_distance(P, STROKE) == pytest.approx((0.5 + 1.5 + 0.0) / 3, rel=1e-15)
    assert mean_distance(P, shapely.MultiLineString()) == np.inf
    assert mean_distance(np.zeros((0, 2)), STROKE) == np.inf


def test_an_isophote_across_a_single_triangle_is_a_line():
    # The shortest isophote piece crosses one triangle: two points. It must be kept.
    one = SimpleNamespace(V2=np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), F=np.array([[0, 1, 2]]))
    lines = isophote_lines(one, np.array([0.0, 1.0, 0.0]), 0.5)
    assert len(lines.geoms) == 1
    assert np.allclose(sorted(map(tuple, shapely.get_coordinates(lines))), [(0.5, 0.0), (0.5, 0.5)])


# --- isophote_lines and honoured_samples on a real layer ---------------------------------------


@pytest.fixture(scope="module")
def ellipse():
    return layer_data(inflated("ellipse"), LIGHT, LAMBERTIAN)


def test_isophote_lines_lie_on_the_level_of_the_shading(ellipse):
    pd, E = ellipse.planar, ellipse.E
    c = float(np.quantile(E, 0.6))
    lines = isophote_lines(pd, E, c)
    assert lines.geom_type == "MultiLineString" and not lines.is_empty
    # Interpolate E linearly at points on the lines (inside a triangle of the mesh): = c.
    P = shapely.get_coordinates(lines)
    tri, bary = locate(pd.V2, pd.F, P)
    ok = tri >= 0
    assert ok.mean() > 0.99
    Ei = (E[pd.F[tri[ok]]] * bary[ok]).sum(1)
    assert np.abs(Ei - c).max() < 1e-9
    # A level no vertex reaches has no line.
    assert isophote_lines(pd, E, float(E.max()) + 1.0).is_empty


def test_honoured_samples_are_the_stroke_points_in_the_band_and_off_the_rim(ellipse):
    pd = ellipse.planar
    xs = np.linspace(-1.2, 1.2, 97)
    P = np.column_stack([xs, np.zeros_like(xs)])  # across the whole ellipse and beyond
    # A band as the tool builds it: inside the layer (here its right part, x > -0.5).
    band = shapely.box(-0.5, -1.0, 2.0, 1.0).intersection(pd.outline)
    got = honoured_samples(pd, [P[:40], P[40:]], band)
    inside = (P[:, 0] > -0.5) & (np.abs(P[:, 0]) < 1.0) & (pd.rim_distance(P) >= pd.margin_at(P))
    assert np.array_equal(got, P[inside])
    # The rim margin keeps out more than the band does: the samples stop short of x = 1.
    assert 0 < len(got) < inside[P[:, 0] > -0.5].size and got[:, 0].max() < 1.0 - pd.margin_at(got).min()
    assert got[:, 0].min() > -0.5
    assert honoured_samples(pd, [], band).shape == (0, 2)
