"""Contracts of small geometry pieces that the suite left unchecked (found by mutation testing).

Each test checks documented behaviour against an independent computation: the analytic
inflated ellipse against its PDE and finite differences, the figures of
``isophote_error`` against a brute-force recomputation from the definition, the gbuffer's
documented shapes/dtypes and ownership, height-field normals against rotation invariance and
the w-/z-form blend, slope Jacobians against finite differences, and the dtype/edge-case
contracts of ``Mesh``, ``reflectance.evaluate`` and the display shaders.
"""

import warnings

import numpy as np
import pytest

from sketchforge.geometry import gbuffer as gb
from sketchforge.geometry.heightfield import SlopeLinearisation, layer_normals
from sketchforge.geometry.intensity import gradient_operators
from sketchforge.geometry.isophote_error import InflatedEllipse, _fragment_points, line_wobble, polyline_wobble
from sketchforge.geometry.isophotes import isophotes
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.normals import NZ_MIN


def _unit(a):
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def _angle(a, b):
    # atan2 form: accurate for nearly parallel vectors, unlike arccos
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("ij,ij->i", a, b))


# ---------------------------------------------------------------- the analytic inflated ellipse


def test_inflated_ellipse_height_solves_the_inflation_problem():
    """u = z² solves -Δu = 4 inside with u = 0 on the ellipse (a != b != 1 so a and b matter)."""
    s = InflatedEllipse(1.7, 0.6)
    rng = np.random.default_rng(0)
    t = rng.uniform(0, 2 * np.pi, 50)
    r = rng.uniform(0, 0.8, 50)
    xy = np.c_[s.a * r * np.cos(t), s.b * r * np.sin(t)]
    e = 1e-3
    u = lambda p: s.height(p) ** 2  # noqa: E731
    lap = (u(xy + [e, 0]) + u(xy - [e, 0]) + u(xy + [0, e]) + u(xy - [0, e]) - 4 * u(xy)) / e**2
    np.testing.assert_allclose(-lap, 4.0, rtol=1e-6)
    rim = np.c_[s.a * np.cos(t), s.b * np.sin(t)]
    np.testing.assert_allclose(s.height(rim), 0.0, atol=1e-6)


def test_inflated_ellipse_normal_is_the_surface_normal_and_unit():
    s = InflatedEllipse(1.7, 0.6)
    rng = np.random.default_rng(1)
    t = rng.uniform(0, 2 * np.pi, 40)
    r = rng.uniform(0, 0.9, 40)
    xy = np.c_[s.a * r * np.cos(t), s.b * r * np.sin(t)]
    e = 1e-6
    hx = (s.height(xy + [e, 0]) - s.height(xy - [e, 0])) / (2 * e)
    hy = (s.height(xy + [0, e]) - s.height(xy - [0, e])) / (2 * e)
    expected = _unit(np.c_[-hx, -hy, np.ones(len(xy))])
    np.testing.assert_allclose(s.normal(xy), expected, atol=1e-7)
    # a small blob (k < 1/4): the raw (−∇u, 2z) is shorter than 1 and must still be normalised
    small = InflatedEllipse(0.3, 0.2)
    pts = np.c_[[0.0, 0.1, -0.2, 0.0, 0.5], [0.0, 0.05, 0.0, -0.19, 0.0]]
    np.testing.assert_allclose(np.linalg.norm(small.normal(pts), axis=1), 1.0, rtol=1e-12)


def test_inflated_ellipse_shading_gradient_matches_differences_of_n_dot_l():
    s = InflatedEllipse(1.4, 0.9)
    light = _unit(np.array([0.3, -0.5, 0.8]))
    rng = np.random.default_rng(2)
    xy = rng.uniform(-0.5, 0.5, (30, 2))
    E, grad = s.shading(xy, light)
    np.testing.assert_allclose(E, s.normal(xy) @ light, rtol=1e-12)
    h = 1e-4  # a step of our own: independent of the method's eps
    gx = (s.normal(xy + [h, 0]) @ light - s.normal(xy - [h, 0]) @ light) / (2 * h)
    gy = (s.normal(xy + [0, h]) @ light - s.normal(xy - [0, h]) @ light) / (2 * h)
    np.testing.assert_allclose(grad, np.hypot(gx, gy), rtol=1e-5)


