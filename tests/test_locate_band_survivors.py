"""Point location (nearest=True snapping, degenerate and rescaled meshes) and the band's edge cases.

These tests come from mutants of ``sketchforge/geometry/locate.py`` and ``band.py`` that the
rest of the suite did not kill. Every expectation is computed without the code under test:

- location is checked against its definition (a located point is a barycentric combination of
  its triangle's corners) and against invariances: scaling the mesh and the points by a power
  of two changes no bit of the arithmetic, a float32 mesh is the same mesh as its exact float64
  copy, and ``nearest=True`` must leave every point that plain location finds untouched;
- snapping is checked against brute force (the nearest used vertex over all vertices) and
  against distance bounds (a snapped point of a point δ outside lies within a few δ of it);
- the band is compared with closed-form regions (a straight strip across a comb-shaped outline,
  points a known distance from a segment), and its errors with the sentences the user sees.
"""

import warnings

import numpy as np
import pytest
from meshes import disk
from shapely.geometry import Point, Polygon

from sketchforge.errors import GeometryError, SculptError
from sketchforge.geometry.band import band
from sketchforge.geometry.locate import BARY_TOL, TriangleLocator, interpolate, locate

# A unit right triangle: its barycentrics are (1 - x - y, x, y) exactly, so points a known
# barycentric distance outside it can be written down by hand.
TRI_V = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
TRI_F = np.array([[0, 1, 2]])


@pytest.fixture(scope="module")
def mesh():
    return disk(1.0, 0.25)


def _outside_boundary(V2, boundary, delta):
    """Midpoints of the boundary edges pushed outward (away from the centre) by delta."""
    a, b = V2[boundary], V2[np.roll(boundary, -1)]
    mid = (a + b) / 2
    e = b - a
    n = np.c_[e[:, 1], -e[:, 0]] / np.hypot(e[:, 0], e[:, 1])[:, None]
    n *= np.sign(np.einsum("ij,ij->i", n, mid))[:, None]
    return mid + delta * n


def _corners_of(V2, F, face, bary):
    """The point each (face, bary) stands for, from the definition sum_j bary_j * V[F[face, j]]."""
    return np.einsum("kj,kjd->kd", bary, V2[F[face]])


# --------------------------------------------------------------------------- locate


def test_nearest_leaves_every_located_point_untouched(mesh):
    # Snapping is for points plain location reports as -1; a point it finds (including one
    # within the BARY_TOL slack just outside an edge) must come back bit for bit the same.
    V2, F, boundary = mesh
    rng = np.random.default_rng(11)
    P = np.vstack([
        rng.uniform(-1.2, 1.2, (400, 2)),
        V2,
        V2[F].mean(axis=1),  # one point deep inside every triangle, face 0 included
        *[_outside_boundary(V2, boundary, d) for d in (-1e-12, 0.0, 1e-13, 1e-12, 1e-11)],
        _outside_boundary(V2, boundary, 1e-3),
    ])
    loc = TriangleLocator(V2, F)
    face0, bary0 = loc.locate(P)
    face1, bary1 = loc.locate(P, nearest=True)
    found = face0 >= 0
    # The batch does exercise the slack (negative barycentrics accepted) and contains misses.
    assert bary0[found].min() < 0 and not found.all()
    assert np.all(found[-2 * len(boundary):-len(boundary)])  # 1e-11 outside is within the slack
    np.testing.assert_array_equal(face1[found], face0[found])
    np.testing.assert_array_equal(bary1[found], bary0[found])


def test_point_exactly_at_the_tolerance_is_located_the_same_with_nearest():
    # (0.5, -BARY_TOL) has barycentrics (0.5 + BARY_TOL, 0.5, -BARY_TOL) in the unit triangle:
    # on the boundary of the slack, it counts as inside and nearest=True must not alter it.
    loc = TriangleLocator(TRI_V, TRI_F)
    P = np.array([[0.5, -BARY_TOL], [0.5, -BARY_TOL / 2]])
    face0, bary0 = loc.locate(P)
    face1, bary1 = loc.locate(P, nearest=True)
    np.testing.assert_array_equal(face0, [0, 0])
    np.testing.assert_array_equal(face1, face0)
    np.testing.assert_array_equal(bary1, bary0)


