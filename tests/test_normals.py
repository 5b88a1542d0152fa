"""Face/vertex normals and slopes, on a hand-made triangle and the analytic hemisphere."""

import numpy as np
import pytest
from meshes import hemisphere, hemisphere_normals

from sketchforge.geometry.normals import (
    NZ_MIN,
    corner_normals,
    face_normals,
    normals_from_slopes,
    slopes,
    vertex_normals,
)


def test_face_normal_and_area_of_one_triangle():
    V = np.array([[0.0, 0, 0], [2, 0, 0], [0, 1, 1]])
    N, area = face_normals(V, np.array([[0, 1, 2]]))
    # (2,0,0) x (0,1,1) = (0,-2,2)
    np.testing.assert_allclose(N[0], np.array([0, -1, 1]) / np.sqrt(2), atol=1e-15)
    assert area[0] == pytest.approx(np.sqrt(8) / 2, abs=1e-15)


def test_ccw_planar_faces_point_up_and_degenerate_face_defaults_up():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]])
    N, area = face_normals(V, np.array([[0, 1, 2], [0, 1, 3]]))
    np.testing.assert_array_equal(N, [[0, 0, 1], [0, 0, 1]])
    assert area[1] == 0.0


def test_vertex_without_faces_gets_up_normal():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]])
    N = vertex_normals(V, np.array([[0, 1, 2]]))
    np.testing.assert_array_equal(N[3], [0, 0, 1])
    assert np.all(np.isfinite(N))


def test_vertex_normals_converge_on_hemisphere_interior():
    # Area-weighted normals are first order in the edge length on irregular meshes; measured
    # max angle error for r < 0.9: 7.7° (h=0.1), 1.9° (h=0.05), 1.1° (h=0.025).
    errs = []
    for h in (0.1, 0.05, 0.025):
        m = hemisphere(1.0, h)
        N = vertex_normals(m.V, m.F)
        cosang = np.clip(np.sum(N * hemisphere_normals(m.V), axis=1), -1, 1)
        r = np.hypot(m.V[:, 0], m.V[:, 1])
        errs.append(np.degrees(np.arccos(cosang[r < 0.9])).max())
    assert errs[0] < 10 and errs[1] < 3 and errs[2] < 1.6
    assert errs[2] < errs[1] < errs[0]


def test_rim_normals_come_from_adjacent_triangles():
    m = hemisphere(1.0, 0.05)
    N = vertex_normals(m.V, m.F)
    rim = N[m.boundary]
    # The exact rim normal lies in the plane; the mesh one tilts up but points outwards.
    assert rim[:, 2].min() > 0.05
    outward = np.sum(rim[:, :2] * m.V[m.boundary, :2], axis=1)
    assert outward.min() > 0.5
    p, q = slopes(N)
    assert np.all(np.isfinite(p)) and np.all(np.isfinite(q))


def test_slopes_exact_away_from_rim_and_roundtrip():
    rng = np.random.default_rng(1)
    p0, q0 = rng.normal(size=50), rng.normal(size=50)
    N = normals_from_slopes(p0, q0)
    np.testing.assert_allclose(np.linalg.norm(N, axis=1), 1.0, atol=1e-15)
    p, q = slopes(N)
    np.testing.assert_allclose(p, p0, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(q, q0, rtol=1e-12, atol=1e-13)


def test_slopes_clamp_in_plane_and_backfacing_normals():
    N = np.array([[1.0, 0, 0], [0, -1, 0], [0.6, 0, -0.8], [0, 0, 1]])
    p, q = slopes(N)
    assert np.all(np.isfinite(p)) and np.all(np.isfinite(q))
    assert np.all(np.hypot(p, q) <= 1 / NZ_MIN + 1e-9)
    # Same direction in the plane as the normal's opposite (z rises against n_xy).
    assert p[0] == pytest.approx(-1 / NZ_MIN) and q[1] == pytest.approx(1 / NZ_MIN)
    assert p[3] == 0 and q[3] == 0
    with pytest.raises(ValueError):
        slopes(N, nz_min=0.0)


def test_corner_normals_are_smooth_on_a_fair_surface_and_keep_creases():
    from meshes import hemisphere

    from sketchforge.geometry.normals import corner_normals

    m = hemisphere(1.0, 0.08)
    C = corner_normals(m.V, m.F, 50.0)
    np.testing.assert_allclose(C, vertex_normals(m.V, m.F)[m.F], atol=1e-12)
    # two squares folded at a right angle along y = 1: each side keeps its own flat normal
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 1, 1], [1, 1, 1.0]])
    F = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4], [3, 5, 4]])
    C = corner_normals(V, F, 50.0)
    np.testing.assert_allclose(C[:2], np.broadcast_to([0, 0, 1.0], (2, 3, 3)), atol=1e-12)
    np.testing.assert_allclose(C[2:], np.broadcast_to([0, -1.0, 0], (2, 3, 3)), atol=1e-12)
    # a crease angle above the fold smooths across it, as area-weighted vertex normals do
    C = corner_normals(V, F, 100.0)
    np.testing.assert_allclose(C, vertex_normals(V, F)[F], atol=1e-12)
    assert abs(C[0, 2, 1]) > 0.4


