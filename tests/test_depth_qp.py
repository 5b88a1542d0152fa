"""The depth-order QP and its solvers (``sketchforge_assemble.depth``), checked against what their
answers must be on seeded random problems shaped like the assembly's: a Laplacian-plus-mass
energy, glue rows of two terms and depth rows of one vertex against a point of a triangle.

The optimum is judged by its optimality conditions (feasible; the energy's gradient a
combination of the glue rows and of the tight depth rows with multipliers >= 0), not by a
second solver, and the depth rows are judged against a brute-force geometric reference.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import shapely
from scipy.optimize import nnls

from sketchforge_assemble import DepthOrderError, active_set, depth_qp
from sketchforge_assemble.active_set import _active_set
from sketchforge_assemble.depth import solve_depth
from sketchforge_assemble.depth_qp import _equality_solution, _polish_glue, _screening_guess
from sketchforge_assemble.depth_rows import _crossing_rows, _pair_rows, _Rows
from sketchforge_assemble.sheet import unique_edges


def _random_qp(seed: int, n: int = 60, n_eq: int = 3, n_in: int = 50, twins: int = 0, sheets: int = 3):
    """(P, q, Aeq, beq, Ain, bin_) shaped like :func:`depth_rows.build_problem`'s: ``sheets`` blocks of
    unknowns, each with a path Laplacian (a shift is free, a bend costs) plus a mass term pulling
    it towards its own rest depth; glue rows of two terms and depth rows of one vertex against a
    point of a triangle of another block. Feasible by construction (every row holds at a random
    point, a fifth of them tightly). ``twins`` depth rows are repeated (linearly dependent rows,
    as touching faces give)."""
    rng = np.random.default_rng(seed)
    block = np.arange(n) * sheets // n  # (n,) block of each unknown
    i = np.flatnonzero(block[:-1] == block[1:])
    W = sp.coo_matrix((rng.uniform(0.5, 2.0, len(i)), (i, i + 1)), shape=(n, n))
    W = W + W.T
    w = 0.05
    P = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W + w * sp.eye(n)).tocsc()
    q = -w * rng.normal(0.0, 1.0, sheets)[block]  # P·1 = w·1: q = -w·M·rest, as the assembly's
    x_ok = rng.normal(0.0, 1.0, n)

    def other(v):
        return rng.choice(np.flatnonzero(block != block[v]), 3, replace=False)

    perm = rng.permutation(n)
    a = perm[:n_eq]
    b = np.array([rng.choice(np.setdiff1d(np.flatnonzero(block != block[v]), a)) for v in a])
    Aeq = sp.csr_matrix((np.tile([1.0, -1.0], n_eq), (np.repeat(np.arange(n_eq), 2), np.c_[a, b].ravel())),
                        shape=(n_eq, n))
    beq = Aeq @ x_ok
    v = rng.integers(0, n, n_in)
    tri = np.array([other(u) for u in v])
    bary = rng.dirichlet(np.ones(3), n_in)
    sign = rng.choice([-1.0, 1.0], n_in)
    rows = np.repeat(np.arange(n_in), 4)
    Ain = sp.csr_matrix(((sign[:, None] * np.c_[np.ones(n_in), -bary]).ravel(), (rows, np.c_[v, tri].ravel())),
                        shape=(n_in, n))
    slack = rng.exponential(0.2, n_in) * (rng.random(n_in) > 0.2)
    bin_ = Ain @ x_ok - slack
    if twins:
        Ain = sp.vstack([Ain, Ain[:twins]]).tocsr()
        bin_ = np.r_[bin_, bin_[:twins]]
    return P, q, Aeq, beq, Ain, bin_


def _kkt_residual(P, q, Aeq, beq, Ain, bin_, x, tight: float) -> float:
    """Relative residual of the stationarity condition Px + q = Aeqᵀμ + Ain_Tᵀλ, λ >= 0, over the
    rows T with slack <= ``tight`` (μ free: both signs as non-negative columns)."""
    g = P @ x + q
    t = np.flatnonzero(Ain @ x - bin_ <= tight)
    M = np.hstack([Aeq.T.toarray(), -Aeq.T.toarray(), Ain[t].T.toarray()])
    _, res = nnls(M, g, maxiter=50 * M.shape[1])
    return res / max(1.0, float(np.linalg.norm(g)))


SEEDS = range(12)


@pytest.mark.parametrize("seed", SEEDS)
def test_active_set_ends_at_the_optimum_of_random_problems(seed):
    P, q, Aeq, beq, Ain, bin_ = _random_qp(seed)
    x0 = sp.linalg.spsolve(P, -q)
    assert np.min(Ain @ x0 - bin_) < -0.1  # the unconstrained minimiser breaks rows: there is work to do
    x, info = solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set")
    slack = Ain @ x - bin_
    assert slack.min() >= -1e-10
    assert np.max(np.abs(Aeq @ x - beq)) <= 1e-10
    assert _kkt_residual(P, q, Aeq, beq, Ain, bin_, x, 1e-9) <= 1e-9
    assert info["method"] == "active_set" and info["osqp_iterations"] == 0
    # every row it reports active is tight, and (strict complementarity, generic here) every
    # tight row is one of them
    assert info["active"] == int(np.sum(slack <= 1e-9))
    assert info["active"] <= info["iterations"]  # each active row took one step to join


@pytest.mark.parametrize("seed", SEEDS)
def test_dependent_twin_rows_do_not_change_the_optimum(seed):
    # touching faces give rows that repeat others: a working set with both twins would be
    # singular; the pivot test keeps one and the answer is the same
    base = _random_qp(seed)
    x1, _ = solve_depth(*base, method="active_set")
    x2, info = solve_depth(*_random_qp(seed, twins=25), method="active_set")
    assert np.abs(x1 - x2).max() <= 1e-9
    assert info["active"] == int(np.sum(base[4] @ x1 - base[5] <= 1e-9))  # one twin of each tight pair


@pytest.mark.parametrize("seed", SEEDS)
def test_osqp_answer_clears_every_row_by_the_pad_and_sits_at_the_padded_optimum(seed):
    P, q, Aeq, beq, Ain, bin_ = _random_qp(seed)
    pad = 0.01
    x, info = solve_depth(P, q, Aeq, beq, Ain, bin_, method="osqp", pad=pad)
    exact, _ = solve_depth(P, q, Aeq, beq, Ain, bin_ + pad, method="active_set")
    slack = Ain @ x - bin_
    assert slack.min() >= 0.5 * pad  # OSQP's 1e-4 accuracy eats a little of the pad, never all
    assert np.max(np.abs(Aeq @ x - beq)) <= 1e-12  # the glue is polished to round-off
    # OSQP's 1e-4 accuracy: over 100 seeds of these problems the answer lies a median 0.004,
    # a 95th percentile 0.10 and at most 0.30 pads from the exact padded optimum
    assert np.abs(x - exact).max() <= 0.5 * pad
    assert info["method"] == "osqp" and info["osqp_status"] == "solved" and info["iterations"] == 0
    assert info["active"] == int(np.sum(slack <= pad + 1e-6))
    assert 1 <= info["osqp_rounds"] <= 6
    assert 0 < info["osqp_iterations"] < 20000
    # every row within reach of the answer was given to OSQP
    assert info["osqp_rows"] >= int(np.sum(slack < depth_qp.SCREEN_PADS * pad))
    assert info["osqp_rows"] <= len(bin_)


def test_osqp_is_given_only_the_rows_near_the_anchored_guess():
    # rows far from any reachable answer (here half of them, 100 units of slack) never go to
    # OSQP, and the answer is the same as with every row given
    P, q, Aeq, beq, Ain, bin_ = _random_qp(3)
    far = sp.vstack([Ain, Ain]).tocsr()
    bfar = np.r_[bin_, bin_ - 100.0]
    pad = 0.01
    x1, info1 = solve_depth(P, q, Aeq, beq, Ain, bin_, pad=pad)
    x2, info2 = solve_depth(P, q, Aeq, beq, far, bfar, pad=pad)
    assert info2["osqp_rows"] == info1["osqp_rows"] <= len(bin_)
    assert np.abs(x1 - x2).max() <= 1e-9


def test_osqp_rounds_grow_the_rows_until_every_row_holds(monkeypatch):
    # a screening guess that sees no row as near makes the first round drop rows the answer
    # needs; they join in the next rounds, warm-started, and the answer is still the optimum
    P, q, Aeq, beq, Ain, bin_ = _random_qp(5)
    pad = 0.01
    x_ref, _ = solve_depth(P, q, Aeq, beq, Ain, bin_ + pad, method="active_set")
    far_guess = np.full(P.shape[0], np.nan)
    far_guess[:] = sp.linalg.spsolve(P, -q)  # the glue-free, anchor-free minimiser
    monkeypatch.setattr(depth_qp, "_screening_guess", lambda *a: far_guess + 0.0)
    x, y, info = depth_qp._osqp_screened(P, q, Aeq, beq, Ain, bin_, pad)
    assert info["osqp_rounds"] >= 2
    assert np.min(Ain @ x - bin_) >= -1e-3 * pad
    assert np.abs(x - x_ref).max() <= 0.5 * pad  # OSQP's accuracy, as above
    assert y.shape == bin_.shape and np.all(y <= 1e-9)  # OSQP's multipliers of >= rows are <= 0
    assert np.count_nonzero(y) <= info["osqp_rows"]  # the rows never given to OSQP have none


def test_warm_started_rounds_need_fewer_iterations_than_a_cold_start(monkeypatch):
    # the second round starts from the first one's answer: it needs fewer OSQP iterations than
    # the same round solved cold
    P, q, Aeq, beq, Ain, bin_ = _random_qp(7)
    pad = 0.01
    calls = []
    import osqp

    real = osqp.OSQP

    class Spy(real):
        def warm_start(self, **kw):
            calls.append(kw)
            return super().warm_start(**kw)

    monkeypatch.setattr(osqp, "OSQP", Spy)
    _, _, info = depth_qp._osqp_screened(P, q, Aeq, beq, Ain, bin_, pad)
    assert len(calls) == info["osqp_rounds"]  # every round starts from the last point
    assert calls[0]["x"].shape == (P.shape[0],) and np.all(np.isfinite(calls[0]["x"]))
    monkeypatch.setattr(depth_qp, "_screening_guess", lambda *a: None)
    calls.clear()
    _, _, cold = depth_qp._osqp_screened(P, q, Aeq, beq, Ain, bin_, pad)
    assert calls == [] and cold["osqp_rows"] == len(bin_)  # no guess: every row at once, cold


def test_osqp_left_short_of_a_row_hands_over_to_the_active_set():
    # without a pad, OSQP's 1e-4 accuracy leaves tight rows violated (here by 1.3e-4): the
    # active set finishes from OSQP's active rows and the answer is exact, not OSQP's
    P, q, Aeq, beq, Ain, bin_ = _random_qp(0)
    x_osqp, _, _ = depth_qp._osqp_screened(P, q, Aeq, beq, Ain, bin_, 0.0)
    assert np.min(Ain @ x_osqp - bin_) < -1e-5
    x, info = solve_depth(P, q, Aeq, beq, Ain, bin_, method="osqp", pad=0.0)
    assert info["osqp_iterations"] > 0
    assert np.min(Ain @ x - bin_) >= -1e-10
    assert _kkt_residual(P, q, Aeq, beq, Ain, bin_, x, 1e-9) <= 1e-9
    exact, cold = solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set")
    assert np.abs(x - exact).max() <= 1e-9
    assert info["iterations"] < cold["iterations"]  # the warm start saved steps


def test_contradicting_glue_rows_are_a_clear_error_within_seconds():
    P, q, Aeq, beq, Ain, bin_ = _random_qp(1)
    Aeq = sp.vstack([Aeq, Aeq[:1]]).tocsr()  # the same vertex glued at two heights
    beq = np.r_[beq, beq[0] + 1.0]
    for method in ("active_set", "osqp"):
        with pytest.raises(DepthOrderError, match="glue rows of the layers contradict each other"):
            solve_depth(P, q, Aeq, beq, Ain, bin_, method=method, pad=0.01)


def test_glue_rows_repeated_exactly_are_not_a_contradiction():
    P, q, Aeq, beq, Ain, bin_ = _random_qp(1)
    x1, _ = solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set")
    x2, _ = solve_depth(P, q, sp.vstack([Aeq, Aeq]).tocsr(), np.r_[beq, beq], Ain, bin_, method="active_set")
    assert np.abs(x1 - x2).max() <= 1e-9


def test_the_step_limit_stops_the_active_set_with_a_clear_error():
    P, q, Aeq, beq, Ain, bin_ = _random_qp(4)
    _, info = solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set")
    with pytest.raises(DepthOrderError, match="did not converge"):
        solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set", max_iter=info["iterations"] - 1)
    x, again = solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set", max_iter=info["iterations"])
    assert again["iterations"] == info["iterations"]


def test_memory_budget_counts_what_the_working_set_holds(monkeypatch):
    # the budget charged at each check is the method's real memory: cached columns P⁻¹cᵀ of the
    # rows probed, the buffer's columns and the m×m factor, never more
    P, q, Aeq, beq, Ain, bin_ = _random_qp(6, n=2000, n_in=20)
    seen = []
    real = active_set._WorkingSet.check_budget

    def spy(self, new_columns=0, z_columns=None, m=None):
        n = len(self.x0)
        zc = self.Z.shape[1] if z_columns is None else z_columns
        mm = self.m if m is None else m
        seen.append((len(self.cache) + new_columns, zc, mm, 8 * n * (len(self.cache) + new_columns + zc) + 8 * mm * mm))
        return real(self, new_columns, z_columns, m)

    monkeypatch.setattr(active_set._WorkingSet, "check_budget", spy)
    solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set")
    rows = len(bin_) + len(beq)
    assert max(s[0] for s in seen) <= rows
    # fewer than 16 rows ever in the set: the first buffer (16 columns) is never doubled
    assert max(s[2] for s in seen) <= 16
    assert all(s[1] == 16 for s in seen)
    peak = max(s[3] for s in seen)
    monkeypatch.setattr(active_set._WorkingSet, "check_budget", real)
    solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set", memory_budget=peak)  # exactly enough
    with pytest.raises(DepthOrderError, match=r"needed \d+ MB, over its budget of 0 MB .*Reorder or redraw"):
        solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set", memory_budget=peak - 1)


def test_a_working_set_of_more_than_16_rows_grows_its_buffer():
    # many tight rows: the buffer of P⁻¹cᵀ columns doubles past 16 and the answer stays exact
    P, q, Aeq, beq, Ain, bin_ = _random_qp(8, n=80, n_in=160)
    x, info = solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set")
    assert info["active"] + len(beq) > 16
    assert np.min(Ain @ x - bin_) >= -1e-10
    assert _kkt_residual(P, q, Aeq, beq, Ain, bin_, x, 1e-9) <= 1e-9


def test_rows_that_leave_the_working_set_keep_its_factor_exact():
    # a warm start with every row in it: most must leave (negative multipliers), some from the
    # middle of the set, and the factor kept for the rest must still give the optimum
    P, q, Aeq, beq, Ain, bin_ = _random_qp(9)
    warm = np.arange(len(bin_))
    x, steps, act = _active_set(P, q, sp.csr_matrix(Aeq), beq, sp.csr_matrix(Ain), bin_, warm, 1e-10, 10000)
    assert np.min(Ain @ x - bin_) >= -1e-10
    assert _kkt_residual(P, q, Aeq, beq, Ain, bin_, x, 1e-9) <= 1e-9
    assert sorted(act.tolist()) == np.flatnonzero(Ain @ x - bin_ <= 1e-9).tolist()


def test_infeasible_depth_rows_are_a_clear_error_for_both_solvers():
    P, q, Aeq, beq, Ain, bin_ = _random_qp(10)
    Ain = sp.vstack([Ain, -Ain[:1]]).tocsr()  # row 0 >= b and row 0 <= b - 0.5
    bin_ = np.r_[bin_, -bin_[0] + 0.5]
    for method in ("active_set", "osqp"):
        with pytest.raises(DepthOrderError, match="could not be satisfied"):
            solve_depth(P, q, Aeq, beq, Ain, bin_, method=method, pad=0.01)


def test_a_violation_at_round_off_is_accepted_not_called_infeasible():
    # the same contradiction, but 1e-13 wide: not a user's problem, the row is skipped
    P, q, Aeq, beq, Ain, bin_ = _random_qp(10)
    x0, _ = solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set")
    r = Ain[:1] @ x0 - bin_[:1]
    Ain2 = sp.vstack([Ain, Ain[:1], -Ain[:1]]).tocsr()
    b2 = np.r_[bin_, bin_[0] + r + 0.5, -(bin_[0] + r + 0.5) - 1e-13]  # row 0 pinned at one value, 1e-13 short
    x, _ = solve_depth(P, q, Aeq, beq, Ain2, b2, method="active_set")
    assert np.min(Ain2 @ x - b2) >= -1e-9


def test_problems_without_glue_or_without_depth_rows():
    P, q, Aeq, beq, Ain, bin_ = _random_qp(11)
    none_eq = sp.csr_matrix((0, P.shape[0])), np.zeros(0)
    none_in = sp.csr_matrix((0, P.shape[0])), np.zeros(0)
    for method in ("active_set", "osqp"):
        x, info = solve_depth(P, q, *none_eq, Ain, bin_, method=method, pad=0.01)
        assert np.min(Ain @ x - bin_) >= -1e-12
        x, info = solve_depth(P, q, Aeq, beq, *none_in, method=method, pad=0.01)
        # only glue: the equality-constrained minimiser, nothing active
        tol = 1e-4 if method == "osqp" else 1e-9  # OSQP's accuracy
        ref = _equality_solution(P, q, Aeq, beq)
        assert np.abs(x - ref).max() <= tol and info["active"] == 0
        x, info = solve_depth(P, q, *none_eq, *none_in, method=method, pad=0.01)
        assert np.abs(x - sp.linalg.spsolve(P, -q)).max() <= tol and info["active"] == 0


# --- the pieces of the OSQP path -------------------------------------------------------------


def test_equality_solution_solves_the_kkt_system_or_says_none():
    P, q, Aeq, beq, _, _ = _random_qp(0)
    x0 = x = _equality_solution(P, q, Aeq, beq)
    assert np.max(np.abs(Aeq @ x - beq)) <= 1e-12
    assert _kkt_residual(P, q, Aeq, beq, sp.csr_matrix((0, P.shape[0])), np.zeros(0), x, 0.0) <= 1e-12
    x = _equality_solution(P, q, sp.csr_matrix((0, P.shape[0])), np.zeros(0))
    assert np.abs(P @ x + q).max() <= 1e-12
    # glue rows that repeat one another (a singular KKT matrix) still have the same answer
    y = _equality_solution(P, q, sp.vstack([Aeq, Aeq]).tocsr(), np.r_[beq, beq])
    assert y is not None and np.abs(y - x0).max() <= 1e-9
    # rows that contradict each other have none: nothing to screen with
    assert _equality_solution(P, q, sp.vstack([Aeq, Aeq]).tocsr(), np.r_[beq, beq + 1.0]) is None
    with np.errstate(all="ignore"):
        assert _equality_solution(P, q * np.inf, Aeq, beq) is None  # no finite answer: none


def test_polish_glue_moves_least_to_make_the_glue_exact():
    P, q, Aeq, beq, _, _ = _random_qp(0)
    rng = np.random.default_rng(0)
    x = rng.normal(size=P.shape[0])
    y = _polish_glue(x, Aeq, beq)
    assert np.max(np.abs(Aeq @ y - beq)) <= 1e-12
    # the least move: along the rows only (x - y in the row space of Aeq)
    d = x - y
    coef = np.linalg.lstsq(Aeq.T.toarray(), d, rcond=None)[0]
    assert np.abs(Aeq.T @ coef - d).max() <= 1e-12
    assert np.abs(y[np.asarray(Aeq.sum(axis=0)).ravel() == 0] - x[np.asarray(Aeq.sum(axis=0)).ravel() == 0]).max() == 0
    # dependent rows, no rows, a non-finite x: left as it is
    assert np.array_equal(_polish_glue(x, sp.vstack([Aeq, Aeq]).tocsr(), np.r_[beq, beq]), x)
    assert _polish_glue(x, Aeq[:0], beq[:0]) is x
    bad = x.copy()
    bad[0] = np.nan
    assert _polish_glue(bad, Aeq, beq) is bad


def test_screening_guess_is_the_anchored_glue_only_minimiser(monkeypatch):
    P, q, Aeq, beq, _, _ = _random_qp(0)
    d = np.asarray(P @ np.ones(P.shape[0])).ravel()
    Pa = (P + sp.diags(depth_qp.ANCHOR * d)).tocsc()
    qa = q + depth_qp.ANCHOR * q
    ref = _equality_solution(Pa, qa, Aeq, beq)
    g = _screening_guess(P, q, Aeq, beq)
    assert np.abs(g - ref).max() <= 1e-9
    # the same without libigl's solver (the SuperLU fallback)
    import igl

    def broken(*a, **k):
        raise RuntimeError("factorisation failed")

    monkeypatch.setattr(igl, "min_quad_with_fixed", broken)
    assert np.abs(_screening_guess(P, q, Aeq, beq) - ref).max() <= 1e-9
    monkeypatch.setattr(igl, "min_quad_with_fixed", lambda *a, **k: np.full((P.shape[0], 1), np.nan))
    assert np.abs(_screening_guess(P, q, Aeq, beq) - ref).max() <= 1e-9
    monkeypatch.undo()
    # and libigl's path on its own: the SuperLU fallback is for a binding that fails, and must
    # not hide a broken call into libigl
    def no_fallback(*a, **k):
        raise AssertionError("the SuperLU fallback was used")

    monkeypatch.setattr(depth_qp.sla, "splu", no_fallback)
    assert np.abs(_screening_guess(P, q, Aeq, beq) - ref).max() <= 1e-9
    monkeypatch.undo()
    # with no glue rows: the anchored minimiser
    g0 = _screening_guess(P, q, Aeq[:0], beq[:0])
    assert np.abs(Pa @ g0 + qa).max() <= 1e-9


# --- the depth rows against brute-force geometry ---------------------------------------------


def _disk_sheet(layer, cx, cy, r, h, angle=0.0):
    """A sheet of a triangulated disk (Triangle, quality mesh)."""
    from sketchforge_assemble.sheet import sheet_from_mesh
    from sketchforge_inflate import inflate_stroke

    t = np.linspace(0, 2 * np.pi, 40, endpoint=False) + angle
    mesh = inflate_stroke(np.c_[cx + r * np.cos(t), cy + 0.8 * r * np.sin(t)], closed=True,
                          params={"resolution": h, "inflation": 1.0, "smoothing": 0.5})
    return sheet_from_mesh(layer, f"disk {layer}", mesh, free=True)


def _segment_crossings(xy_k, ek, xy_i, ei, eps=1e-9):
    """Every (edge of k, edge of i, s, t) whose segments cross properly: a + s(b-a) = c + t(d-c)."""
    a, b = xy_k[ek[:, 0]][:, None], xy_k[ek[:, 1]][:, None]
    c, d = xy_i[ei[:, 0]][None], xy_i[ei[:, 1]][None]
    r, sv, w = b - a, d - c, c - a
    den = r[..., 0] * sv[..., 1] - r[..., 1] * sv[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (w[..., 0] * sv[..., 1] - w[..., 1] * sv[..., 0]) / den
        t = (w[..., 0] * r[..., 1] - w[..., 1] * r[..., 0]) / den
    ok = (np.abs(den) > 1e-14) & (s > eps) & (s < 1 - eps) & (t > eps) & (t < 1 - eps)
    pk, pi = np.nonzero(ok)
    return pk, pi, s[ok], t[ok]


@pytest.mark.parametrize("dx, dy", [(0.3, 0.0), (0.0, 0.35), (-0.25, -0.3), (0.2, 0.45), (-0.55, 0.3)])
def test_crossing_rows_are_exactly_the_edge_crossings_in_the_overlap(dx, dy):
    # one row per pair of crossing edges, at the crossing point of both, requiring the front
    # sheet's back face to clear the back sheet's front face by the gap there
    si, sk = _disk_sheet(0, 0.0, 0.0, 0.5, 0.08), _disk_sheet(1, dx, dy, 0.4, 0.07, angle=0.3)
    sheets = [si, sk]
    region = si.polygon().intersection(sk.polygon())
    ek, ei = unique_edges(sk.F), unique_edges(si.F)
    rng = np.random.default_rng(1)
    back_k, front_i = rng.uniform(0, 0.1, sk.n), rng.uniform(0, 0.1, si.n)
    out = _Rows()
    _crossing_rows(out, sheets, {1: 0, 0: sk.n}, 1, 0, ek, ei, region, np.zeros(sk.n), np.zeros(si.n),
                   back_k, front_i, 0.05)
    A, b = out.matrix(sk.n + si.n)
    pk, pi, s, t = _segment_crossings(sk.xy, ek, si.xy, ei)
    p = sk.xy[ek[pk, 0]] * (1 - s)[:, None] + sk.xy[ek[pk, 1]] * s[:, None]
    inside = shapely.contains_xy(region.buffer(1e-9), p[:, 0], p[:, 1])
    assert inside.sum() > 20  # the two outlines overlap over many edges
    # every crossing in the overlap has its row (rows outside it, near its box, are harmless)
    want = {(int(ek[a].min()), int(ek[a].max()), int(ei[c].min()), int(ei[c].max())) for a, c in
            zip(pk[inside], pi[inside])}
    got = set()
    for r in range(A.shape[0]):
        row = A.getrow(r)
        cols, vals = row.indices, row.data
        kk, ii = cols[cols < sk.n], cols[cols >= sk.n] - sk.n
        got.add((int(kk.min()), int(kk.max()), int(ii.min()), int(ii.max())))
        # the row's two points are one point: Σ coef·xy = 0 over both sheets
        xy = np.vstack([sk.xy, si.xy])
        assert np.abs(vals @ xy[cols]).max() <= 1e-12
        assert abs(vals[vals > 0].sum() - 1.0) <= 1e-12 and abs(vals[vals < 0].sum() + 1.0) <= 1e-12
        # rhs: the gap plus both faces' offsets interpolated at the crossing
        off = np.r_[back_k, front_i]
        assert abs(b[r] - (0.05 + np.abs(vals) @ off[cols])) <= 1e-12
    assert want <= got
    assert len(got) == A.shape[0]  # no crossing twice
    assert out.pair[0][0].tolist() == [1, 0]


def test_crossing_rows_shrink_the_gap_to_zero_at_glued_vertices():
    si, sk = _disk_sheet(0, 0.0, 0.0, 0.5, 0.08), _disk_sheet(1, 0.3, 0.1, 0.4, 0.07, angle=0.3)
    region = si.polygon().intersection(sk.polygon())
    ek, ei = unique_edges(sk.F), unique_edges(si.F)
    zero_k, zero_i = np.zeros(sk.n), np.zeros(si.n)
    out = _Rows()
    _crossing_rows(out, [si, sk], {1: 0, 0: sk.n}, 1, 0, ek, ei, region, np.ones(sk.n), zero_i, zero_k, zero_i, 0.05)
    _, b = out.matrix(sk.n + si.n)
    assert len(b) and np.abs(b).max() <= 1e-15  # every vertex of k glued: no gap anywhere
    out = _Rows()
    _crossing_rows(out, [si, sk], {1: 0, 0: sk.n}, 1, 0, ek, ei, region, zero_k, np.ones(si.n), zero_k, zero_i, 0.05)
    _, b = out.matrix(sk.n + si.n)
    assert len(b) and np.abs(b).max() <= 1e-15


@pytest.mark.parametrize("sign", [1, -1])
def test_pair_rows_constrain_every_vertex_over_the_other_sheet_at_its_exact_point(sign):
    si, sk = _disk_sheet(0, 0.0, 0.0, 0.5, 0.08), _disk_sheet(1, 0.3, -0.2, 0.4, 0.07, angle=0.3)
    from sketchforge.geometry.locate import TriangleLocator

    rng = np.random.default_rng(2)
    off_k, off_i = rng.uniform(0, 0.1, sk.n), rng.uniform(0, 0.1, si.n)
    skip_k = (rng.random(sk.n) < 0.2).astype(float)
    skip_i = np.zeros(si.n)
    skip_i[si.boundary[:5]] = 1.0
    out = _Rows()
    _pair_rows(out, [si, sk], {0: 0, 1: si.n}, 1, 0, TriangleLocator(si.xy, si.F), si.F, skip_k, skip_i, off_k, off_i,
               0.05, sign)
    A, b = out.matrix(si.n + sk.n)
    inside = shapely.contains_xy(si.polygon().buffer(-1e-9), sk.xy[:, 0], sk.xy[:, 1])
    want = np.flatnonzero(inside & (skip_k == 0))
    A = A.tocsr()
    vert = np.array([A.indices[A.indptr[r]:A.indptr[r + 1]][A.indices[A.indptr[r]:A.indptr[r + 1]] >= si.n][0]
                     for r in range(A.shape[0])]) - si.n
    assert set(want.tolist()) <= set(vert.tolist()) <= set(np.flatnonzero(skip_k == 0).tolist())
    xy = np.vstack([si.xy, sk.xy])
    off = np.r_[off_i, off_k]
    for r in range(A.shape[0]):
        cols, vals = A.indices[A.indptr[r]:A.indptr[r + 1]], A.data[A.indptr[r]:A.indptr[r + 1]]
        assert np.abs(vals @ xy[cols]).max() <= 1e-9  # the vertex and the point below are one point
        assert abs(vals[cols >= si.n].sum() - sign) <= 1e-12 and abs(vals.sum()) <= 1e-12
        bary = np.abs(vals[cols < si.n])
        glued = bary @ skip_i[cols[cols < si.n]]
        assert abs(b[r] - (0.05 * (1 - glued) + np.abs(vals) @ off[cols])) <= 1e-12
    assert np.all(np.vstack(out.pair) == ([1, 0] if sign > 0 else [0, 1]))


@pytest.mark.parametrize("seed", SEEDS[:4])
def test_a_glue_only_optimum_that_clears_every_row_is_the_answer_with_no_iterative_solver(seed, monkeypatch):
    # issue 39: where no depth row is active at the optimum (every QP the benchmark captured),
    # the glue-only optimum is the exact answer; OSQP, 1e-4 accurate, ended 17 gaps from it
    P, q, Aeq, beq, Ain, bin_ = _random_qp(seed)
    x_eq = _equality_solution(P, q, Aeq, beq)
    loose = bin_ - (np.max(bin_ - Ain @ x_eq) + 0.5)  # every row now holds there, with room
    calls = []
    monkeypatch.setattr(depth_qp, "_osqp_screened", lambda *a: calls.append(a) or (_ for _ in ()).throw(AssertionError))
    x, info = solve_depth(P, q, Aeq, beq, Ain, loose, method="osqp", pad=0.01)
    assert calls == [] and info["exact"] and info["osqp_iterations"] == 0 and info["iterations"] == 0
    assert np.array_equal(x, x_eq) and info["active"] == 0
    exact, _ = solve_depth(P, q, Aeq, beq, Ain, loose, method="active_set")
    assert np.abs(x - exact).max() <= 1e-9
    # one row violated there: the iterative solvers take over, and the answer clears it
    monkeypatch.undo()
    tight = loose.copy()
    k = int(np.argmin(Ain @ x_eq - loose))
    tight[k] = (Ain @ x_eq)[k] + 0.05
    x2, info2 = solve_depth(P, q, Aeq, beq, Ain, tight, method="osqp", pad=0.01)
    assert "exact" not in info2 and info2["osqp_iterations"] > 0
    assert np.min(Ain @ x2 - tight) >= 0.0
