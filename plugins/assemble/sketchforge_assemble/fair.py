"""Junction fairing (issue 12): the rings around every glued junction of the assembled mesh
smoothed by a bi-Laplacian with everything farther away fixed.

Why after the fillet. The fillet of :mod:`.blend` opens the U-turn under a part into a
crevice with a vertical strip, but it is built from per-vertex height offsets along the
distance to the junction, so where two of them meet (the junction's two ends, the strip's
top and bottom) the surface still bends by up to ~150 degrees over one edge. Minimising the
squared Laplacian of the positions in a few rings around the seam spreads each of those
bends over the rings (a bi-Laplacian surface is as smooth as its fixed surroundings allow),
while the surface beyond them keeps every vertex as the depth solve placed it.

Why not on the plain sleeve. Without the fillet the part's back face lies a margin above the
host, so the faired U-turn has to turn 180 degrees within that margin and the result crosses
itself; :func:`fair_seams` is only used with the fillet (see :mod:`.assemble`).

The uniform ("umbrella") Laplacian, not the cotangent one: the strip and the slit's ends have
needle triangles whose cotangent weights are huge or negative, and a graph operator keeps the
system positive definite whatever the triangles look like. It also moves vertices along the
surface, which evens out the needles the fillet leaves.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import shapely
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import splu

from .diagnostics import intersecting_pairs
from .sheet import directed_edges


def adjacency(F: np.ndarray, n: int) -> sp.csr_matrix:
    """(n, n) vertex adjacency of the triangles F (m, 3): 1 where an edge joins two vertices.

    From the directed half-edges, both ways, so no sort of the edge list is needed (np.unique
    over rows costs more than the whole fairing)."""
    D = directed_edges(F)
    A = sp.coo_matrix((np.ones(2 * len(D)), (np.r_[D[:, 0], D[:, 1]], np.r_[D[:, 1], D[:, 0]])), shape=(n, n)).tocsr()
    A.data[:] = 1.0
    return A


def ring_region(A: sp.csr_matrix, seed: np.ndarray, rings: int) -> np.ndarray:
    """(n,) bool: the vertices at most ``rings`` edges away from ``seed`` (k,) int64 over the
    vertex adjacency A (n, n) (see :func:`adjacency`)."""
    region = np.zeros(A.shape[0], bool)
    region[seed] = True
    for _ in range(rings):
        region |= (A @ region.astype(np.float64)) > 0
    return region


def seam_zone(F: np.ndarray, n: int, seam: np.ndarray, rings: int):
    """The vertices :func:`fair_seams` may move: those at most ``rings`` edges from ``seam``
    (k,) int64 over the triangles F (m, 3) of n vertices.

    Returns
    -------
    A : (n, n) csr_matrix
        The vertex adjacency (:func:`adjacency`), for :func:`fair_seams`.
    zone : (n,) bool
    """
    A = adjacency(F, n)
    return A, ring_region(A, np.asarray(seam, np.int64), rings)


def supports(V: np.ndarray, F: np.ndarray, face_layer: np.ndarray, face_kind: np.ndarray, part: int,
             footprint, zone: np.ndarray) -> np.ndarray:
    """(n,) bool: the vertices within ``zone`` of the faces a free part rests on.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    face_layer, face_kind : (m,) int64, int8
        As :func:`.stitch.build_mesh` gives them (kind 0 front, 1 back).
    part : int
        The free part's layer.
    footprint : shapely geometry
        Where in the drawing plane it may rest on something (its outline, a little widened).
    zone : (n,) bool
        The vertices that would move (:func:`seam_zone`); only these are looked at.

    Every layer is a height field with its front face above its back face, so below the part
    only a front face can hold it and, of those, the one nearest to it in z (the median gap
    over the footprint); above it, the nearest back face (a part settled behind a layer).
    """
    from scipy.spatial import cKDTree

    out = np.zeros(len(V), bool)
    cand = np.flatnonzero(zone)
    cand = cand[shapely.contains_xy(footprint, V[cand, 0], V[cand, 1])]
    own = np.unique(F[face_layer == part])
    if len(cand) == 0 or len(own) == 0:
        return out
    mark = np.zeros(len(V), bool)
    mark[cand] = True
    near = np.flatnonzero(mark[F].any(axis=1))  # the faces with a candidate vertex
    tree = cKDTree(V[own, :2])
    for kind, sign in ((0, 1.0), (1, -1.0)):
        best, best_gap = None, np.inf
        mine = near[face_kind[near] == kind]
        for layer in np.unique(face_layer[mine]):
            if layer == part:
                continue
            v = np.unique(F[mine[face_layer[mine] == layer]])
            v = v[mark[v]]
            # the part's front and back vertex share their xy: the two nearest are both
            _, nn = tree.query(V[v, :2], k=2)
            z = V[own[nn], 2]
            gap = sign * ((z.min(axis=1) if sign > 0 else z.max(axis=1)) - V[v, 2])
            g = float(np.median(gap))
            if 0 <= g < best_gap:
                best, best_gap = v, g
        if best is not None:
            out[best] = True
    return out


def fair_seams(V: np.ndarray, F: np.ndarray, moved: np.ndarray, A: sp.csr_matrix | None = None) -> np.ndarray:
    """Bi-Laplacian fairing of the vertices ``moved``.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions of a closed mesh.
    F : (m, 3) int64
        Its triangles.
    moved : (n,) bool
        The vertices that move (:func:`seam_zone`, less those a free part rests on, see
        :func:`supports`); every other vertex is fixed.
    A : (n, n) csr_matrix, optional
        The vertex adjacency, if already built (:func:`seam_zone`).

    Returns
    -------
    (n, 3) float64
        ``V`` with the moved vertices replaced; every other vertex is bit-identical (and so is
        every vertex of a component that ``moved`` covers whole).

    Solves  min Σ_i |(L x)_i|² / d_i  over the moved vertices (L the graph Laplacian, d_i the
    vertex degree, the usual lumped mass), the others fixed: one sparse LDLᵀ of the moved
    block (:func:`_spd_solve`), three right-hand sides.
    """
    A = adjacency(F, len(V)) if A is None else A
    # A component with no fixed vertex (a small model inside the rings) has no boundary to
    # hold it: its system would be singular, so it keeps its place.
    _, label = connected_components(A, directed=False)
    held = np.zeros(label.max() + 1, bool)
    held[label[~moved]] = True
    moved = moved & held[label]
    free = np.flatnonzero(moved)
    if len(free) == 0:
        return V.copy()
    deg = np.asarray(A.sum(axis=1)).ravel()
    L = (sp.diags(deg) - A).tocsr()
    # Only the rows of L near the moved vertices matter: restrict before squaring.
    near = ring_region(A, free, 1)
    Ln = L[np.flatnonzero(near)]
    Q = (Ln.T @ sp.diags(1.0 / deg[near]) @ Ln).tocsr()
    fixed = np.flatnonzero(~moved)
    Qf = Q[free]
    rhs = -(Qf[:, fixed] @ V[fixed])
    X = _spd_solve(Qf[:, free].tocsc(), rhs)
    V2 = V.copy()
    V2[free] = X
    return V2


def _spd_solve(K: sp.csc_matrix, rhs: np.ndarray) -> np.ndarray:
    """(k, 3) solution of K X = rhs for the symmetric positive definite K (k, k), rhs (k, 3).

    libigl's sparse LDLᵀ (Eigen's, AMD ordering): on the creature's 8.4k moved vertices
    ~60 ms against ~85-130 ms for SuperLU's LU, same answer to 2e-12; SuperLU if the binding
    fails. K is a graph bi-Laplacian block with finite entries (degrees >= 1), so libigl only
    ever sees validated input.
    """
    import igl

    try:
        X = np.asarray(igl.min_quad_with_fixed(K, -rhs, np.zeros(0, np.int64), np.zeros((0, rhs.shape[1])),
                                               sp.csc_matrix((0, K.shape[0])), np.zeros((0, rhs.shape[1])),
                                               True))
    except (RuntimeError, ValueError, TypeError):  # failed factorisation, other binding: SuperLU
        X = None
    if X is not None and X.shape == rhs.shape and np.all(np.isfinite(X)):
        return X
    return splu(K, permc_spec="COLAMD").solve(rhs)


def fairing_is_safe(V: np.ndarray, F: np.ndarray, moved: np.ndarray, h: float) -> bool:
    """Whether the faired mesh V (n, 3), F (m, 3) is still fit to hand out: no triangle with a
    moved vertex (``moved`` (n,) bool) of area below 1e-6 h² (h: the layers' edge length), and
    none that crosses another triangle."""
    touched = np.flatnonzero(moved[F].any(axis=1))
    T = V[F[touched]]
    area = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    if not np.all(np.isfinite(T)) or np.any(area < 1e-6 * h * h):
        return False
    return len(intersecting_pairs(V, F, among=touched)) == 0
