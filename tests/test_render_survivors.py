"""The software G-buffer and the headless renderer, checked pixel by pixel against brute force.

Every expectation here is computed from the definition, independently of the rasteriser: which
pixel centres a triangle contains, the true distance from a pixel centre to a layer's outline,
the coverage and the outline darkening that follow from it, Lambert's n·l of the interpolated
normal, the isophote coverage |t - level| / |∇t|, back-to-front compositing, and the bytes of a
PNG. Shapes are given in pixel coordinates through a view with one pixel per unit
(:func:`_px_view`), so positions such as "an edge 255/512 px from a pixel centre" are exact.
"""

from types import SimpleNamespace

import numpy as np
import pytest
from meshes import hemisphere
from test_raster import _decode_png

from sketchforge.errors import LimitError
from sketchforge.geometry import gbuffer as gb
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.raster import check_raster_cost, encode_png, render_top
from sketchforge.geometry.shaders import AMBIENT, CEL_TONES, CLAY, lambert_shade

BG = np.array([0.2, 0.5, 0.8])  # three different channels: a swapped channel shows
LIGHT = np.array([0.48, 0.36, 0.8])  # unit, no zero component
ROUND = 0.5 + 0.02  # a displayed value is the exact one rounded to nearest (float32 slack)


# --------------------------------------------------------------------------- helpers


def _px_view(W, H):
    """Document point (x, y) -> pixel (column x, row H - y): shapes are drawn in pixels."""
    return gb.View(0.0, float(H), 1.0, W, H)


def _centres(W, H):
    r, c = np.divmod(np.arange(W * H), W)
    return np.c_[c + 0.5, r + 0.5]


def _ellipse(cx, cy, a, b, n, rot, rng):
    """A convex polygon (pixel coordinates): n points at sorted random angles on an ellipse."""
    phi = np.sort(rng.uniform(0, 2 * np.pi, n))
    p = np.c_[a * np.cos(phi), b * np.sin(phi)]
    c, s = np.cos(rot), np.sin(rot)
    return p @ np.array([[c, s], [-s, c]]) + [cx, cy]


def _poly_mesh(P, H, z=0.0):
    """A convex polygon (pixel coordinates) as a fan around its centroid; its outline is P."""
    P = np.asarray(P, dtype=float)
    n = len(P)
    Q = np.vstack([P, P.mean(axis=0)])
    V = np.c_[Q[:, 0], H - Q[:, 1], np.full(n + 1, z)]
    F = np.c_[np.full(n, n), np.arange(n), (np.arange(n) + 1) % n]
    return Mesh(V, F, boundary=np.arange(n))


def _seg_dist(Q, A, B):
    """Distances (q, m) from points Q to the segments A[j] B[j], and the nearest parameters."""
    d = B - A
    dd = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("qmk,mk->qm", Q[:, None, :] - A[None], d) / dd, 0.0, 1.0)
    near = A[None] + t[..., None] * d[None]
    return np.linalg.norm(near - Q[:, None, :], axis=2), t


def _inside_convex(Q, P):
    """Closed point-in-convex-polygon test, and each point's distance to the polygon's lines
    (how far from a tie the answer is)."""
    A, B = P, np.roll(P, -1, axis=0)
    area = np.sum(A[:, 0] * B[:, 1] - B[:, 0] * A[:, 1])
    e = B - A
    cross = e[None, :, 0] * (Q[:, None, 1] - A[None, :, 1]) - e[None, :, 1] * (Q[:, None, 0] - A[None, :, 0])
    cross *= np.sign(area)
    return np.all(cross >= 0, axis=1), np.min(np.abs(cross) / np.linalg.norm(e, axis=1), axis=1)


def _expected_layer(P, W, H):
    """What one polygon layer must give at every pixel: (inside, distance to the outline,
    coverage as stored (float32), whether a fragment exists, nearest edge, its parameter)."""
    P = np.asarray(P, dtype=float)
    Q = _centres(W, H)
    dist, t = _seg_dist(Q, P, np.roll(P, -1, axis=0))
    k = np.argmin(dist, axis=1)
    d = dist[np.arange(len(Q)), k]
    inside, _ = _inside_convex(Q, P)
    cov = np.where(inside, np.clip(0.5 + d, 0.0, 1.0), np.clip(0.5 - d, 0.0, 1.0))
    present = inside | (cov > 1.0 / 512.0)
    return inside, d, cov.astype(np.float32), present, k, t[np.arange(len(Q)), k]


def _per_pixel(g, values, fill=0.0):
    out = np.full((g.view.width * g.view.height,) + np.shape(values)[1:], fill, dtype=float)
    out[g.pix] = values
    return out


def _owner(g):
    owner = np.full(g.view.width * g.view.height, -1)
    ok = g.front >= 0
    owner[ok] = g.layer[g.front[ok]]
    return owner


def _derivatives(g):
    """Finite differences of the owner's normal from the definition: central where both
    neighbours (in the image) belong to the same layer, one-sided where one does, 0 else."""
    W, H = g.view.width, g.view.height
    owner = _owner(g).reshape(H, W)
    ok = (g.front >= 0).reshape(H, W)
    N = np.zeros((H, W, 3))
    N[ok] = g.normal[g.front.reshape(H, W)[ok]].astype(float)
    out = []
    for axis in (1, 0):
        grad, count = np.zeros((H, W, 3)), np.zeros((H, W))
        for sign in (1, -1):
            nb_owner = np.full((H, W), -2)
            nb_n = np.zeros((H, W, 3))
            src = [slice(None)] * 2
            dst = [slice(None)] * 2
            ahead, behind = slice(1, None), slice(None, -1)
            src[axis], dst[axis] = (ahead, behind) if sign == 1 else (behind, ahead)
            nb_owner[tuple(dst)] = owner[tuple(src)]
            nb_n[tuple(dst)] = N[tuple(src)]
            same = ok & (nb_owner == owner)
            grad += same[..., None] * sign * (nb_n - N)
            count += same
        out.append((grad / np.maximum(count, 1)[..., None])[ok])
    return out


def _isophote_cov(g, light, K, width=1.2):
    """Coverage of the front fragments by the lines n·l = j/(K+1), from the definition."""
    ok = g.front >= 0
    n = g.normal[g.front[ok]].astype(float)
    dx, dy = _derivatives(g)
    t = (K + 1) * (n @ light)
    d = np.abs(t - np.clip(np.rint(t), 1, K))
    grad = (K + 1) * np.hypot(dx @ light, dy @ light)
    reach = 0.5 * width + 0.5
    return np.where(d < reach * grad, np.clip(reach - d / np.maximum(grad, 1e-6), 0.0, 1.0), 0.0)


