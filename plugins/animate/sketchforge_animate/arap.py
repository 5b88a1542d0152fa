"""As-rigid-as-possible deformation (Sorkine & Alexa 2007), spokes energy, point handles.

One sparse factorisation per handle set (:class:`ArapSolver`), then a few local/global
iterations per frame. The local step fits a rotation per vertex with the warm-started polar
iteration of Müller et al. 2016 ("A robust method to extract the rotational part of
deformations"): a handful of vectorised 3×3 operations instead of 16k SVDs (numpy's batched
SVD alone costs ~55 ms at 16k vertices on this machine kind). It always yields a proper
rotation, so no reflection fix-up is needed. Everything is float64 numpy/scipy/libigl with a
fixed iteration count, so a pose is a deterministic function of its inputs.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from sketchforge.plugin_api import ParameterError

#: Polar iterations per local step (warm-started from the previous rotations).
POLAR_ITERATIONS = 1


def edge_weights(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Undirected edges (i, j) with cotangent weights ½(cot α + cot β).

    V (n,3) float64, F (m,3) int64 -> i (e,) int64, j (e,) int64, w (e,) float64 > 0.
    Weights are clamped to [1e-3, 1e3] × their median: obtuse or sliver triangles of an
    assembled model (glued seams) would otherwise give negative or infinite weights and an
    indefinite system (libigl's own ARAP precomputation refuses the example creature).
    """
    cots = []
    for k in range(3):
        a, b, c = F[:, k], F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        u, v = V[b] - V[a], V[c] - V[a]
        cross = np.linalg.norm(np.cross(u, v), axis=1)
        dot = np.einsum("ij,ij->i", u, v)
        with np.errstate(divide="ignore", invalid="ignore"):
            cots.append((b, c, dot / cross))  # the angle at a faces the edge (b, c)
    i = np.concatenate([c[0] for c in cots])
    j = np.concatenate([c[1] for c in cots])
    w = 0.5 * np.concatenate([c[2] for c in cots])
    lo, hi = np.minimum(i, j), np.maximum(i, j)
    key = lo * (len(V) + 1) + hi
    uniq, inv = np.unique(key, return_inverse=True)
    w = np.where(np.isfinite(w), w, 0.0)
    wsum = np.bincount(inv, weights=w, minlength=len(uniq))
    med = float(np.median(np.abs(wsum))) or 1.0
    wsum = np.clip(wsum, 1e-3 * med, 1e3 * med)
    return uniq // (len(V) + 1), uniq % (len(V) + 1), wsum


