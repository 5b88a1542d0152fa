"""Isophotes, isophote picking, the intensity field's gradients and the mesh normals, checked at
the edges of their contracts.

These tests come from mutants of isophotes.py, intensity.py and normals.py that the rest of the
suite let through. Each checks a property a caller relies on against an independent answer:
the exact distance to a polyline (computed in a rotated frame, not by projection), the exact
gradient of a linear field, a level set drawn by hand on a small grid, a fold of known dihedral
angle, and invariances (float32 or float-typed inputs give the float64 answer, an extra z column
is ignored, a scaled mesh gives the scaled gradient). The documented degenerate cases are
covered too: zero-area faces, vertices exactly on the isovalue, vanishing normal sums, empty
results, and the messages a user sees.
"""

import warnings

import numpy as np
import pytest
from meshes import hemisphere

from sketchforge.errors import SculptError
from sketchforge.geometry.intensity import (
    face_gradient,
    gradient_operators,
    vertex_gradient,
    vertex_intensity,
)
from sketchforge.geometry.isophotes import isophotes, isovalue_at, select_isophote
from sketchforge.geometry.locate import TriangleLocator
from sketchforge.geometry.normals import (
    corner_normals,
    corner_normals_grouped,
    crease_groups,
    face_normals,
    normals_from_slopes,
    slopes,
    vertex_normals,
)

# --------------------------------------------------------------------------- helpers


def _grid(nx, ny):
    """Unit grid [0, nx] x [0, ny]: vertex (i, j) has index j (nx + 1) + i; two counter-clockwise
    triangles per cell, numbered cell by cell along rows from the bottom."""
    J, I = np.divmod(np.arange((nx + 1) * (ny + 1)), nx + 1)
    V = np.c_[I, J].astype(float)
    F = []
    for j in range(ny):
        for i in range(nx):
            v00 = j * (nx + 1) + i
            v10, v01 = v00 + 1, v00 + nx + 1
            F += [[v00, v10, v01 + 1], [v00, v01 + 1, v01]]
    return V, np.array(F, dtype=np.int64)


def _vid(nx, i, j):
    return j * (nx + 1) + i


def _distance_to_polyline(line, p):
    """Exact plane distance from p to a polyline: each segment is turned onto the real axis
    (complex numbers), where the nearest point is either straight below p or an endpoint."""
    z = np.asarray(line, dtype=float)[:, 0] + 1j * np.asarray(line, dtype=float)[:, 1]
    w0 = p[0] + 1j * p[1]
    best = np.abs(z - w0).min()
    for a, b in zip(z[:-1], z[1:]):
        length = abs(b - a)
        if length == 0:
            continue
        w = (w0 - a) * np.conj(b - a) / length
        if 0.0 <= w.real <= length:
            best = min(best, abs(w.imag))
    return best


def _signed_area(P):
    x, y = P[:, 0], P[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


def _triangles_containing(V2, F, q, eps=1e-12):
    a, b, c = V2[F[:, 0]], V2[F[:, 1]], V2[F[:, 2]]

    def cross(u, v):
        return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]

    s1, s2, s3 = cross(b - a, q - a), cross(c - b, q - b), cross(a - c, q - c)
    inside = ((s1 >= -eps) & (s2 >= -eps) & (s3 >= -eps)) | ((s1 <= eps) & (s2 <= eps) & (s3 <= eps))
    return np.nonzero(inside)[0]


def _linear(V, a=0.3, b=2.0, c=-1.5):
    return a + b * V[:, 0] + c * V[:, 1]


def _degenerate_square():
    """A unit square (two good triangles) plus a face whose corners are collinear (one of them
    the edge's midpoint, added as vertex 4) and a face collapsed to the point of vertex 0
    (vertices 5 and 6 sit on it). Vertices 4, 5 and 6 belong to zero-area faces only."""
    V2 = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [0, 0], [0, 0]], dtype=float)
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 4, 1], [0, 5, 6]])
    return V2, F


# --------------------------------------------------------------------------- isophotes