def _lambert255(n, light):
    k = np.clip(np.asarray(n, dtype=float) @ light, 0.0, 1.0)
    return 255.0 * (AMBIENT + (1 - AMBIENT) * k)[:, None] * CLAY




# --------------------------------------------------------------------------- scan conversion


def _check_scan(T, W, H, exact=False):
    """scan_triangles of one triangle T (pixel coordinates) against a closed point-in-triangle
    test over every pixel centre; barycentric coordinates must give back the centre."""
    T = np.asarray(T, dtype=float)
    pix, tri, bary = gb.scan_triangles(T, np.array([[0, 1, 2]]), W, H)
    assert pix.dtype == np.int64 and tri.dtype == np.int64 and bary.shape == (len(pix), 3)
    assert np.all((pix >= 0) & (pix < W * H)) and len(np.unique(pix)) == len(pix)
    inside, margin = _inside_convex(_centres(W, H), T)
    got = np.zeros(W * H, bool)
    got[pix] = True
    sure = np.ones(W * H, bool) if exact else margin > 1e-9
    np.testing.assert_array_equal(got[sure], inside[sure])
    if len(pix):
        r, c = np.divmod(pix, W)
        np.testing.assert_allclose(bary @ T, np.c_[c + 0.5, r + 0.5], atol=1e-9)
        assert bary.min() > -1e-12 and bary.max() < 1 + 1e-12
        np.testing.assert_allclose(bary.sum(axis=1), 1.0, atol=1e-12)
    return int(inside.sum())


def test_a_triangle_covers_exactly_the_pixel_centres_it_contains():
    W, H = 23, 17
    rng = np.random.default_rng(7)
    counts = []
    for _ in range(60):
        # corners anywhere from 6 px outside the image to 6 px past it: across every border
        centre = rng.uniform([-3, -3], [W + 3, H + 3])
        T = centre + rng.normal(0, rng.choice([0.6, 3.0, 9.0]), (3, 2))
        counts.append(_check_scan(T, W, H))
    assert sum(c > 0 for c in counts) > 20  # many triangles show
    # a triangle entirely past each border shows nothing (and no pixel wraps to another row)
    for T in ([[W + 0.2, 2.0], [W + 4, 3.0], [W + 1, 12.0]], [[-4.0, 2.0], [-0.6, 5.0], [-3, 12.0]],
              [[2.0, H + 0.3], [12.0, H + 0.6], [6.0, H + 5.0]], [[2.0, -0.6], [12.0, -4.0], [6.0, -2.0]]):
        assert _check_scan(T, W, H) == 0
    # a triangle over the whole image: every pixel, none twice, none outside
    assert _check_scan([[-30.0, -30.0], [90.0, -20.0], [-20.0, 90.0]], W, H) == W * H


def test_closed_triangles_keep_the_centres_on_their_edges_and_corners():
    # corners on pixel centres: the centres along all three edges belong to the triangle
    assert _check_scan([[2.5, 2.5], [10.5, 2.5], [2.5, 10.5]], 14, 14, exact=True) == 45
    # an edge rising by exactly one pixel crosses a row of centres
    assert _check_scan([[2.25, 2.25], [9.75, 3.25], [4.0, 12.0]], 14, 14, exact=True) > 20
    # a thin triangle over a single row of centres
    assert _check_scan([[2.1, 3.2], [8.7, 3.9], [5.0, 3.3]], 14, 14, exact=True) == 1
    # centres on the edge opposite the first corner: barycentric coordinates still add up
    _check_scan([[3.4434906746075775, 10.229302081065406], [6.5, 13.5], [15.5, 4.5]], 16, 16)
    # a flat (zero-area) triangle through pixel centres covers nothing
    flat = np.array([[0.5, 0.5], [3.5, 3.5], [7.5, 7.5]])
    pix, tri, bary = gb.scan_triangles(flat, np.array([[0, 1, 2]]), 9, 9)
    assert len(pix) == len(tri) == len(bary) == 0


def test_scanning_nothing_gives_empty_typed_results():
    P = np.array([[1.0, 1.0], [6.0, 1.0], [1.0, 6.0]])
    # no triangle at all; one triangle below the image
    for P_, F in ((P, np.zeros((0, 3), np.int64)), (P + [0.0, 40.0], np.array([[0, 1, 2]]))):
        pix, tri, bary = gb.scan_triangles(P_, F, 8, 8)
        assert pix.shape == (0,) and pix.dtype == np.int64
        assert tri.shape == (0,) and tri.dtype == np.int64
        assert bary.shape == (0, 3)


def test_a_layer_of_sub_pixel_triangles_covers_every_centre_inside_its_outline():
    """Triangles smaller than a pixel (a fine mesh seen from afar) leave no holes."""
    W = H = 12
    g = np.linspace(1.0, 11.0, 41)  # 0.25 px apart: every triangle has an area of 1/32 px²
    X, Y = np.meshgrid(g, g)
    V = np.c_[X.ravel(), H - Y.ravel(), np.zeros(X.size)]
    i = (np.arange(40)[:, None] * 41 + np.arange(40)[None]).ravel()
    F = np.r_[np.c_[i, i + 1, i + 42], np.c_[i, i + 42, i + 41]]
    buf = gb.rasterise([Mesh(V, F)], _px_view(W, H), antialias=False)
    covered = np.zeros(W * H, bool)
    covered[buf.pix] = True
    inside, _ = _inside_convex(_centres(W, H), np.array([[1.0, 1.0], [11.0, 1.0], [11.0, 11.0], [1.0, 11.0]]))
    np.testing.assert_array_equal(covered, inside)
    assert inside.sum() == 100


# --------------------------------------------------------------------------- coverage and outline


