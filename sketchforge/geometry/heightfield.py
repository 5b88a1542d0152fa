"""Normals of an inflated height field, recovered through w = z² (smooth up to the rim).

An inflated layer meets the drawing plane at a right angle: near its rim z ~ sqrt(distance),
so z's second derivatives are unbounded there, and normals averaged from z's own triangles
(area-weighted vertex normals) are noisy next to the rim: measured on the exact inflation of
an ellipse, up to 6° at the rim, which drew the highest isophotes near the lit rim as 2–5
ragged pieces each. w = z² behaves like the distance to the rim (for the inflation's Poisson
solution it is that solution, times inflation²), smooth up to the rim. Since ∇w = 2z∇z,

    n ∝ (−∇z, 1) ∝ (−∇w, 2z),

and the right-hand form stays well conditioned where z → 0: at the rim it is the in-plane
normal −∇w/|∇w| the true surface has. ∇w at a vertex is the area-weighted mean of the adjacent
faces' gradients of the piecewise-linear w (the same averaging as
:func:`sketchforge.geometry.intensity.gradient_operators`), so the slopes are

    p = (Gx w) / (2z),  q = (Gy w) / (2z),   w = z².

On that exact ellipse (default resolution) the normals' median error is 0.03° (0.06° for the
area-weighted ones) and the largest, at the rim, 0.6–1.7° (5.9–6.6°); the isophotes drawn
from them are as close to the exact ones as exact vertex normals draw them
(``benchmarks/bench_isophotes.py``).

A faired rim (the inflate plugin's smoothing) is not vertical: z ~ distance there, w ~
distance², and the w-form would stand its rim vertices up. Such a rim vertex's |∇w| is a
fraction (0.1–0.5) of its inner neighbours' (1.0 on an unfaired rim), so the rim vertices
blend from the w-form to the area-weighted normal by that ratio (:data:`RIM_VERTICAL`,
:data:`RIM_FAIRED`), and their first ring inside follows them.

One definition serves the display (:func:`layer_normals`, interpolated per pixel by
:mod:`gbuffer`) and the sculpt solver (:func:`slopes_from_heights`,
:class:`SlopeLinearisation`), so the isophotes drawn, the picked one, its band and the shading
the solver fits are the same field. Where the w-form does not apply — z < 0, or a flat layer —
the slopes are those of the area-weighted vertex normals, (Gx z, Gy z). Slopes are clamped
like :func:`sketchforge.geometry.normals.slopes` (n_z >= NZ_MIN), so a vertical rim vertex
gets a finite slope of magnitude 1 / NZ_MIN, its normal 0.6° off the drawing plane.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sketchforge.cache import LRUCache, array_key
from sketchforge.geometry.intensity import gradient_operators
from sketchforge.geometry.normals import NZ_MIN, normals_from_slopes, vertex_normals

#: A rim vertex is vertical (the w-form's in-plane normal) where |∇w| there is at least this
#: fraction of its inner neighbours' (w ~ distance: ratio 1.0 measured on unfaired layers at
#: any resolution), tilted (the z-form's one-sided slope) where it is at most RIM_FAIRED (w ~
#: distance²: a faired rim with a finite slope, ratio 0.1–0.5 measured at smoothing 0.5), and
#: a blend of the two normals in between, so neighbours along a rim never jump between them.
RIM_VERTICAL = 0.9
RIM_FAIRED = 0.6


def _field(Gx, Gy, z, nz_min):
    """(p, q, w_form, free) at every vertex from the heights z (n,) and the full operators.

    ``w_form`` marks the vertices whose slope is Gx z² / 2z (or, at a rim vertex, leans on
    the in-plane normal); ``free`` the ones whose slope is not clamped and follows its formula
    (the Jacobian's rows)."""
    z = np.asarray(z, dtype=np.float64)
    wz = np.column_stack([z * z, z])  # one product per operator for both fields
    gx, gy = Gx @ wz, Gy @ wz
    gwx, gwy, gzx, gzy = gx[:, 0], gy[:, 0], gx[:, 1], gy[:, 1]
    inner = z > 0
    # Rim vertices (z = 0 with w rising away from them): is the rim vertical there?
    a = np.hypot(gwx, gwy)
    rim = np.nonzero((z == 0) & (a > 0))[0]
    lam = np.zeros(len(z))
    wt_inner = np.ones(len(z))
    if len(rim):
        P = (abs(Gx[rim]) + abs(Gy[rim])).tocoo()  # the rim vertices' one-rings
        ok = inner[P.col]
        total = np.bincount(P.row[ok], a[P.col[ok]], len(rim))
        count = np.bincount(P.row[ok], None, len(rim))
        ratio = a[rim] / np.maximum(total / np.maximum(count, 1), 1e-300)
        # no neighbour above the plane (a flat or sunken spot): not a rim of a raised surface
        lam[rim] = np.where(count > 0, np.clip((ratio - RIM_FAIRED) / (RIM_VERTICAL - RIM_FAIRED), 0.0, 1.0), 0.0)
        # the first ring inside follows its rim vertices
        s_l = np.bincount(P.col[ok], lam[rim][P.row[ok]], len(z))
        s_c = np.bincount(P.col[ok], None, len(z))
        near = s_c > 0
        wt_inner[near] = s_l[near] / s_c[near]
    w_form = (inner & (wt_inner > 0)) | (lam > 0)
    # unit normals of both forms; the w-form's is in the plane at a rim vertex
    nw = np.column_stack([-gwx, -gwy, 2.0 * z])
    nz = np.column_stack([-gzx, -gzy, np.ones(len(z))])
    nw /= np.maximum(np.linalg.norm(nw, axis=1, keepdims=True), 1e-300)
    nz /= np.linalg.norm(nz, axis=1, keepdims=True)
    wt = np.where(inner, wt_inner, lam)
    n = wt[:, None] * nw + (1.0 - wt)[:, None] * nz
    norm = np.linalg.norm(n, axis=1)
    nzu = n[:, 2] / norm
    free = (nzu >= nz_min) & ((wt == 1.0) | (wt == 0.0))
    den = np.maximum(nzu, nz_min) * norm  # = n_z unclamped, else nz_min scaled back
    return -n[:, 0] / den, -n[:, 1] / den, w_form, free


def slopes_from_heights(Gx, Gy, z: np.ndarray, nz_min: float = NZ_MIN) -> tuple[np.ndarray, np.ndarray]:
    """Slopes p, q of a layer's surface at its vertices from the heights alone.

    Parameters
    ----------
    Gx, Gy : (n, n) scipy.sparse.csr_matrix float64
        :func:`sketchforge.geometry.intensity.gradient_operators` of the layer.
    z : (n,) float64
        Heights.
    nz_min : float
        Clamp of the normal's z component (see :func:`sketchforge.geometry.normals.slopes`).

    Returns
    -------
    p, q : (n,) float64
        Finite: (Gx z², Gy z²) / 2z where z > 0; at a rim vertex (z = 0) the clamped slope of
        the in-plane normal, the one-sided (Gx z, Gy z), or a blend (:data:`RIM_VERTICAL`);
        (Gx z, Gy z) where z < 0 or the layer is flat there.
    """
    p, q, _, _ = _field(Gx, Gy, z, nz_min)
    return p, q


class SlopeLinearisation:
    """The slopes at some vertices (``rows``) as functions of the heights at others (``cols``),
    linearised at any surface: what a Gauss–Newton height solve needs, step after step.

    Where the w-form holds and the slope is not clamped,
    ∂p_r/∂z_j = Gx[r, j] z_j / z_r − δ_rj p_r / z_r (and likewise q); where the z-form holds
    it is Gx[r, j]; a clamped slope does not change (0).

    Parameters
    ----------
    Gx, Gy : (n, n) sparse float64
        :func:`sketchforge.geometry.intensity.gradient_operators` of the layer.
    rows : (k,) int64, sorted
    cols : (u,) int64
    """

    def __init__(self, Gx, Gy, rows: np.ndarray, cols: np.ndarray, nz_min: float = NZ_MIN):
        self.rows = np.asarray(rows, dtype=np.int64)
        self.cols = np.asarray(cols, dtype=np.int64)
        self.nz_min = nz_min
        self._G = (sp.csr_matrix(Gx), sp.csr_matrix(Gy))
        # The heights at cols move; the operators' rows and columns there, stacked (p rows,
        # then q rows), and their transpose are fixed: built once, so a step costs a few
        # sparse products.
        self._Gc = sp.vstack([G[self.rows][:, self.cols] for G in self._G]).tocsr()
        self._GcT = self._Gc.T.tocsr()
        pos = np.minimum(np.searchsorted(self.rows, self.cols), len(self.rows) - 1)
        hit = self.rows[pos] == self.cols
        self._diag_row, self._diag_col = pos[hit], np.nonzero(hit)[0]

    def at(self, z: np.ndarray) -> Linearised:
        """The slopes (p, q at ``rows``, bit for bit :func:`slopes_from_heights` there) and
        their Jacobians at heights z (n,)."""
        z = np.asarray(z, dtype=np.float64)
        zr = z[self.rows]
        p, q, w_form, free = (a[self.rows] for a in _field(*self._G, z, self.nz_min))
        wf = w_form & free & (zr > 0)
        inv = np.divide(1.0, zr, out=np.zeros(len(zr)), where=wf)
        zm = (~w_form & free).astype(np.float64)
        return Linearised(self, p, q, inv, zm, z[self.cols])


class Linearised:
    """Slopes and their Jacobians at one surface (see :class:`SlopeLinearisation`).

    Attributes
    ----------
    p, q : (k,) float64
        The slopes at the rows.
    """

    def __init__(self, lin: SlopeLinearisation, p, q, inv, zm, zc):
        self._lin, self.p, self.q = lin, p, q
        self._inv, self._zm, self._zc = inv, zm, zc

    def _diag(self, v):
        """δ_rj (p, q)_r inv_r v_j stacked over the rows (2k,)."""
        k, lin = len(self.p), self._lin
        out = np.zeros(2 * k)
        r, c = lin._diag_row, lin._diag_col
        out[r] = (self.p * self._inv)[r] * v[c]
        out[k + r] = (self.q * self._inv)[r] * v[c]
        return out

    def apply(self, v: np.ndarray):
        """(Jp v, Jq v), each (k,), for a height change v (u,)."""
        k, Gc = len(self.p), self._lin._Gc
        out = np.tile(self._inv, 2) * (Gc @ (self._zc * v)) - self._diag(v)
        if self._zm.any():
            out += np.tile(self._zm, 2) * (Gc @ v)
        return out[:k], out[k:]

    def apply_t(self, yp: np.ndarray, yq: np.ndarray) -> np.ndarray:
        """Jpᵀ yp + Jqᵀ yq, (u,), for row values yp, yq (k,)."""
        lin = self._lin
        y = np.concatenate([yp, yq])
        out = self._zc * (lin._GcT @ (np.tile(self._inv, 2) * y))
        if self._zm.any():
            out += lin._GcT @ (np.tile(self._zm, 2) * y)
        r, c = lin._diag_row, lin._diag_col
        out[c] -= ((self.p * yp + self.q * yq) * self._inv)[r]
        return out

    def matrices(self):
        """(Jp, Jq): (k, u) scipy.sparse.csr_matrix float64."""
        lin, k = self._lin, len(self.p)
        coo = lin._Gc.tocoo()
        inv2, zm2 = np.tile(self._inv, 2), np.tile(self._zm, 2)
        data = coo.data * (inv2[coo.row] * self._zc[coo.col] + zm2[coo.row])
        r, c = lin._diag_row, lin._diag_col
        rr = np.r_[coo.row, r, k + r]
        cc = np.r_[coo.col, c, c]
        dd = np.r_[data, -(self.p * self._inv)[r], -(self.q * self._inv)[r]]
        J = sp.csr_matrix((dd, (rr, cc)), shape=(2 * k, len(lin.cols)))
        return J[:k], J[k:]


def layer_normals(mesh) -> np.ndarray:
    """Unit normals (n, 3) float64 at a mesh's vertices: the height-field normals of
    :func:`slopes_from_heights` for a layer (an open surface; vertex by vertex, so wherever
    z < 0 they are the area-weighted ones, as the sculpt solver sees them), the area-weighted
    vertex normals for a closed mesh (an assembled model, a posed one), shared across the
    rim pairs it carries by their weights (:attr:`sketchforge.geometry.mesh.AssembledMesh.rim_pairs`).

    The gradient operators are kept per planar mesh (an edit changes only heights)."""
    V = np.asarray(mesh.V, dtype=np.float64)
    F = np.asarray(mesh.F, dtype=np.int64)
    z = V[:, 2]
    if len(mesh.boundary) == 0 or len(F) == 0:
        return vertex_normals(V, F, getattr(mesh, "rim_pairs", None), getattr(mesh, "rim_weights", None))
    p, q = slopes_from_heights(*_operators(V[:, :2], F), z)
    return normals_from_slopes(p, q)


#: gradient_operators of the last few planar meshes (thread-safe: the canvas rasterises on a
#: worker thread).
_OPERATORS = LRUCache(16, name="gradient operators")


def _operators(V2: np.ndarray, F: np.ndarray):
    """gradient_operators(V2, F), kept for the last few planar meshes."""
    return _OPERATORS.get_or_make(array_key(V2, F), lambda: gradient_operators(V2, F))