def _quat_to_columns(q: np.ndarray) -> np.ndarray:
    """Unit quaternions q (4,n) (w, x, y, z) -> (3,3,n): [c] is column c of each rotation, (3,n)."""
    w, x, y, z = q
    xx, yy, zz, xy, xz, yz, wx, wy, wz = x * x, y * y, z * z, x * y, x * z, y * z, w * x, w * y, w * z
    R = np.empty((3, 3, q.shape[1]))
    R[0, 0], R[0, 1], R[0, 2] = 1 - 2 * (yy + zz), 2 * (xy + wz), 2 * (xz - wy)
    R[1, 0], R[1, 1], R[1, 2] = 2 * (xy - wz), 1 - 2 * (xx + zz), 2 * (yz + wx)
    R[2, 0], R[2, 1], R[2, 2] = 2 * (xz + wy), 2 * (yz - wx), 1 - 2 * (xx + yy)
    return R


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of (3,n) column stacks (np.cross on this layout is ~5x slower)."""
    out = np.empty_like(a)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


def polar_rotations(A_cols: list[np.ndarray], q: np.ndarray, iterations: int, R: np.ndarray | None = None) -> np.ndarray:
    """Rotations maximising tr(Rᵀ A) per vertex, warm-started at q.

    A_cols: the three columns of A, each (3,n) float64; q (4,n) unit quaternions -> (4,n).
    R: q's rotation columns (3,3,n) when the caller has them already.
    Structure-of-arrays on purpose: numpy's batched 3×3 matmul/SVD loop in C per matrix and
    cost ~10x more at 16k vertices.
    """
    for k in range(iterations):
        r = R if (k == 0 and R is not None) else _quat_to_columns(q)
        num = _cross(r[0], A_cols[0]) + _cross(r[1], A_cols[1]) + _cross(r[2], A_cols[2])
        den = np.abs((r[0] * A_cols[0]).sum(0) + (r[1] * A_cols[1]).sum(0) + (r[2] * A_cols[2]).sum(0)) + 1e-12
        omega = num / den
        ang = np.sqrt((omega * omega).sum(0))
        scale = np.sin(0.5 * ang) / np.where(ang > 1e-30, ang, 1.0)
        dw, dv = np.cos(0.5 * ang), omega * scale
        w, v = q[0], q[1:]
        # q <- dq ⊗ q
        nw = dw * w - (dv * v).sum(0)
        nv = dw * v + w * dv + _cross(dv, v)
        q = np.concatenate([nw[None], nv])
        q /= np.sqrt((q * q).sum(0))
    return q


def _tie_parts(V, i, j, w, handles):
    """Tie each connected part that has no pin to the nearest other part with extra spokes
    (one per vertex, median weight): a separate eye rides along with the head it sits on
    instead of floating still. Returns the extended (i, j, w)."""
    n = len(V)
    _, comp = connected_components(sp.csr_matrix((np.ones(len(i)), (i, j)), shape=(n, n)), directed=False)
    if comp.max() == 0:
        return i, j, w
    pinned = set(comp[handles].tolist())
    med = float(np.median(w))
    ei, ej = [i], [j]
    for c in range(comp.max() + 1):
        if c in pinned:
            continue
        inside = np.flatnonzero(comp == c)
        outside = np.flatnonzero(comp != c)
        _, nearest = cKDTree(V[outside]).query(V[inside])
        ei.append(inside)
        ej.append(outside[nearest])
    i2, j2 = np.concatenate(ei), np.concatenate(ej)
    w2 = np.concatenate([w, np.full(len(i2) - len(i), med)])
    return i2, j2, w2


class ArapSolver:
    """ARAP for one rest mesh and one set of handle vertices (one factorisation).

    Parameters
    ----------
    V : (n,3) float64 rest positions; F : (m,3) int64 triangles.
    handles : (k,) int64 distinct vertex indices, k >= 1.
    """

    def __init__(self, V: np.ndarray, F: np.ndarray, handles, solver: str = "llt") -> None:
        V = np.ascontiguousarray(V, dtype=np.float64)
        F = np.ascontiguousarray(F, dtype=np.int64)
        handles = np.asarray(handles, dtype=np.int64).reshape(-1)
        n = len(V)
        if V.ndim != 2 or V.shape[1] != 3 or F.ndim != 2 or F.shape[1] != 3 or len(F) == 0:
            raise ParameterError("ARAP needs vertices (n,3) and at least one triangle (m,3)")
        if not np.all(np.isfinite(V)):
            raise ParameterError("ARAP needs finite vertex positions")
        if F.min() < 0 or F.max() >= n:
            raise ParameterError("ARAP: a triangle refers to a vertex that does not exist")
        if len(handles) == 0:
            raise ParameterError("ARAP needs at least one pin")
        if handles.min() < 0 or handles.max() >= n or len(np.unique(handles)) != len(handles):
            raise ParameterError("ARAP: pins must be distinct vertices of the mesh")
        i, j, w = edge_weights(V, F)
        i, j, w = _tie_parts(V, i, j, w, handles)
        # A part still unconnected to any pin would make the system singular: it stays where
        # it is, held by an implicit anchor at its lowest-numbered vertex.
        _, comp = connected_components(sp.csr_matrix((np.ones(len(i)), (i, j)), shape=(n, n)), directed=False)
        pinned = np.zeros(comp.max() + 1, dtype=bool)
        pinned[comp[handles]] = True
        _, first = np.unique(comp, return_index=True)
        self.anchors = np.sort(first[~pinned]).astype(np.int64)
        self.V, self.F, self.handles = V, F, handles
        fixed = np.concatenate([handles, self.anchors])
        self._fixed = fixed
        # directed both ways: row i sums over the one-ring of i
        I, J, W = np.concatenate([i, j]), np.concatenate([j, i]), np.concatenate([w, w])
        L = sp.csr_matrix((np.concatenate([W, -W]), (np.concatenate([I, I]), np.concatenate([I, J]))), shape=(n, n))
        E = V[I] - V[J]  # rest spokes e_ij = p_i - p_j
        # K_b[i, j] = w_ij e_ij[b]: the spoke sums of the local and global steps as sparse products
        self._K = [sp.csr_matrix((W * E[:, b], (I, J)), shape=(n, n)) for b in range(3)]
        self._K = sp.vstack(self._K).tocsr()  # (3n, n): the three products in one call
        self._c = np.stack([np.bincount(I, weights=W * E[:, b], minlength=n) for b in range(3)])  # (3,n)
        # [K_0 K_1 K_2] (n, 3n): the global step's three products in one call
        self._Kh = sp.hstack([sp.csr_matrix((W * E[:, b], (I, J)), shape=(n, n)) for b in range(3)]).tocsr()
        free = np.setdiff1d(np.arange(n), fixed)
        self.free = free
        self._L_fb = L[free][:, fixed].tocsr()
        Lff = L[free][:, free].tocsc()
        # The system is symmetric positive definite. "llt": libigl's sparse Cholesky (Eigen,
        # AMD ordering) — its solve is ~2x faster than SuperLU's here; "splu": SuperLU in
        # symmetric mode. benchmarks/bench_animate.py measures both.
        self.solver = solver
        if solver == "llt":
            import igl

            self._mq = igl.min_quad_with_fixed_data()
            ok = igl.min_quad_with_fixed_precompute(
                Lff, np.zeros(0, dtype=np.int64), sp.csc_matrix((0, len(free))), True, self._mq
            )
            if ok is False:
                raise ParameterError("ARAP: the pinned system could not be factorised")
            self._empty = np.zeros((0, 3))
        elif solver == "splu":
            self._lu = sla.splu(Lff, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        else:
            raise ParameterError(f"unknown ARAP linear solver {solver!r} (llt or splu)")
        self._q = np.zeros((4, n))
        self._q[0] = 1.0
        self._r = None  # the rotation columns of _q, once computed

    def _linear_solve(self, b: np.ndarray) -> np.ndarray:
        """x (f,3) with L_ff x = b (f,3)."""
        if self.solver == "llt":
            import igl

            # min_quad_with_fixed minimises ½xᵀAx + xᵀB: A x = -B
            return igl.min_quad_with_fixed_solve(self._mq, -b, self._empty, self._empty)
        return self._lu.solve(b)

    def reset(self) -> None:
        """Forget the warm-start rotations (the next solve starts from the identity)."""
        self._q = np.zeros_like(self._q)
        self._q[0] = 1.0
        self._r = None

    def solve(self, targets: np.ndarray, init: np.ndarray, iterations: int) -> np.ndarray:
        """Positions (n,3) float64 with the handles at ``targets`` (k,3), after ``iterations``
        local/global steps from ``init`` (n,3). Rotations are warm-started from the previous
        call, so a sequence of solves is deterministic given its order."""
        targets = np.asarray(targets, dtype=np.float64).reshape(len(self.handles), 3)
        if not np.all(np.isfinite(targets)):
            raise ParameterError("pin targets must be finite")
        P = np.array(init, dtype=np.float64, copy=True)
        P[self.handles] = targets
        P[self.anchors] = self.V[self.anchors]
        rhs_fixed = self._L_fb @ P[self._fixed]
        n = len(P)
        for _ in range(iterations):
            # local: column b of A_i = Σ_j w_ij (p'_i - p'_j) e_ij[b] = p'_i c_i[b] - Σ_j w_ij e_ij[b] p'_j
            KP = self._K @ P
            PT = P.T
            A_cols = [PT * self._c[b] - KP[b * n:(b + 1) * n].T for b in range(3)]
            self._q = polar_rotations(A_cols, self._q, POLAR_ITERATIONS, self._r)
            r = self._r = _quat_to_columns(self._q)
            # global: L p' = Σ_j w_ij/2 (R_i + R_j) e_ij
            rhs = 0.5 * ((r[0] * self._c[0] + r[1] * self._c[1] + r[2] * self._c[2]).T + self._Kh @ r.transpose(0, 2, 1).reshape(-1, 3))
            P[self.free] = self._linear_solve(rhs[self.free] - rhs_fixed)
        return P