def _shapes(W, H):
    rng = np.random.default_rng(3)
    shapes = [
        _ellipse(20.3, 17.6, 14.2, 9.1, 9, 0.4, rng),  # inside, edges of several 8-px pieces
        _ellipse(3.1, 2.4, 16.0, 11.0, 10, -0.3, rng),  # across the left and top borders
        _ellipse(W - 2.2, H - 3.3, 15.0, 12.0, 10, 0.9, rng),  # across the right and bottom borders
        _ellipse(30.7, 11.2, 5.3, 4.9, 70, 0.0, rng),  # edges much shorter than a pixel
        # just past each border: 1.2 px beyond it, out of reach of the last pixel centres
        np.array([[W + 1.2, 4.3], [W + 9.1, 6.2], [W + 8.3, 22.4], [W + 1.25, 25.1]]),
        np.array([[5.3, H + 1.2], [30.7, H + 1.25], [28.1, H + 9.2], [7.4, H + 8.3]]),
        np.array([[-1.2, 4.3], [-1.25, 25.1], [-8.3, 22.4], [-9.1, 6.2]]),
        np.array([[5.3, -1.2], [7.4, -8.3], [28.1, -9.2], [30.7, -1.25]]),
        # edges placed at the coverage thresholds: a column of centres 255/512 px outside the
        # left edge (coverage exactly 1/512: no fragment), 0.497 px outside the right edge
        # (coverage 0.003: a fragment), a row 0.49805 px above the top edge (0.00195: none),
        # and the bottom edge on pixel borders (centres exactly 1.5 px away: not outline pixels)
        np.array([[9.5 + 255 / 512, 8.5 + 0.49805], [30.5 - 0.497, 8.5 + 0.49805], [30.5 - 0.497, 30.0],
                  [9.5 + 255 / 512, 30.0]]),
    ]
    return shapes


@pytest.mark.parametrize("k", range(9))
def test_coverage_and_outline_pixels_follow_the_true_distance_to_the_outline(k):
    """Inside the outline a pixel is covered by 0.5 + d, outside by 0.5 - d (d: the distance
    from its centre to the outline, in pixels); the outline pixels are those with d < 1.5."""
    W, H = 41, 35
    P = _shapes(W, H)[k]
    g = gb.rasterise([_poly_mesh(P, H)], _px_view(W, H))
    inside, d, cov, present, _, _ = _expected_layer(P, W, H)
    assert np.bincount(g.pix, minlength=W * H).max() <= 1  # one fragment per pixel and layer
    got = np.zeros(W * H, bool)
    got[g.pix] = True
    np.testing.assert_array_equal(got, present)
    np.testing.assert_allclose(_per_pixel(g, g.alpha)[present], cov[present], atol=2e-7)
    edge = np.zeros(W * H, bool)
    edge[g.edge_pix] = True
    np.testing.assert_array_equal(edge, d < 1.5)
    np.testing.assert_allclose(g.edge_dist, d[g.edge_pix], atol=1e-5)
    # the owner of a pixel is the layer whose outline contains its centre
    np.testing.assert_array_equal(g.front_layer().ravel(), np.where(inside, 0, -1))


def test_the_crafted_threshold_pixels_are_where_they_should_be():
    """The last shape's edges really sit on the thresholds the test above relies on."""
    W, H = 41, 35
    _, d, cov, present, _, _ = _expected_layer(_shapes(W, H)[-1], W, H)
    assert np.any(cov == np.float32(1 / 512)) and np.any(np.isclose(cov, 0.003, atol=1e-6))
    assert np.any(np.isclose(d, 0.49805, atol=1e-9)) and np.any(d == 1.5)
    assert not present[np.isclose(cov, 1 / 512, atol=1e-5)].any()


def test_rim_fragments_take_the_normal_of_the_nearest_outline_point():
    """Given vertex normals are interpolated inside the outline; outside, a rim fragment has the
    normal interpolated along the outline at the point nearest its centre."""
    W, H = 41, 35
    rng = np.random.default_rng(11)
    P = _ellipse(20.3, 17.6, 15.2, 11.1, 7, 0.4, rng)
    n = len(P)
    N = np.c_[rng.uniform(-0.7, 0.7, (n + 1, 2)), np.ones(n + 1)]
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    g = gb.rasterise([_poly_mesh(P, H)], _px_view(W, H), normals=[N])
    inside, d, cov, present, k, t = _expected_layer(P, W, H)
    Q = _centres(W, H)
    expect = np.zeros((W * H, 3))
    # outside: along edge k (corners k, k+1) at parameter t
    out = ~inside
    e = (1 - t)[:, None] * N[k] + t[:, None] * N[(k + 1) % n]
    expect[out] = e[out]
    # inside: barycentric in the fan triangle (centroid, corner i, corner i+1) holding the centre
    C = P.mean(axis=0)
    for i in range(n):
        T = np.array([C, P[i], P[(i + 1) % n]])
        inn, _ = _inside_convex(Q, T)
        sel = inn & inside
        M = np.c_[T, np.ones(3)].T
        b = np.linalg.solve(M, np.c_[Q[sel], np.ones(sel.sum())].T).T
        expect[sel] = b @ N[[n, i, (i + 1) % n]]
    expect /= np.maximum(np.linalg.norm(expect, axis=1, keepdims=True), 1e-300)
    got = _per_pixel(g, g.normal.astype(float))
    np.testing.assert_allclose(np.linalg.norm(g.normal, axis=1), 1.0, atol=1e-6)
    assert (present & out).sum() > 25
    np.testing.assert_allclose(got[present], expect[present], atol=2e-6)


def test_the_outline_is_every_edge_of_one_triangle_holes_included():
    """A square ring (outer square 0-3, inner square 4-7) in 8 triangles: the outline is the
    4 outer and 4 inner sides, as int64 vertex pairs whatever the index type given."""
    F = np.array([[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]],
                 dtype=np.int32)
    E = gb.boundary_edges(F)
    assert E.dtype == np.int64 and E.shape == (8, 2)
    sides = {frozenset(e) for e in ([0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4])}
    assert {frozenset(e) for e in E.tolist()} == sides
    # each edge keeps the direction of the triangle it bounds
    assert {tuple(e) for e in E.tolist()} == {(0, 1), (1, 2), (2, 3), (3, 0), (5, 4), (6, 5), (7, 6), (4, 7)}


def test_one_outline_segment_reaches_the_pixels_within_one_and_a_half_pixels():
    P = np.array([[3.3, 4.1], [17.8, 9.6]])
    N = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    pix, dist, nrm = gb._outline_distance(P, N, np.array([[0, 1]]), 22, 14)
    d, t = _seg_dist(_centres(22, 14), P[:1], P[1:])
    want = np.flatnonzero(d[:, 0] < 1.5)
    np.testing.assert_array_equal(np.sort(pix), want)
    order = np.argsort(pix)
    np.testing.assert_allclose(dist[order], d[want, 0], atol=1e-9)
    e = (1 - t[want]) * N[0] + t[want] * N[1]
    np.testing.assert_allclose(nrm[order], e / np.linalg.norm(e, axis=1, keepdims=True), atol=1e-9)
    # no outline at all, or one far outside the view: nothing, as three matching empty arrays
    for edges, Pv in ((np.zeros((0, 2), np.int64), P), (np.array([[0, 1]]), P + [100.0, 0.0])):
        pix, dist, nrm = gb._outline_distance(Pv, N, edges, 22, 14)
        assert pix.shape == (0,) and pix.dtype == np.int64 and dist.shape == (0,) and nrm.shape == (0, 3)