def test_posed_corner_normals_turn_with_the_pose_and_keep_the_rest_creases():
    """The 3D view shades a posed frame with the crease groups found at rest (issue 13): a
    rigid turn of the model turns every corner normal with it, exactly as computing afresh."""
    from sketchforge.geometry.normals import corner_normals, corner_normals_grouped, crease_groups

    # a box: 90° creases everywhere, 12 triangles
    V = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 2.0) for z in (0.0, 0.5)])
    F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    groups = crease_groups(V, F, 50.0)
    rest = corner_normals_grouped(V, F, groups)
    assert np.allclose(rest, corner_normals(V, F, 50.0))
    # creases kept: every corner normal is its face's normal (no smoothing across 90°)
    assert np.allclose(rest[:, 0], rest[:, 1]) and np.allclose(rest[:, 1], rest[:, 2])
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    posed = corner_normals_grouped(V @ R.T + [0.3, -1.0, 2.0], F, groups)
    assert np.abs(posed - rest @ R.T).max() < 1e-12


def test_a_zero_crease_angle_gives_each_corner_its_own_face_s_normal():
    # crease_deg = 0 is flat shading. n·n of a computed unit normal can round to just below 1 =
    # cos(0); a face must still smooth with itself, not fall back to "up" (40 of 200 random
    # tilted triangles did before the fix).
    rng = np.random.default_rng(7)
    V = np.c_[rng.uniform(-1, 1, (600, 2)), rng.uniform(-1, 1, 600)]
    F = np.arange(600).reshape(200, 3)
    Nf, _ = face_normals(V, F)
    C = corner_normals(V, F, 0.0)
    assert np.abs(C - Nf[:, None, :]).max() < 1e-12
    # the triangle, by hand: normal of (1, 0, 0.3) x (0, 1, 0.7), normalised
    n = np.cross([1.0, 0.0, 0.3], [0.0, 1.0, 0.7])
    n /= np.linalg.norm(n)
    C1 = corner_normals(np.array([[0, 0, 0], [1, 0, 0.3], [0, 1, 0.7]], float), np.array([[0, 1, 2]]), 0.0)
    assert np.allclose(C1, n, atol=1e-12) and n[2] < 0.8


def test_face_cross_products_keep_the_textbook_formula_s_bits():
    """The cross products behind every normal were rewritten on coordinate rows for speed
    (issue 34: a played frame computes them); they must stay the same operations, so every
    normal the core computes keeps its bits. Random triangles over 6 orders of magnitude."""
    from sketchforge.geometry.normals import _face_cross

    rng = np.random.default_rng(34)
    V = rng.normal(size=(500, 3)) * 10.0 ** rng.uniform(-3, 3, (500, 1))
    F = rng.integers(0, 500, (3000, 3))
    a = V[F[:, 0]]
    u, v = V[F[:, 1]] - a, V[F[:, 2]] - a
    ref = np.column_stack([u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1],
                           u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
                           u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]])
    got = _face_cross(V, F)
    assert got.flags.c_contiguous and got.shape == (3000, 3)
    assert np.array_equal(got, ref)
    assert _face_cross(V, F[:0]).shape == (0, 3)