def test_inflated_ellipse_mesh_is_mirror_symmetric_like_its_outline():
    """A coarse sampling (12 points) of an ellipse is symmetric about the x axis; the closed
    outline is resampled evenly all round, so the mesh's rim keeps that symmetry."""
    from scipy.spatial import cKDTree

    s = InflatedEllipse(2.0, 1.0)
    m = s.mesh(12, 0.1)
    rim = m.V[m.boundary, :2]
    dist, _ = cKDTree(rim).query(rim * [1.0, -1.0])
    assert dist.max() < 1e-9
    assert len(m.junction) == 0


# --------------------------------------------------------------------- line_wobble's figures

HEMI = InflatedEllipse(1.0, 1.0)


@pytest.fixture(scope="module")
def hemi():
    mesh = HEMI.mesh(160, 0.05)
    view = gb.View(-1.1, 1.1, 100.0, 220, 220)  # radius 100 px
    return mesh, view


def test_fragment_points_are_pixel_centres(hemi):
    mesh, view = hemi
    g = gb.rasterise([mesh], view)
    r, c = np.divmod(g.pix, view.width)
    np.testing.assert_allclose(view.to_pixels(_fragment_points(g)), np.c_[c + 0.5, r + 0.5], atol=1e-9)


def test_line_wobble_default_draws_the_displays_eight_levels(hemi):
    mesh, view = hemi
    light = np.array([np.cos(0.5), np.sin(0.5), 0.0])
    w = line_wobble(HEMI, mesh, view, light)
    assert len(w.pieces) == len(w.exact_pieces) == 8
    assert w.pieces == w.exact_pieces == (1,) * 8


def test_a_wide_line_is_measured_to_its_own_level(hemi):
    """One level (K = 1, n·l = 1/2) drawn 56 px wide under an in-plane light: n·l = x/ρ, so the
    line is the strip |x - ρ/2| <= 28 px and each centre pixel's distance is |x - ρ/2|, also
    where n·l < 1/4 or > 3/4 (never to an undrawn n·l = 0 or 1). Brute force over the pixel
    centres inside the rim gives the median and p95."""
    mesh, view = hemi
    w = line_wobble(HEMI, mesh, view, np.array([1.0, 0.0, 0.0]), K=1, width=56.0)
    c = np.arange(220) + 0.5
    X, Y = np.meshgrid(c - 110, 110 - c)  # px from the centre
    dist = np.abs(X - 50.0)
    strip = (np.hypot(X, Y) < 99.0) & (dist <= 28.0)
    assert abs(w.median - np.median(dist[strip])) <= 0.5, w
    assert abs(w.p95 - np.percentile(dist[strip], 95)) <= 0.5, w
    assert w.pieces == w.exact_pieces == (1,)


def test_a_level_the_light_never_reaches_draws_nothing(hemi):
    """Light from below: n·l <= 0 on the whole blob, so the n·l = 1/2 line is nowhere: no
    pieces, no centre pixels, NaN figures (and no warnings about empty statistics)."""
    mesh, view = hemi
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        w = line_wobble(HEMI, mesh, view, np.array([0.0, 0.0, -1.0]), K=1)
    assert w.centre_pixels == 0
    assert w.pieces == w.exact_pieces == (0,)
    assert np.isnan(w.median) and np.isnan(w.p95) and np.isnan(w.max)


# ----------------------------------------------------------------- polyline_wobble's figures