@pytest.mark.parametrize("delta", [1e-6, 1e-4, 1e-2])
def test_points_just_outside_snap_to_a_nearby_point_of_the_mesh(mesh, delta):
    V2, F, boundary = mesh
    P = _outside_boundary(V2, boundary, delta)
    loc = TriangleLocator(V2, F)
    assert np.all(loc.locate(P)[0] == -1)  # really outside: plain location misses them all
    face, bary = loc.locate(P, nearest=True)
    assert np.all(face >= 0)
    assert bary.min() >= 0.0 and bary.max() <= 1.0
    np.testing.assert_allclose(bary.sum(axis=1), 1.0, atol=1e-14)
    Q = _corners_of(V2, F, face, bary)
    # Each P is delta from its boundary edge; a point of the adjacent 30°-quality triangle
    # is within a small multiple of that.
    assert np.hypot(*(Q - P).T).max() <= 3 * delta
    # Linear fields read at the snapped points are what curves on the outline expect.
    field = 2 * V2[:, 0] - 3 * V2[:, 1] + 1
    np.testing.assert_allclose(interpolate(field, F, face, bary), 2 * Q[:, 0] - 3 * Q[:, 1] + 1, atol=1e-13)


def test_outside_points_of_a_single_triangle_snap_into_it():
    # Every candidate is triangle 0 here. Distances to the triangle are exact: (0.6, 0.6) is
    # 0.2/sqrt(2) from the hypotenuse, the others 1e-3 from a leg.
    P = np.array([[0.6, 0.6], [0.5, -1e-3], [-1e-3, 0.5], [0.2, -1e-3]])
    dist = np.array([0.2 / np.sqrt(2), 1e-3, 1e-3, 1e-3])
    loc = TriangleLocator(TRI_V, TRI_F)
    np.testing.assert_array_equal(loc.locate(P)[0], -1)
    face, bary = loc.locate(P, nearest=True)
    np.testing.assert_array_equal(face, 0)
    assert bary.min() >= 0.0
    np.testing.assert_allclose(bary.sum(axis=1), 1.0, atol=1e-15)
    Q = _corners_of(TRI_V, TRI_F, face, bary)
    assert np.all(np.hypot(*(Q - P).T) <= 3 * dist)


def test_far_points_snap_to_their_nearest_used_vertex(mesh):
    V2, F, _ = mesh
    # An extra vertex that no triangle uses, close to the query points: it has no triangle
    # to report, so the answer must be the nearest vertex that one does use.
    V2x = np.vstack([V2, [[2.5, 0.0]]])
    loc = TriangleLocator(V2x, F)
    rng = np.random.default_rng(3)
    ang = rng.uniform(0, 2 * np.pi, 25)
    far = np.c_[4 * np.cos(ang), 4 * np.sin(ang)]
    far = np.vstack([far, [[3.0, 0.0], [1.6, 1.6]]])
    inside = rng.uniform(-0.5, 0.5, (30, 2))

    def expected(Q):
        d = np.linalg.norm(Q[:, None, :] - V2[None, :, :], axis=2)  # used vertices only
        return np.argmin(d, axis=1)

    for P in (far[-2:-1], far, np.vstack([inside, far])):  # one miss alone, many, mixed
        for _ in range(2):  # the second call reuses what the first one built
            face, bary = loc.locate(P, nearest=True)
            miss = slice(len(P) - len(far), None) if len(P) > 1 else slice(None)
            v = expected(P[miss])
            f, b = face[miss], bary[miss]
            assert np.all(f >= 0)
            np.testing.assert_array_equal(np.sort(b, axis=1), np.tile([0.0, 0.0, 1.0], (len(v), 1)))
            np.testing.assert_array_equal(F[f, np.argmax(b, axis=1)], v)
            np.testing.assert_array_equal(interpolate(V2x, F, f, b), V2[v])
    # Plain location still reports them as outside.
    assert np.all(loc.locate(far)[0] == -1)