def test_no_crossing_gives_an_empty_list_and_an_empty_bool_flag_array():
    V, F = _grid(3, 3)
    E = _linear(V)
    for c in (E.max() + 1.0, E.min() - 1.0):
        lines, closed = isophotes(V, F, E, c)
        assert lines == []
        assert closed.shape == (0,) and closed.dtype == bool
    # a peak exactly at c is a curve shrunk to a point: removed, and the flags are still bool
    E = np.zeros(len(V))
    E[_vid(3, 1, 1)] = 1.0
    lines, closed = isophotes(V, F, E, 1.0)
    assert lines == [] and closed.shape == (0,) and closed.dtype == bool


def test_a_non_finite_isovalue_is_refused_with_its_value_in_the_message():
    V, F = _grid(1, 1)
    for c, shown in ((np.nan, "nan"), (np.inf, "inf")):
        with pytest.raises(ValueError) as err:
            isophotes(V, F, _linear(V), c)
        assert str(err.value) == f"the isovalue must be finite, got {shown}"


def test_vertices_exactly_on_c_count_as_above_it():
    # c is perturbed downwards: with two corners at c and the third below, the level set is the
    # edge through the two corners; with the third above, every corner is above and nothing is.
    V = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    F = np.array([[0, 1, 2]])
    lines, closed = isophotes(V, F, np.array([1.0, 1.0, 0.0]), 1.0)
    assert len(lines) == 1 and not closed[0]
    line = lines[0]
    assert {tuple(p) for p in line} == {(0.0, 0.0), (1.0, 0.0)} and len(line) == 2
    # the brighter side (towards the edge, E = 1 - y) is on the left of the direction of travel
    d = line[-1] - line[0]
    assert np.array([-d[1], d[0]]) @ [0.0, -1.0] > 0  # left normal along the gradient of E
    lines, closed = isophotes(V, F, np.array([1.0, 1.0, 2.0]), 1.0)
    assert lines == [] and closed.shape == (0,)


def test_a_face_edge_on_in_the_drawing_plane_does_not_break_the_curve():
    # A vertical fin of a surface mesh: its corners are collinear seen from +z (zero area in
    # the plane). The winding of every face with area is counter-clockwise, and the level set
    # of x crosses the fin: it is one curve, not pieces.
    V = np.array([[0, 0, 0], [1, 0, 0.5], [2, 0, 0], [1, 1, 0], [0.5, -1, 0], [1.5, -1, 0]], dtype=float)
    F = np.array([[0, 2, 3], [2, 0, 1], [1, 0, 4], [2, 1, 5]])
    for c in (0.3, 0.7, 1.2):
        lines, closed = isophotes(V, F, V[:, 0], c)
        assert len(lines) == 1 and not closed[0]
        np.testing.assert_allclose(lines[0][:, 0], c, rtol=0, atol=1e-15)
        # brighter side (larger x) on the left: the curve runs downwards in the plane
        assert lines[0][0, 1] > 0.2 and lines[0][-1, 1] < -0.2