def test_a_closed_mesh_has_no_outline_and_hard_pixel_centre_edges():
    """A closed surface (every edge shared) seen from above: no outline, no partial pixels."""
    W, H = 20, 18
    base = np.array([[2.3, 3.1], [17.4, 5.2], [6.2, 15.9]])
    corners = np.r_[base, [base.mean(axis=0)]]  # the apex over the middle
    V = np.c_[corners[:, 0], H - corners[:, 1], [0, 0, 0, 2.0]]
    F = np.array([[0, 1, 3], [1, 2, 3], [2, 0, 3], [0, 2, 1]])
    g = gb.rasterise([Mesh(V, F)], _px_view(W, H))
    inside, _ = _inside_convex(_centres(W, H), base)
    got = np.zeros(W * H, bool)
    got[g.pix] = True
    np.testing.assert_array_equal(got, inside)
    assert np.all(g.alpha == 1) and len(g.edge_pix) == 0 and g.edge_dist.dtype == np.float32
    img = gb.shade(g, LIGHT, lambert_shade, BG, outline_alpha=1.0)
    assert np.all(img.reshape(-1, 3)[~inside] == np.round(BG * 255))


def test_a_layer_larger_than_the_view_covers_it_whole_without_an_outline():
    W, H = 16, 12
    big = _poly_mesh([[-9.0, -7.0], [30.0, -8.0], [29.0, 25.0], [-8.0, 26.0]], H)
    g = gb.rasterise([big], _px_view(W, H))
    assert np.array_equal(np.sort(g.pix), np.arange(W * H))
    assert np.all(g.alpha == 1) and len(g.edge_pix) == 0 and len(g.edge_dist) == 0


def test_a_sub_pixel_triangle_shows_as_a_faint_antialiased_dot():
    W, H = 16, 16
    P = np.array([[7.95, 8.05], [8.25, 8.0], [8.1, 8.3]])  # covers no pixel centre
    g = gb.rasterise([_poly_mesh(P, H)], _px_view(W, H))
    _, _, cov, present, _, _ = _expected_layer(P, W, H)
    assert 0 < present.sum() <= 4 and g.normal.shape == (len(g.pix), 3)
    np.testing.assert_array_equal(np.sort(g.pix), np.flatnonzero(present))
    np.testing.assert_allclose(_per_pixel(g, g.alpha)[present], cov[present], atol=2e-7)
    hard = gb.rasterise([_poly_mesh(P, H)], _px_view(W, H), antialias=False)
    assert len(hard.pix) == 0 and hard.normal.shape == (0, 3)
    assert np.all(gb.shade(hard, LIGHT, lambert_shade, BG) == np.round(BG * 255))


def test_single_triangle_layers_are_drawn():
    W, H = 16, 16
    tri = Mesh([[2.2, 3.1, 0.0], [13.6, 2.4, 0.0], [6.1, 14.3, 0.0]], [[0, 1, 2]])
    g = gb.rasterise([tri], _px_view(W, H), antialias=False)
    inside, _ = _inside_convex(_centres(W, H), np.c_[tri.V[:, 0], H - tri.V[:, 1]])
    assert len(g.pix) == inside.sum() > 40
    img = render_top([tri], LIGHT, 20)
    assert np.any(img != np.round(np.array([0.95, 0.94, 0.92]) * 255))


# --------------------------------------------------------------------------- layers


def test_within_one_mesh_the_higher_sheet_wins_and_a_single_sheet_stays():
    """A folded mesh: a small sheet over part of a large one. Where both are, the higher one
    shows; where only the large one is, it shows."""
    W, H = 24, 20
    big = _poly_mesh([[2.23, 2.1], [21.7, 2.6], [21.1, 17.8], [2.6, 17.3]], H, z=0.0)
    small = _poly_mesh([[8.33, 6.21], [15.62, 6.93], [14.81, 13.74], [8.92, 13.17]], H)
    for z_small, small_wins in ((1.0, True), (-1.0, False)):
        nb, ns = big.n_vertices, small.n_vertices
        V = np.r_[big.V, np.c_[small.V[:, :2], np.full(ns, z_small)]]
        m = Mesh(V, np.r_[big.F, small.F + nb])
        N = np.r_[np.tile([0.0, 0.0, 1.0], (nb, 1)), np.tile([0.6, 0.0, 0.8], (ns, 1))]
        g = gb.rasterise([m], _px_view(W, H), antialias=False, normals=[N])
        Q = _centres(W, H)
        in_big, _ = _inside_convex(Q, np.c_[big.V[:4, 0], H - big.V[:4, 1]])
        in_small, _ = _inside_convex(Q, np.c_[small.V[:4, 0], H - small.V[:4, 1]])
        assert np.bincount(g.pix, minlength=W * H).max() == 1
        np.testing.assert_array_equal(np.sort(g.pix), np.flatnonzero(in_big))
        nx = _per_pixel(g, g.normal[:, 0])
        tilted = np.isclose(nx, 0.6)
        np.testing.assert_array_equal(tilted, in_small & small_wins)


def _three_layers(W, H):
    rng = np.random.default_rng(5)
    return [
        _ellipse(17.2, 15.3, 14.1, 10.2, 9, 0.3, rng),
        _ellipse(26.4, 19.1, 9.3, 8.2, 8, -0.5, rng),
        _ellipse(2.7, 21.6, 9.1, 7.4, 8, 1.1, rng),  # across the left border
    ]


def test_layers_composite_back_to_front_with_their_coverage():
    """Each layer blends over what lies behind it by its coverage of the pixel: the later
    layer's antialiased rim lets the earlier layer, not the background, show through."""
    W, H = 40, 32
    polys = _three_layers(W, H)
    g = gb.rasterise([_poly_mesh(P, H) for P in polys], _px_view(W, H))
    tints = np.array([[0.9, 0.2, 0.1], [0.1, 0.8, 0.3], [0.2, 0.3, 0.95]])
    img = gb.shade(g, LIGHT, lambda N, l: np.ones((len(N), 3), np.float32), BG, tints=tints)
    acc = np.tile(BG * 255.0, (W * H, 1))
    for P, tint in zip(polys, tints):
        a = _expected_layer(P, W, H)[2].astype(float)
        acc += a[:, None] * (tint * 255.0 - acc)
    assert np.abs(img.reshape(-1, 3) - acc).max() <= ROUND
    assert len(g.stack_pixels) > 100  # many pixels blend


