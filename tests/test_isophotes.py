"""Isophote extraction, picking the isovalue and selecting a component."""

import numpy as np
import pytest
from meshes import disk, gaussian_bump, hemisphere

from sketchforge.errors import SculptError
from sketchforge.geometry.contour import signed_area
from sketchforge.geometry.intensity import vertex_intensity
from sketchforge.geometry.isophotes import isophotes, isovalue_at, select_isophote

L = np.array([np.cos(0.3), np.sin(0.3), 0.0])


def test_one_triangle_by_hand():
    V = np.array([[0.0, 0], [1, 0], [0, 1]])
    lines, closed = isophotes(V, np.array([[0, 1, 2]]), np.array([0.0, 1.0, 2.0]), 0.5)
    assert len(lines) == 1 and not closed[0]
    # Crossings on edges (0,2) at y = 0.25 and (0,1) at x = 0.5. E = x + 2y grows away from
    # the origin, so with the brighter side on the left the curve runs from the y axis down.
    np.testing.assert_allclose(lines[0], [[0.0, 0.25], [0.5, 0.0]], atol=1e-15)


def test_hemisphere_isophotes_are_chords_with_exact_vertex_values():
    m = hemisphere(1.0, 0.05)
    E = m.V[:, :2] @ L[:2]  # exact n·l at the vertices; linear, so interpolation is exact
    for c in (0.0, 0.3, 0.8):
        lines, closed = isophotes(m.V[:, :2], m.F, E, c)
        assert len(lines) == 1 and not closed[0]
        line = lines[0]
        np.testing.assert_allclose(line @ L[:2], c, atol=1e-14)
        # Open at the rim: both ends on the boundary polygon (within its chord sag).
        ends = np.hypot(line[[0, -1], 0], line[[0, -1], 1])
        assert np.all(ends > 1 - 0.05**2) and np.all(ends <= 1 + 1e-12)
        # Ordered: consecutive points are at most one triangle apart.
        assert np.max(np.linalg.norm(np.diff(line, axis=0), axis=1)) < 0.1
        # Brighter side on the left: the tangent is the light turned clockwise.
        d = line[-1] - line[0]
        assert d[0] * L[1] - d[1] * L[0] > 0


def test_hemisphere_isophotes_from_mesh_normals_within_normal_error():
    # Distance of an isophote point from the chord x·l = c is ρ|E_mesh - n·l| there, bounded by
    # the vertex error of E: 0.017 for r < 0.9 at h = 0.05 (see test_shading).
    m = hemisphere(1.0, 0.05)
    E = vertex_intensity(m.V, m.F, L)
    lines, _ = isophotes(m.V[:, :2], m.F, E, 0.5)
    pts = np.concatenate(lines)
    interior = np.hypot(pts[:, 0], pts[:, 1]) < 0.85
    assert interior.sum() > 20
    assert np.abs(pts[interior] @ L[:2] - 0.5).max() < 0.025
    main = lines[select_isophote(lines, [0.5 * L[0], 0.5 * L[1]])]
    assert len(main) > 25


def test_closed_isophote_on_gaussian_bump():
    m = gaussian_bump(1.0, 0.05, amp=0.5, sigma=0.35)
    z = m.V[:, 2]
    lines, closed = isophotes(m.V, m.F, z, 0.25)  # level set of height: circle r² = 2σ² ln 2
    assert len(lines) == 1 and closed[0]
    line = lines[0]
    np.testing.assert_array_equal(line[0], line[-1])
    np.testing.assert_allclose(line[:, 2], 0.25, atol=1e-12)  # (n,3) input: curve on the surface
    r = np.hypot(line[:, 0], line[:, 1])
    r0 = 0.35 * np.sqrt(2 * np.log(2))
    assert np.abs(r - r0).max() < 0.005
    area = signed_area(line[:-1, :2])  # the closed curve repeats its first point
    assert area > 0  # counter-clockwise around the bright (higher) side
    assert area == pytest.approx(np.pi * r0**2, rel=0.01)


def test_vertex_exactly_on_the_isovalue():
    # A fan around a centre vertex whose value equals c: the curve passes through the vertex
    # without duplicate points and without breaking into pieces.
    V2, F, _ = disk(1.0, 0.2)
    E = V2[:, 0].copy()
    centre = np.argmin(np.hypot(V2[:, 0], V2[:, 1]))
    c = E[centre]
    E[np.abs(E - c) < 1e-3] = c  # several vertices exactly on c
    lines, closed = isophotes(V2, F, E, c)
    assert len(lines) == 1 and not closed[0]
    line = lines[0]
    assert np.all(np.linalg.norm(np.diff(line, axis=0), axis=1) > 0)
    np.testing.assert_allclose(line[:, 0], c, atol=1e-3)


def test_isolated_peak_exactly_at_c_gives_nothing():
    V2, F, _ = disk(1.0, 0.3)
    E = np.zeros(len(V2))
    E[np.argmin(np.hypot(V2[:, 0], V2[:, 1]))] = 1.0
    lines, closed = isophotes(V2, F, E, 1.0)
    assert lines == [] and closed.shape == (0,)


def test_two_bumps_give_two_components_and_select_nearest():
    V2, F, _ = disk(1.0, 0.05)
    E = sum(np.exp(-np.sum((V2 - [x, 0]) ** 2, axis=1) / 0.02) for x in (0.4, -0.4))
    lines, closed = isophotes(V2, F, E, 0.5)
    assert len(lines) == 2 and np.all(closed)
    centres = [line[:-1].mean(axis=0) for line in lines]
    i = select_isophote(lines, [-0.5, 0.1])
    assert centres[i][0] < 0
    j = select_isophote(lines, [0.52, 0.0])
    assert centres[j][0] > 0
    with pytest.raises(SculptError):
        select_isophote([], [0, 0])


def test_isovalue_at_pick():
    m = hemisphere(1.0, 0.05)
    E = m.V[:, :2] @ L[:2]
    pick = 0.4 * L[:2] + 0.2 * np.array([-L[1], L[0]])
    assert isovalue_at(m, E, pick) == pytest.approx(0.4, abs=1e-12)
    # In shadow: the rim of the self-shadowed region, c = 0 (thesis 2.3.1).
    assert isovalue_at(m, E, -0.5 * L[:2]) == 0.0
    with pytest.raises(SculptError, match="outside the layer"):
        isovalue_at(m, E, [2.0, 0.0])