def test_locator_interpolate_defaults_to_snapping(mesh):
    V2, F, boundary = mesh
    rng = np.random.default_rng(8)
    inside = rng.uniform(-0.6, 0.6, (50, 2))
    near = _outside_boundary(V2, boundary, 1e-3)
    P = np.vstack([inside, near, [[5.0, 0.0]], [[np.nan, 0.0]]])
    field = np.c_[V2, 2 * V2[:, 0] - V2[:, 1]]
    loc = TriangleLocator(V2, F)
    out = loc.interpolate(field, P)
    assert out.shape == (len(P), 3)
    # Inside: exact for a linear field. Just outside: the value a few 1e-3 away. Far: the
    # value at the nearest vertex. Non-finite point: NaN.
    lin = np.c_[P, 2 * P[:, 0] - P[:, 1]]
    np.testing.assert_allclose(out[:50], lin[:50], atol=1e-13)
    assert np.all(np.abs(out[50:-2] - lin[50:-2]) <= 3 * 3e-3)
    v = np.argmin(np.hypot(V2[:, 0] - 5.0, V2[:, 1]))
    np.testing.assert_array_equal(out[-2], field[v])
    assert np.all(np.isnan(out[-1]))
    # A 1-D field gives a 1-D result; nearest=False reports outside points as NaN.
    np.testing.assert_allclose(loc.interpolate(field[:, 2], P[:50]), lin[:50, 2], atol=1e-13)
    plain = loc.interpolate(field[:, 0], P, nearest=False)
    assert np.all(np.isnan(plain[50:]))
    np.testing.assert_allclose(plain[:50], P[:50, 0], atol=1e-13)


def test_interpolate_outside_rows_are_nan_even_for_a_one_triangle_mesh():
    field = np.array([[1.0, 10.0], [2.0, 20.0], [4.0, 40.0]])
    face = np.array([-1, 0, -1])
    bary = np.array([[0.0, 0.0, 0.0], [0.25, 0.25, 0.5], [0.0, 0.0, 0.0]])
    out = interpolate(field, TRI_F, face, bary)
    assert np.all(np.isnan(out[[0, 2]]))
    np.testing.assert_array_equal(out[1], [0.25 * 1 + 0.25 * 2 + 0.5 * 4, 27.5])


@pytest.mark.parametrize("scale", [2.0**-20, 2.0**-10, 2.0**12])
def test_location_is_invariant_under_scaling_by_powers_of_two(mesh, scale):
    # Multiplying every coordinate by a power of two is exact in floating point, so a tiny or
    # a huge copy of a mesh must give the very same faces and barycentrics.
    V2, F, _ = mesh
    P = np.random.default_rng(4).uniform(-1.1, 1.1, (1500, 2))
    face, bary = locate(V2, F, P)
    assert (face >= 0).sum() > 800  # about pi / 4.84 of them
    face_s, bary_s = locate(V2 * scale, F, P * scale)
    np.testing.assert_array_equal(face_s, face)
    np.testing.assert_array_equal(bary_s, bary)


def test_float32_vertices_are_located_in_double_precision(mesh):
    # A float32 mesh (e.g. from a GPU buffer) is the same mesh as its exact float64 copy; the
    # answer must not lose precision to the input's type.
    V2, F, _ = mesh
    V32 = V2.astype(np.float32)
    P = np.random.default_rng(6).uniform(-1.0, 1.0, (1000, 2))
    face, bary = locate(V32, F, P)
    face64, bary64 = locate(V32.astype(np.float64), F, P)
    np.testing.assert_array_equal(face, face64)
    np.testing.assert_array_equal(bary, bary64)


