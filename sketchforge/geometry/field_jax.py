"""JAX-callable evaluation of a scalar/vector field on a layer and its gradient at (x, y).

The ODE right-hand sides of the isophote tool (thesis 4.3.3 and 4.5) need a field (E, or p and
q) and its gradient at arbitrary points, inside ``jax.jit``/``vmap``. Two lookups are offered:

``GridField`` (default for solvers)
    The per-vertex field is sampled (barycentrically, i.e. the piecewise-linear field) at the
    nodes of a uniform square grid of fixed size ``GRID_SIZE``, extended outside the layer by the
    nearest covered node, and interpolated with a cubic B-spline (C²). Adaptive solvers need a
    smooth right-hand side: with the C⁰ piecewise-linear field they miss their tolerance by
    50-200× (measured-facts.md). Sampling error is that of the linear interpolant (O(h²));
    analytic data sampled on the grid is reproduced to ~1e-8 (tests/test_field_jax.py).

``BucketField``
    Exact barycentric lookup of the piecewise-linear field with per-face gradients, through a
    uniform grid of triangle buckets (padded candidate lists). Agrees with numpy barycentric
    interpolation to round-off; kept for comparison and tests (its gradient jumps across edges,
    which forces adaptive solvers to tiny steps).

Grid sizes are fixed (``GRID_SIZE``) and the origin/spacing are traced arrays, so a layer of a
different size never triggers a recompile of a function that takes a ``GridField``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.ndimage as ndi

from sketchforge.geometry.intensity import face_gradient
from sketchforge.geometry.locate import TriangleLocator
from sketchforge.numerics import enable_x64

enable_x64()

import jax  # noqa: E402  (x64 must be switched on before JAX makes any array)
import jax.numpy as jnp  # noqa: E402

#: Nodes per side of every resampling grid. One size for all layers keeps one compiled
#: function per batch size; 256 gives a spacing below the edge length up to ~20k-vertex layers
#: of round shapes (the spacing is the layer's larger extent / ~245).
GRID_SIZE = 256

#: Empty nodes kept around the layer's bounding box, so B-spline supports (4 nodes) near the
#: outline stay inside the grid.
GRID_PAD = 5


@jax.tree_util.register_pytree_node_class
@dataclass(frozen=True)
class GridField:
    """A field sampled on a uniform grid, interpolated with a cubic B-spline.

    Attributes
    ----------
    coeffs : (G, G, k) float64
        B-spline coefficients (prefiltered node values), indexed ``[ix, iy, channel]``.
    origin : (2,) float64
        Position of node (0, 0).
    spacing : () float64
        Node spacing (same in x and y).
    """

    coeffs: jax.Array
    origin: jax.Array
    spacing: jax.Array

    def tree_flatten(self):
        return (self.coeffs, self.origin, self.spacing), None

    @classmethod
    def tree_unflatten(cls, aux, children):
        return cls(*children)

    def __call__(self, xy):
        """Value and gradient at one point.

        Parameters
        ----------
        xy : (2,) float64

        Returns
        -------
        value : (k,) float64
        grad : (k, 2) float64
            d/dx and d/dy of every channel.
        """
        return bspline_eval(self.coeffs, self.origin, self.spacing, xy)


def grid_spec(V2: np.ndarray, size: int = GRID_SIZE, pad: int = GRID_PAD) -> tuple[np.ndarray, float]:
    """Origin (2,) and spacing of the square grid covering the points' bounding box.

    Parameters
    ----------
    V2 : (n, 2) float64
    size, pad : int
        Nodes per side; empty nodes kept on each side.
    """
    lo, hi = V2.min(axis=0), V2.max(axis=0)
    spacing = float((hi - lo).max()) / (size - 1 - 2 * pad)
    centre = 0.5 * (lo + hi)
    origin = centre - 0.5 * spacing * (size - 1)
    return origin.astype(np.float64), spacing


def rasterize(V2: np.ndarray, F: np.ndarray, origin: np.ndarray, spacing: float, size: int = GRID_SIZE):
    """Which triangle covers each grid node, with barycentric coordinates.

    Parameters
    ----------
    V2 : (n, 2) float64
    F : (m, 3) int64
    origin : (2,) float64
    spacing : float
    size : int

    Returns
    -------
    face : (size, size) int64
        Covering triangle per node ``[ix, iy]``, -1 where none.
    bary : (size, size, 3) float64
        Barycentric coordinates in that triangle (0 where none).
    """
    P = (V2[F] - origin) / spacing  # (m, 3, 2) in grid units
    lo = np.ceil(P.min(axis=1) - 1e-9).astype(np.int64)
    hi = np.floor(P.max(axis=1) + 1e-9).astype(np.int64)
    lo = np.clip(lo, 0, size - 1)
    hi = np.clip(hi, 0, size - 1)
    span = hi - lo + 1
    kx, ky = int(max(span[:, 0].max(), 1)), int(max(span[:, 1].max(), 1))
    # Candidate nodes of every triangle's bounding box, as a padded (m, kx, ky) block: one
    # vectorised barycentric test instead of a Python loop over triangles.
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
    face[gx, gy] = fi
    bary[gx, gy] = np.stack([l0[fi, u, v], l1[fi, u, v], l2[fi, u, v]], axis=1)
    return face, bary


def resample(values: np.ndarray, F: np.ndarray, face: np.ndarray, bary: np.ndarray) -> np.ndarray:
    """Sample a per-vertex field at the grid nodes; extend it outside by the nearest covered node.

    Parameters
    ----------
    values : (n,) or (n, k) float64
    F : (m, 3) int64
    face, bary : from :func:`rasterize`

    Returns
    -------
    (G, G, k) float64
    """
    vals = np.asarray(values, np.float64)
    if vals.ndim == 1:
        vals = vals[:, None]
    covered = face >= 0
    f = np.where(covered, face, 0)
    out = np.einsum("ijc,ijck->ijk", bary, vals[F[f]])
    if not covered.all():
        # Constant extension outside the outline: the B-spline then stays bounded there, and
        # solvers stop at the rim margin anyway, two or more cells inside.
        _, (ii, jj) = ndi.distance_transform_edt(~covered, return_indices=True)
        out = out[ii, jj]
    return out


def bspline_coefficients(node_values: np.ndarray) -> np.ndarray:
    """Prefilter node values (G, G, k) so that the cubic B-spline interpolates them."""
    out = np.empty_like(node_values)
    for k in range(node_values.shape[2]):
        out[:, :, k] = ndi.spline_filter(node_values[:, :, k], order=3, mode="mirror")
    return out


def make_grid_field(
    V2: np.ndarray,
    F: np.ndarray,
    values: np.ndarray,
    size: int = GRID_SIZE,
    raster=None,
) -> GridField:
    """Build a :class:`GridField` of a per-vertex field.

    Parameters
    ----------
    V2 : (n, 2) float64
    F : (m, 3) int64
    values : (n,) or (n, k) float64
    size : int
    raster : (origin, spacing, face, bary) or None
        Reuse a rasterisation (see :func:`layer_raster`) across fields of one layer.
    """
    if raster is None:
        raster = layer_raster(V2, F, size)
    origin, spacing, face, bary = raster
    nodes = resample(values, F, face, bary)
    return grid_field_from_nodes(nodes, origin, spacing)


def grid_field_from_nodes(nodes: np.ndarray, origin: np.ndarray, spacing: float) -> GridField:
    """A :class:`GridField` interpolating node values (G, G, k)."""
    return GridField(
        jnp.asarray(bspline_coefficients(nodes)), jnp.asarray(origin, jnp.float64), jnp.asarray(spacing, jnp.float64)
    )


def layer_raster(V2: np.ndarray, F: np.ndarray, size: int = GRID_SIZE):
    """(origin, spacing, face, bary) of a layer's grid; see :func:`grid_spec`, :func:`rasterize`."""
    origin, spacing = grid_spec(V2, size)
    face, bary = rasterize(V2, F, origin, spacing, size)
    return origin, spacing, face, bary