def _grid_disk(R, a):
    """Triangles of a 2a x a grid inside the disk r < R, every face with edges (0,1), (1,2),
    (2,0) of lengths √5 a, a, 2 a: the mean edge length is (3 + √5) a / 3 whatever is counted."""
    xs = np.arange(-R, R + 1e-9, 2 * a)
    ys = np.arange(-R, R + 1e-9, a)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    V2 = np.c_[X.ravel(), Y.ravel()]
    idx = lambda i, j: i * len(ys) + j  # noqa: E731
    F = []
    for i in range(len(xs) - 1):
        for j in range(len(ys) - 1):
            p00, p10, p01, p11 = idx(i, j), idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1)
            F += [[p10, p01, p00], [p01, p10, p11]]
    F = np.array(F)
    inside = np.hypot(V2[:, 0], V2[:, 1]) < R - 1e-9
    F = F[inside[F].all(axis=1)]
    return V2, F, (3 + np.sqrt(5)) * a / 3


def _sphere_E(P, light, R):
    """Exact n·l of the hemisphere of radius R at points P and |∇(n·l)| (closed form)."""
    x, y = P[:, 0], P[:, 1]
    z = np.sqrt(np.maximum(R * R - x * x - y * y, 0.0))
    E = (x * light[0] + y * light[1] + z * light[2]) / R
    with np.errstate(divide="ignore", invalid="ignore"):  # infinite on the rim itself
        gx = (light[0] - light[2] * x / z) / R
        gy = (light[1] - light[2] * y / z) / R
    return E, np.hypot(gx, gy)


R_HEMI = 2.0


@pytest.fixture(scope="module")
def grid_hemi():
    V2, F, h = _grid_disk(R_HEMI, 0.1)
    z = np.sqrt(np.maximum(R_HEMI**2 - (V2**2).sum(axis=1), 0.0))
    return Mesh(np.c_[V2, z], F), h


def test_polyline_wobble_measures_exact_distances_in_mean_edge_lengths(grid_hemi):
    """A closed isophote well inside the rim: every point counts; p95 and max of
    |E - c| / |∇E| / h from the closed-form field must match."""
    mesh, h = grid_hemi
    surface = InflatedEllipse(R_HEMI, R_HEMI)
    light = np.array([np.sin(0.3), 0.0, np.cos(0.3)])
    E_v, _ = _sphere_E(mesh.V[:, :2], light, R_HEMI)
    c = 0.9
    p95, worst, pieces = polyline_wobble(surface, mesh, E_v, c, light)
    lines, _ = isophotes(mesh.V[:, :2], mesh.F, E_v, c)
    P = np.concatenate(lines)
    assert np.hypot(P[:, 0], P[:, 1]).max() < R_HEMI - 3 * h  # all well inside
    E, g = _sphere_E(P, light, R_HEMI)
    d = np.abs(E - c) / g / h
    assert pieces == len(lines) == 1
    assert d.max() > 1e-3  # a real, measurable error
    np.testing.assert_allclose([p95, worst], [np.percentile(d, 95), d.max()], rtol=1e-5)


@pytest.mark.parametrize("c", [0.125, 0.2, 0.3, 0.45])
def test_polyline_wobble_leaves_out_points_within_an_edge_of_the_rim(grid_hemi, c):
    """An isophote from rim to rim: the figures cover the points more than about one edge
    length h inside the rim (bracketed by 0.95 h .. 1.1 h), where the interpolated field's
    error grows fastest."""
    mesh, h = grid_hemi
    surface = InflatedEllipse(R_HEMI, R_HEMI)
    light = np.array([0.8, 0.0, 0.6])
    E_v, _ = _sphere_E(mesh.V[:, :2], light, R_HEMI)
    p95, worst, pieces = polyline_wobble(surface, mesh, E_v, c, light)
    lines, _ = isophotes(mesh.V[:, :2], mesh.F, E_v, c)
    P = np.concatenate(lines)
    E, g = _sphere_E(P, light, R_HEMI)
    d = np.abs(E - c) / g / h
    rim_dist = R_HEMI - np.hypot(P[:, 0], P[:, 1])
    lo = d[rim_dist > 1.1 * h].max()
    hi = d[rim_dist > 0.95 * h].max()
    assert lo <= worst * (1 + 1e-6) and worst <= hi * (1 + 1e-6), (lo, worst, hi)
    assert pieces == len(lines)


