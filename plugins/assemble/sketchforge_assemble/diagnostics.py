"""Checks of an assembled mesh: manifoldness, orientation, volume, components, Euler
characteristic, degenerate and intersecting triangles. Used by the tests and the benchmark."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

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


def candidate_pairs(V: np.ndarray, F: np.ndarray, among: np.ndarray | None = None) -> np.ndarray:
    """(k, 2) int64 triangle pairs ``i < j`` whose bounding boxes overlap (broad phase).

    Centroids go in KD-trees, one per size class (corner radius within a power of two), each
    class queried with the largest radii of the two classes: one long triangle (a rim bridge,
    a coarse layer) then widens only the queries of its own class, not every query. Pairs are
    kept if their centroids lie within the sum of their radii and their axis-aligned boxes
    overlap. With ``among`` (indices or (m,) bool), only pairs with at least one triangle in
    it.
    """
    T = V[F]
    cen = T.mean(axis=1)
    rad = np.linalg.norm(T - cen[:, None, :], axis=2).max(axis=1)
    if len(F) < 2:
        return np.zeros((0, 2), np.int64)
    scale = max(float(np.median(rad)), 1e-300)
    size = np.ceil(np.log2(np.maximum(rad / scale, 1.0))).astype(np.int64)
    classes = [np.flatnonzero(size == k) for k in np.unique(size)]
    trees = [cKDTree(cen[c]) for c in classes]
    if among is None:
        query = classes
    else:
        mask = np.zeros(len(F), bool)
        mask[among] = True
        query = [c[mask[c]] for c in classes]
    found = []
    for a, qa in enumerate(query):
        if len(qa) == 0:
            continue
        qtree = cKDTree(cen[qa]) if among is not None else trees[a]
        for b, cb in enumerate(classes):
            if among is None and b < a:
                continue
            m = qtree.sparse_distance_matrix(trees[b], float(rad[qa].max() + rad[cb].max()), output_type="ndarray")
            found.append(np.c_[qa[m["i"]], cb[m["j"]]])
    if not found:
        return np.zeros((0, 2), np.int64)
    pairs = np.vstack(found)
    # the exact tests before the de-duplication: far fewer pairs are left to sort
    d = np.linalg.norm(cen[pairs[:, 0]] - cen[pairs[:, 1]], axis=1)
    pairs = pairs[(d <= rad[pairs[:, 0]] + rad[pairs[:, 1]]) & (pairs[:, 0] != pairs[:, 1])]
    lo, hi = T.min(axis=1), T.max(axis=1)
    ok = np.all((lo[pairs[:, 0]] <= hi[pairs[:, 1]]) & (lo[pairs[:, 1]] <= hi[pairs[:, 0]]), axis=1)
    pairs = np.sort(pairs[ok], axis=1).astype(np.int64)
    key = np.unique(pairs[:, 0] * len(F) + pairs[:, 1])  # 1-D: far faster than unique rows
    return np.c_[key // len(F), key % len(F)]


def intersecting_pairs(V: np.ndarray, F: np.ndarray, face_group: np.ndarray | None = None,
                       chunk: int = 200_000, among: np.ndarray | None = None) -> np.ndarray:
    """Triangle pairs that intersect (narrow phase on the broad-phase candidates).

    Pairs that share a vertex are skipped (neighbours always touch there); coplanar overlaps
    are not counted. With ``face_group`` (m,), only pairs from different groups (e.g. layers)
    are tested; with ``among`` (indices or (m,) bool), only pairs with at least one triangle in
    it (e.g. the triangles an operation moved).

    Returns
    -------
    (k, 2) int64 triangle index pairs.
    """
    pairs = candidate_pairs(V, F, among)
    if face_group is not None and len(pairs):
        pairs = pairs[face_group[pairs[:, 0]] != face_group[pairs[:, 1]]]
    if len(pairs):
        A, B = F[pairs[:, 0]], F[pairs[:, 1]]
        share = (A[:, :, None] == B[:, None, :]).any(axis=(1, 2))
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
    return np.vstack(hits) if hits else np.zeros((0, 2), np.int64)


def dihedral_angles(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(e,) float64 bend angle in degrees across every interior edge of F (m, 3) over V (n, 3).

    0 where the two triangles are coplanar, 180 where the surface folds back onto itself (a
    sleeve ending in a wedge). Edges not shared by exactly two triangles are left out.
    """
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    D = directed_edges(F)
    tri = np.repeat(np.arange(len(F)), 3)
    key = np.sort(D, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    k = key[order]
    same = np.all(k[1:] == k[:-1], axis=1)
    first = np.flatnonzero(same)
    # an edge used by exactly two triangles: a run of length 2
    ok = np.ones(len(first), bool)
    ok &= (first + 2 >= len(k)) | ~np.r_[same, False][first + 1]
    ok &= (first == 0) | ~np.r_[False, same][first]
    a, b = tri[order[first[ok]]], tri[order[first[ok] + 1]]
    c = np.clip(np.einsum("ij,ij->i", n[a], n[b]), -1.0, 1.0)
    return np.degrees(np.arccos(c))