def test_a_mesh_with_a_duplicated_triangle_still_gives_its_curve():
    # Overlapping triangles make two segments start on one edge; extraction must not give up.
    V, F = _grid(4, 3)
    E = _linear(V, 0.0, 1.0, 0.1)
    above = (E[F] >= 2.1).sum(axis=1)
    crossed = np.nonzero((above == 1) | (above == 2))[0]
    F2 = np.vstack([F, F[crossed[len(crossed) // 2]]])
    lines, closed = isophotes(V, F2, E, 2.1)
    assert isinstance(lines, list) and len(lines) >= 1 and len(closed) == len(lines)
    pts = np.concatenate(lines)
    np.testing.assert_allclose(_linear(pts, 0.0, 1.0, 0.1), 2.1, rtol=0, atol=1e-12)
    # together the pieces still span the mesh from bottom to top
    assert pts[:, 1].min() == 0.0 and pts[:, 1].max() == 3.0


def test_components_come_in_the_order_of_the_first_triangle_they_cross():
    # E = 0.5 - |x - 2| on a 4 x 3 grid: two vertical curves, bright between them, so x = 1.5
    # runs down and x = 2.5 runs up. The first one starts in the top row of triangles but
    # crosses the bottom row first: the order is by first triangle crossed, not by start.
    V, F = _grid(4, 3)
    E = 0.5 - np.abs(V[:, 0] - 2.0)
    lines, closed = isophotes(V, F, E, 0.0)
    assert len(lines) == 2 and not closed.any()
    first = []
    for line in lines:
        mids = 0.5 * (line[1:] + line[:-1])
        first.append(min(_triangles_containing(V, F, m).min() for m in mids))
    assert first[0] < first[1]
    assert np.all(lines[0][:, 0] == 1.5) and np.all(lines[1][:, 0] == 2.5)
    assert lines[0][0, 1] > lines[0][-1, 1]  # bright side (x > 1.5) on the left: downwards
    assert lines[1][0, 1] < lines[1][-1, 1]


def test_closed_curves_always_enclose_area():
    # A ridge edge exactly at c (both ends on c, all around below): the perturbed level set is a
    # sliver around the edge, with no area; it must not come out as a two-point "closed" curve.
    V, F = _grid(3, 2)
    E = np.zeros(len(V))
    E[[_vid(3, 1, 1), _vid(3, 2, 1)]] = 1.0
    lines, closed = isophotes(V, F, E, 1.0)
    for line, cl in zip(lines, closed):
        if cl:
            distinct = np.unique(line, axis=0)
            assert len(distinct) >= 3 and abs(_signed_area(line[:-1])) > 0


def test_the_smallest_closed_curve_is_a_triangle():
    # A peak with three neighbours: the curve crosses its three spokes at their midpoints.
    V = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1 / 3, 1 / 3]])
    F = np.array([[0, 1, 3], [1, 2, 3], [2, 0, 3]])
    lines, closed = isophotes(V, F, np.array([0.0, 0.0, 0.0, 1.0]), 0.5)
    assert len(lines) == 1 and closed[0]
    line = lines[0]
    assert len(line) == 4 and np.array_equal(line[0], line[-1])
    expected = 0.5 * (V[:3] + V[3])
    got = line[:-1]
    assert all(np.abs(got - e).max(axis=1).min() < 1e-15 for e in expected)
    assert _signed_area(got) > 0  # counter-clockwise around the bright peak


def test_a_curve_shrunk_to_a_point_does_not_hide_the_curves_after_it():
    # Peak exactly at c at (1, 1) (first triangles), a real bump at (4, 1) (later triangles).
    V, F = _grid(6, 2)
    E = np.zeros(len(V))
    E[_vid(6, 1, 1)] = 1.0
    E[_vid(6, 4, 1)] = 2.0
    lines, closed = isophotes(V, F, E, 1.0)
    assert len(lines) == 1 and closed[0]
    r = np.hypot(lines[0][:, 0] - 4.0, lines[0][:, 1] - 1.0)
    assert np.all(np.isclose(r, 0.5) | np.isclose(r, 0.5 * np.sqrt(2)))


def test_float32_positions_and_values_give_the_float64_curve():
    rng = np.random.default_rng(3)
    V, F = _grid(5, 5)
    V32 = (V + rng.uniform(-0.3, 0.3, V.shape)).astype(np.float32) * np.float32(0.37)
    V64 = V32.astype(np.float64)
    # a linear field: the exact level set is a straight line, so every point must lie on it
    E = _linear(V64, 0.1, 0.8, 0.55)
    lines, _ = isophotes(V32, F, E, 1.0)
    assert len(lines) == 1 and lines[0].dtype == np.float64
    np.testing.assert_allclose(_linear(lines[0], 0.1, 0.8, 0.55), 1.0, rtol=0, atol=1e-13)
    # values stored in float32 are the same numbers as their float64 copies
    E32 = (np.sin(3 * V64[:, 0]) * np.cos(2 * V64[:, 1])).astype(np.float32)
    for c in (0.1234567, -0.3):
        got, got_closed = isophotes(V64, F, E32, c)
        ref, ref_closed = isophotes(V64, F, E32.astype(np.float64), c)
        assert len(got) == len(ref) > 0 and np.array_equal(got_closed, ref_closed)
        for a, b in zip(got, ref):
            assert a.shape == b.shape
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-14)


# --------------------------------------------------------------------------- picking