def test_the_owner_of_a_pixel_is_the_frontmost_layer_containing_its_centre():
    W, H = 40, 32
    polys = _three_layers(W, H)
    g = gb.rasterise([None] + [_poly_mesh(P, H) for P in polys], _px_view(W, H))
    owner = np.full(W * H, -1)
    for li, P in enumerate(polys):
        owner[_inside_convex(_centres(W, H), P)[0]] = li + 1
    lay = g.front_layer()
    assert lay.dtype == np.int32 and lay.shape == (H, W)
    np.testing.assert_array_equal(lay.ravel(), owner)
    assert set(np.unique(owner)) == {-1, 1, 2, 3}


def test_an_outline_shows_unless_an_opaque_layer_in_front_hides_it():
    W, H = 40, 32
    polys = _three_layers(W, H)
    g = gb.rasterise([_poly_mesh(P, H) for P in polys], _px_view(W, H))
    layers = [_expected_layer(P, W, H) for P in polys]
    top = np.full(W * H, -1)
    for li, (_, _, cov, _, _, _) in enumerate(layers):
        top[cov >= 1] = li
    best = np.full(W * H, np.inf)
    for li, (_, d, _, _, _, _) in enumerate(layers):
        seen = (d < 1.5) & (top <= li)
        best[seen] = np.minimum(best[seen], d[seen])
    np.testing.assert_array_equal(g.edge_pix, np.flatnonzero(np.isfinite(best)))
    np.testing.assert_allclose(g.edge_dist, best[g.edge_pix], atol=1e-5)


def test_the_buffers_have_their_documented_types():
    W, H = 40, 32
    scenes = {
        "layers": [_poly_mesh(P, H) for P in _three_layers(W, H)],
        "empty": [],
        "nothing drawn": [None, Mesh(np.zeros((3, 3)), np.zeros((0, 3), np.int64))],
    }
    for name, meshes in scenes.items():
        g = gb.rasterise(meshes, _px_view(W, H))
        k = len(g.pix)
        assert g.n_layers == len(meshes), name
        assert g.pix.dtype == np.int64 and g.layer.dtype == np.int32 and g.layer.shape == (k,), name
        assert g.alpha.dtype == np.float32 and g.alpha.shape == (k,), name
        assert g.normal.dtype == np.float32 and g.normal.shape == (k, 3), name
        assert g.front.dtype == np.int64 and g.front.shape == (W * H,), name
        for a in (g.bounds, g.stack_pixels, g.stack_frag, g.stack_slot, g.stack_bounds, g.front_frag,
                  g.edge_pix):
            assert a.dtype == np.int64, name
        assert g.edge_dist.dtype == np.float32, name
        assert g.front_layer().dtype == np.int32, name
        cov = gb.isophote_coverage(g, LIGHT, 3)
        assert cov.dtype == np.float32 and cov.shape == g.front_frag.shape, name


def test_an_empty_scene_shades_to_the_background():
    W, H = 12, 9
    for meshes in ([], [None], [None, Mesh(np.zeros((3, 3)), np.zeros((0, 3), np.int64))]):
        g = gb.rasterise(meshes, _px_view(W, H))
        assert len(g.pix) == len(g.front_frag) == len(g.edge_pix) == 0
        assert np.all(g.front_layer() == -1)
        img = gb.shade(g, LIGHT, lambert_shade, BG, isophotes=3, outline_alpha=0.5)
        assert img.shape == (H, W, 3) and np.all(img == np.round(BG * 255))


def test_fragments_are_kept_per_mesh_for_the_three_latest_views():
    m = hemisphere(0.5, 0.1)
    views = [gb.View(-1.0, 1.0, 20.0 + k, 40, 40) for k in range(4)]
    first = gb._layer_fragments(m, views[0], True)
    assert gb._layer_fragments(m, views[0], True) is first  # a second look is free
    for a in (first[0], first[1], first[2], *first[3]):
        assert not a.flags.writeable  # shared between buffers: never written
    r1 = gb._layer_fragments(m, views[1], True)
    r2 = gb._layer_fragments(m, views[2], True)
    assert gb._layer_fragments(m, views[0], True) is first  # three views are kept
    gb._layer_fragments(m, views[3], True)  # a fourth one pushes out the least recently used
    assert gb._layer_fragments(m, views[0], True) is first
    assert gb._layer_fragments(m, views[2], True) is r2
    assert gb._layer_fragments(m, views[1], True) is not r1


# --------------------------------------------------------------------------- derivatives and lines


def _two_domes(view_size=90):
    back = hemisphere(1.0, 0.08)
    small = hemisphere(0.45, 0.05)
    front = Mesh(small.V + [0.5, -0.2, 0.0], small.F, boundary=small.boundary)
    return [back, front], gb.View(-1.1, 1.1, view_size / 2.2, view_size, view_size)


def test_normal_derivatives_are_differences_within_the_owning_layer():
    meshes, view = _two_domes()
    inside_view = gb.View(-0.5, 0.6, 40.0, 40, 44)  # the dome covers every pixel, to the borders
    for ms, v in ((meshes, view), ([meshes[0]], inside_view)):
        g = gb.rasterise(ms, v)
        dx, dy = gb._normal_derivatives(g.front, g.normal, g.layer, v.width, v.height)
        ex, ey = _derivatives(g)
        assert dx.shape == ex.shape and dy.shape == ey.shape
        np.testing.assert_allclose(dx, ex, atol=2e-6)
        np.testing.assert_allclose(dy, ey, atol=2e-6)
        assert np.abs(ex).max() > 0.01 and np.abs(ey).max() > 0.01
    assert np.all(g.front >= 0)


@pytest.mark.parametrize("K, width", [(1, None), (4, None), (4, 2.5)])
def test_isophote_coverage_is_the_distance_to_the_level_over_the_gradient(K, width):
    meshes, view = _two_domes()
    g = gb.rasterise(meshes, view)
    light = np.array([0.5, -0.4, 0.6])
    light /= np.linalg.norm(light)
    cov = gb.isophote_coverage(g, light, K) if width is None else gb.isophote_coverage(g, light, K, width)
    want = _isophote_cov(g, light, K, 1.2 if width is None else width)
    assert cov.dtype == np.float32 and cov.min() >= 0 and cov.max() <= 1
    np.testing.assert_allclose(cov, want, atol=2e-3)
    assert (want > 0.99).sum() > 20 * K and (want == 0).sum() > 0.5 * len(want)