def _bspline_weights(t):
    t2, t3 = t * t, t * t * t
    w = jnp.stack([(1 - t) ** 3 / 6, (3 * t3 - 6 * t2 + 4) / 6, (-3 * t3 + 3 * t2 + 3 * t + 1) / 6, t3 / 6])
    dw = jnp.stack([-0.5 * (1 - t) ** 2, 1.5 * t2 - 2 * t, -1.5 * t2 + t + 0.5, 0.5 * t2])
    return w, dw


def bspline_eval(coeffs, origin, spacing, xy):
    """Cubic B-spline value and gradient at one point (JAX; vmap it over points).

    Parameters
    ----------
    coeffs : (G, G, k) float64
    origin : (2,) float64
    spacing : () float64
    xy : (2,) float64

    Returns
    -------
    value : (k,) float64
    grad : (k, 2) float64
    """
    G = coeffs.shape[0]
    u = (xy - origin) / spacing
    # Clamp far-away points into the grid: the field there is the constant extension anyway.
    u = jnp.clip(u, 1.0, G - 3.0)
    i = jnp.floor(u)
    t = u - i
    i = i.astype(jnp.int32)
    wx, dwx = _bspline_weights(t[0])
    wy, dwy = _bspline_weights(t[1])
    ix = i[0] - 1 + jnp.arange(4)
    iy = i[1] - 1 + jnp.arange(4)
    C = coeffs[ix[:, None], iy[None, :]]  # (4, 4, k)
    val = jnp.einsum("a,b,abk->k", wx, wy, C)
    gx = jnp.einsum("a,b,abk->k", dwx, wy, C) / spacing
    gy = jnp.einsum("a,b,abk->k", wx, dwy, C) / spacing
    return val, jnp.stack([gx, gy], axis=1)