def test_select_isophote_picks_the_nearest_polyline_by_exact_distance():
    rng = np.random.default_rng(7)
    polylines = []
    for k in (1, 2, 2, 3, 5, 6, 1, 4):
        P = rng.uniform(0.0, 4.0, (k, 3))  # (k, 3): curves on the surface; z is not distance
        if k >= 4:
            P = np.insert(P, 2, P[1], axis=0)  # a zero-length segment
        polylines.append(P)
    picks = rng.uniform(-1.0, 5.0, (400, 2))
    for scale, shift in ((1.0, 0.0), (0.01, 3.0)):  # small: every segment shorter than 1
        lines = [scale * P + shift for P in polylines]
        checked = 0
        for p in scale * picks + shift:
            d = np.array([_distance_to_polyline(line, p) for line in lines])
            order = np.argsort(d)
            if d[order[1]] - d[order[0]] <= 1e-9 * scale:
                continue  # a near-tie: round-off may decide
            assert select_isophote(lines, p) == order[0]
            checked += 1
        assert checked > 350


def test_select_isophote_by_hand():
    # beyond the ends of an open polyline the nearest point is its end, not the extended line
    seg = np.array([[0.0, 0.0], [2.0, 0.0]])
    assert select_isophote([seg, np.array([[-1.0, 0.3]])], [-1.5, 0.0]) == 1
    assert select_isophote([seg, np.array([[3.0, 0.3]])], [3.5, 0.0]) == 1
    # the middle of a long segment is nearer than its ends
    assert select_isophote([np.array([[3.0, 0.9]]), seg], [1.0, 0.5]) == 1
    # a one-point polyline; the pick may come as a one-row array
    dot = np.array([[1.0, 1.0]])
    assert select_isophote([seg, dot], np.array([[1.2, 0.9]])) == 1
    assert select_isophote([dot, seg], [1.0, -0.1]) == 1
    # ties go to the lower index
    assert select_isophote([seg, seg.copy()], [1.0, 1.0]) == 0
    with pytest.raises(SculptError) as err:
        select_isophote([], [0.0, 0.0])
    assert str(err.value) == "there is no isophote at this value on the layer"


def _picking_mesh():
    m = hemisphere(1.0, 0.1)
    return m, 0.5 + 0.3 * m.V[:, 0] + 0.2 * m.V[:, 1]  # positive everywhere on the disk


def test_isovalue_at_interpolates_in_every_face_and_accepts_a_row_pick():
    m, E = _picking_mesh()
    for f in (0, 1, m.n_faces - 1):
        p = m.V[m.F[f], :2].mean(axis=0)
        exact = 0.5 + 0.3 * p[0] + 0.2 * p[1]
        assert isovalue_at(m, E, p) == pytest.approx(exact, abs=1e-13)
        assert isovalue_at(m, E, p.reshape(1, 2)) == pytest.approx(exact, abs=1e-13)
        assert isovalue_at(m, E, tuple(p)) == pytest.approx(exact, abs=1e-13)


def test_isovalue_at_uses_the_locator_it_is_given():
    m, E = _picking_mesh()

    class CountingLocator(TriangleLocator):
        calls = 0

        def locate(self, *args, **kwargs):
            self.calls += 1
            return super().locate(*args, **kwargs)

    loc = CountingLocator(m.V, m.F)
    assert isovalue_at(m, E, [0.1, 0.2], locator=loc) == pytest.approx(0.5 + 0.03 + 0.04, abs=1e-13)
    assert loc.calls == 1


def test_isovalue_at_refuses_bad_picks_with_a_readable_message():
    m, E = _picking_mesh()
    with pytest.raises(SculptError) as err:
        isovalue_at(m, E, [2.0, 0.0])
    assert str(err.value) == "the pick is outside the layer: click on the shape to choose an isophote"
    for point, shown in (([0.1, 0.2, 0.3], "[0.1, 0.2, 0.3]"), ([np.nan, 0.2], "[nan, 0.2]"),
                         ([None, 0.2], "[nan, 0.2]"), ([0.1, np.inf], "[0.1, inf]")):
        with pytest.raises(SculptError) as err:
            isovalue_at(m, E, point)
        assert str(err.value) == f"the pick must be one finite point [x, y], got {shown}"


# --------------------------------------------------------------------------- intensity


