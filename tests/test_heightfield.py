"""Height-field normals through w = z²: one field for the display and the sculpt solver."""

import numpy as np
import pytest

from sketchforge.geometry.heightfield import SlopeLinearisation, layer_normals, slopes_from_heights
from sketchforge.geometry.intensity import gradient_operators
from sketchforge.geometry.isophote_error import InflatedEllipse
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.normals import NZ_MIN, normals_from_slopes, vertex_normals
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.testing import LIGHT, inflated


def _angle(A, B):
    return np.degrees(np.arccos(np.clip(np.sum(A * B, axis=1), -1.0, 1.0)))


@pytest.fixture(scope="module")
def ellipsoid():
    s = InflatedEllipse(1.5, 1.0)
    return s, s.mesh(120, 0.03)


def test_normals_match_the_exact_inflation_up_to_the_rim(ellipsoid):
    s, m = ellipsoid
    exact = s.normal(m.V[:, :2])
    new = _angle(layer_normals(m), exact)
    old = _angle(vertex_normals(m.V, m.F), exact)
    rim = np.zeros(m.n_vertices, bool)
    rim[m.boundary] = True
    # the area-weighted normals err by up to ~6 degrees at and next to the rim
    assert old.max() > 4.0
    assert new.max() < 2.0 and new.max() < old.max() / 3
    assert np.median(new) < 0.6 * np.median(old)
    # at the rim the normal lies in the plane (to the slope clamp) and points outwards
    n = layer_normals(m)[rim]
    assert np.all(np.abs(n[:, 2]) <= 1.01 * NZ_MIN)
    outward = m.V[rim, :2] / np.array([s.a**2, s.b**2])
    assert np.all(np.sum(n[:, :2] * outward, axis=1) > 0)


def test_display_normals_and_the_solver_shading_are_one_field():
    m = inflated("m", 0.04)  # faired, with concave corners
    Gx, Gy = gradient_operators(m.V[:, :2], m.F)
    p, q = slopes_from_heights(Gx, Gy, m.V[:, 2])
    N = layer_normals(m)
    assert np.abs(N - normals_from_slopes(p, q)).max() < 1e-12
    ld = layer_data(m, LIGHT, LAMBERTIAN)
    assert np.abs(ld.E - N @ LIGHT).max() < 1e-12
    rows = np.arange(40, 900)
    at = SlopeLinearisation(Gx, Gy, rows, rows).at(m.V[:, 2])  # the solver's
    assert np.array_equal(at.p, p[rows]) and np.array_equal(at.q, q[rows])


def test_slope_jacobians_match_finite_differences():
    m = inflated("ellipse", 0.04)
    z = m.V[:, 2]
    Gx, Gy = gradient_operators(m.V[:, :2], m.F)
    cols = np.nonzero(z > 0.3 * z.max())[0]
    rows = np.unique(np.concatenate([Gx[:, cols].tocoo().row, cols]))
    lin = SlopeLinearisation(Gx, Gy, rows, cols)
    at = lin.at(z)
    v = np.random.default_rng(3).standard_normal(len(cols)) * 1e-6 * z.max()
    z2 = z.copy()
    z2[cols] += v
    moved = lin.at(z2)
    dp, dq = at.apply(v)
    for d, a, b in ((dp, moved.p, at.p), (dq, moved.q, at.q)):
        assert np.abs(a - b - d).max() < 1e-4 * np.abs(d).max()
    Jp, Jq = at.matrices()
    assert np.abs(Jp @ v - dp).max() < 1e-12 and np.abs(Jq @ v - dq).max() < 1e-12
    y1, y2 = np.random.default_rng(4).standard_normal((2, len(rows)))
    assert np.allclose(at.apply_t(y1, y2), Jp.T @ y1 + Jq.T @ y2, rtol=0, atol=1e-9 * np.abs(Jp).max())


def test_what_is_not_an_inflated_layer_keeps_area_weighted_normals(ellipsoid):
    _, m = ellipsoid
    closed = Mesh(m.V, m.F)  # no boundary: an assembled model, a posed one
    np.testing.assert_array_equal(layer_normals(closed), vertex_normals(m.V, m.F))
    below = Mesh(m.V * [1, 1, -1], m.F, m.boundary)  # z < 0: vertex by vertex, area-weighted
    np.testing.assert_allclose(layer_normals(below), vertex_normals(below.V, m.F), rtol=0, atol=1e-12)
    flat = Mesh(m.V * [1, 1, 0], m.F, m.boundary)  # inflation 0
    np.testing.assert_allclose(layer_normals(flat), np.tile([0.0, 0.0, 1.0], (m.n_vertices, 1)), atol=1e-15)


@pytest.mark.parametrize("smoothing", [0.5, 0.8])
def test_a_faired_rim_keeps_its_finite_slope(smoothing):
    """The fairing bends the rim off the vertical (w ~ distance² there, not ~ distance): its rim
    vertices and their first ring keep the area-weighted normals, the rest of the layer the
    w-form, and an unfaired layer's rim stays vertical."""
    from inflate_shapes import ellipse

    from sketchforge_inflate.inflate import inflate_stroke

    faired = inflate_stroke(ellipse(300, 0.75, 0.5), closed=True, params={"smoothing": smoothing})
    rim = faired.boundary
    N, A = layer_normals(faired), vertex_normals(faired.V, faired.F)
    assert np.abs(N[rim] - A[rim]).max() < 1e-12
    assert np.all(N[rim, 2] > 0.1)  # tilted, not in the plane
    plain = inflate_stroke(ellipse(300, 0.75, 0.5), closed=True, params={"smoothing": 0.0})
    assert np.all(np.abs(layer_normals(plain)[plain.boundary, 2]) <= 1.01 * NZ_MIN)
