"""The dual active-set method (Goldfarb-Idnani) that finishes the depth-order QP where OSQP
leaves a row violated, or solves it alone (``qp_solver="active_set"``); see :mod:`.depth` for
how it works and what it costs, :func:`.depth_qp.solve_depth` for when it runs.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from scipy.linalg import cho_solve, cholesky, solve_triangular

from .errors import DepthOrderError

#: Memory the active-set method may hold (bytes): its cached columns P⁻¹cᵀ (8·N bytes per row
#: ever probed), the working-set buffer and the Schur factors. The creature needs ~20 MB; a
#: problem that would need more is not converging towards anything a person could use (a
#: planted sign error in the back glue once grew the assembly to 24 GB before the kernel killed
#: it), so it stops with a clear error instead.
MEMORY_BUDGET = 1 << 30


class _WorkingSet:
    """Working set of the active-set method in range-space form.

    P is factorised once; row c of the working set keeps z = P⁻¹cᵀ (computed once per row that
    ever enters, in ``cache``) and G = C P⁻¹ Cᵀ is held as its Cholesky factor L alone (G itself
    is never solved with), grown by one row and column per added row: the new pivot
    g_pp - |L⁻¹g|² is the squared distance (in the
    P⁻¹ metric) of the row from the span of the working set, so a row that is linearly
    dependent on the set shows up as a pivot at round-off level and is never added. The z of
    the rows in the set live in the columns ``slot`` of one buffer (a row that leaves frees its
    column, nothing is copied), so x = x0 + Z λ is one product over the buffer.
    """

    def __init__(self, lu, Aeq, Ain, x0, beq, bin_, budget=MEMORY_BUDGET):
        self.lu, self.Aeq, self.Ain = lu, Aeq, Ain
        self.budget = budget
        self.x0 = x0
        self.eq_cx0, self.in_cx0 = Aeq @ x0, Ain @ x0
        self.beq, self.bin_ = beq, bin_
        self.cache: dict[int, np.ndarray] = {}  # row key -> P⁻¹cᵀ; keys: depth row r >= 0, glue row i -> -1 - i
        self.keys: list[int] = []
        self.slot: list[int] = []
        self.free: list[int] = []
        self.Z = np.zeros((len(x0), 16))
        self.used = 0  # columns of Z ever used
        self.L = np.zeros((0, 0))

    @property
    def m(self):
        return len(self.keys)

    def check_budget(self, new_columns: int = 0, z_columns: int | None = None, m: int | None = None) -> None:
        """Refuse to grow past the memory budget (before allocating, so nothing is ever
        half-grown): cached and buffered columns of N floats, and the m×m factor L."""
        n = len(self.x0)
        z_columns = self.Z.shape[1] if z_columns is None else z_columns
        m = self.m if m is None else m
        need = 8 * n * (len(self.cache) + new_columns + z_columns) + 8 * m * m
        if need > self.budget:
            raise DepthOrderError(
                f"The depth-order solve stopped: it needed {need / 2**20:.0f} MB, over its budget of "
                f"{self.budget / 2**20:.0f} MB ({len(self.cache) + new_columns} rows in play); the layers are "
                "glued and stacked in a way it cannot resolve. Reorder or redraw the parts."
            )

    def row(self, key):
        A, r = (self.Ain, key) if key >= 0 else (self.Aeq, -1 - key)
        s, e = A.indptr[r], A.indptr[r + 1]
        return A.indices[s:e], A.data[s:e]

    def z(self, keys):
        """P⁻¹cᵀ of each row (one solve for all the missing ones)."""
        ins = [k for k in keys if k >= 0 and k not in self.cache]
        eqs = [-1 - k for k in keys if k < 0 and k not in self.cache]
        self.check_budget(new_columns=len(ins) + len(eqs))
        for A, rows, key in ((self.Ain, ins, lambda r: r), (self.Aeq, eqs, lambda i: -1 - i)):
            if rows:
                Zn = self.lu.solve(A[rows].T.toarray())
                for c, r in enumerate(rows):
                    self.cache[key(r)] = Zn[:, c]
        return [self.cache[k] for k in keys]

    def spread(self, v):
        """(m,) coefficients of the rows in the set -> (used,) coefficients of Z's columns."""
        out = np.zeros(self.used)
        out[self.slot] = v
        return out

    def probe(self, key):
        """For a row c not in the set: z = P⁻¹cᵀ, r = G⁻¹ C z, the pivot c z - (C z)ᵀ G⁻¹ (C z), c z,
        and l = L⁻¹ C z (to add the row)."""
        (zp,) = self.z([key])
        cols, vals = self.row(key)
        cz = float(vals @ zp[cols])
        if self.m == 0:
            return zp, np.zeros(0), cz, cz, np.zeros(0)
        g = vals @ self.Z[cols][:, self.slot]  # C P⁻¹ cᵀ (P symmetric)
        l = solve_triangular(self.L, g, lower=True, check_finite=False)
        r = solve_triangular(self.L, l, lower=True, trans="T", check_finite=False)
        return zp, r, cz - float(l @ l), cz, l

    def add(self, key, zp, l, piv):
        m = self.m
        full = not self.free and self.used == self.Z.shape[1]
        self.check_budget(z_columns=self.Z.shape[1] * (2 if full else 1), m=m + 1)
        if self.free:
            j = self.free.pop()
        else:
            if self.used == self.Z.shape[1]:
                self.Z = np.concatenate([self.Z, np.zeros_like(self.Z)], axis=1)
            j = self.used
            self.used += 1
        self.Z[:, j] = zp
        L = np.zeros((m + 1, m + 1))
        L[:m, :m] = self.L
        L[m, :m] = l
        L[m, m] = np.sqrt(piv)
        self.L = L
        self.keys.append(key)
        self.slot.append(j)

    def remove(self, j):
        """Drop the j-th row of the set. The factor keeps its leading block; only the trailing
        block is refactorised (L33 L33ᵀ + l l ᵀ, with l the dropped column below the diagonal)."""
        m = self.m
        self.free.append(self.slot.pop(j))
        del self.keys[j]
        keep = np.r_[0:j, j + 1:m]
        L = self.L[np.ix_(keep, keep)]
        if j < m - 1:
            l = self.L[j + 1:, j]
            T = self.L[j + 1:, j + 1:]
            L[j:, j:] = cholesky(T @ T.T + np.outer(l, l), lower=True, check_finite=False)
        self.L = L

    def minimiser(self):
        """x minimising the energy with every row of the set an equality, and its multipliers."""
        if self.m == 0:
            return self.x0.copy(), np.zeros(0)
        k = np.asarray(self.keys)
        # Each kind of row indexes only its own arrays: with no glue rows (or no depth rows)
        # the other array is empty, and np.where would index it anyway (IndexError).
        ins = k >= 0
        i, e = k[ins], -1 - k[~ins]
        rhs = np.empty(len(k))
        rhs[ins] = self.bin_[i] - self.in_cx0[i]
        rhs[~ins] = self.beq[e] - self.eq_cx0[e]
        lam = cho_solve((self.L, True), rhs, check_finite=False)
        return self.x0 + self.Z[:, :self.used] @ self.spread(lam), lam