def test_polyline_wobble_without_points_to_measure(grid_hemi):
    mesh, h = grid_hemi
    surface = InflatedEllipse(R_HEMI, R_HEMI)
    light = np.array([1.0, 0.0, 0.0])
    E_v, _ = _sphere_E(mesh.V[:, :2], light, R_HEMI)
    # no isophote at all: n·l never reaches 2
    p95, worst, pieces = polyline_wobble(surface, mesh, E_v, 2.0, light)
    assert np.isnan(p95) and np.isnan(worst) and pieces == 0
    # one isophote, but only within an edge of the rim (the chord y = 0.93 ρ, h ≈ 0.17)
    assert R_HEMI * (1 - 0.93) < 0.95 * h
    light = np.array([0.0, 1.0, 0.0])
    E_v, _ = _sphere_E(mesh.V[:, :2], light, R_HEMI)
    p95, worst, pieces = polyline_wobble(surface, mesh, E_v, 0.93, light)
    assert np.isnan(p95) and np.isnan(worst) and pieces == 1


# ----------------------------------------------------------------------------- gbuffer


def _rect(x0, x1, y0, y1):
    V = np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]])
    return Mesh(V, [[0, 1, 2], [0, 2, 3]], [0, 1, 2, 3])


def test_gbuffer_documented_shapes_dtypes_and_empty_pixels():
    view = gb.View(0.0, 12.0, 1.0, 12, 12)  # x = column, y = 12 - row
    meshes = [_rect(1.3, 6.7, 1.3, 6.7), None, _rect(4.2, 9.6, 3.3, 10.4)]
    g = gb.rasterise(meshes, view)
    assert g.normal.dtype == np.float32 and g.normal.shape == (len(g.pix), 3)
    assert g.bounds.shape == g.stack_bounds.shape == (len(meshes) + 1,)
    assert g.stack_bounds[-1] == len(g.stack_frag)
    # brute force: pixels whose centre is in no rectangle have no owner (-1)
    r, c = np.divmod(np.arange(12 * 12), 12)
    x, y = c + 0.5, 12 - (r + 0.5)
    inside = ((1.3 < x) & (x < 6.7) & (1.3 < y) & (y < 6.7)) | ((4.2 < x) & (x < 9.6) & (3.3 < y) & (y < 10.4))
    assert np.all(g.front[~inside] == -1)
    assert np.all(g.front[inside] >= 0)


def test_layers_meeting_on_a_row_of_pixel_centres_leave_no_unowned_seam():
    """Two layers share the edge x = 4.5, which runs through pixel centres (column 4): each
    covers half of those pixels, and the one in front must own them (no gap in picking or
    isophote lines between adjacent layers)."""
    view = gb.View(0.0, 10.0, 1.0, 10, 10)
    g = gb.rasterise([_rect(1.2, 4.5, 1.2, 8.8), _rect(4.5, 8.8, 1.2, 8.8)], view)
    r, c = np.divmod(np.arange(100), 10)
    x, y = c + 0.5, 10 - (r + 0.5)
    inside = (1.2 < x) & (x < 8.8) & (1.2 < y) & (y < 8.8)
    np.testing.assert_array_equal(g.front >= 0, inside)


# ------------------------------------------------------------------------- height fields


def _grid_square(n):
    xs = np.linspace(-1, 1, n + 1)
    X, Y = np.meshgrid(xs, xs, indexing="xy")
    V2 = np.c_[X.ravel(), Y.ravel()]
    idx = lambda i, j: j * (n + 1) + i  # noqa: E731
    F = []
    for j in range(n):
        for i in range(n):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            F += [[a, b, c], [a, c, d]]
    b = ([idx(i, 0) for i in range(n)] + [idx(n, j) for j in range(n)]
         + [idx(i, n) for i in range(n, 0, -1)] + [idx(0, j) for j in range(n, 0, -1)])
    return V2, np.array(F), np.array(b)