def test_lines_are_drawn_where_the_normal_turns_within_a_pixel():
    """A pleated layer (vertex normals facing right and left in turn, 2.3 px apart): the normal
    turns by more than a radian per pixel, and the lines still follow the definition."""
    W, H = 30, 16
    rng = np.random.default_rng(9)
    xs, ys = np.arange(2.0, 28.5, 2.3), np.arange(2.0, 14.5, 1.3)
    X, Y = np.meshgrid(xs, ys)
    nx, ny = len(xs), len(ys)
    V = np.c_[X.ravel(), H - Y.ravel(), np.zeros(X.size)]
    i = (np.arange(ny - 1)[:, None] * nx + np.arange(nx - 1)[None]).ravel()
    F = np.r_[np.c_[i, i + 1, i + nx + 1], np.c_[i, i + nx + 1, i + nx]]
    flip = np.where(np.arange(X.size) % nx % 2 == 0, 1.0, -1.0)  # facing right, left, right...
    N = np.c_[flip, rng.uniform(-0.3, 0.3, X.size), np.full(X.size, 0.15)]
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    g = gb.rasterise([Mesh(V, F)], _px_view(W, H), normals=[N])
    light = np.array([0.8, 0.36, 0.48])
    assert g._line_data()[3].max() > 1.2  # |dn/dx| + |dn/dy| over a radian per pixel
    for K in (1, 3):
        np.testing.assert_allclose(gb.isophote_coverage(g, light, K), _isophote_cov(g, light, K), atol=2e-3)


def test_a_flat_layer_lit_exactly_at_a_level_is_not_flooded_with_line_colour():
    W, H = 30, 30
    flat = _poly_mesh(_ellipse(15.2, 14.7, 11.0, 9.0, 12, 0.0, np.random.default_rng(0)), H)
    g = gb.rasterise([flat], _px_view(W, H))
    light = np.array([0.8, 0.0, 0.6])  # n·l = 0.6 = 3/5, the level j = 3 of K = 4
    assert np.all(gb.isophote_coverage(g, light, 4) == 0)
    plain = gb.shade(g, light, lambert_shade, BG)
    np.testing.assert_array_equal(gb.shade(g, light, lambert_shade, BG, isophotes=4), plain)


# --------------------------------------------------------------------------- shading


def test_a_pixel_shows_lambert_of_its_interpolated_normal():
    meshes, view = _two_domes(64)
    g = gb.rasterise(meshes, view)
    img = gb.shade(g, LIGHT, lambert_shade, BG).reshape(-1, 3).astype(float)
    alone = np.zeros(view.width * view.height, bool)
    alone[g.pix[g.alpha == 1]] = True
    alone[g.stack_pixels] = False
    want = np.zeros((len(alone), 3))
    want[g.pix[g.alpha == 1]] = _lambert255(g.normal[g.alpha == 1], LIGHT)
    assert alone.sum() > 1500
    assert np.abs(img[alone] - want[alone]).max() <= ROUND
    empty = np.ones(len(alone), bool)
    empty[g.pix] = False
    assert np.all(img[empty] == np.round(BG * 255))


@pytest.mark.parametrize("explicit", [False, True])
def test_isophote_lines_blend_the_pixel_towards_the_line_colour(explicit):
    meshes, view = _two_domes(64)
    g = gb.rasterise(meshes, view)
    K = 1 if explicit else 3
    if explicit:
        colour, alpha, width = np.array([1.0, 0.2, 0.0]), 0.6, 2.5
        img = gb.shade(g, LIGHT, lambert_shade, BG, isophotes=K, line_colour=colour, line_alpha=alpha,
                       line_width=width)
    else:
        colour, alpha, width = np.array([0.12, 0.10, 0.10]), 0.85, 1.2
        img = gb.shade(g, LIGHT, lambert_shade, BG, isophotes=K)
    img = img.reshape(-1, 3).astype(float)
    cov = gb.isophote_coverage(g, LIGHT, K, width).astype(float)
    np.testing.assert_allclose(cov, _isophote_cov(g, LIGHT, K, width), atol=2e-3)
    pix = g.pix[g.front_frag]
    ok = (g.alpha[g.front_frag] == 1) & ~np.isin(pix, g.stack_pixels)
    c = _lambert255(g.normal[g.front_frag], LIGHT)
    want = c + (alpha * cov)[:, None] * (colour * 255.0 - c)
    assert (ok & (cov > 0.9)).sum() > 30
    assert np.abs(img[pix[ok]] - want[ok]).max() <= ROUND


def _tilted_layers(polys, H, seed, tilt, z):
    """Meshes of the polygons and random unit vertex normals (x, y uniform in ±tilt, z fixed
    before normalising), drawn in order from one seeded generator."""
    rng = np.random.default_rng(seed)
    meshes = [_poly_mesh(P, H) for P in polys]
    normals = []
    for m in meshes:
        N = np.c_[rng.uniform(-tilt, tilt, (m.n_vertices, 2)), np.full(m.n_vertices, z)]
        normals.append(N / np.linalg.norm(N, axis=1, keepdims=True))
    return meshes, normals


@pytest.mark.parametrize("alpha, width", [(0.7, None), (0.5, 3.0)])
def test_the_outline_darkens_with_the_true_distance_to_the_silhouette(alpha, width):
    W, H = 40, 32
    polys = _three_layers(W, H)
    meshes, normals = _tilted_layers(polys, H, seed=2, tilt=0.5, z=1.0)
    g = gb.rasterise(meshes, _px_view(W, H), normals=normals)
    colour = np.array([1.0, 0.3, 0.05])
    base = gb.shade(g, LIGHT, lambert_shade, BG).reshape(-1, 3).astype(float)
    kw = {} if width is None else {"outline_width": width}
    lined = gb.shade(g, LIGHT, lambert_shade, BG, line_colour=colour, outline_alpha=alpha, **kw)
    lined = lined.reshape(-1, 3).astype(float)
    # brute force: the visible outlines (not under an opaque layer in front) and their distances
    layers = [_expected_layer(P, W, H) for P in polys]
    top = np.full(W * H, -1)
    for li, lay in enumerate(layers):
        top[lay[2] >= 1] = li
    d = np.full(W * H, np.inf)
    for li, lay in enumerate(layers):
        seen = (lay[1] < 1.5) & (top <= li)
        d[seen] = np.minimum(d[seen], lay[1][seen])
    cov = np.clip(0.5 * (1.0 if width is None else width) + 0.5 - d, 0.0, 1.0) * alpha
    want = base + cov[:, None] * (colour * 255.0 - base)
    assert (cov > 0.3).sum() > 100
    assert np.abs(lined - want).max() <= ROUND
    np.testing.assert_array_equal(lined[cov == 0], base[cov == 0])