@pytest.mark.parametrize("noise", [0.0, 0.01, 0.03, 0.08, 0.2])
def test_shading_vertices_shade_every_corner_as_its_own_normal_would(noise):
    """The 3D view draws the model as an indexed mesh whose vertices are the corners that
    shade alike (issue 34): each corner must keep its vertex and its normal bit for bit, rest
    and posed, and corners merge exactly where they sit on one vertex and smooth over the same
    faces. Hemispheres roughened by seeded noise, from smooth (one vertex each) to creased."""
    from sketchforge.geometry.normals import corner_normals_grouped, crease_groups, group_normals, shading_vertices

    rng = np.random.default_rng(int(noise * 1000) + 34)
    m = hemisphere(1.0, 0.12)
    V, F = m.V + rng.normal(0.0, noise, m.V.shape), m.F
    groups = crease_groups(V, F, 50.0)
    src, tris, rows = shading_vertices(F, groups)
    assert tris.shape == F.shape and rows.shape == (len(src), len(F))
    np.testing.assert_array_equal(src[tris], F)
    np.testing.assert_array_equal(group_normals(V, F, rows)[tris], corner_normals_grouped(V, F, groups))
    posed = V + rng.normal(0.0, 0.05, V.shape)
    np.testing.assert_array_equal(group_normals(posed, F, rows)[tris], corner_normals_grouped(posed, F, groups))
    distinct = {(F.ravel()[c], tuple(groups.indices[groups.indptr[c]:groups.indptr[c + 1]])) for c in range(3 * len(F))}
    assert len(src) == len(distinct)
    if noise == 0.0:
        assert len(src) == len(V)  # a smooth surface: one shading vertex per vertex
    else:
        assert len(V) < len(src) < 3 * len(F)


def test_a_box_has_one_shading_vertex_per_corner_and_side():
    from sketchforge.geometry.normals import crease_groups, group_normals, shading_vertices

    V = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 2.0) for z in (0.0, 0.5)])
    F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    src, tris, rows = shading_vertices(F, crease_groups(V, F, 50.0))
    assert len(src) == 24 and np.bincount(src).tolist() == [3] * 8  # 8 corners x 3 sides
    N = group_normals(V, F, rows)
    # each face's three corners carry the face's own normal: the box stays sharp
    Nf, _ = face_normals(V, F)
    np.testing.assert_allclose(N[tris], np.repeat(Nf[:, None, :], 3, axis=1), atol=1e-12)
    # without creases (crease angle above 90°) every vertex is one shading vertex
    src, _, _ = shading_vertices(F, crease_groups(V, F, 100.0))
    assert len(src) == 8


def test_faces_outward_only_for_a_closed_surface_wound_outwards():
    """The 3D view skips triangles facing away only on such a surface (issue 34): a box and
    a seeded random convex hull pass; turned inside out, with a face missing or flipped, with
    a degenerate triangle, or an open sheet (a layer's surface) they do not."""
    from scipy.spatial import ConvexHull

    from sketchforge.geometry.normals import faces_outward

    V = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 2.0) for z in (0.0, 0.5)])
    F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    if not faces_outward(V, F):
        F = F[:, ::-1]  # whichever way the box was written, one winding is outward
    assert faces_outward(V, F) and not faces_outward(V, F[:, ::-1])
    assert not faces_outward(V, F[1:])  # a hole
    flipped = F.copy()
    flipped[3] = flipped[3, ::-1]
    assert not faces_outward(V, flipped)
    assert not faces_outward(V, np.r_[F, [[0, 0, 1]]])
    assert not faces_outward(V, np.r_[F, F])  # every edge twice
    rng = np.random.default_rng(34)
    P = rng.normal(size=(300, 3))
    hull = ConvexHull(P)
    H = hull.simplices.copy()
    # orient every hull triangle away from the centroid, as a closed outward surface is
    c = P.mean(axis=0)
    n = np.cross(P[H[:, 1]] - P[H[:, 0]], P[H[:, 2]] - P[H[:, 0]])
    inward = np.einsum("ij,ij->i", n, P[H[:, 0]] - c) < 0
    H[inward] = H[inward][:, ::-1]
    assert faces_outward(P, H) and not faces_outward(P, H[:, ::-1])
    # two pieces (a part left free): each must face out, a bigger one cannot hide the other
    Q = np.r_[P, V + 10.0]
    box = F + len(P)
    assert faces_outward(Q, np.r_[H, box])
    assert not faces_outward(Q, np.r_[H, box[:, ::-1]])
    m = hemisphere(1.0, 0.12)
    assert not faces_outward(m.V, m.F)


