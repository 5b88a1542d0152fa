"""The band: isophote ⊕ disk, clipped to the layer's outline."""

import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon

from meshes import gaussian_bump, hemisphere
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