def _active_set(P, q, Aeq, beq, Ain, bin_, warm, tol, max_iter, memory_budget=MEMORY_BUDGET):
    """Dual active-set method (Goldfarb & Idnani 1983) in range-space form.

    Why a dual method. A primal active-set method needs a feasible start, which is exactly what
    is missing when OSQP leaves a row violated. The dual method starts from any minimiser of
    the energy on a working set W of independent rows with multipliers >= 0 (the equality rows
    alone, or OSQP's active set cleaned up below) and keeps that true while it adds the most
    violated row p: it moves x along z = P⁻¹(c_pᵀ - Cᵀr) (r = G⁻¹ C P⁻¹ c_pᵀ), which keeps the
    rows of W tight, and lowers their multipliers by t·r while p's grows by t. The step is the
    smaller of the full step that makes p tight (then p joins W) and the partial step at which
    the first multiplier of W reaches 0 (that row leaves W and the step continues). A row p
    linearly dependent on W (Schur pivot at round-off level relative to c_p P⁻¹ c_pᵀ) is never
    added: only multipliers move (a pure dual step) until a row of W leaves; if none can leave,
    W already implies c_p x <= its current value and the rows are infeasible (up to round-off:
    a violation at round-off level is accepted). For a strictly convex QP the dual objective
    strictly increases, so no working set repeats and the method ends in finitely many steps,
    with no anti-cycling rule.

    Warm start. OSQP's active rows (strongest multiplier first) enter W while independent
    (pivot check); then the row with the most negative multiplier leaves, one at a time, until
    all are >= 0: a valid start for the dual method.

    Returns
    -------
    x : (N,) float64, steps : int, active : (a,) int64 depth rows in the final working set.
    """
    lu = sla.splu(sp.csc_matrix(P), permc_spec="COLAMD")
    x0 = lu.solve(-q)
    W = _WorkingSet(lu, Aeq, Ain, x0, beq, bin_, memory_budget)
    dep = 1e-10  # relative pivot below which a row counts as dependent on the working set
    scale = 1.0 + float(np.abs(bin_).max(initial=0.0)) + float(np.abs(beq).max(initial=0.0))

    def try_add(key):
        zp, _, piv, cz, l = W.probe(key)
        if piv > dep * cz:
            W.add(key, zp, l, piv)

    W.z([-1 - i for i in range(len(beq))] + [int(k) for k in warm])
    for i in range(len(beq)):
        try_add(-1 - i)
    n_eq = W.m
    for k in warm:
        try_add(int(k))
    x, lam = W.minimiser()
    while W.m > n_eq and lam[n_eq:].min() < 0.0:
        W.remove(n_eq + int(np.argmin(lam[n_eq:])))
        x, lam = W.minimiser()
    if len(beq) and np.max(np.abs(Aeq @ x - beq)) > 1e-8 * scale:
        raise DepthOrderError("The glue rows of the layers contradict each other.")

    in_set = np.zeros(len(bin_), bool)
    in_set[[k for k in W.keys if k >= 0]] = True
    skipped = np.zeros(len(bin_), bool)
    steps = 0
    while True:
        slack = Ain @ x - bin_ if len(bin_) else np.zeros(0)
        slack[in_set | skipped] = np.inf
        p = int(np.argmin(slack)) if len(slack) else -1
        if p < 0 or slack[p] >= -tol:
            break
        s_p = float(slack[p])
        while True:
            steps += 1
            if steps > max_iter:
                raise DepthOrderError("The depth-order solve did not converge; reorder or redraw the parts.")
            zp, r, piv, cz, l = W.probe(p)
            dependent = piv <= dep * cz
            # partial step: the first depth row of W whose multiplier reaches 0 (equality rows have
            # free multipliers)
            ri = r[n_eq:]
            pos = np.flatnonzero(ri > 1e-14 * max(1.0, float(np.abs(r).max(initial=0.0))))
            t1, k1 = np.inf, -1
            if len(pos):
                ratios = np.maximum(lam[n_eq:][pos], 0.0) / ri[pos]
                j = int(np.argmin(ratios))
                t1, k1 = float(ratios[j]), n_eq + int(pos[j])
            t2 = np.inf if dependent else -s_p / piv
            if not np.isfinite(t1) and not np.isfinite(t2):
                # W implies c_p x <= its value now: infeasible, unless the gap is round-off
                if s_p < -1e-9 * scale:
                    raise DepthOrderError(
                        "The depth order of the layers could not be satisfied (the layers are glued and "
                        "stacked in a way that leaves no room); reorder or redraw the parts."
                    )
                skipped[p] = True
                break
            t = min(t1, t2)
            lam = lam - t * r  # (p's own multiplier, t so far, is recomputed when p joins W)
            if not dependent:
                # x moves by t·P⁻¹(c_pᵀ - Cᵀr) here, but nothing reads it before the full step
                # recomputes it from W: p, independent of W, stays so as rows leave, so this
                # loop ends in a full step. Only p's slack is tracked.
                s_p += t * piv
            if t2 <= t1:  # full step: p joins W; x and λ afresh (no drift from the updates)
                W.add(p, zp, l, piv)
                in_set[p] = True
                x, lam = W.minimiser()
                lam[n_eq:] = np.maximum(lam[n_eq:], 0.0)
                break
            in_set[W.keys[k1]] = False  # partial step: the blocking row leaves, p is tried again
            lam = np.delete(lam, k1)
            W.remove(k1)
    if not np.all(np.isfinite(x)):
        raise DepthOrderError("The depth-order solve produced non-finite heights.")
    return x, steps, np.array([k for k in W.keys if k >= 0], np.int64)
