"""Point location in a 2D triangle mesh through a uniform grid of triangle buckets (numpy)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Locator:
    """Bucket grid over a mesh's triangles.

    Attributes
    ----------
    V2 : (n, 2) float64
    F : (m, 3) int64
    origin : (2,) float64
    cell : float
    nb : int
        Buckets per side.
    start, count : (nb*nb,) int64
        Slice of ``items`` per bucket.
    items : (t,) int64
        Triangle indices sorted by bucket.
    """

    V2: np.ndarray
    F: np.ndarray
    origin: np.ndarray
    cell: float
    nb: int
    start: np.ndarray
    count: np.ndarray
    items: np.ndarray

    @classmethod
    def build(cls, V2: np.ndarray, F: np.ndarray) -> "Locator":
        lo, hi = V2.min(axis=0), V2.max(axis=0)
        # About two triangles per bucket on average.
        nb = int(np.clip(np.sqrt(len(F) / 2.0), 4, 512))
        cell = float((hi - lo).max()) / nb * (1 + 1e-9)
        P = V2[F]
        blo = np.clip(np.floor((P.min(axis=1) - lo) / cell).astype(np.int64), 0, nb - 1)
        bhi = np.clip(np.floor((P.max(axis=1) - lo) / cell).astype(np.int64), 0, nb - 1)
        keys, tris = [], []
        for dx in range(int((bhi - blo)[:, 0].max()) + 1):
            for dy in range(int((bhi - blo)[:, 1].max()) + 1):
                ok = (blo[:, 0] + dx <= bhi[:, 0]) & (blo[:, 1] + dy <= bhi[:, 1])
                f = np.nonzero(ok)[0]
                keys.append((blo[f, 0] + dx) * nb + blo[f, 1] + dy)
                tris.append(f)
        keys, tris = np.concatenate(keys), np.concatenate(tris)
        order = np.lexsort((tris, keys))
        keys, tris = keys[order], tris[order]
        count = np.bincount(keys, minlength=nb * nb)
        start = np.concatenate([[0], np.cumsum(count)[:-1]])
        return cls(V2, F, lo, cell, nb, start, count, tris)

    def locate(self, P: np.ndarray):
        """Triangle and barycentric coordinates of points.

        Parameters
        ----------
        P : (k, 2) float64

        Returns
        -------
        face : (k,) int64
            Containing triangle; for a point outside the mesh, the candidate triangle it is
            closest to being inside (its barycentrics then have a negative entry).
        bary : (k, 3) float64
        inside : (k,) bool
        """
        P = np.asarray(P, np.float64).reshape(-1, 2)
        b = np.clip(np.floor((P - self.origin) / self.cell).astype(np.int64), 0, self.nb - 1)
        key = b[:, 0] * self.nb + b[:, 1]
        cnt = self.count[key]
        c = int(max(cnt.max(initial=0), 1))
        slot = np.arange(c)
        idx = self.start[key][:, None] + np.minimum(slot[None, :], np.maximum(cnt[:, None] - 1, 0))
        cand = self.items[np.minimum(idx, len(self.items) - 1)]  # (k, c)
        lam = barycentric(self.V2[self.F[cand]], P[:, None, :])  # (k, c, 3)
        score = np.where(slot[None, :] < cnt[:, None], lam.min(axis=2), -np.inf)
        best = np.argmax(score, axis=1)
        r = np.arange(len(P))
        face = cand[r, best]
        bary = lam[r, best]
        inside = score[r, best] >= -1e-9
        # Points in empty buckets (far outside): nearest vertex's first triangle.
        empty = cnt == 0
        if empty.any():
            face[empty] = 0
            bary[empty] = np.array([1.0, 0.0, 0.0])
            inside[empty] = False
        return face, bary, inside

    def interpolate(self, values: np.ndarray, P: np.ndarray) -> np.ndarray:
        """Piecewise-linear interpolation of per-vertex ``values`` (n,) or (n, k) at P (k, 2).
        Outside the mesh the barycentrics are clamped to the closest candidate triangle."""
        face, bary, inside = self.locate(P)
        bary = np.clip(bary, 0.0, None)
        bary /= bary.sum(axis=1, keepdims=True)
        vals = np.asarray(values)[self.F[face]]  # (k, 3[, c])
        if vals.ndim == 2:
            return np.einsum("kc,kc->k", bary, vals)
        return np.einsum("kc,kcj->kj", bary, vals)


def barycentric(T: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Barycentric coordinates (..., 3) of points P (..., 2) in triangles T (..., 3, 2)."""
    a, b, c = T[..., 0, :], T[..., 1, :], T[..., 2, :]
    det = (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (c[..., 0] - a[..., 0]) * (b[..., 1] - a[..., 1])
    det = np.where(np.abs(det) < 1e-300, 1e-300, det)
    dx, dy = P[..., 0] - a[..., 0], P[..., 1] - a[..., 1]
    l1 = (dx * (c[..., 1] - a[..., 1]) - dy * (c[..., 0] - a[..., 0])) / det
    l2 = (dy * (b[..., 0] - a[..., 0]) - dx * (b[..., 1] - a[..., 1])) / det
    return np.stack([1.0 - l1 - l2, l1, l2], axis=-1)