@pytest.mark.parametrize("p", [0.6, 0.7, 1.0])
def test_layer_normals_rotate_with_the_layer(p):
    """Nothing in the definition of the normals depends on the axes: rotating a layer in the
    drawing plane rotates its normals. A regular grid with 45° diagonals (where |Gx| and |Gy|
    coincide) and heights between a vertical and a faired rim exercises the rim blend."""
    V2, F, b = _grid_square(10)
    z = ((1 - V2[:, 0] ** 2) * (1 - V2[:, 1] ** 2)) ** p
    z[b] = 0.0
    th = 0.5
    rot = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    N = layer_normals(Mesh(np.c_[V2, z], F, b))
    Nr = layer_normals(Mesh(np.c_[V2 @ rot.T, z], F, b))
    np.testing.assert_allclose(Nr, np.c_[N[:, :2] @ rot.T, N[:, 2]], atol=1e-12)


@pytest.mark.parametrize("p", [0.7, 0.8])
def test_layer_normals_lie_between_the_w_form_and_the_area_weighted_normal(p):
    """Every normal is the w-form (−∇w, 2z), the area-weighted one (−∇z, 1), or a blend of the
    two: on the great-circle arc between them (clamped, nearly in-plane ones aside)."""
    V2, F, b = _grid_square(10)
    z = ((1 - V2[:, 0] ** 2) * (1 - V2[:, 1] ** 2)) ** p * (1 + 0.3 * V2[:, 0] + 0.2 * V2[:, 1] ** 2)
    z[b] = 0.0
    N = layer_normals(Mesh(np.c_[V2, z], F, b))
    Gx, Gy = gradient_operators(V2, F)
    w = z * z
    raw_w = np.c_[-(Gx @ w), -(Gy @ w), 2 * z]
    ok = (N[:, 2] > 1.5 * NZ_MIN) & (np.linalg.norm(raw_w, axis=1) > 0)
    nw = _unit(raw_w[ok])
    nz = _unit(np.c_[-(Gx @ z), -(Gy @ z), np.ones(len(z))][ok])
    n = N[ok]
    gap = _angle(n, nw) + _angle(n, nz) - _angle(nw, nz)
    assert np.abs(gap).max() < 1e-9
    blended = (_angle(n, nw) > 1e-6) & (_angle(n, nz) > 1e-6)
    assert blended.sum() >= 10  # the test sees real blends


def test_a_one_triangle_layer_gets_height_field_normals():
    """A single raised triangle: its apex (z > 0) has the w-form normal (−∇w, 2z), w = z²
    interpolated linearly over the face, not the face's normal."""
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]])
    m = Mesh(V, [[0, 1, 2]], [0, 1, 2])
    N = layer_normals(m)
    # w = 0.25 y over the face: ∇w = (0, 0.25); at the apex 2z = 1
    np.testing.assert_allclose(N[2], _unit(np.array([0.0, -0.25, 1.0])), atol=1e-12)


def _slope_setup():
    V2, F, b = _grid_square(8)
    z = ((1 - V2[:, 0] ** 2) * (1 - V2[:, 1] ** 2)) ** 0.8
    z[b] = 0.0
    Gx, Gy = gradient_operators(V2, F)
    return V2, z, Gx, Gy


def test_slope_jacobians_with_columns_beyond_the_rows():
    """Columns past the last row and columns no row depends on: Jacobians keep the documented
    (k, u) shape and match finite differences."""
    V2, z, Gx, Gy = _slope_setup()
    n = len(z)
    rows = np.nonzero(np.abs(V2).max(axis=1) <= 0.5)[0]  # inside, away from the rim's blend
    cols = np.r_[rows[2:-2], n - 6, n - 5]  # the last two: past every row, on no row's ring
    lin = SlopeLinearisation(Gx, Gy, rows, cols)
    at = lin.at(z)
    Jp, Jq = at.matrices()
    assert Jp.shape == Jq.shape == (len(rows), len(cols))
    assert Jp[:, -2:].nnz == 0 and Jq[:, -2:].nnz == 0
    e = 1e-7
    for j in range(len(cols)):
        zp, zm = z.copy(), z.copy()
        zp[cols[j]] += e
        zm[cols[j]] -= e
        a, bm = lin.at(zp), lin.at(zm)
        np.testing.assert_allclose(Jp[:, j].toarray().ravel(), (a.p - bm.p) / (2 * e), atol=1e-6)
        np.testing.assert_allclose(Jq[:, j].toarray().ravel(), (a.q - bm.q) / (2 * e), atol=1e-6)