def bilinear_eval(nodes, origin, spacing, xy):
    """Bilinear value of node data (G, G, k) at one point (JAX); used for masks and distances."""
    G = nodes.shape[0]
    u = jnp.clip((xy - origin) / spacing, 0.0, G - 1.000001)
    i = jnp.floor(u)
    t = u - i
    i = i.astype(jnp.int32)
    c00 = nodes[i[0], i[1]]
    c10 = nodes[i[0] + 1, i[1]]
    c01 = nodes[i[0], i[1] + 1]
    c11 = nodes[i[0] + 1, i[1] + 1]
    return (c00 * (1 - t[0]) + c10 * t[0]) * (1 - t[1]) + (c01 * (1 - t[0]) + c11 * t[0]) * t[1]


# --- piecewise-linear lookup through triangle buckets ---------------------------------------


@jax.tree_util.register_pytree_node_class
@dataclass(frozen=True)
class BucketField:
    """Exact piecewise-linear field with per-face gradients, located through triangle buckets.

    Attributes
    ----------
    table : (Bx, By, c) int32
        Candidate triangles per bucket ``[bx, by]``, padded with 0 (``count`` says how many).
    count : (Bx, By) int32
    corners : (m, 3, 2) float64
        Triangle corner positions.
    values : (m, 3, k) float64
        Field at the triangle corners.
    grads : (m, k, 2) float64
        Per-face gradient of the linear field.
    origin : (2,) float64
    cell : () float64
        Bucket size.
    """

    table: jax.Array
    count: jax.Array
    corners: jax.Array
    values: jax.Array
    grads: jax.Array
    origin: jax.Array
    cell: jax.Array

    def tree_flatten(self):
        return (self.table, self.count, self.corners, self.values, self.grads, self.origin, self.cell), None

    @classmethod
    def tree_unflatten(cls, aux, children):
        return cls(*children)

    def __call__(self, xy):
        """Value (k,) and per-face gradient (k, 2) at one point; points outside every
        triangle use the candidate triangle they are closest to being inside."""
        last = jnp.array(self.table.shape[:2]) - 1
        b = jnp.clip(jnp.floor((xy - self.origin) / self.cell).astype(jnp.int32), 0, last)
        cand = self.table[b[0], b[1]]  # (c,)
        n = self.count[b[0], b[1]]
        P = self.corners[cand]  # (c, 3, 2)
        lam = _bary(P, xy)  # (c, 3)
        score = jnp.where(jnp.arange(cand.shape[0]) < n, lam.min(axis=1), -jnp.inf)
        k = jnp.argmax(score)
        f = cand[k]
        val = jnp.einsum("c,ck->k", lam[k], self.values[f])
        return val, self.grads[f]


