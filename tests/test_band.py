"""The band: isophote ⊕ disk, clipped to the layer's outline."""

import numpy as np
import pytest
from meshes import gaussian_bump, hemisphere
from shapely.geometry import LineString, Point, Polygon

from sketchforge.errors import SculptError
from sketchforge.geometry.band import band
from sketchforge.geometry.isophotes import isophotes


def test_band_of_a_chord_is_clipped_to_the_outline():
    m = hemisphere(1.0, 0.05)
    outline = m.V[m.boundary, :2]
    E = m.V[:, 0]
    line = isophotes(m.V[:, :2], m.F, E, 0.3)[0][0]
    b = band(line, 0.1, outline)
    poly = Polygon(outline)
    assert b.difference(poly).area < 1e-12
    assert b.contains(Point(0.3, 0.0)) and b.contains(Point(0.39, 0.0))
    assert not b.contains(Point(0.41, 0.0)) and not b.contains(Point(0.19, 0.0))
    # Area: the strip |x - 0.3| <= 0.1 inside the disk (the caps are clipped away).
    exact = poly.intersection(Polygon([(0.2, -2), (0.4, -2), (0.4, 2), (0.2, 2)])).area
    assert b.area == pytest.approx(exact, rel=2e-3)


def test_band_around_a_closed_isophote_has_a_hole():
    m = gaussian_bump(1.0, 0.05)
    lines, closed = isophotes(m.V[:, :2], m.F, m.V[:, 2], 0.25)
    assert closed[0]
    b = band(lines[0], 0.05, m.V[m.boundary])
    assert b.geom_type == "Polygon" and len(b.interiors) == 1
    assert not b.contains(Point(0, 0))
    L = LineString(lines[0]).length
    assert b.area == pytest.approx(2 * 0.05 * L, rel=0.01)


@pytest.mark.parametrize("radius", [0.0, -0.1, float("nan"), float("inf"), "wide"])
def test_bad_radius_is_a_sculpt_error(radius):
    square = np.array([[-1.0, -1], [1, -1], [1, 1], [-1, 1]])
    with pytest.raises(SculptError, match="radius"):
        band(np.array([[0.0, 0], [0.5, 0]]), radius, square)


def test_degenerate_inputs():
    square = np.array([[-1.0, -1], [1, -1], [1, 1], [-1, 1]])
    with pytest.raises(SculptError):
        band(np.array([[0.0, 0], [0.0, 0]]), 0.1, square)
    with pytest.raises(SculptError, match="does not overlap"):
        band(np.array([[5.0, 5], [6, 5]]), 0.1, square)


@pytest.mark.parametrize("radius", [10.0, 1e6, 1e9])
def test_a_band_wider_than_the_layer_is_the_whole_layer(radius):
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    outline = np.column_stack([np.cos(t), 0.7 * np.sin(t)])
    layer = Polygon(outline)
    chord = np.array([[-0.5, 0.1], [0.0, 0.2], [0.5, 0.1]])
    B = band(chord, radius, outline)
    assert B.is_valid and B.symmetric_difference(layer).area < 1e-9 * layer.area


@pytest.mark.parametrize("radius", [2e9, 1e200, 1e300])
def test_a_band_beyond_the_drawing_s_range_is_refused_before_geos_sees_it(radius):
    # 1e300 once made GEOS throw a TopologyException from inside the buffer.
    square = np.array([[-1.0, -1], [1, -1], [1, 1], [-1, 1]])
    with pytest.raises(SculptError, match=r"too large; it must be at most 1e\+09 drawing units"):
        band(np.array([[0.0, 0], [0.5, 0]]), radius, square)


def test_the_band_grows_with_its_radius_up_to_the_layer():
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    outline = np.column_stack([np.cos(t), 0.7 * np.sin(t)])
    layer = Polygon(outline)
    chord = np.array([[-0.5, 0.1], [0.0, 0.2], [0.5, 0.1]])
    radii = np.geomspace(0.01, 40.0, 60)
    areas = np.array([band(chord, r, outline).area for r in radii])
    assert np.all(np.diff(areas) >= -1e-12) and areas[-1] == pytest.approx(layer.area, rel=1e-9)
    # no jump where the radius starts being capped (twice the drawing's extent, 4.88 here):
    # the band is the whole layer on both sides of it
    cap = 2.0 * np.hypot(2.0, 1.4)
    for r in (0.999 * cap, 1.001 * cap):
        assert band(chord, r, outline).symmetric_difference(layer).area < 1e-9 * layer.area