def test_slope_linearisation_of_nothing():
    """No rows and no free heights (plain empty lists): empty slopes and (k, 0) Jacobians."""
    V2, z, Gx, Gy = _slope_setup()
    at = SlopeLinearisation(Gx, Gy, [], []).at(z)
    assert at.p.shape == at.q.shape == (0,)
    assert at.matrices()[0].shape == (0, 0)
    at = SlopeLinearisation(Gx, Gy, [30, 31], []).at(z)
    assert at.p.shape == (2,)
    assert at.matrices()[0].shape == (2, 0)


# -------------------------------------------------------------------------------- Mesh


def _mesh_with_everything():
    V = np.array([[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0], [1, 1, 0], [3, 1, 0], [2, 3, 0]], dtype=float)
    F = [[0, 1, 5], [0, 5, 4], [1, 2, 5], [2, 6, 5], [2, 3, 6], [3, 4, 6], [3, 0, 4]]
    return Mesh(V, F, boundary=[0, 1, 2, 3], junction=[1, 2], holes=([4, 6, 5],))


def test_with_heights_keeps_boundary_junction_and_holes():
    m = _mesh_with_everything()
    z = np.arange(7) * 0.5
    m2 = m.with_heights(z)
    np.testing.assert_array_equal(m2.V[:, 2], z)
    np.testing.assert_array_equal(m2.V[:, :2], m.V[:, :2])
    np.testing.assert_array_equal(m2.boundary, m.boundary)
    np.testing.assert_array_equal(m2.junction, m.junction)
    assert len(m2.holes) == 1
    np.testing.assert_array_equal(m2.holes[0], m.holes[0])
    assert m2.with_heights(m.V[:, 2]).identical(m)


def test_identical_compares_values_not_only_shapes():
    m = _mesh_with_everything()
    assert m.identical(Mesh(m.V, m.F, m.boundary, m.junction, m.holes))
    assert not m.identical(None)
    assert not m.identical(m.with_heights(np.full(7, 1.0)))  # same shapes, other values
    V = np.array(m.V)
    V[0, 2] = -0.0  # documented: raw bytes, so -0.0 != 0.0
    assert not m.identical(Mesh(V, m.F, m.boundary, m.junction, m.holes))
    other_junction = Mesh(m.V, m.F, m.boundary, [2, 3], m.holes)
    assert not m.identical(other_junction)


# ------------------------------------------------------------------- reflectance.evaluate


def _models():
    import jax.numpy as jnp

    from sketchforge.geometry.reflectance_model import ReflectanceModel

    # normalises its inputs (a plugin model may): exact only if evaluated in float64
    tidy = ReflectanceModel("tidy", lambda n, l: jnp.dot(n / jnp.linalg.norm(n), l / jnp.linalg.norm(l)) ** 3)
    # written for float32 hardware
    low = ReflectanceModel("low", lambda n, l: jnp.dot(n.astype(jnp.float32), l.astype(jnp.float32)))
    return tidy, low


def test_evaluate_runs_any_model_in_float64_for_any_count():
    from sketchforge.geometry.reflectance import evaluate

    tidy, low = _models()
    # one normal (a single pick) and the empty set; one shape keeps the jit compiles few
    n = _unit(np.array([[0.3, -0.4, 0.85]]))
    l = _unit(np.array([0.2, 0.3, 0.9]))
    ref = lambda N, l: (_unit(N) @ _unit(l)) ** 3  # noqa: E731
    one = evaluate(tidy, n, l)
    assert one.shape == (1,)
    np.testing.assert_allclose(one, ref(n, l), rtol=1e-12)
    assert evaluate(tidy, np.zeros((0, 3)), l).shape == (0,)
    # float32 normals and light (a display buffer): the model still runs in float64
    n32, l32 = n.astype(np.float32), l.astype(np.float32)
    out = evaluate(tidy, n32, l32)
    assert out.dtype == np.float64
    np.testing.assert_allclose(out, ref(n32.astype(np.float64), l32.astype(np.float64)), rtol=1e-13, atol=0)
    assert evaluate(low, n, l).dtype == np.float64