def test_degenerate_triangles_never_claim_points_and_raise_no_warnings():
    # The unit square as two triangles, plus a zero-area triangle along its bottom edge and
    # one whose three corners coincide (vertices 4..6 duplicate existing positions).
    V2 = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1, 1], [1, 1]])
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 4, 1], [2, 5, 6]])
    rng = np.random.default_rng(9)
    P = np.vstack([rng.uniform(0, 1, (200, 2)), [[0.25, 0.0], [0.5, 0.0], [1.0, 1.0]]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no divide-by-zero or invalid-value on the way
        loc = TriangleLocator(V2, F)
        face, bary = loc.locate(P)
        face_n, bary_n = loc.locate(P, nearest=True)
    assert np.all(np.isin(face, [0, 1]))
    np.testing.assert_allclose(_corners_of(V2, F, face, bary), P, atol=1e-15)
    np.testing.assert_array_equal(face_n, face)
    np.testing.assert_array_equal(bary_n, bary)


# --------------------------------------------------------------------------- band

SQUARE = np.array([[-1.0, -1], [1, -1], [1, 1], [-1, 1]])


def test_band_ignores_extra_columns_of_the_isophote():
    line = np.array([[-0.5, 0.0], [0.5, 0.1]])
    flat = band(line, 0.2, SQUARE)
    lifted = band(np.c_[line, [0.3, 0.7]], 0.2, SQUARE)
    assert lifted.symmetric_difference(flat).area == 0.0


def test_band_is_the_disk_sum_to_within_its_arc_approximation():
    # Points at distance d from the segment (0,0)-(1,0), all around it (caps included): the
    # band holds those a hair inside the radius and none beyond it. The arcs are polygons
    # with 16 segments per quarter circle, whose chords sag by r (1 - cos(pi/64)) ≈ 1.2e-3 r.
    r = 0.1
    b = band(np.array([[0.0, 0.0], [1.0, 0.0]]), r, 4 * SQUARE)
    phi = np.linspace(0, 2 * np.pi, 721)
    def ring(d):
        left = np.c_[d * np.cos(phi), d * np.sin(phi)]
        right = left + [1.0, 0.0]
        return np.vstack([left[np.cos(phi) <= 0], right[np.cos(phi) >= 0], [[0.5, d], [0.5, -d]]])
    assert all(b.contains(Point(p)) for p in ring(r * (1 - 1.5e-3)))
    assert not any(b.intersects(Point(p)) for p in ring(r * (1 + 1e-9)))


def test_band_across_a_comb_keeps_every_tooth():
    # The strip |y| <= 1 around a horizontal segment crosses two teeth of a comb-shaped
    # outline, and touches a third part of it along the line y = 1 only. The band is the two
    # rectangles where the strip overlaps the teeth; the touching line adds no area.
    comb = np.array([(1, -0.5), (3, -0.5), (3, 2), (4, 2), (4, -0.5), (5, -0.5), (5, 2), (6, 2),
                     (6, 1), (8, 1), (8, 3), (1, 3)], dtype=float)
    b = band(np.array([[0.0, 0.0], [10.0, 0.0]]), 1.0, comb)
    teeth = Polygon([(1, -0.5), (3, -0.5), (3, 1), (1, 1)]).union(
        Polygon([(4, -0.5), (5, -0.5), (5, 1), (4, 1)]))
    assert b.geom_type == "MultiPolygon" and len(b.geoms) == 2
    assert b.area == pytest.approx(4.5, rel=1e-12)
    assert b.symmetric_difference(teeth).area < 1e-12


def test_band_touching_the_outline_along_an_edge_is_still_a_band():
    # One overlap plus a shared edge: GEOS returns a polygon and a line; the band is the polygon.
    outline = np.array([(1, -0.5), (3, -0.5), (3, 2), (6, 2), (6, 1), (8, 1), (8, 3), (1, 3)], dtype=float)
    b = band(np.array([[0.0, 0.0], [10.0, 0.0]]), 1.0, outline)
    assert b.geom_type == "Polygon"
    assert b.symmetric_difference(Polygon([(1, -0.5), (3, -0.5), (3, 1), (1, 1)])).area < 1e-12


def test_band_error_messages_name_what_is_wrong():
    seg = np.array([[0.0, 0.0], [0.5, 0.0]])
    with pytest.raises(GeometryError, match=r"^the selected isophote has a point that is not a finite number"):
        band(np.array([[0.0, 0.0], [np.nan, 0.5]]), 0.1, SQUARE)
    with pytest.raises(SculptError, match=r"^the selected isophote is a single point; pick another isophote$"):
        band(np.array([[0.2, 0.3], [0.2, 0.3], [0.2, 0.3]]), 0.1, SQUARE)
    with pytest.raises(SculptError, match=r"^the layer has no outline to clip the band to$"):
        band(seg, 0.1, np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]]))
    with pytest.raises(SculptError, match=r"^the band does not overlap the layer$"):
        band(np.array([[5.0, 5.0], [6.0, 5.0]]), 0.1, SQUARE)
    # An isophote reaching the coordinate limit is fine; its band, a radius beyond, is not.
    with pytest.raises(GeometryError, match=r"^the band has coordinates reaching"):
        band(np.array([[0.0, 0.0], [1e9, 0.0]]), 10.0, SQUARE)
