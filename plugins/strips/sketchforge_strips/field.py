"""Per-vertex fields as smooth functions of (x, y) for the strips' right-hand side.

The strips read the characteristic direction (R_p, R_q) of the surface and a rim mask at
arbitrary points, inside ``jax.jit``/``vmap``. The layer's fields are
piecewise linear (one value per vertex); their gradients jump across every edge, which forces
an adaptive solver into tiny steps and makes it miss its tolerance by 50–200× (measured
facts). So each field is sampled at the nodes of a square grid (barycentrically: the
piecewise-linear field itself), extended outside the layer by the nearest covered node, and
interpolated by a cubic B-spline: C², error that of the linear interpolant (O(h²)).

The grid has a fixed number of nodes (:data:`GRID_SIZE`) and its origin and spacing are
traced arrays, so one compiled strip function serves every layer.
"""

from __future__ import annotations

import numpy as np
import scipy.ndimage as ndi

#: Nodes per side. 256 gives a spacing below the edge length up to ~20k-vertex layers of round
#: shapes (the spacing is the layer's larger extent / ~245).
GRID_SIZE = 256
#: Empty nodes kept around the layer's bounding box, so B-spline supports (4 nodes) near the
#: outline stay inside the grid.
GRID_PAD = 5


def grid_spec(V2: np.ndarray, size: int = GRID_SIZE, pad: int = GRID_PAD) -> tuple[np.ndarray, float]:
    """Origin (2,) and spacing of the square grid covering points V2 (n, 2)."""
    lo, hi = V2.min(axis=0), V2.max(axis=0)
    spacing = max(float((hi - lo).max()), 1e-12) / (size - 1 - 2 * pad)
    origin = 0.5 * (lo + hi) - 0.5 * spacing * (size - 1)
    return origin.astype(np.float64), spacing


def rasterize(V2: np.ndarray, F: np.ndarray, origin: np.ndarray, spacing: float, size: int = GRID_SIZE):
    """The triangle covering each grid node and its barycentric coordinates there.

    Returns
    -------
    face : (size, size) int64
        Covering triangle per node ``[ix, iy]``, -1 where none.
    bary : (size, size, 3) float64
    """
    P = (V2[F] - origin) / spacing  # (m, 3, 2) in grid units
    lo = np.clip(np.ceil(P.min(axis=1) - 1e-9).astype(np.int64), 0, size - 1)
    hi = np.clip(np.floor(P.max(axis=1) + 1e-9).astype(np.int64), 0, size - 1)
    span = hi - lo + 1
    kx, ky = int(max(span[:, 0].max(), 1)), int(max(span[:, 1].max(), 1))
    # Every triangle's bounding-box nodes as one padded (m, kx, ky) block: a vectorised
    # barycentric test instead of a loop over triangles.
    ix = lo[:, 0, None, None] + np.arange(kx)[None, :, None]
    iy = lo[:, 1, None, None] + np.arange(ky)[None, None, :]
    ix, iy = np.broadcast_arrays(ix, iy)
    valid = (ix <= hi[:, 0, None, None]) & (iy <= hi[:, 1, None, None])
    a, b, c = P[:, 0], P[:, 1], P[:, 2]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    det = np.where(np.abs(det) < 1e-300, 1e-300, det)[:, None, None]
    dx = ix - a[:, 0, None, None]
    dy = iy - a[:, 1, None, None]
    l1 = (dx * (c[:, 1, None, None] - a[:, 1, None, None]) - dy * (c[:, 0, None, None] - a[:, 0, None, None])) / det
    l2 = (dy * (b[:, 0, None, None] - a[:, 0, None, None]) - dx * (b[:, 1, None, None] - a[:, 1, None, None])) / det
    l0 = 1.0 - l1 - l2
    inside = valid & (l0 >= -1e-10) & (l1 >= -1e-10) & (l2 >= -1e-10)
    fi, u, v = np.nonzero(inside)
    face = np.full((size, size), -1, np.int64)
    bary = np.zeros((size, size, 3))
    gx, gy = ix[fi, u, v], iy[fi, u, v]
    # A node on a shared edge is covered by two triangles: the later one wins, the same value.
    face[gx, gy] = fi
    bary[gx, gy] = np.stack([l0[fi, u, v], l1[fi, u, v], l2[fi, u, v]], axis=1)
    return face, bary


class Raster:
    """A layer's grid: where its triangles cover the nodes (reused by every field of a layer).

    Attributes
    ----------
    origin : (2,) float64
    spacing : float
    face : (G, G) int64
    bary : (G, G, 3) float64
    F : (m, 3) int64
    """

    def __init__(self, V2: np.ndarray, F: np.ndarray, size: int = GRID_SIZE) -> None:
        self.origin, self.spacing = grid_spec(V2, size)
        self.F = np.asarray(F, np.int64)
        self.face, self.bary = rasterize(V2, self.F, self.origin, self.spacing, size)
        covered = self.face >= 0
        # Outside the layer every node takes its nearest covered node's value: the spline then
        # stays bounded there, and the strips stop at the rim margin anyway.
        if covered.all() or not covered.any():
            self._nearest = None
        else:
            _, self._nearest = ndi.distance_transform_edt(~covered, return_indices=True)

    def node_values(self, values: np.ndarray) -> np.ndarray:
        """A per-vertex field (n,) or (n, k) sampled at the nodes: (G, G, k) float64."""
        vals = np.asarray(values, np.float64)
        if vals.ndim == 1:
            vals = vals[:, None]
        f = np.where(self.face >= 0, self.face, 0)
        out = np.einsum("ijc,ijck->ijk", self.bary, vals[self.F[f]])
        if self._nearest is not None:
            ii, jj = self._nearest
            out = out[ii, jj]
        return out

    def coefficients(self, values: np.ndarray) -> np.ndarray:
        """Cubic B-spline coefficients (G, G, k) interpolating :meth:`node_values`."""
        nodes = self.node_values(values)
        out = np.empty_like(nodes)
        for k in range(nodes.shape[2]):
            out[:, :, k] = ndi.spline_filter(nodes[:, :, k], order=3, mode="mirror")
        return out


def bspline_eval(coeffs, origin, spacing, xy):
    """Value (k,) of the cubic B-spline with coefficients (G, G, k) at one point xy (2,), in
    ``jax.numpy`` (vmap it over points). Points beyond the grid read its border."""
    import jax.numpy as jnp

    G = coeffs.shape[0]
    u = jnp.clip((xy - origin) / spacing, 1.0, G - 3.0)
    i = jnp.floor(u)
    t = u - i
    i = i.astype(jnp.int32)

    def weights(s):
        s2, s3 = s * s, s * s * s
        return jnp.stack([(1 - s) ** 3 / 6, (3 * s3 - 6 * s2 + 4) / 6, (-3 * s3 + 3 * s2 + 3 * s + 1) / 6, s3 / 6])

    wx, wy = weights(t[0]), weights(t[1])
    ix = i[0] - 1 + jnp.arange(4)
    iy = i[1] - 1 + jnp.arange(4)
    C = coeffs[ix[:, None], iy[None, :]]  # (4, 4, k)
    return jnp.einsum("a,b,abk->k", wx, wy, C)