# ------------------------------------------------------------------------------ shaders


def test_shaders_keep_float32_buffers_in_float32():
    from sketchforge.geometry.shaders import CEL_TONES, CLAY, cel_shade, lambert_shade

    light = np.array([0.0, 0.0, 1.0])
    N = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.6, 0.8]])
    for shade in (lambert_shade, cel_shade):
        assert shade(N.astype(np.float32), light).dtype == np.float32
        assert shade(N, light).dtype == np.float64
    np.testing.assert_allclose(lambert_shade(N.astype(np.float32), light), [CLAY, 0.3 * CLAY, (0.3 + 0.7 * 0.8) * CLAY], rtol=1e-6)
    np.testing.assert_array_equal(cel_shade(N.astype(np.float32), light), CEL_TONES[[2, 0, 2]].astype(np.float32))
    # integer normals are values, not a reason to truncate the light
    k = lambert_shade(np.array([[0, 0, 1]]), np.array([0.0, 0.6, 0.8]))
    np.testing.assert_allclose(k[0], (0.3 + 0.7 * 0.8) * CLAY, rtol=1e-12)


# --- from the seeded sample of geometry's unchecked mutants (mutation/results/geometry.sample.json)


def _square_contour(side=2.0, resolution=0.1):
    from sketchforge.geometry.contour import clean_contour

    s = side / 2.0
    return clean_contour([[-s, -s], [s, -s], [s, s], [-s, s]], resolution, closed=True, smooth=False)


def _circle(cx, cy, r, n=48):
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.c_[cx + r * np.cos(t), cy + r * np.sin(t)]


def test_a_hole_outside_the_outline_is_placed_in_the_message():
    from sketchforge.errors import ContourError
    from sketchforge.geometry.contour import prepare_holes

    with pytest.raises(ContourError) as info:
        prepare_holes([_circle(3.0, 0.5, 0.3)], _square_contour())
    msg = str(info.value)
    assert msg.startswith("hole 1 near (") and "lies outside the outline" in msg
    x, y = (float(v) for v in msg[len("hole 1 near ("):msg.index(")")].split(","))
    assert np.hypot(x - 3.0, y - 0.5) < 0.3  # a point of the hole


def test_a_hole_across_the_outline_is_placed_where_they_cross():
    from sketchforge.errors import ContourError
    from sketchforge.geometry.contour import prepare_holes

    # a circle centred on the right edge x = 1 crosses it near (1, 0.4 +- 0.3): the mean is (1, 0.4)
    with pytest.raises(ContourError) as info:
        prepare_holes([_circle(1.0, 0.4, 0.3)], _square_contour())
    msg = str(info.value)
    assert msg.startswith("hole 1 crosses the outline near (") and msg.endswith("a hole must lie inside its part")
    x, y = (float(v) for v in msg[msg.index("(") + 1:msg.index(")")].split(","))
    assert abs(x - 1.0) < 0.02 and abs(y - 0.4) < 0.02


def test_a_system_with_every_vertex_fixed_returns_the_fixed_values():
    import scipy.sparse as sp

    from sketchforge.geometry.dirichlet import DirichletSolver

    A = sp.csr_matrix(np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]]))
    s = DirichletSolver(A, [2, 0, 1])
    assert s.n_free == 0 and s._data is None
    assert np.array_equal(s.solve(np.ones(3), [5.0, 6.0, 7.0]), [5.0, 6.0, 7.0])


def test_the_dirichlet_solver_names_the_linear_system_by_default():
    import scipy.sparse as sp

    from sketchforge.errors import SketchforgeError
    from sketchforge.geometry.dirichlet import DirichletSolver

    with pytest.raises(SketchforgeError) as info:
        DirichletSolver(sp.csr_matrix((2, 3)), [0])
    assert str(info.value) == "the linear system: the matrix must be square, got shape (2, 3)"


