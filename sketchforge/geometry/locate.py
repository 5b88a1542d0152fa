"""Point location in a planar triangulation and barycentric interpolation.

A uniform grid of triangle buckets: each triangle is listed in every grid cell its bounding box
touches, and a query point tests only the triangles of its cell. Cells are sized so that there
are about as many cells as triangles, which keeps buckets short on the quality meshes `triangle`
makes. All loops run over bucket slots (a few tens at most), never over points.
"""

from __future__ import annotations

import numpy as np

#: Barycentric slack: a point whose smallest barycentric coordinate is above -BARY_TOL counts as
#: inside, so points on shared edges and at vertices are always found despite rounding.
BARY_TOL = 1e-10


class TriangleLocator:
    """A reusable point-location structure for one triangulation.

    Build it once per mesh and call :meth:`locate` for many batches of points.

    Parameters
    ----------
    V2 : (n, 2) float64
        Vertex positions in the plane (extra columns are ignored).
    F : (m, 3) int64
        Triangles, either orientation.
    """

    def __init__(self, V2: np.ndarray, F: np.ndarray) -> None:
        V2 = np.asarray(V2, dtype=np.float64)[:, :2]
        F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
        m = len(F)
        self._m = m
        self._V2, self._F = V2, F
        self._vertex_face = None  # built on demand by locate(..., nearest=True)
        if m == 0:
            return
        tri = V2[F]  # (m, 3, 2)
        self._a = tri[:, 0]
        e1 = tri[:, 1] - tri[:, 0]
        e2 = tri[:, 2] - tri[:, 0]
        det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
        scale = np.maximum(np.einsum("ij,ij->i", e1, e1), np.einsum("ij,ij->i", e2, e2))
        # Degenerate (zero-area) triangles never claim a point.
        self._valid = np.abs(det) > 1e-14 * scale
        safe = np.where(self._valid, det, 1.0)
        # Rows of the inverse of [e1 e2] (columns), so (l1, l2) = inv @ (P - a).
        self._inv = np.empty((m, 2, 2))
        self._inv[:, 0, 0] = e2[:, 1] / safe
        self._inv[:, 0, 1] = -e2[:, 0] / safe
        self._inv[:, 1, 0] = -e1[:, 1] / safe
        self._inv[:, 1, 1] = e1[:, 0] / safe

        # Pairwise over the corners and column by column: numpy's reductions over a short
        # axis cost ~20 times these (the assembly builds ~13 locators of ~3k triangles).
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        lo, hi = np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)
        self._origin = np.array([lo[:, 0].min(), lo[:, 1].min()])
        ext = np.maximum(np.array([hi[:, 0].max(), hi[:, 1].max()]) - self._origin, 1e-300)
        h = np.sqrt(ext[0] * ext[1] / m)
        h = max(h, ext.max() / max(m, 1), 1e-300)
        self._h = h
        self._nx = int(min(np.ceil(ext[0] / h), 4 * m + 1)) or 1
        self._ny = int(min(np.ceil(ext[1] / h), 4 * m + 1)) or 1
        i0 = self._cell_xy(lo)
        i1 = self._cell_xy(hi)
        wx = i1[:, 0] - i0[:, 0] + 1
        wy = i1[:, 1] - i0[:, 1] + 1
        counts = wx * wy
        total = int(counts.sum())
        tri_id = np.repeat(np.arange(m), counts)
        local = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
        wxr = np.repeat(wx, counts)
        cx = np.repeat(i0[:, 0], counts) + local % wxr
        cy = np.repeat(i0[:, 1], counts) + local // wxr
        cell = cy * self._nx + cx
        order = np.argsort(cell, kind="stable")
        self._cell_tris = tri_id[order]
        self._cell_start = np.zeros(self._nx * self._ny + 1, dtype=np.int64)
        np.cumsum(np.bincount(cell, minlength=self._nx * self._ny), out=self._cell_start[1:])

    def _cell_xy(self, P: np.ndarray) -> np.ndarray:
        ij = np.floor((P - self._origin) / self._h).astype(np.int64)
        ij[:, 0] = np.clip(ij[:, 0], 0, self._nx - 1)
        ij[:, 1] = np.clip(ij[:, 1], 0, self._ny - 1)
        return ij

    def locate(self, P: np.ndarray, nearest: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Containing triangle and barycentric coordinates of each point.

        Parameters
        ----------
        P : (k, 2) float64
        nearest : bool
            If True, a finite point outside the mesh is snapped to it instead of reported as
            -1: it gets the candidate triangle of its grid cell that it is closest to being
            inside, with its barycentrics clipped to [0, 1] (a point of that triangle), or, in a
            cell without triangles, its nearest vertex. Callers that sample curves lying on the
            outline (where rounding puts half the samples just outside) use this.

        Returns
        -------
        face : (k,) int64
            Index of the containing triangle, -1 outside the mesh (or for a non-finite point).
            A point on a shared edge gets the triangle where it lies deepest.
        bary : (k, 3) float64
            Barycentric coordinates in that triangle (sum 1); zeros where face is -1.
        """
        P = np.asarray(P, dtype=np.float64).reshape(-1, 2)
        k = len(P)
        face = np.full(k, -1, dtype=np.int64)
        bary = np.zeros((k, 3))
        if k == 0 or self._m == 0:
            return face, bary
        finite = np.all(np.isfinite(P), axis=1)
        raw = np.floor((np.where(finite[:, None], P, 0.0) - self._origin) / self._h)
        in_grid = (
            finite
            & (raw[:, 0] >= -1) & (raw[:, 0] <= self._nx)
            & (raw[:, 1] >= -1) & (raw[:, 1] <= self._ny)
        )
        # Points just outside the grid (rounding at the bounding box) use the border cell.
        ij = self._cell_xy(np.where(in_grid[:, None], P, self._origin))
        cell = ij[:, 1] * self._nx + ij[:, 0]
        start = self._cell_start[cell]
        count = np.where(in_grid, self._cell_start[cell + 1] - start, 0)
        # Process points with the longest buckets first so the active set is always a prefix.
        order = np.argsort(-count, kind="stable")
        Ps, start_s, count_s = P[order], start[order], count[order]
        best = np.full(k, -np.inf)
        best_face = np.full(k, -1, dtype=np.int64)
        best_l = np.zeros((k, 2))
        for j in range(int(count_s.max(initial=0))):
            n_act = int(np.searchsorted(-count_s, -j, side="left"))
            t = self._cell_tris[start_s[:n_act] + j]
            d = Ps[:n_act] - self._a[t]
            inv = self._inv[t]
            l1 = inv[:, 0, 0] * d[:, 0] + inv[:, 0, 1] * d[:, 1]
            l2 = inv[:, 1, 0] * d[:, 0] + inv[:, 1, 1] * d[:, 1]
            mn = np.minimum(np.minimum(l1, l2), 1.0 - l1 - l2)
            mn = np.where(self._valid[t], mn, -np.inf)
            better = mn > best[:n_act]
            idx = np.nonzero(better)[0]
            best[idx] = mn[idx]
            best_face[idx] = t[idx]
            best_l[idx, 0] = l1[idx]
            best_l[idx, 1] = l2[idx]
        hit = best >= -BARY_TOL
        if nearest:
            hit = best > -np.inf
        sel = order[hit]
        face[sel] = best_face[hit]
        bary[sel, 0] = 1.0 - best_l[hit, 0] - best_l[hit, 1]
        bary[sel, 1] = best_l[hit, 0]
        bary[sel, 2] = best_l[hit, 1]
        if nearest:
            self._snap(P, finite, face, bary)
        return face, bary

    def _snap(self, P: np.ndarray, finite: np.ndarray, face: np.ndarray, bary: np.ndarray) -> None:
        """In place: clip outside barycentrics to the triangle; unlocated finite points take
        their nearest vertex (one-hot barycentrics in one of its triangles)."""
        out = (face >= 0) & (bary.min(axis=1, initial=0.0) < -BARY_TOL)
        if out.any():
            b = np.clip(bary[out], 0.0, None)
            bary[out] = b / b.sum(axis=1, keepdims=True)
        miss = np.nonzero((face < 0) & finite)[0]
        if len(miss) == 0:
            return
        from scipy.spatial import cKDTree

        if self._vertex_face is None:
            used = np.unique(self._F)
            vf = np.full((len(self._V2), 2), -1, dtype=np.int64)  # (face, corner) per vertex
            vf[self._F.ravel(), 0] = np.repeat(np.arange(self._m), 3)
            vf[self._F.ravel(), 1] = np.tile(np.arange(3), self._m)
            self._vertex_face = (cKDTree(self._V2[used]), used, vf)
        tree, used, vf = self._vertex_face
        _, i = tree.query(P[miss])
        v = used[i]
        face[miss] = vf[v, 0]
        bary[miss] = 0.0
        bary[miss, vf[v, 1]] = 1.0

    def interpolate(self, field: np.ndarray, P: np.ndarray, nearest: bool = True) -> np.ndarray:
        """Barycentric interpolation of a vertex field at points (locate + :func:`interpolate`).

        Parameters
        ----------
        field : (n,) or (n, d) float64
            Values at the vertices of this triangulation.
        P : (k, 2) float64
        nearest : bool
            As in :meth:`locate`; by default points outside take the value at the nearest
            point found there, so curves on the outline never produce NaN.

        Returns
        -------
        (k,) or (k, d) float64
            NaN only for non-finite points (or points outside with ``nearest=False``).
        """
        face, bary = self.locate(P, nearest=nearest)
        return interpolate(field, self._F, face, bary)


def locate(V2: np.ndarray, F: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Containing triangle and barycentric coordinates of many points.

    Builds a :class:`TriangleLocator` (a few ms for 10k vertices); keep one instead when the
    same mesh is queried repeatedly.

    Parameters
    ----------
    V2 : (n, 2) float64
        Vertex positions in the plane (extra columns are ignored).
    F : (m, 3) int64
    P : (k, 2) float64

    Returns
    -------
    face : (k,) int64
        -1 outside.
    bary : (k, 3) float64
        Zeros where face is -1.
    """
    return TriangleLocator(V2, F).locate(P)


def interpolate(field: np.ndarray, F: np.ndarray, face: np.ndarray, bary: np.ndarray) -> np.ndarray:
    """Barycentric interpolation of a vertex field at located points.

    Parameters
    ----------
    field : (n,) or (n, d) float64
        Values at vertices.
    F : (m, 3) int64
    face : (k,) int64
        From :func:`locate`; -1 outside.
    bary : (k, 3) float64

    Returns
    -------
    (k,) or (k, d) float64
        NaN where face is -1.
    """
    field = np.asarray(field, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    face = np.asarray(face, dtype=np.int64)
    bary = np.asarray(bary, dtype=np.float64)
    inside = face >= 0
    corners = field[F[np.where(inside, face, 0)]]  # (k, 3) or (k, 3, d)
    out = np.einsum("kj,kj...->k...", bary, corners)
    out[~inside] = np.nan
    return out
