"""The interior edges of a triangle mesh and the bend across them.

One pairing of each edge's two triangles for every measure of creases and folds: the assembly's
fairing and its diagnostics, the sculpt host's crease bounds and the strips solver's shape
limit each had their own (three sorts of the same (3m, 2) edge list).
"""

from __future__ import annotations

import numpy as np


def interior_edges(F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The edges of F (m, 3) int64 shared by exactly two triangles.

    Returns
    -------
    E : (e, 2) int64
        Each edge as (smaller vertex, larger vertex), in lexicographic order.
    fa, fb : (e,) int64
        Its two triangles (in no particular order: every use is symmetric in them). An edge of
        one triangle (a rim) or of three or more (not a manifold) is left out.
    """
    F = np.asarray(F, np.int64)
    D = F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    lo, hi = np.minimum(D[:, 0], D[:, 1]), np.maximum(D[:, 0], D[:, 1])
    n = int(F.max(initial=0)) + 1
    code = lo * n + hi
    # Not a stable sort: which of an edge's two triangles comes first does not matter, and
    # the default sort takes half the time of a stable one.
    order = np.argsort(code)
    c = code[order]
    start = np.flatnonzero(np.r_[True, c[1:] != c[:-1]])
    count = np.diff(np.r_[start, len(c)])
    two = start[count == 2]
    tri = np.repeat(np.arange(len(F)), 3)
    first = order[two]
    return np.column_stack([lo[first], hi[first]]), tri[first], tri[order[two + 1]]


def edge_angles(V: np.ndarray, F: np.ndarray, fa: np.ndarray, fb: np.ndarray) -> np.ndarray:
    """(k,) float64: the dihedral angle in degrees between triangles fa[i] and fb[i] (k,) of
    F (m, 3) over V (n, 3): 0 where they are coplanar, 180 where the surface folds back onto
    itself. A zero-area triangle has no normal: its angle to any other is 90."""

    def normals(f):
        a, b, c = V[F[f, 0]], V[F[f, 1]], V[F[f, 2]]
        nrm = np.cross(b - a, c - a)
        return nrm / np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)

    if len(fa) + len(fb) > len(F):  # most of the mesh: each face once, then looked up
        N = normals(np.arange(len(F)))
        na, nb = N[fa], N[fb]
    else:  # a few edges: per occurrence, cheaper than finding their unique faces first
        na, nb = normals(fa), normals(fb)
    cos = np.clip(np.einsum("ij,ij->i", na, nb), -1.0, 1.0)
    return np.degrees(np.arccos(cos))