def test_face_and_vertex_gradients_ignore_zero_area_faces():
    V2, F = _degenerate_square()
    f = _linear(V2)
    # quietly: a sliver in every frame must not flood the console with divide-by-zero warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        G = face_gradient(V2, F, f)
        Gv = vertex_gradient(V2, F, f)
        Gx, Gy = gradient_operators(V2, F)
    np.testing.assert_allclose(G[:2], [[2.0, -1.5]] * 2, rtol=0, atol=1e-14)
    assert np.array_equal(G[2:], np.zeros((2, 2)))
    np.testing.assert_allclose(Gv[:4], [[2.0, -1.5]] * 4, rtol=0, atol=1e-14)
    assert np.array_equal(Gv[4:], np.zeros((3, 2)))  # only zero-area faces: no faces at all
    assert Gx.shape == Gy.shape == (7, 7)
    assert np.all(np.isfinite(Gx.toarray())) and np.all(np.isfinite(Gy.toarray()))


def test_gradient_operators_have_one_row_and_column_per_vertex():
    V2, F = _grid(2, 2)
    V2 = np.vstack([V2, [[7.0, 7.0], [8.0, 8.0]]])  # the last two vertices are in no face
    Gx, Gy = gradient_operators(V2, F)
    assert Gx.shape == Gy.shape == (11, 11)
    f = _linear(V2)
    np.testing.assert_allclose(Gx @ f, [2.0] * 9 + [0.0] * 2, rtol=0, atol=1e-14)
    np.testing.assert_allclose(Gy @ f, [-1.5] * 9 + [0.0] * 2, rtol=0, atol=1e-14)


def test_gradients_of_a_linear_field_at_any_scale_and_with_any_z():
    rng = np.random.default_rng(11)
    V, F = _grid(4, 4)
    V = V + rng.uniform(-0.25, 0.25, V.shape)
    for s in (1e-5, 1.0, 1e4):  # a mesh in other units: f = a + b x + c y on the scaled points
        Vs = s * V
        f = _linear(Vs)
        np.testing.assert_allclose(face_gradient(Vs, F, f), np.tile([2.0, -1.5], (len(F), 1)), rtol=1e-9)
        np.testing.assert_allclose(vertex_gradient(Vs, F, f), np.tile([2.0, -1.5], (len(V), 1)), rtol=1e-9)
    # a z column (here a tall cliff) is ignored: same bits as the plane positions alone
    V3 = np.c_[V, 1e8 * rng.uniform(0.0, 1.0, len(V))]
    f = _linear(V)
    assert np.array_equal(face_gradient(V3, F, f), face_gradient(V, F, f))
    for A, B in zip(gradient_operators(V3, F), gradient_operators(V, F)):
        assert np.array_equal(A.toarray(), B.toarray())


def _solve_face_gradients(V2, F, f):
    """The gradient g of the linear interpolant on each face: g·(b - a) = f_b - f_a and
    g·(c - a) = f_c - f_a, solved by numpy."""
    a, b, c = V2[F[:, 0]], V2[F[:, 1]], V2[F[:, 2]]
    A = np.stack([b - a, c - a], axis=1)
    rhs = np.stack([f[F[:, 1]] - f[F[:, 0]], f[F[:, 2]] - f[F[:, 0]]], axis=1)
    return np.linalg.solve(A, rhs[..., None])[..., 0]


def test_float32_inputs_give_the_float64_gradients():
    rng = np.random.default_rng(5)
    V, F = _grid(4, 4)
    V32 = ((V + rng.uniform(-0.3, 0.3, V.shape)) * 0.731).astype(np.float32)
    V64 = V32.astype(np.float64)
    f = _linear(V64)
    np.testing.assert_allclose(face_gradient(V32, F, f), np.tile([2.0, -1.5], (len(F), 1)), rtol=0, atol=1e-12)
    np.testing.assert_allclose(vertex_gradient(V32, F, f), np.tile([2.0, -1.5], (len(V), 1)), rtol=0, atol=1e-12)
    f32 = rng.uniform(-1.0, 1.0, len(V)).astype(np.float32)
    G = face_gradient(V64, F, f32)
    assert G.dtype == np.float64
    np.testing.assert_allclose(G, _solve_face_gradients(V64, F, f32.astype(np.float64)), rtol=0, atol=1e-12)


