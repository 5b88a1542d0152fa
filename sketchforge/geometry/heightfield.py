"""Normals of an inflated height field, recovered through w = z² (smooth up to the rim).

An inflated layer meets the drawing plane at a right angle: near its rim z ~ sqrt(distance),
so z's second derivatives are unbounded there, and normals averaged from z's own triangles
(area-weighted vertex normals) are noisy next to the rim: measured on an exact ellipsoid,
up to 6° at the rim, which drew the highest isophotes near the lit rim as 2–5 ragged pieces
each. w = z² behaves like the distance to the rim (for the inflation's Poisson solution it is
that solution, times inflation²), smooth up to and across the rim. Since ∇w = 2z∇z,

    n ∝ (−∇z, 1) ∝ (−∇w, 2z),

and the right-hand form stays well conditioned where z → 0: at the rim it is the in-plane
normal −∇w/|∇w| the true surface has. ∇w at a vertex is the area-weighted mean of the adjacent
faces' gradients of the piecewise-linear w (the same averaging as
:func:`sketchforge.geometry.intensity.gradient_operators`), so the slopes are

    p = (Gx w) / (2z),  q = (Gy w) / (2z),   w = z²,

measured on the exact inflation of an ellipse (default resolution): median error 0.03° against
0.06°, largest (at the rim) 0.6–1.7° against 5.9–6.6° for the area-weighted normals. One definition serves the display
(:func:`layer_normals`, per-pixel interpolation in :mod:`gbuffer`) and the sculpt solver
(:func:`slopes_from_heights`, :class:`SlopeLinearisation`), so the isophotes drawn, the picked one,
its band and the shading the solver fits are the same field.

Where this does not apply — a vertex with z < 0, or one where both ∇w and z vanish (a flat
layer) — the slopes are those of the area-weighted vertex normals, (Gx z, Gy z). Slopes are
clamped like :func:`sketchforge.geometry.normals.slopes` (|n_z| >= NZ_MIN), so a rim vertex
gets a finite slope of magnitude 1 / NZ_MIN, its normal 0.6° off the drawing plane.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sketchforge.geometry.normals import NZ_MIN, _face_cross, normals_from_slopes, vertex_normals


def _slopes(gwx, gwy, gzx, gzy, z, nz_min):
    """(p, q, w_form, free) from the averaged gradients of w and of z at each vertex.

    ``w_form`` marks the vertices that use (−∇w, 2z); ``free`` the ones whose slope is not
    clamped (where the slope depends on z, for the Jacobian)."""
    w_form = (z > 0) | ((z == 0) & ((gwx != 0) | (gwy != 0)))
    nx = np.where(w_form, -gwx, -gzx)
    ny = np.where(w_form, -gwy, -gzy)
    nz = np.where(w_form, 2.0 * z, 1.0)
    norm = np.sqrt(nx * nx + ny * ny + nz * nz)
    nzu = nz / norm
    free = nzu >= nz_min
    den = np.maximum(nzu, nz_min) * norm  # = n_z unclamped, else nz_min scaled back
    return -nx / den, -ny / den, w_form, free


def slopes_from_heights(Gx, Gy, z: np.ndarray, nz_min: float = NZ_MIN) -> tuple[np.ndarray, np.ndarray]:
    """Slopes p, q of a layer's surface at its vertices from the heights alone.

    Parameters
    ----------
    Gx, Gy : (k, n) scipy.sparse matrices float64
        Rows of :func:`sketchforge.geometry.intensity.gradient_operators` (all n, or the k
        vertices wanted: the result is the same, row by row, bit for bit).
    z : (n,) float64
        Heights of every vertex.
    nz_min : float
        Clamp of the normal's z component (see :func:`sketchforge.geometry.normals.slopes`).

    Returns
    -------
    p, q : (k,) float64
        Finite; (Gx z², Gy z²) / 2z where z > 0, the in-plane normal's clamped slope at a rim
        vertex, (Gx z, Gy z) where z < 0 or the layer is flat there.
    """
    p, q, _, _ = _slopes_rows(Gx, Gy, z, _rows_of(Gx, z), nz_min)
    return p, q


def _rows_of(Gx, z) -> np.ndarray:
    """z at the rows of Gx when it has all n rows; otherwise the caller passes them."""
    if Gx.shape[0] != len(z):
        raise ValueError(
            f"pass z at the operators' {Gx.shape[0]} rows with slopes_at_rows, got {len(z)} heights"
        )
    return z


def _slopes_rows(Gx, Gy, z, z_rows, nz_min):
    z = np.asarray(z, dtype=np.float64)
    wz = np.column_stack([z * z, z])  # one product per operator for both fields
    gx, gy = Gx @ wz, Gy @ wz
    return _slopes(gx[:, 0], gy[:, 0], gx[:, 1], gy[:, 1], np.asarray(z_rows, dtype=np.float64), nz_min)


def slopes_at_rows(Gx_rows, Gy_rows, z: np.ndarray, rows: np.ndarray, nz_min: float = NZ_MIN):
    """:func:`slopes_from_heights` at some vertices only.

    Parameters
    ----------
    Gx_rows, Gy_rows : (k, n) sparse float64
        The operators' rows ``rows``.
    z : (n,) float64
    rows : (k,) int64

    Returns
    -------
    p, q : (k,) float64
        Equal, bit for bit, to ``slopes_from_heights(Gx, Gy, z)`` at ``rows``.
    """
    p, q, _, _ = _slopes_rows(Gx_rows, Gy_rows, z, np.asarray(z)[rows], nz_min)
    return p, q


class SlopeLinearisation:
    """The slopes at some vertices (``rows``) as functions of the heights at others (``cols``),
    linearised at any surface: what a Gauss–Newton height solve needs, step after step.

    Where the w-form holds and the slope is not clamped,
    ∂p_r/∂z_j = Gx[r, j] z_j / z_r − δ_rj p_r / z_r (and likewise q); where the z-form holds
    it is Gx[r, j]; a clamped slope does not change (0).

    Parameters
    ----------
    Gx_rows, Gy_rows : (k, n) sparse float64
        The rows ``rows`` of :func:`sketchforge.geometry.intensity.gradient_operators`.
    rows : (k,) int64, sorted
    cols : (u,) int64
    """

    def __init__(self, Gx_rows, Gy_rows, rows: np.ndarray, cols: np.ndarray, nz_min: float = NZ_MIN):
        self.rows = np.asarray(rows, dtype=np.int64)
        self.cols = np.asarray(cols, dtype=np.int64)
        self.nz_min = nz_min
        self._G = (sp.csr_matrix(Gx_rows), sp.csr_matrix(Gy_rows))
        # The heights at cols move; the operators' columns there, stacked (p rows, then q
        # rows), and their transpose are fixed: built once, so a step costs two sparse products.
        self._Gc = sp.vstack([G[:, self.cols] for G in self._G]).tocsr()
        self._GcT = self._Gc.T.tocsr()
        pos = np.minimum(np.searchsorted(self.rows, self.cols), len(self.rows) - 1)
        hit = self.rows[pos] == self.cols
        self._diag_row, self._diag_col = pos[hit], np.nonzero(hit)[0]

    def at(self, z: np.ndarray) -> "Linearised":
        """The slopes (p, q at ``rows``, bit for bit :func:`slopes_at_rows`) and their
        Jacobians at heights z (n,)."""
        z = np.asarray(z, dtype=np.float64)
        zr = z[self.rows]
        p, q, w_form, free = _slopes_rows(*self._G, z, zr, self.nz_min)
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
    :func:`slopes_from_heights` for a layer (an open surface, z >= 0), the area-weighted
    vertex normals for anything else (a closed assembled model, a posed or folded one).

    The area-weighted means of the face gradients of w and z are accumulated from face
    cross products like :func:`sketchforge.geometry.normals.vertex_normals` (no sparse
    operators: a few ms at 10k vertices); they equal the operators' products to rounding.
    """
    V = np.asarray(mesh.V, dtype=np.float64)
    F = np.asarray(mesh.F, dtype=np.int64)
    z = V[:, 2]
    if len(mesh.boundary) == 0 or len(F) == 0 or not (z >= 0).all():
        return vertex_normals(V, F)
    cw = _face_cross(np.column_stack([V[:, :2], z * z]), F)
    cz = _face_cross(V, F)
    # A face's cross product is 2A·(−∇f, 1) for f = w or z; planar areas are the same in both.
    acc = np.zeros((len(V), 5))
    for k in range(3):
        np.add.at(acc, F[:, k], np.column_stack([cw, cz[:, :2]]))
    area = acc[:, 2]
    ok = area > 0
    g = np.zeros((len(V), 4))
    g[ok] = -acc[ok][:, [0, 1, 3, 4]] / area[ok, None]
    p, q, _, _ = _slopes(g[:, 0], g[:, 1], g[:, 2], g[:, 3], z, NZ_MIN)
    return normals_from_slopes(p, q)
