"""Solving one depth-order QP (:func:`solve_depth`): OSQP on a screened subset of the depth
rows, the glue rows' residual closed to round-off, and the dual active-set method of
:mod:`.active_set` where a row is still violated (measured comparison: :mod:`.depth`'s
docstring and ``benchmarks/bench_depth_qp.py``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from sketchforge.plugin_api import guard

from .active_set import MEMORY_BUDGET, _active_set


def solve_depth(P, q, Aeq, beq, Ain, bin_, method: str = "osqp", pad: float = 0.0, tol: float = 1e-10,
                max_iter: int | None = None, memory_budget: int = MEMORY_BUDGET):
    """Solve  min ½δᵀPδ + qᵀδ  s.t.  Aeq δ = beq,  Ain δ >= bin_.

    Parameters
    ----------
    P : (N, N) sparse, symmetric positive definite
    q : (N,) float64
    Aeq : (e, N) sparse, beq : (e,)
    Ain : (r, N) sparse, bin_ : (r,)
    method : {"osqp", "active_set"}
        "osqp" (default): OSQP to 1e-4 on the rows tightened by ``pad``, so that its residual
        still leaves every true row satisfied (measured on the creature: 1300 iterations,
        0.4 s, objective within 0.2% of a 1e-5 solve that needs 20000 iterations), given the
        rows near an anchored glue-only solution first (:func:`_osqp_screened`), its glue
        residual then closed to round-off (:func:`_polish_glue`); if some depth row is still
        violated, the dual active-set method (:func:`_active_set`) finishes from
        OSQP's active set; all that only when the glue-only optimum leaves some depth row
        violated (otherwise it is the exact answer, ``info["exact"]``: see the comment in the
        code). "active_set": the active-set method alone, from the equality rows.
    pad : float
        Extra clearance asked of OSQP (a fraction of the gap).
    tol : float
        Violation of a depth row that the active-set method accepts.
    max_iter : int, optional
        Safety net on the active-set steps (default: ten per row, at least 1000).
    memory_budget : int
        Bytes the active-set method may hold (default :data:`MEMORY_BUDGET`); OSQP is bounded
        by its 20000 iterations.

    Returns
    -------
    delta : (N,) float64
    info : dict
        ``osqp_iterations``, ``iterations`` (active-set steps, 0 if not needed), ``active``.

    Raises
    ------
    DepthOrderError
        The rows cannot all be satisfied, or the active-set method did not finish within
        ``max_iter`` steps or ``memory_budget`` bytes.
    GeometryError
        The problem has a NaN, an infinity outside the bounds or inconsistent shapes; checked
        before either solver runs, in the form that solver reads (:func:`guard.qp` for OSQP,
        :func:`guard.objective` and :func:`guard.constraints` for the active set alone).
    """
    what = "the depth-order problem"
    info = {"method": method, "osqp_iterations": 0, "iterations": 0}
    warm = np.zeros(0, np.int64)
    if method == "osqp":
        # OSQP takes the glue and depth rows as one matrix: the guard checks it in that form
        # (the active-set fallback below reads the same rows apart, as CSR).
        Ain, Aeq = sp.csr_matrix(Ain), sp.csr_matrix(Aeq)
        P, q, _, _, _ = guard.qp(P, q, sp.vstack([Aeq, Ain]).tocsc(), np.r_[beq, bin_ + pad],
                                 np.r_[beq, np.full(len(bin_), np.inf)], what)
        # The glue-only optimum first: where it satisfies every depth row, it is the QP's exact
        # optimum (no depth row is active) and no iterative solver is needed. Measured (issue 39,
        # benchmarks/bench_depth_qp.py, 10 QPs: the example creature, its 3-layer part, 8 seeded
        # random creatures): that held for all ten. OSQP at 1e-4 on the padded rows ended up to
        # 17 gaps from it on the creature (39 with polishing on, which is also slower); the
        # interior-point Clarabel and PIQP reach it within 1e-3 gap in 3x and 1.6x OSQP's time;
        # the active set alone exactly, in 6x. This solve costs about half an OSQP run (27 ms on
        # the creature, where OSQP took 57); where some row is active, OSQP and the active set
        # below take over as before.
        x = _equality_solution(P, q, Aeq, beq)
        if x is not None and (len(bin_) == 0 or np.min(Ain @ x - bin_) >= 0.0):
            info["exact"] = True
            info["active"] = int(np.sum(Ain @ x - bin_ <= pad + 1e-6)) if len(bin_) else 0
            return x, info
        x, y, osqp_info = _osqp_screened(P, q, Aeq, beq, Ain, bin_, pad)
        info.update(osqp_info)
        x = _polish_glue(x, Aeq, beq)
        if np.all(np.isfinite(x)) and (len(bin_) == 0 or np.min(Ain @ x - bin_) >= 0.0):
            info["active"] = int(np.sum(Ain @ x - bin_ <= pad + 1e-6)) if len(bin_) else 0
            return x, info
        if len(y) and np.all(np.isfinite(y)):
            # OSQP's multipliers of the rows >= are <= 0; strongest rows first
            warm = np.flatnonzero(y < -1e-9 * max(1.0, float(np.abs(y).max())))
            warm = warm[np.argsort(y[warm], kind="stable")]
    else:
        # The active-set method alone reads the glue and depth rows apart, row by row (CSR):
        # each kind is checked in that form, and nothing is stacked for OSQP.
        P, q = guard.objective(P, q, what)
        Aeq, beq, _ = guard.constraints(Aeq, beq, beq, P.shape[0], what, fmt="csr")
        Ain, bin_, _ = guard.constraints(Ain, bin_, None, P.shape[0], what, fmt="csr")
    if max_iter is None:
        max_iter = max(1000, 10 * (len(bin_) + len(beq)))
    x, it, active = _active_set(P, q, Aeq, beq, Ain, bin_, warm, tol, max_iter, memory_budget)
    info["iterations"] = it
    info["active"] = len(active)
    return x, info


#: Rows whose slack at the screening guess is below this many pads go to OSQP's first round
#: (see :func:`_osqp_screened`); 6 pads = 3 gaps.
SCREEN_PADS = 6.0
#: OSQP's absolute and relative tolerance (see :func:`solve_depth`).
EPS = 1e-4


#: Relative residual of the glue rows below which libigl's glue-only solution is taken.
GLUE_TOL = 1e-9

#: How much harder the screening guess pulls towards the rest depths (see :func:`_screening_guess`).
ANCHOR = 1000.0


def _screening_guess(P, q, Aeq, beq):
    """(N,) the glue-only solution with the pull towards the rest depths ``ANCHOR`` times
    stronger, or None (see :func:`_equality_solution`).

    Why. The plain glue-only solution lets every part swing through the layer it hangs from
    (the creature: 4 532 of 11 570 rows violated there, 72 gaps off the optimum), so nearly
    half the rows look relevant. Anchored, the parts stay near their rest stack and only the
    rows near the junctions come close (creature: 2 022 rows, 300 iterations in two rounds
    instead of 475 in one). Only a guess: which rows go in first and where OSQP starts, never
    the answer. The pull's weight is read off P: the energy's only term that does not vanish
    on a constant offset is the mass term (Laplacian and springs are differences), so
    P·1 = w·M·1, and q = -w·M·rest on those rows.
    """
    d = np.maximum(np.asarray(P @ np.ones(P.shape[0])).ravel(), 0.0)
    Pa = (P + sp.diags(ANCHOR * d)).tocsc()
    qa = q + ANCHOR * np.where(d > 0, q, 0.0)
    return _equality_solution(Pa, qa, Aeq, beq)


def _equality_solution(P, q, Aeq, beq):
    """(N,) minimiser of ½δᵀPδ + qᵀδ subject to the glue rows alone, or None when there is none
    (glue rows that contradict each other, no finite answer): then nothing is screened and the
    glue-only shortcut is not taken.

    libigl's min_quad_with_fixed first (Eigen's sparse factorisation of the KKT system): on the
    12-part drawn creature (15.6k vertices) 17-27 ms against 36-80 ms for SuperLU's LU of the
    same KKT matrix, same answer to 1e-13; SuperLU where the binding fails or gives a
    non-finite answer. P and q passed the guard in solve_depth (P symmetric positive definite
    plus a non-negative diagonal), the glue rows are two-term rows of finite entries: libigl
    only ever sees validated input.
    """
    N = P.shape[0]
    if len(beq):
        import igl

        try:
            x = np.asarray(igl.min_quad_with_fixed(sp.csc_matrix(P), np.asarray(q, np.float64)[:, None],
                                                   np.zeros(0, np.int64), np.zeros((0, 1)),
                                                   sp.csc_matrix(Aeq), np.asarray(beq, np.float64)[:, None],
                                                   True)).ravel()
        except (RuntimeError, ValueError, TypeError):  # failed factorisation, other binding: SuperLU
            x = None
        # libigl also takes glue rows that repeat one another (it finds the independent ones)
        # and then answers where SuperLU says "singular"; rows that contradict each other it
        # cannot meet, so its answer is taken only where every glue row holds.
        if (x is not None and x.shape == (N,) and np.all(np.isfinite(x))
                and np.max(np.abs(Aeq @ x - beq)) <= GLUE_TOL * (1.0 + np.max(np.abs(beq)))):
            return x
    try:
        if len(beq) == 0:
            return sla.splu(sp.csc_matrix(P), permc_spec="COLAMD").solve(-q)
        K = sp.bmat([[P, Aeq.T], [Aeq, None]], format="csc")
        x = sla.splu(K, permc_spec="COLAMD").solve(np.r_[-q, beq])[:N]
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        return None
    return x if np.all(np.isfinite(x)) else None


def _polish_glue(x, Aeq, beq):
    """(N,) x moved by the least amount (Euclidean) that makes every glue row hold to
    round-off: x - Aeqᵀ(Aeq Aeqᵀ)⁻¹(Aeq x - beq); x itself when there is nothing to do or the
    glue rows are dependent (the active set then judges them).

    Why. OSQP meets its rows only to its tolerance (1e-4, scaled): with the blended junction's
    lifted glue and springs the glue rows were left 1.3e-4 off on the creature (8e-8 with the
    plain sleeve). A glue row is one vertex of a part equal to a point of the face below, so
    its residual is a sub-micro step between what stitching then treats as one vertex: closing
    it exactly costs one tiny solve (e rows, two terms each, ~60 on the creature) where
    tightening OSQP would cost iterations on every row. The move is of the residual's size,
    far below the ``pad`` of clearance OSQP leaves on each depth row, and the caller still
    checks every depth row afterwards.
    """
    if len(beq) == 0 or not np.all(np.isfinite(x)):
        return x
    Aeq = sp.csr_matrix(Aeq)
    r = Aeq @ x - beq
    try:
        lam = sla.splu(sp.csc_matrix(Aeq @ Aeq.T), permc_spec="NATURAL").solve(r)
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        return x
    if not np.all(np.isfinite(lam)):
        return x
    return x - Aeq.T @ lam


def _osqp_screened(P, q, Aeq, beq, Ain, bin_, pad, rounds: int = 6):
    """OSQP on the rows that can matter, grown until every row holds.

    Why. Of the ~11k depth rows of the creature fewer than 200 are active at the optimum, and
    OSQP's cost per iteration (and, measured, its iteration count) grows with the rows it
    carries. The rows whose slack at an anchored glue-only solution (:func:`_screening_guess`)
    is below ``SCREEN_PADS`` pads go to the first round, from that solution; any other row that
    the round's answer leaves closer than that joins and OSQP runs again, warm-started. A
    solution of fewer rows that satisfies all of them solves the whole problem (the rows left
    out are inactive), so the answer is the same QP's, to OSQP's accuracy; the caller still
    checks every row. Without ``pad`` (no scale to screen with) every row goes in at once.

    Returns
    -------
    x : (N,) float64, y : (r,) float64
        OSQP's answer and its multipliers of the depth rows (0 on rows never given to it).
    info : dict
        ``osqp_iterations`` (all rounds), ``osqp_status``, ``osqp_rounds``, ``osqp_rows``.
    """
    import osqp

    r = len(bin_)
    x0 = _screening_guess(P, q, Aeq, beq) if pad > 0 and r else None
    if x0 is None:
        use = np.ones(r, bool)
    else:
        use = Ain @ x0 - bin_ < SCREEN_PADS * pad
    Pu = sp.triu(P).tocsc()
    y_all = np.zeros(r)
    y_eq = np.zeros(len(beq))
    info: dict[str, Any] = {"osqp_iterations": 0, "osqp_rounds": 0}
    x = x0
    for _ in range(rounds):
        rows = np.flatnonzero(use)
        A = sp.vstack([Aeq, Ain[rows]]).tocsc()
        solver = osqp.OSQP()
        solver.setup(P=Pu, q=q, A=A, l=np.r_[beq, bin_[rows] + pad], u=np.r_[beq, np.full(len(rows), np.inf)],
                     verbose=False, eps_abs=EPS, eps_rel=EPS, polishing=False, max_iter=20000,
                     adaptive_rho_interval=25)
        if x is not None:
            solver.warm_start(x=x, y=np.r_[y_eq, y_all[rows]])
        # a status other than "solved" is handled by the caller (feasibility check, then the active set)
        res = solver.solve(raise_error=False)
        info["osqp_iterations"] += int(res.info.iter)
        info["osqp_rounds"] += 1
        info["osqp_status"] = str(res.info.status)
        info["osqp_rows"] = int(len(rows))
        x = np.asarray(res.x)
        y = np.asarray(res.y)
        y_eq = y[:len(beq)]
        y_all = np.zeros(r)
        y_all[rows] = y[len(beq):]
        if not np.all(np.isfinite(x)) or r == 0:
            break
        grow = ~use & (Ain @ x - bin_ < SCREEN_PADS * pad)
        if not grow.any():
            break
        use |= grow
    return x, y_all, info