def test_vertex_intensity_evaluates_the_given_reflectance_model():
    import jax.numpy as jnp

    from sketchforge.geometry.reflectance_model import ReflectanceModel

    m = hemisphere(1.0, 0.2)
    light = np.array([0.48, 0.36, 0.8])
    N = vertex_normals(m.V, m.F)
    cubic = ReflectanceModel("cubic", lambda n, l: jnp.dot(n, l) ** 3)
    E = vertex_intensity(m.V, m.F, light, cubic)
    np.testing.assert_allclose(E, (N @ light) ** 3, rtol=1e-12, atol=1e-15)
    # no model: signed n·l; the light may come as a (1, 3) row
    np.testing.assert_allclose(vertex_intensity(m.V, m.F, light.reshape(1, 3)), N @ light, rtol=1e-15)


# --------------------------------------------------------------------------- normals


def test_integer_coordinates_give_float_normals():
    V = [[0, 0, 0], [2, 0, 0], [0, 1, 1]]  # plain Python ints
    N, area = face_normals(V, [[0, 1, 2]])
    assert N.dtype == np.float64
    np.testing.assert_allclose(N[0], np.array([0, -1, 1]) / np.sqrt(2), rtol=0, atol=1e-15)
    assert area[0] == pytest.approx(np.sqrt(2), abs=1e-15)
    np.testing.assert_allclose(vertex_normals(V, [[0, 1, 2]]), np.tile(N[0], (3, 1)), rtol=0, atol=1e-15)


def test_faces_stored_as_floats_are_read_as_indices():
    # e.g. faces read with np.loadtxt: float64 holding integers
    m = hemisphere(1.0, 0.2)
    Ff = m.F.astype(np.float64)
    V2 = m.V[:, :2]
    z = m.V[:, 2]
    assert np.array_equal(face_gradient(V2, Ff, z), face_gradient(V2, m.F, z))
    assert np.array_equal(vertex_gradient(V2, Ff, z), vertex_gradient(V2, m.F, z))
    for A, B in zip(face_normals(m.V, Ff), face_normals(m.V, m.F)):
        assert np.array_equal(A, B)
    assert np.array_equal(vertex_normals(m.V, Ff), vertex_normals(m.V, m.F))
    assert np.array_equal(corner_normals(m.V, Ff), corner_normals(m.V, m.F))
    assert (crease_groups(m.V, Ff) != crease_groups(m.V, m.F)).nnz == 0
    lines, closed = isophotes(V2, Ff, z, 0.5)
    ref, ref_closed = isophotes(V2, m.F, z, 0.5)
    assert len(lines) == len(ref) == 1 and np.array_equal(lines[0], ref[0])


def _fold(angle_deg):
    """Two triangles sharing the edge x = 0..1 on the x axis: one flat in z = 0, the other
    turned up about that edge so that their normals are angle_deg apart."""
    t = np.radians(angle_deg)
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, -1, 0], [0.5, np.cos(t), np.sin(t)]])
    F = np.array([[0, 2, 1], [0, 1, 3]])
    return V, F


def test_creases_default_to_fifty_degrees():
    for angle, smooth in ((49.5, True), (50.5, False)):
        V, F = _fold(angle)
        N, _ = face_normals(V, F)
        assert np.degrees(np.arccos(N[0] @ N[1])) == pytest.approx(angle, abs=1e-9)
        C = corner_normals(V, F)
        shared = C[0, [0, 2]]  # face 0's corners at vertices 0 and 1, on the fold
        if smooth:
            np.testing.assert_allclose(shared, vertex_normals(V, F)[[0, 1]], rtol=0, atol=1e-12)
        else:
            np.testing.assert_allclose(shared, [N[0], N[0]], rtol=0, atol=1e-12)
        G = crease_groups(V, F).toarray()
        assert G.shape == (6, 2)
        # corner 0 of face 0 (vertex 0) smooths over face 1 only below the default crease
        assert G[0, 1] == (1.0 if smooth else 0.0) and G[0, 0] == 1.0


