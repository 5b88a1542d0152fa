"""Checks of an assembled mesh: manifoldness, orientation, volume, components, Euler
characteristic, degenerate and intersecting triangles. Used by the tests and the benchmark."""

from __future__ import annotations

import os

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .sheet import directed_edges, unique_edges


def edge_counts(F: np.ndarray):
    """Undirected edges of F (m, 3) and how many triangles use each.

    Returns
    -------
    edges : (e, 2) int64, sorted per row
    count : (e,) int64
    """
    return np.unique(np.sort(directed_edges(F), axis=1), axis=0, return_counts=True)


def is_consistently_oriented(F: np.ndarray) -> bool:
    """Every directed edge appears once and its reverse appears once."""
    D = directed_edges(F)
    n = int(F.max()) + 1
    key = D[:, 0] * n + D[:, 1]
    rkey = D[:, 1] * n + D[:, 0]
    if len(np.unique(key)) != len(key):
        return False
    return bool(np.all(np.isin(rkey, key)))


def signed_volume(V: np.ndarray, F: np.ndarray) -> float:
    """Volume enclosed by a closed mesh; positive when its triangles face outwards."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def components(F: np.ndarray, n: int | None = None) -> np.ndarray:
    """(n,) int64 component label of every vertex (by shared triangles)."""
    n = int(F.max()) + 1 if n is None else n
    r = F[:, [0, 1, 2]].ravel()
    c = F[:, [1, 2, 0]].ravel()
    A = sp.coo_matrix((np.ones(len(r)), (r, c)), shape=(n, n))
    return connected_components(A, directed=False)[1]


def euler_characteristics(F: np.ndarray) -> list[int]:
    """V - E + F of every connected component (by triangles)."""
    labels = components(F)
    out = []
    for c in np.unique(labels[F[:, 0]]):
        Fc = F[labels[F[:, 0]] == c]
        out.append(int(len(np.unique(Fc)) - len(unique_edges(Fc)) + len(Fc)))
    return out


def _orient(a, b, c, d):
    """Signed volume orient3d of row-wise points (k, 3)."""
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)


def _edge_crosses_triangle(p, q, a, b, c):
    """Row-wise: does segment pq cross triangle abc properly (coplanar cases count as no)?"""
    s1, s2 = _orient(a, b, c, p), _orient(a, b, c, q)
    straddle = s1 * s2 < 0
    o1 = _orient(p, q, a, b)
    o2 = _orient(p, q, b, c)
    o3 = _orient(p, q, c, a)
    inside = ((o1 > 0) & (o2 > 0) & (o3 > 0)) | ((o1 < 0) & (o2 < 0) & (o3 < 0))
    return straddle & inside


def box_pairs(lo: np.ndarray, hi: np.ndarray, among: np.ndarray | None = None, big: int = 64,
              ordered: bool = True) -> np.ndarray:
    """(k, 2) int64 sorted, unique index pairs ``i < j`` of boxes ``lo``/``hi`` (m, 3) that
    overlap (closed boxes), at least one of the two in ``among`` (indices or (m,) bool) if given.
    With ``ordered=False`` the same pairs, each once, in no particular order and either way
    round (the sort costs a fifth of the whole on the fairing's check, whose narrow phase
    keeps under 1% of the pairs: :func:`intersecting_pairs` sorts what it keeps instead).

    A uniform grid, all in numpy: cells twice the median box extent, every box entered in each
    cell it touches, pairs taken within each cell (each pair in one cell only: that of its
    overlap's low corner). A box touching more than ``big`` cells (a long rim bridge) is
    tested against every box directly. Why not KD-trees on the centroids, one per size class
    (as before): the faired zone of a blended model holds half of its triangles (creature:
    17k of 32k), and the trees' queries cost 0.28 s CPU there, the grid ~0.045 s (0.10 s before
    its gathers went column by column and the cells no asked-for box touches were dropped).
    """
    m = len(lo)
    if m < 2:
        return np.zeros((0, 2), np.int64)
    mask = np.ones(m, bool)
    if among is not None:
        mask = np.zeros(m, bool)
        mask[among] = True
    e = hi - lo
    ext = np.maximum(np.maximum(e[:, 0], e[:, 1]), e[:, 2])
    cell = 2.0 * float(np.median(ext))
    if not np.isfinite(cell) or cell <= 0.0:
        cell = float(ext.max(initial=0.0))  # most boxes are points (collapsed triangles)
    # Never so fine that the grid's indices overflow int64 (a cell of 1e-300 over a unit spread
    # cast 1e300 to int64: garbage keys decided the pairs): at most 2^20 cells a side, so a
    # cell's key (three axes) stays below 2^61.
    origin, top = _column_min(lo), _column_max(hi)
    span = float(np.max(top - origin, initial=0.0))
    cell = max(cell, span / 2.0**20, 1e-300)
    a = np.floor((lo - origin) / cell).astype(np.int64)
    b = np.floor((hi - origin) / cell).astype(np.int64)
    dims = _column_max(b) + 1
    r = b - a + 1
    count = r[:, 0] * r[:, 1] * r[:, 2]
    small = np.flatnonzero(count <= big)
    # Per-axis contiguous columns: gathers from them cost a third of gathers of (k, 3) rows.
    ax, ay, az = (np.ascontiguousarray(a[:, d]) for d in range(3))
    found = []
    if len(small):
        cs = count[small]
        idx = np.repeat(small, cs)
        j = np.arange(len(idx)) - np.repeat(np.cumsum(cs) - cs, cs)
        rx, ry = r[idx, 0], r[idx, 1]
        key = ((ax[idx] + j % rx) * dims[1] + ay[idx] + (j // rx) % ry) * dims[2] + az[idx] + j // (rx * ry)
        # Within a cell the boxes of ``among`` come first and each pairs with every box after
        # it; the others pair with nothing (a pair of two of them is not asked for, and a cell
        # no box of ``among`` touches gives none). One sort of one int64 key (the cell's key
        # is below 2^61, see above): a third of a two-key lexsort's time.
        order = np.argsort(2 * key + ~mask[idx], kind="stable")
        key, idx = key[order], idx[order]
        start = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
        end = np.r_[start[1:], len(key)]
        run_end = np.repeat(end, end - start)
        n_after = (run_end - np.arange(len(key)) - 1) * mask[idx]  # partners later in the same cell
        first = np.repeat(np.arange(len(key)), n_after)
        second = first + 1 + np.arange(len(first)) - np.repeat(np.cumsum(n_after) - n_after, n_after)
        i, k = idx[first], idx[second]
        ok = np.ones(len(i), bool)
        for d in range(3):
            lo_d, hi_d = np.ascontiguousarray(lo[:, d]), np.ascontiguousarray(hi[:, d])
            ok &= (lo_d[i] <= hi_d[k]) & (lo_d[k] <= hi_d[i])
        i, k, key = i[ok], k[ok], key[first[ok]]
        # Two boxes share every cell their overlap touches: the pair is kept only in the cell
        # of the overlap's low corner (floor is monotonic: the larger of the two low cells),
        # so it comes out once, with no de-duplication sort.
        low = (np.maximum(ax[i], ax[k]) * dims[1] + np.maximum(ay[i], ay[k])) * dims[2] + np.maximum(az[i], az[k])
        keep = low == key
        found.append(np.c_[i[keep], k[keep]])
    bigs = np.flatnonzero(count > big)
    is_big = np.zeros(m, bool)
    is_big[bigs] = True
    for i in bigs:  # few: each against every box, a pair of two big ones once
        others = np.flatnonzero(np.all((lo <= hi[i]) & (lo[i] <= hi), axis=1))
        others = others[(others != i) & (~is_big[others] | (others > i)) & (mask[i] | mask[others])]
        found.append(np.c_[np.full(len(others), i), others])
    pairs = np.vstack(found) if found else np.zeros((0, 2), np.int64)
    if not ordered:
        return pairs.astype(np.int64, copy=False)
    return _ordered(pairs)


def _column_min(X: np.ndarray) -> np.ndarray:
    """(d,) the least of each column of X (m, d), m >= 1: a reduction over the short axis
    of a (m, 3) array costs numpy 20 times one over each column (0.8 against 0.04 ms at 32k)."""
    return np.array([X[:, j].min() for j in range(X.shape[1])], X.dtype)


def _column_max(X: np.ndarray) -> np.ndarray:
    """(d,) the largest of each column of X (m, d), m >= 1 (see :func:`_column_min`)."""
    return np.array([X[:, j].max() for j in range(X.shape[1])], X.dtype)


def _ordered(pairs: np.ndarray) -> np.ndarray:
    """(k, 2) int64: the index pairs with each row ``i < j``, sorted by i then j."""
    pairs = np.sort(pairs, axis=1).astype(np.int64)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


#: Split the check of ``among`` triangles over two threads from this many on (see
#: :func:`intersecting_pairs`).
SPLIT_FROM = 4000
_POOL = None


def _pool():
    global _POOL
    if _POOL is None:
        from concurrent.futures import ThreadPoolExecutor

        _POOL = ThreadPoolExecutor(max_workers=2, thread_name_prefix="sketchforge-pairs")
    return _POOL


def _in_pool() -> bool:
    import threading

    return threading.current_thread().name.startswith("sketchforge-pairs")


def intersecting_pairs(V: np.ndarray, F: np.ndarray, face_group: np.ndarray | None = None,
                       chunk: int = 200_000, among: np.ndarray | None = None, split: bool = True) -> np.ndarray:
    """Triangle pairs that intersect (narrow phase on the broad-phase candidates).

    Pairs that share a vertex are skipped (neighbours always touch there); coplanar overlaps
    are not counted. With ``face_group`` (m,), only pairs from different groups (e.g. layers)
    are tested; with ``among`` (indices or (m,) bool), only pairs with at least one triangle in
    it (e.g. the triangles an operation moved). Broad phase: :func:`box_pairs`.

    With ``among`` of ``SPLIT_FROM`` triangles or more on a machine with two cores or more, its
    two halves (left and right of their median x) are checked in two threads and the answers
    merged: numpy lets go of the GIL in the long array operations, so the fairing's check of the
    creature takes 43 instead of 66 ms of wall time; the answer is the same array. It costs CPU
    (80 against 57 ms on the 16k-vertex creature: each half's broad phase sees the other's
    border), so ``split=False`` keeps it in one thread where CPU time is what counts.

    Returns
    -------
    (k, 2) int64 triangle index pairs, sorted by first then second index.
    """
    if among is not None:
        idx = np.flatnonzero(among) if np.asarray(among).dtype == bool else np.asarray(among, np.int64)
        # (never from one of the pool's own threads: waiting there for the pool could deadlock)
        if split and len(idx) >= SPLIT_FROM and (os.cpu_count() or 1) >= 2 and not _in_pool():
            x = V[F[idx]].mean(axis=1)[:, 0]
            order = idx[np.argsort(x, kind="stable")]
            half = len(order) // 2
            jobs = [_pool().submit(_intersecting_pairs, V, F, face_group, chunk, part)
                    for part in (order[:half], order[half:])]
            found = np.vstack([j.result() for j in jobs])
            return np.unique(found, axis=0) if len(found) else found  # a pair across the halves comes twice
    return _intersecting_pairs(V, F, face_group, chunk, among)


def _intersecting_pairs(V, F, face_group, chunk, among):
    """:func:`intersecting_pairs` in one thread."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    # The broad phase on float32 boxes rounded outwards (a superset of the float64 pairs; the
    # narrow phase below is exact): half the memory traffic, and steadier (median 32 against
    # 45 ms on the creature's fairing check). The corners' least and largest taken pairwise:
    # numpy's min over the middle axis of V[F] (m, 3, 3) took 2.7 ms, this 0.05.
    lo = np.nextafter(np.minimum(np.minimum(a, b), c).astype(np.float32), np.float32(-np.inf))
    hi = np.nextafter(np.maximum(np.maximum(a, b), c).astype(np.float32), np.float32(np.inf))
    pairs = box_pairs(lo, hi, among, ordered=False)
    if face_group is not None and len(pairs):
        pairs = pairs[face_group[pairs[:, 0]] != face_group[pairs[:, 1]]]
    if len(pairs):
        Fc = [np.ascontiguousarray(F[:, d]) for d in range(3)]
        A = [f[pairs[:, 0]] for f in Fc]
        B = [f[pairs[:, 1]] for f in Fc]
        share = np.zeros(len(pairs), bool)
        for x in A:
            for y in B:
                share |= x == y
        pairs = pairs[~share]
    hits = []
    for s in range(0, len(pairs), chunk):
        P = pairs[s:s + chunk]
        TA, TB = V[F[P[:, 0]]], V[F[P[:, 1]]]
        hit = np.zeros(len(P), bool)
        for X, Y in ((TA, TB), (TB, TA)):
            a, b, c = Y[:, 0], Y[:, 1], Y[:, 2]
            for e0, e1 in ((0, 1), (1, 2), (2, 0)):
                hit |= _edge_crosses_triangle(X[:, e0], X[:, e1], a, b, c)
        hits.append(P[hit])
    return _ordered(np.vstack(hits)) if hits else np.zeros((0, 2), np.int64)


def dihedral_angles(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(e,) float64 bend angle in degrees across every interior edge of F (m, 3) over V (n, 3).

    0 where the two triangles are coplanar, 180 where the surface folds back onto itself (a
    sleeve ending in a wedge). Edges not shared by exactly two triangles are left out.
    """
    from sketchforge.plugin_api import edge_angles, interior_edges

    _, fa, fb = interior_edges(F)
    return edge_angles(V, F, fa, fb)