def test_out_of_range_colours_and_backgrounds_are_clamped_everywhere():
    """A shader that overshoots (even to ±1e38) and a background outside [0, 1] are clamped,
    on the rims and overlaps too, where colours blend: each fragment's colour is clamped to
    0..255 (the display's rounding offset of half a level included) before it blends."""
    W, H = 40, 32
    polys = _three_layers(W, H)
    meshes, normals = _tilted_layers(polys, H, seed=4, tilt=1.0, z=0.3)
    g = gb.rasterise(meshes, _px_view(W, H), normals=normals)

    def wild(N, l):
        c = 3.0 * np.asarray(N, dtype=np.float64) - 1.0  # -4..2: most channels out of range
        c[N[:, 0] > 0.8] = 1e38
        c[N[:, 0] < -0.8] = -1e38
        return c

    background = np.array([-0.5, 0.4, 1.7])
    with np.errstate(over="ignore", invalid="ignore"):
        img = gb.shade(g, LIGHT, wild, background).reshape(-1, 3).astype(float)
        colour = np.clip(wild(g.normal, LIGHT).astype(np.float32).astype(float) * 255.0 + 0.5, 0.0, 255.0)
    acc = np.tile(np.clip(background, 0, 1) * 255.0 + 0.5, (W * H, 1))
    for li in range(g.n_layers):
        k = np.arange(g.bounds[li], g.bounds[li + 1])
        acc[g.pix[k]] += g.alpha[k, None] * (colour[k] - acc[g.pix[k]])
    assert (np.abs(wild(g.normal, LIGHT)) >= 1e38).any(axis=1).sum() > 20
    assert len(g.stack_pixels) > 100 and np.isin(g.pix[np.abs(wild(g.normal, LIGHT)).max(axis=1) >= 1e38],
                                                  g.stack_pixels).sum() > 5
    # shown values are the blended ones truncated (the half level added above rounds them)
    assert np.all(img > acc - 1 - 1e-3) and np.all(img <= acc + 1e-3)


def test_the_shader_gets_float32_normals_and_a_float64_light_and_may_answer_read_only():
    g = gb.rasterise([hemisphere(1.0, 0.1)], gb.View(-1.1, 1.1, 20.0, 44, 44))
    seen = []

    def spy(N, l):
        seen.append((N.dtype, N.shape, l.dtype, l.shape))
        return np.broadcast_to(np.float32([0.2, 0.4, 0.6]), (len(N), 3))  # one colour, read-only

    for light in ([0, 0, 1], [[0, 0, 1]], (0.0, 0.6, 0.8)):
        img = gb.shade(g, light, spy, (0, 0, 0))
        inner = np.zeros(44 * 44, bool)
        inner[g.pix[g.alpha == 1]] = True
        inner[g.stack_pixels] = False
        assert np.all(img.reshape(-1, 3)[inner] == [51, 102, 153])
    assert seen == [(np.float32, (len(g.pix), 3), np.float64, (3,))] * 3
    with pytest.raises(ValueError) as err:
        gb.shade(g, [0, 0, 1], lambda N, l: np.ones((len(N), 4)), BG)
    assert str(err.value) == (
        f"the display shader returned an array of shape ({len(g.pix)}, 4) for {len(g.pix)} normals; "
        "it must return one finite RGB row per normal"
    )


# --------------------------------------------------------------------------- render_top


def _dome_and_light():
    return hemisphere(1.0, 0.1), np.array([1.0, 0.0, 0.0])


def test_render_top_defaults_to_clay_lambert():
    m, light = _dome_and_light()
    plain = render_top([m], light, 48)
    np.testing.assert_array_equal(plain, render_top([m], light, 48, cel=False))
    assert np.any(plain != render_top([m], light, 48, cel=True))
    cel = render_top([m], light, 48, cel=True)
    tones = np.round(CEL_TONES * 255)
    assert np.abs(cel[24, 24] - tones[1]).max() <= 1 or np.abs(cel[24, 24] - tones[2]).max() <= 1
    assert len(np.unique(plain[20:28, 25:40].reshape(-1, 3), axis=0)) > 5  # a smooth ramp, not tones


def test_render_top_normalises_the_light_and_applies_tints():
    m, light = _dome_and_light()
    plain = render_top([m], light, 48)
    np.testing.assert_array_equal(render_top([m], 3.0 * light, 48), plain)
    tinted = render_top([m], light, 48, tints=[[0.5, 1.0, 1.0]]).astype(int)
    inner = slice(14, 34)
    np.testing.assert_array_equal(tinted[inner, inner, 1:], plain[inner, inner, 1:])
    assert np.abs(tinted[inner, inner, 0] - 0.5 * plain[inner, inner, 0]).max() <= 1


def test_render_top_skips_missing_and_empty_layers():
    m, light = _dome_and_light()
    plain = render_top([m], light, 40)
    np.testing.assert_array_equal(render_top([None, m], light, 40), plain)
    far_points = Mesh([[50.0, 50.0, 0.0], [60.0, -40.0, 0.0], [-70.0, 9.0, 0.0]], np.zeros((0, 3), np.int64))
    np.testing.assert_array_equal(render_top([m, far_points], light, 40), plain)


def test_render_top_empty_scene_is_the_background_exactly():
    img = render_top([], np.array([0.0, 0.0, 1.0]), 5, background=(0.2, 0.5, 1.0))
    assert img.dtype == np.uint8 and img.shape == (5, 5, 3)
    assert np.all(img == [51, 128, 255])