def test_a_crease_angle_of_180_degrees_smooths_across_everything():
    # A sheet folded flat onto itself: the second face's normal is exactly opposite the first's.
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0]], dtype=float)
    F = np.array([[0, 1, 2], [2, 1, 3]])
    N, _ = face_normals(V, F)
    assert np.array_equal(N, [[0, 0, 1], [0, 0, -1]])
    C = corner_normals(V, F, 180.0)
    np.testing.assert_allclose(C, vertex_normals(V, F)[F], rtol=0, atol=1e-15)


def test_corner_normals_are_up_where_the_summed_faces_vanish():
    # A zero-area face alone (collinear corners) and a face flat on a twin with opposite winding
    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]], dtype=float)
    F = np.array([[0, 1, 2], [3, 4, 5], [3, 5, 4]])
    C = corner_normals(V, F, 180.0)
    assert np.array_equal(C, np.broadcast_to([0.0, 0.0, 1.0], (3, 3, 3)))
    groups = crease_groups(V, F, 50.0)
    C = corner_normals_grouped(V, F, groups)
    assert np.array_equal(C[0], np.broadcast_to([0.0, 0.0, 1.0], (3, 3)))
    np.testing.assert_allclose(np.linalg.norm(C, axis=2), 1.0, rtol=0, atol=1e-15)


def test_corner_normals_of_a_mesh_without_faces():
    V = np.zeros((3, 3))
    F = np.zeros((0, 3), dtype=np.int64)
    assert crease_groups(V, F).shape == (0, 0)
    C = corner_normals(V, F)
    assert C.shape == (0, 3, 3)


def test_slopes_accept_nz_min_in_the_half_open_unit_interval_only():
    N = np.array([[0.6, 0.0, 0.8], [0.0, -1.0, 0.0]])
    p, q = slopes(N, nz_min=1.0)  # every n_z is replaced by 1: p, q = -n_x, -n_y
    assert np.array_equal(p, [-0.6, 0.0]) and np.array_equal(q, [0.0, 1.0])
    for bad in (0.0, -0.1, 1.0000001, 1.5, 2.0):
        with pytest.raises(ValueError) as err:
            slopes(N, nz_min=bad)
        assert str(err.value) == f"nz_min must be in (0, 1], got {bad}"


def test_slopes_and_normals_of_float32_inputs_are_float64():
    rng = np.random.default_rng(9)
    N64 = rng.normal(size=(50, 3))
    N64[:, 2] = np.abs(N64[:, 2]) + 0.5
    N32 = (N64 / np.linalg.norm(N64, axis=1, keepdims=True)).astype(np.float32)
    p, q = slopes(N32, 1e-3)
    assert p.dtype == q.dtype == np.float64
    N = N32.astype(np.float64)
    np.testing.assert_allclose(p, -N[:, 0] / N[:, 2], rtol=1e-15)
    np.testing.assert_allclose(q, -N[:, 1] / N[:, 2], rtol=1e-15)
    p32, q32 = rng.normal(size=(2, 60)).astype(np.float32)
    for pp, qq in ((p32, q32.astype(np.float64)), (p32.astype(np.float64), q32), (p32, q32)):
        n = normals_from_slopes(pp, qq)
        assert n.dtype == np.float64 and n.shape == (60, 3)
        np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=0, atol=4e-16)
        np.testing.assert_allclose(-n[:, 0] / n[:, 2], pp, rtol=1e-15)
        np.testing.assert_allclose(-n[:, 1] / n[:, 2], qq, rtol=1e-15)


def test_normals_from_slopes_keep_the_slopes_shape():
    n = normals_from_slopes(0.0, 0.0)
    assert n.shape == (3,) and np.array_equal(n, [0.0, 0.0, 1.0])
    n = normals_from_slopes(np.float64(3.0), np.float64(4.0))
    np.testing.assert_allclose(n, np.array([-3.0, -4.0, 1.0]) / np.sqrt(26.0), rtol=1e-15)
    rng = np.random.default_rng(2)
    p, q = rng.normal(size=(2, 4, 5))
    n = normals_from_slopes(p, q)
    assert n.shape == (4, 5, 3)
    np.testing.assert_allclose(n[..., 0] / n[..., 2], -p, rtol=1e-14)
    np.testing.assert_allclose(n[..., 1] / n[..., 2], -q, rtol=1e-14)