def test_bad_triangle_and_fixed_indices_are_named_in_the_message():
    import scipy.sparse as sp

    from sketchforge.errors import SketchforgeError
    from sketchforge.geometry import guard

    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    with pytest.raises(SketchforgeError) as info:
        guard.mesh(V, [[0, 1, 7]], "the leg")
    assert str(info.value).startswith("the leg") and "triangle indices" in str(info.value)
    with pytest.raises(SketchforgeError) as info:
        guard.sparse_system(sp.identity(3, format="csr"), "the fairing", fixed=[0, 9])
    assert str(info.value).startswith("the fairing") and "fixed indices" in str(info.value)


def test_inflated_heights_default_to_unit_inflation_and_build_their_own_laplacian():
    from sketchforge.geometry.inflation import inflate_heights
    from sketchforge.geometry.laplacian import laplacian_and_mass
    from sketchforge.geometry.triangulate import triangulate_polygon

    c = _square_contour(resolution=0.25)
    V, F = triangulate_polygon(c.points, c.edge_length)[:2]
    b = np.arange(len(c.points))
    L, M = laplacian_and_mass(V[:, :2], F)
    z = inflate_heights(V, F, b)
    assert np.array_equal(z, inflate_heights(V, F, b, 1.0, L, M))
    assert np.allclose(inflate_heights(V, F, b, 2.0), 2.0 * z, rtol=1e-12, atol=0) and z.max() > 0.1


def test_an_edge_length_too_small_to_count_is_counted_as_ten_to_the_eighteen():
    from sketchforge.geometry.triangulate import estimate_vertex_count

    assert estimate_vertex_count(1.0, 4.0, 1e-300) == 10**18
    assert estimate_vertex_count(1.0, 4.0, 0.0) == 10**18
    assert 100 < estimate_vertex_count(1.0, 4.0, 0.1) < 10**4


_TRI_V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


@pytest.mark.parametrize("field, value, message", [
    ("V", np.zeros(3), "Mesh.V must have 2 dimensions, got shape (3,)"),
    ("boundary", [[0, 1]], "Mesh.boundary must have 1 dimensions, got shape (1, 2)"),
    ("junction", [[0, 1]], "Mesh.junction must have 1 dimensions, got shape (1, 2)"),
    ("boundary", [0, 1, 5], "Mesh.boundary refers to a vertex outside 0..2"),
    ("junction", [7], "Mesh.junction refers to a vertex outside 0..2"),
])
def test_a_malformed_mesh_names_the_field_that_is_wrong(field, value, message):
    from sketchforge.geometry.mesh import Mesh

    kw = {"V": _TRI_V, "F": [[0, 1, 2]], "boundary": [0, 1, 2], "junction": []}
    kw[field] = value
    with pytest.raises(ValueError) as info:
        Mesh(**kw)
    assert str(info.value) == message


def test_a_point_that_is_not_a_number_is_named_by_its_index():
    from sketchforge.errors import ContourError
    from sketchforge.geometry.contour import validate_stroke

    with pytest.raises(ContourError) as info:
        validate_stroke([[0.0, 0.0], [1.0, 0.0], [1.0, float("nan")], [0.0, 1.0]])
    assert str(info.value).endswith("has a point that is not a finite number (point 2: [1.0, nan])")


def test_a_3d_triangle_standing_in_the_xz_plane_is_not_flat():
    from sketchforge.errors import GeometryError
    from sketchforge.geometry import guard

    # its area is all in the y component of the cross product, whose two terms add up here
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [1.0, 0.0, -1.0]])
    V2, F2 = guard.mesh(V, [[0, 1, 2]], "the part")
    assert F2.tolist() == [[0, 1, 2]]
    flat = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [2.0, 0.0, 2.0]])
    with pytest.raises(GeometryError) as info:
        guard.mesh(flat, [[0, 1, 2]], "the part")
    assert str(info.value).startswith("the part has a triangle of zero area (triangle 0, near (0, 0")
