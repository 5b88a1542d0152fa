"""Cotangent Laplacian, mass matrix, Dirichlet solver and fairing on small analytic cases."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from meshes import disk

from sketchforge.geometry import guard
from sketchforge.geometry.contour import signed_area
from sketchforge.geometry.dirichlet import DirichletSolver
from sketchforge.geometry.fairing import FairingSolver, fair_heights, fairing_weight, squared_laplacian_matrix
from sketchforge.geometry.laplacian import laplacian_and_mass


def test_one_right_triangle_by_hand():
    V = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    L, M = laplacian_and_mass(V, np.array([[0, 1, 2]], dtype=np.int32))
    # Right angle at vertex 0: the edge opposite it (1-2) gets ½cot(90°) = 0; edges 0-1 and
    # 0-2 are opposite 45° angles: ½cot(45°) = ½.
    expected = np.array([[-1.0, 0.5, 0.5], [0.5, -0.5, 0.0], [0.5, 0.0, -0.5]])
    assert np.allclose(L.toarray(), expected, atol=1e-14)
    assert M.diagonal().sum() == pytest.approx(0.5, rel=1e-14)


def test_one_check_or_none_the_operators_are_the_same():
    V2, F, _ = disk(1.0, 0.2)
    L, M = laplacian_and_mass(V2, F.astype(np.int32))
    L2, M2 = laplacian_and_mass(*guard.mesh(V2, F), checked=True)  # already through the guard
    assert (L2 != L).nnz == 0 and (M2 != M).nnz == 0


def test_rows_sum_to_zero_and_linear_functions_are_harmonic():
    V2, F, b = disk(1.0, 0.1)
    L, M = laplacian_and_mass(V2, F)
    assert abs(L - L.T).max() < 1e-12
    assert np.abs(L @ np.ones(len(V2))).max() < 1e-12
    interior = np.setdiff1d(np.arange(len(V2)), b)
    f = 2.0 * V2[:, 0] - 3.0 * V2[:, 1] + 1.0
    assert np.abs((L @ f)[interior]).max() < 1e-12
    assert M.diagonal().sum() == pytest.approx(signed_area(V2[b]), rel=1e-12)


def test_dirichlet_solver_matches_scipy_and_keeps_fixed_values_exactly():
    V2, F, b = disk(1.0, 0.1)
    L, M = laplacian_and_mass(V2, F)
    rhs = M @ np.cos(V2[:, 0])
    fixed_vals = np.sin(3 * np.arctan2(V2[b, 1], V2[b, 0]))
    order = np.argsort(b)
    x = DirichletSolver(-L, b).solve(rhs, fixed_vals[order])
    free = np.setdiff1d(np.arange(len(V2)), b)
    A = (-L).tocsr()
    y = np.zeros(len(V2))
    y[b] = fixed_vals
    y[free] = sla.spsolve(A[free][:, free].tocsc(), rhs[free] - A[free][:, b] @ fixed_vals)
    assert np.abs(x - y).max() < 1e-11
    assert np.array_equal(x[b], fixed_vals)


def test_fairing_alpha_zero_is_identity():
    V2, F, b = disk(1.0, 0.1)
    L, M = laplacian_and_mass(V2, F)
    z0 = np.sqrt(np.maximum(1 - (V2**2).sum(1), 0))
    z = fair_heights(L, M, b, z0, 0.0)
    assert z.tobytes() == z0.tobytes()


def test_fairing_solves_the_stationarity_condition_with_the_factor_two():
    V2, F, b = disk(1.0, 0.08)
    L, M = laplacian_and_mass(V2, F)
    z0 = np.sqrt(np.maximum(1 - (V2**2).sum(1), 0))
    alpha, unit = 0.3, 0.05
    z = FairingSolver(L, M, b, alpha, unit).solve(z0)
    K = squared_laplacian_matrix(L, M)

    def objective(y):  # α E + (1-α)‖y - z0‖²_M with lengths in `unit`
        return alpha * (y @ (K @ y)) + (1 - alpha) * ((y - z0) @ (M @ (y - z0))) / unit**4

    free = np.setdiff1d(np.arange(len(V2)), b)
    rng = np.random.default_rng(0)
    for _ in range(3):
        d = np.zeros(len(V2))
        d[free] = rng.standard_normal(len(free)) * 1e-3
        assert objective(z) < objective(z + d) and objective(z) < objective(z - d)
    # 4.2.2 as printed (no factor 2 on the linear term) would give half this height.
    zi = np.argmax(z0)
    assert z[zi] > 0.9 * z0[zi]


def test_fairing_is_scale_invariant_when_the_unit_scales():
    V2, F, b = disk(1.0, 0.1)
    z0 = np.sqrt(np.maximum(1 - (V2**2).sum(1), 0))
    L1, M1 = laplacian_and_mass(V2, F)
    L3, M3 = laplacian_and_mass(3.0 * V2, F)
    z1 = fair_heights(L1, M1, b, z0, 0.5, 0.04)
    z3 = fair_heights(L3, M3, b, 3.0 * z0, 0.5, 0.12)
    assert np.abs(z3 - 3.0 * z1).max() < 1e-10


def test_fairing_weight_rejects_alpha_one():
    assert fairing_weight(0.5, 2.0) == pytest.approx(16.0)
    with pytest.raises(ValueError):
        fairing_weight(1.0)


def test_squared_laplacian_is_psd_and_kills_constants_only_through_rows():
    V2, F, b = disk(1.0, 0.15)
    L, M = laplacian_and_mass(V2, F)
    K = squared_laplacian_matrix(L, M)
    assert isinstance(K, sp.csc_matrix)
    assert np.abs(K @ np.ones(len(V2))).max() < 1e-10
    w = np.linalg.eigvalsh(K.toarray())
    assert w.min() > -1e-8 * w.max()


def test_fairing_measures_lengths_in_drawing_units_by_default():
    # The inflate plugin always passes its unit; a script calling the helpers without one gets
    # the documented default of 1 drawing unit, β = α/(1-α).
    V2, F, b = disk(1.0, 0.12)
    L, M = laplacian_and_mass(V2, F)
    z0 = np.sqrt(np.maximum(1 - (V2**2).sum(1), 0))
    assert fairing_weight(0.5) == 1.0
    assert FairingSolver(L, M, b, 0.5).beta == 1.0
    assert np.array_equal(fair_heights(L, M, b, z0, 0.5), fair_heights(L, M, b, z0, 0.5, 1.0))


def test_fairing_weight_says_which_alpha_it_refuses():
    for alpha in (1.0, -0.25, 2.5):
        with pytest.raises(ValueError) as info:
            fairing_weight(alpha)
        assert "alpha" in str(info.value) and str(alpha) in str(info.value)


def test_fairing_keeps_nonzero_boundary_heights_and_is_stationary_inside():
    # A sculpted layer re-fairs heights whose rim is not at 0 (a raised base): the rim must
    # stay where it was, not drop to 0, and the interior must minimise the energy for that rim.
    V2, F, b = disk(1.0, 0.1)
    L, M = laplacian_and_mass(V2, F)
    z0 = 0.7 + 0.3 * V2[:, 0] + np.sqrt(np.maximum(1 - (V2**2).sum(1), 0))
    alpha = 0.4
    z = FairingSolver(L, M, b, alpha).solve(z0)
    assert np.array_equal(z[b], z0[b]) and np.abs(z0[b]).min() > 0.3
    K = squared_laplacian_matrix(L, M)
    grad = alpha * 2 * (K @ z) + (1 - alpha) * 2 * (M @ (z - z0))
    free = np.setdiff1d(np.arange(len(V2)), b)
    assert np.abs(grad[free]).max() < 1e-9 * max(1.0, np.abs(z).max())


def test_squared_laplacian_ignores_a_vertex_no_face_uses_without_warnings():
    # Vertices used by no face have zero mass: they must drop out of M⁻¹ quietly instead of
    # producing inf (a divide-by-zero warning on every fairing of such a mesh).
    import warnings

    V2, F, _ = disk(1.0, 0.2)
    Vx = np.vstack([V2, [[5.0, 5.0]]])  # one vertex outside every face
    L, M = laplacian_and_mass(V2, F)
    Lx, Mx = laplacian_and_mass(Vx, F)
    # libigl's own mass matrix leaves a trailing unused vertex out: L and M must still fit.
    assert Lx.shape == Mx.shape == (len(Vx), len(Vx))
    assert Mx.diagonal()[-1] == 0.0 and np.array_equal(Mx.diagonal()[:-1], M.diagonal())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Kx = squared_laplacian_matrix(Lx, Mx).toarray()
    K = squared_laplacian_matrix(L, M).toarray()
    assert np.isfinite(Kx).all()
    assert np.array_equal(Kx[:-1, :-1], K) and not Kx[-1].any() and not Kx[:, -1].any()


def test_fairing_returns_float64_heights_even_from_integer_input():
    # Heights read from a hand-written file can arrive as integers; the result is float64
    # whatever α is, α = 0 (a plain copy) included.
    V2, F, b = disk(1.0, 0.2)
    L, M = laplacian_and_mass(V2, F)
    z0 = np.arange(len(V2)) % 3
    for alpha in (0.0, 0.3):
        z = FairingSolver(L, M, b, alpha).solve(z0)
        assert z.dtype == np.float64 and np.array_equal(z[b], z0[b].astype(np.float64))