def _bary(P, xy):
    a, b, c = P[:, 0], P[:, 1], P[:, 2]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    det = jnp.where(jnp.abs(det) < 1e-300, 1e-300, det)
    dx, dy = xy[0] - a[:, 0], xy[1] - a[:, 1]
    l1 = (dx * (c[:, 1] - a[:, 1]) - dy * (c[:, 0] - a[:, 0])) / det
    l2 = (dy * (b[:, 0] - a[:, 0]) - dx * (b[:, 1] - a[:, 1])) / det
    return jnp.stack([1 - l1 - l2, l1, l2], axis=1)


def face_gradients(V2: np.ndarray, F: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Per-face gradient (m, k, 2) of the piecewise-linear field ``values`` (n, k): the core's
    :func:`~sketchforge.geometry.intensity.face_gradient`, column by column."""
    return np.stack([face_gradient(V2, F, values[:, j]) for j in range(values.shape[1])], axis=1)


def make_bucket_field(
    V2: np.ndarray, F: np.ndarray, values: np.ndarray, locator: TriangleLocator | None = None
) -> BucketField:
    """Build a :class:`BucketField` of a per-vertex field (n,) or (n, k).

    The buckets are those of :class:`~sketchforge.geometry.locate.TriangleLocator` (pass one
    already built for this mesh to reuse it); candidate lists are padded to the largest bucket,
    so the shapes (and compiled functions) depend on the mesh.
    """
    V2 = np.asarray(V2, np.float64)[:, :2]
    F = np.asarray(F, np.int64)
    vals = np.asarray(values, np.float64)
    if vals.ndim == 1:
        vals = vals[:, None]
    bk = (locator if locator is not None else TriangleLocator(V2, F)).buckets
    counts = np.diff(bk.start)  # (nx*ny,), cell = cy * nx + cx
    c = int(max(counts.max(), 1))
    cell = np.repeat(np.arange(len(counts)), counts)
    slot = np.arange(len(bk.tris)) - bk.start[cell]
    table = np.zeros((len(counts), c), np.int32)
    table[cell, slot] = bk.tris
    # Cells are numbered row by row (y major); the table is indexed [bx, by].
    table = table.reshape(bk.ny, bk.nx, c).transpose(1, 0, 2)
    return BucketField(
        jnp.asarray(np.ascontiguousarray(table)),
        jnp.asarray(counts.reshape(bk.ny, bk.nx).T.astype(np.int32)),
        jnp.asarray(V2[F]),
        jnp.asarray(vals[F]),
        jnp.asarray(face_gradients(V2, F, vals)),
        jnp.asarray(bk.origin),
        jnp.asarray(bk.h),
    )


_EVAL_CHUNK = 2048


@jax.jit
def _eval_many(coeffs, origin, spacing, P):
    return jax.vmap(lambda x: bspline_eval(coeffs, origin, spacing, x))(P)


def eval_points(field: GridField, P: np.ndarray):
    """Evaluate a :class:`GridField` at many points (numpy in and out).

    Parameters
    ----------
    field : GridField
    P : (N, 2) float64

    Returns
    -------
    values : (N, k) float64
    grads : (N, k, 2) float64
    """
    P = np.asarray(P, np.float64).reshape(-1, 2)
    k = field.coeffs.shape[2]
    vals, grads = np.empty((len(P), k)), np.empty((len(P), k, 2))
    # Fixed chunk size: one compiled function per channel count, whatever N is.
    for s in range(0, len(P), _EVAL_CHUNK):
        blk = P[s : s + _EVAL_CHUNK]
        pad = np.zeros((_EVAL_CHUNK, 2))
        pad[: len(blk)] = blk
        pad[len(blk) :] = blk[0]
        v, g = _eval_many(field.coeffs, field.origin, field.spacing, jnp.asarray(pad))
        vals[s : s + len(blk)] = np.asarray(v)[: len(blk)]
        grads[s : s + len(blk)] = np.asarray(g)[: len(blk)]
    return vals, grads