def test_a_rim_pair_shares_its_normal_and_the_lens_is_round_at_its_rim():
    """Issue 34: an assembled part's front and back rim vertices are kept apart; their own
    normals tilt by ±15-20° towards their own side, so seen edge-on the shading jumped across
    the rim (a line along the outline). Shared, they stand for one round rim: horizontal,
    pointing out of the outline; weight 0 leaves every normal as it was."""
    from rim_lens import lens

    from sketchforge.geometry.normals import faces_outward

    V, F, P = lens(0.01)
    assert faces_outward(V, F)
    own = vertex_normals(V, F)
    assert np.all(own[P[:, 0], 2] > 0.25) and np.all(own[P[:, 1], 2] < -0.25)  # the jump
    N = vertex_normals(V, F, P)  # weights 1 by default
    np.testing.assert_array_equal(N, vertex_normals(V, F, P, np.ones(len(P))))
    np.testing.assert_allclose(N[P[:, 0]], N[P[:, 1]], atol=1e-12)
    assert np.max(np.abs(N[P[:, 0], 2])) < 1e-12
    out = V[P[:, 0], :2] / np.linalg.norm(V[P[:, 0], :2], axis=1, keepdims=True)
    assert np.degrees(np.arccos(np.min(np.einsum("ij,ij->i", N[P[:, 0], :2], out)))) < 10.0
    # every vertex off the rim keeps its own normal, bit for bit; weight 0: every vertex
    off = np.setdiff1d(np.arange(len(V)), P.ravel())
    np.testing.assert_array_equal(N[off], own[off])
    np.testing.assert_array_equal(vertex_normals(V, F, P, np.zeros(len(P))), own)
    with pytest.raises(ValueError, match="rim weights"):
        vertex_normals(V, F, P, np.ones(len(P) - 1))


def test_rim_normals_follow_the_pairs_weight_continuously():
    """The share fades with the pair's weight without a step (decisions continuous in the
    input): the rim normal turns monotonically from its own to the shared one."""
    from rim_lens import lens

    V, F, P = lens(0.01)
    own = vertex_normals(V, F)[P[0, 0]]
    prev, turned = None, []
    for w in np.linspace(0.0, 1.0, 41):
        N = vertex_normals(V, F, P, np.full(len(P), w))[P[0, 0]]
        turned.append(np.degrees(np.arccos(min(1.0, float(N @ own)))))
        if prev is not None:
            assert np.degrees(np.arccos(min(1.0, float(N @ prev)))) < 1.5
        prev = N
    assert turned[0] == 0.0 and np.all(np.diff(turned) >= 0) and turned[-1] > 15.0


def test_the_3d_view_s_shading_vertices_share_the_rim_as_the_headless_normals_do():
    """The 3D view's per-corner groups (crease_groups, computed at rest) with rim pairs: every
    corner at a fully shared pair shades with the headless renderer's normal, the indexed
    mesh still shades each corner as its own group would (rest and posed), also where the
    weights differ along the rim."""
    from rim_lens import lens

    from sketchforge.geometry.normals import corner_normals_grouped, crease_groups, group_normals, shading_vertices

    V, F, P = lens(0.01)
    groups = crease_groups(V, F, 50.0, P)
    src, tris, rows = shading_vertices(F, groups)
    N = group_normals(V, F, rows)
    rim = np.isin(src, P.ravel())
    np.testing.assert_allclose(N[rim], vertex_normals(V, F, P)[src[rim]], atol=1e-12)
    assert np.bincount(src[rim]).max() == 1  # one shading vertex per rim vertex
    # weights from shared to let go around the rim (x from -1 to 1)
    w = np.clip(1.5 * (0.5 - 0.5 * V[P[:, 0], 0]) - 0.25, 0.0, 1.0)
    assert w.min() == 0.0 and w.max() == 1.0 and np.sum((w > 0) & (w < 1)) >= 3
    for crease in (50.0, 15.0):  # at 15° a pair's corners smooth over faces by other weights
        groups = crease_groups(V, F, crease, P, w)
        src, tris, rows = shading_vertices(F, groups)
        np.testing.assert_array_equal(src[tris], F)
        np.testing.assert_array_equal(group_normals(V, F, rows)[tris], corner_normals_grouped(V, F, groups))
        posed = V + np.random.default_rng(34).normal(0.0, 0.003, V.shape)
        np.testing.assert_array_equal(group_normals(posed, F, rows)[tris], corner_normals_grouped(posed, F, groups))
    # with the crease test off, the groups are the headless normals exactly
    src, tris, rows = shading_vertices(F, crease_groups(V, F, 180.0, P, w))
    np.testing.assert_allclose(group_normals(V, F, rows)[tris], vertex_normals(V, F, P, w)[F], atol=1e-12)