def test_render_top_sizes_margins_and_their_messages():
    m, light = _dome_and_light()
    assert render_top([m], light, 1).shape == (1, 1, 3)
    with pytest.raises(ValueError) as err:
        render_top([m], light, 0)
    assert str(err.value) == "image size must be at least 1 pixel, got 0"
    full = render_top([m], light, 40, margin=0.0)
    cols = np.flatnonzero(np.any(full != full[0, 0], axis=2).any(axis=0))
    assert cols[0] == 0 and cols[-1] == 39  # no margin: the disk touches the image's sides
    wide = render_top([m], light, 100, margin=0.25)
    cols = np.flatnonzero(np.any(wide != wide[0, 0], axis=2).any(axis=0))
    assert abs(cols[0] - 25) <= 1 and abs(cols[-1] - 74) <= 1  # half the width is the disk
    for margin in (0.5, 0.7, -0.1):
        with pytest.raises(ValueError) as err:
            render_top([m], light, 40, margin=margin)
        assert str(err.value) == f"margin must be in [0, 0.5), got {margin}"
    with pytest.raises(ValueError) as err:
        render_top([m], light, 40, isophotes=-1)
    assert str(err.value) == "the number of isophotes must be >= 0, got -1"
    for bad in (np.zeros(3), np.array([np.nan, 0.0, 1.0])):
        with pytest.raises(ValueError) as err:
            render_top([m], bad, 40)
        assert str(err.value) == "the light direction must be a finite non-zero vector"


def test_render_top_refuses_an_image_over_the_pixel_limit_naming_size_and_limit():
    m, light = _dome_and_light()
    # exactly at the limit (two units per pixel) is allowed
    assert render_top([], light, 100, max_cost=20_000).shape == (100, 100, 3)
    for meshes in ([], [m]):
        with pytest.raises(LimitError) as err:
            render_top(meshes, light, 100, max_cost=19_999)
        assert str(err.value) == (
            "a 100x100 image is over the rendering limit of 9,999 pixels; use a smaller size"
        )
    # the triangles count too, against the same limit
    with pytest.raises(LimitError, match="this render would test about"):
        render_top([m], light, 64, max_cost=9_000)


def test_raster_cost_is_twice_the_pixels_plus_every_triangles_box_in_the_view():
    W = H = 1000
    view = _px_view(W, H)

    def mesh(tris):
        P = np.asarray(tris, dtype=float).reshape(-1, 2)
        return Mesh(np.c_[P[:, 0], H - P[:, 1], np.zeros(len(P))], np.arange(len(P)).reshape(-1, 3))

    square = mesh([[[100, 100], [600, 100], [600, 600]], [[100, 100], [600, 600], [100, 600]],
                   [[700.1, 700.1], [700.9, 700.2], [700.5, 700.9]]])  # 250,000 + 250,000 + 1
    edges = mesh([[[-50, 10], [30, 10], [-50, 60]],  # clipped to 30 x 50 = 1,500
                  [[990, 980], [1050, 980], [990, 1040]],  # clipped to 10 x 20 = 200
                  [[-30, 10], [-10, 10], [-30, 40]]])  # left of the view: 0
    cost = 2 * W * H + 500_001 + 1_700
    check_raster_cost([square, edges], view, cost)
    with pytest.raises(LimitError):
        check_raster_cost([square, edges], view, cost - 1)
    with pytest.raises(LimitError) as err:
        check_raster_cost([square], view, 1_500_001)
    assert str(err.value) == (
        "this render would test about 3 M pixels, over the rendering limit of 2 M "
        "(overlapping layers count once each): use a smaller size"
    )


# --------------------------------------------------------------------------- PNG


def test_png_decodes_back_to_the_same_pixels_with_a_standard_header():
    rng = np.random.default_rng(0)
    for shape in ((1, 1, 3), (1, 6, 3), (5, 1, 3), (9, 4, 3)):
        rgb = rng.integers(0, 256, shape, dtype=np.uint8)
        np.testing.assert_array_equal(_decode_png(encode_png(rgb)), rgb)


def test_png_refuses_anything_but_an_rgb_uint8_image():
    for bad in (np.zeros((2, 2, 4), np.uint8), np.zeros((2, 2), np.uint8), np.zeros((0, 3, 3), np.uint8),
                np.zeros((2, 2, 3), np.float64)):
        with pytest.raises(ValueError) as err:
            encode_png(bad)
        assert str(err.value) == f"write_png needs an (H, W, 3) uint8 image, got {bad.shape} {bad.dtype}"


# --------------------------------------------------------------------------- views


def test_a_view_needs_a_finite_origin_a_positive_scale_and_a_pixel():
    bad = ((0.0, 0.0, np.inf), (0.0, np.nan, 1.0), (np.nan, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
    for x0, y1, scale in bad:
        with pytest.raises(ValueError, match="a view needs a finite origin and a positive scale"):
            gb.View(x0, y1, scale, 4, 4)
    for w, h in ((0, 5), (5, 0), (0, 0)):
        with pytest.raises(ValueError) as err:
            gb.View(0.0, 0.0, 1.0, w, h)
        assert str(err.value) == f"a view needs at least one pixel, got {w}x{h}"
    assert gb.View(0.0, 0.0, 0.5, 1, 1).scale == 0.5


def test_framing_centres_the_meshes_with_a_five_percent_margin_by_default():
    m = hemisphere(1.0, 0.1)
    P = gb.View.framing([m], 100, 60).to_pixels(m.V)
    assert abs(P[:, 1].min() - 3.0) < 1e-9 and abs(P[:, 1].max() - 57.0) < 1e-9  # 5% of 60
    assert abs(P[:, 0].min() + P[:, 0].max() - 100.0) < 1e-9
    small = hemisphere(0.4, 0.05)  # smaller than a unit: still fills the image
    P = gb.View.framing([small], 100, 100, 0.1).to_pixels(small.V)
    assert abs(np.ptp(P, axis=0).max() - 80.0) < 1e-9 and np.all(P >= 10 - 1e-9) and np.all(P <= 90 + 1e-9)
    bar = SimpleNamespace(V=np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 5.0], [4.0, 1.0, -3.0]]))
    P = gb.View.framing([bar], 100, 100).to_pixels(bar.V)
    assert abs(P[:, 0].min() - 5.0) < 1e-9 and abs(P[:, 0].max() - 95.0) < 1e-9
    assert abs(P[:, 1].min() + P[:, 1].max() - 100.0) < 1e-9  # centred vertically too
    point = SimpleNamespace(V=np.array([[1.0, 2.0, 0.0], [1.0, 2.0, 3.0]]))
    view = gb.View.framing([point], 10, 10)
    assert view.scale == 1.0
    np.testing.assert_allclose(view.to_pixels(point.V[:1]), [[5.0, 5.0]])
