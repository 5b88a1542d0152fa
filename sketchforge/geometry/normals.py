"""Face and vertex normals of a triangle mesh, and the slopes p, q of a height field.

Conventions: x right, y up, z towards the viewer; a face's normal follows its winding
(counter-clockwise seen from +z gives n_z > 0). Slopes follow thesis eq. 2.3.2:
p = -n_x / n_z = dz/dx and q = -n_y / n_z = dz/dy.
"""

from __future__ import annotations

import numpy as np

#: Smallest n_z used when turning normals into slopes. An inflated surface meets the drawing
#: plane at a right angle, so the true normal at the rim lies in the plane (n_z = 0) and its
#: slopes are infinite. Mesh rim normals come from the adjacent triangles and are never
#: exactly in the plane, but a steep sliver can still give n_z ~ 1e-8; clamping to 1e-2 caps the
#: slope magnitude at 100 (a surface angle of 89.4 degrees), keeping the strip equations
#: finite while changing no normal that is less steep than that.
NZ_MIN = 1e-2


def _face_cross(V, F) -> np.ndarray:
    """(m, 3) unnormalised face normals (b - a) x (c - a): twice the area times the unit normal."""
    X = np.ascontiguousarray(np.asarray(V, dtype=np.float64).T)  # (3, n)
    Ft = np.ascontiguousarray(np.asarray(F, dtype=np.int64).T)  # (3, m)
    # written out on coordinate rows: np.cross on (m, 3) rows is several times slower, and
    # gathering and multiplying whole rows 2.5x faster than strided columns (a posed frame
    # pays this at every displayed frame); the same operations, so the same bits
    a = X.take(Ft[0], axis=1)
    u = X.take(Ft[1], axis=1)
    u -= a
    v = X.take(Ft[2], axis=1)
    v -= a
    out = np.empty((3, Ft.shape[1]))
    np.subtract(u[1] * v[2], u[2] * v[1], out=out[0])
    np.subtract(u[2] * v[0], u[0] * v[2], out=out[1])
    np.subtract(u[0] * v[1], u[1] * v[0], out=out[2])
    return np.ascontiguousarray(out.T)


def face_normals(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit face normals and face areas.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions.
    F : (m, 3) int64
        Triangles; the normal follows the winding (right-hand rule).

    Returns
    -------
    N : (m, 3) float64
        Unit normals; (0, 0, 1) for a degenerate (zero-area) triangle.
    area : (m,) float64
        Triangle areas in 3D.
    """
    cross = _face_cross(V, F)
    norm = np.linalg.norm(cross, axis=1)
    N = np.zeros_like(cross)
    N[:, 2] = 1.0
    ok = norm > 0
    N[ok] = cross[ok] / norm[ok, None]
    return N, 0.5 * norm


def faces_outward(V: np.ndarray, F: np.ndarray) -> bool:
    """Whether (V, F) is a closed surface with every triangle facing out: each directed edge
    belongs to one triangle and its reverse to one other (closed, consistently wound, no
    triangle with a repeated corner), and each connected piece winds around a positive
    volume (a model with a part left free is several pieces; one inside out fails it).

    Then, if the surface does not cut through itself, a viewer outside never sees a triangle
    from its back (a ray from outside first crosses the surface inwards), which is what lets
    a renderer skip the triangles that face away (the 3D view does, issue 34).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64

    Returns
    -------
    bool
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if F.ndim != 2 or F.shape[1] != 3 or len(F) == 0 or F.min() < 0 or F.max() >= len(V):
        return False
    if np.any((F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])):
        return False
    n = len(V)
    a, b = F.ravel(), F[:, [1, 2, 0]].ravel()
    edges = np.sort(a * n + b)
    if np.any(edges[1:] == edges[:-1]):
        return False  # an edge walked twice the same way: not one consistent orientation
    reverse = b * n + a
    at = np.minimum(np.searchsorted(edges, reverse), len(edges) - 1)
    if not np.array_equal(edges[at], reverse):
        return False  # an edge without its twin: the surface has a boundary
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    _, piece = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)
    # a·((b−a)×(c−a)) = a·(b×c): six times the signed volume of the tetrahedron (0, a, b, c)
    signed = np.einsum("ij,ij->i", V[F[:, 0]], _face_cross(V, F))
    volume = np.bincount(piece[F[:, 0]], weights=signed)
    return bool(np.all(volume[np.unique(piece[F[:, 0]])] > 0.0))


def _pair_weights(pairs: np.ndarray, weights) -> np.ndarray:
    """(r,) float64 in [0, 1]: ``weights`` for the (r, 2) ``pairs`` (all 1 when None)."""
    if weights is None:
        return np.ones(len(pairs))
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    if len(w) != len(pairs):
        raise ValueError(f"{len(w)} rim weights for {len(pairs)} rim pairs")
    return np.clip(w, 0.0, 1.0)


def vertex_normals(V: np.ndarray, F: np.ndarray, rim_pairs=None, rim_weights=None) -> np.ndarray:
    """Area-weighted unit vertex normals.

    Each vertex gets the sum of its faces' normals weighted by face area (the sum of the
    unnormalised cross products). A rim vertex thus takes its normal from the triangles next to
    it (thesis 4.5), which are never vertical on a height field, so n_z > 0 there.

    With ``rim_pairs`` (an assembled model's, :attr:`sketchforge.geometry.mesh.AssembledMesh.rim_pairs`)
    each vertex of a pair adds its twin's sum times the pair's weight (``rim_weights``, default
    1): the two vertices a part's front and back keep apart at its rim stand for one rounded
    rim, whose normal lies in between (issue 34: seen edge-on, a part's outline showed as a line
    where the front's tilted rim normals met the back's).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    rim_pairs : (r, 2) int64, optional
    rim_weights : (r,) float64 in [0, 1], optional

    Returns
    -------
    (n, 3) float64
        Unit normals; (0, 0, 1) for a vertex without faces or whose faces cancel out.
    """
    F = np.asarray(F, dtype=np.int64)
    cross = _face_cross(V, F)
    acc = np.zeros((len(V), 3))
    for k in range(3):
        np.add.at(acc, F[:, k], cross)
    if rim_pairs is not None and len(rim_pairs):
        pairs = np.asarray(rim_pairs, dtype=np.int64).reshape(-1, 2)
        w = _pair_weights(pairs, rim_weights)[:, None]
        a, b = pairs[:, 0], pairs[:, 1]
        own_a, own_b = acc[a], acc[b]
        np.add.at(acc, a, w * own_b)
        np.add.at(acc, b, w * own_a)
    norm = np.linalg.norm(acc, axis=1)
    N = np.zeros_like(acc)
    N[:, 2] = 1.0
    ok = norm > 1e-300
    N[ok] = acc[ok] / norm[ok, None]
    return N


def slopes(N: np.ndarray, nz_min: float = NZ_MIN) -> tuple[np.ndarray, np.ndarray]:
    """Slopes p = -n_x/n_z, q = -n_y/n_z of unit normals, finite everywhere.

    n_z is replaced by ``max(n_z, nz_min)`` before dividing, so a normal at (or beyond, for a
    fold-over) the rim gives a slope of magnitude at most ``1 / nz_min`` (|n_xy| <= 1), rising
    against n_xy as a true slope would, instead of inf or NaN. Normals with n_z >= nz_min
    are converted exactly.

    Parameters
    ----------
    N : (..., 3) float64
        Unit normals.
    nz_min : float
        Clamp for n_z, in (0, 1].

    Returns
    -------
    p, q : (...) float64
    """
    if not 0.0 < nz_min <= 1.0:
        raise ValueError(f"nz_min must be in (0, 1], got {nz_min}")
    N = np.asarray(N, dtype=np.float64)
    nz = np.maximum(N[..., 2], nz_min)
    return -N[..., 0] / nz, -N[..., 1] / nz


def normals_from_slopes(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Unit normals (-p, -q, 1) / sqrt(1 + p² + q²) (thesis eq. 2.3.1).

    Parameters
    ----------
    p, q : (...) float64

    Returns
    -------
    (..., 3) float64
    """
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    n = np.stack([-p, -q, np.ones_like(p)], axis=-1)
    return n / np.sqrt(1.0 + p * p + q * q)[..., None]


def corner_normals(V: np.ndarray, F: np.ndarray, crease_deg: float = 50.0) -> np.ndarray:
    """Smooth normals per triangle corner that keep the mesh's creases.

    A corner's normal is the area-weighted sum of the normals of the faces around its vertex
    whose normal is within ``crease_deg`` of its own face's: smooth across a fair surface
    (what :func:`vertex_normals` gives there), sharp where the geometry folds (a seam between
    assembled parts, a pinched rim), instead of one faceted colour per triangle.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    crease_deg : float
        Dihedral angle in degrees above which two faces do not smooth into each other.

    Returns
    -------
    (m, 3, 3) float64
        Unit normal of corner j of face i at [i, j].
    """
    return corner_normals_grouped(V, F, crease_groups(V, F, crease_deg))


def crease_groups(V: np.ndarray, F: np.ndarray, crease_deg: float = 50.0, rim_pairs=None, rim_weights=None):
    """Which faces each triangle corner smooths over (the expensive, pose-independent half of
    :func:`corner_normals`): the faces around the corner's vertex whose normals are within
    ``crease_deg`` of the corner's own face. A near-rigid deformation (a posed model) keeps
    them, so its normals cost only :func:`corner_normals_grouped` (one sparse product).

    With ``rim_pairs`` and ``rim_weights`` (as for :func:`vertex_normals`) a corner at a vertex
    of a pair also smooths over its twin's faces, and over every face of its own, each with the
    pair's weight: a part's rim is no crease, and at weight 1 both vertices' corners shade as
    one point, whatever face they belong to.

    Returns
    -------
    (3m, m) scipy.sparse.csr_matrix
        Row 3·face + j (corner j of face) has a 1 in the column of every face it smooths over
        (with rim pairs, a weight in (0, 1] more for the faces the pair adds).
    """
    import scipy.sparse as sp

    F = np.asarray(F, dtype=np.int64)
    Nf, _ = face_normals(V, F)
    m = len(F)
    corner_v = F.ravel()
    corner_f = np.repeat(np.arange(m), 3)
    order = np.argsort(corner_v, kind="stable")
    sv, sf = corner_v[order], corner_f[order]
    start = np.searchsorted(sv, np.arange(len(V)))
    deg = np.bincount(corner_v, minlength=len(V))
    # for each corner c (vertex v), all faces in v's group
    reps = deg[corner_v]
    c = np.repeat(np.arange(3 * m), reps)
    k = np.arange(len(c)) - np.repeat(np.cumsum(reps) - reps, reps)
    nb = sf[start[corner_v[c]] + k]
    # A face always smooths with itself: n·n of a unit normal rounds to just below 1, so with
    # crease_deg = 0 (flat shading) the test alone dropped the face from its own group and the
    # corner fell back to (0, 0, 1).
    same = (np.einsum("ij,ij->i", Nf[corner_f[c]], Nf[nb]) >= np.cos(np.radians(crease_deg))) | (
        nb == corner_f[c]
    )
    rows, cols, data = c[same], nb[same], np.ones(int(same.sum()))
    if rim_pairs is not None and len(rim_pairs):
        pairs = np.asarray(rim_pairs, dtype=np.int64).reshape(-1, 2)
        w_pair = _pair_weights(pairs, rim_weights)
        twin = np.full(len(V), -1, np.int64)
        weight = np.zeros(len(V))
        twin[pairs[:, 0]], twin[pairs[:, 1]] = pairs[:, 1], pairs[:, 0]
        weight[pairs[:, 0]] = weight[pairs[:, 1]] = w_pair
        # the own faces a crease left out, with the weight
        left = ~same & (weight[corner_v[c]] > 0.0)
        # the twin's faces, with the weight
        cc = np.flatnonzero((twin[corner_v] >= 0) & (weight[corner_v] > 0.0))
        t = twin[corner_v[cc]]
        reps_t = deg[t]
        ct = np.repeat(cc, reps_t)
        kt = np.arange(len(ct)) - np.repeat(np.cumsum(reps_t) - reps_t, reps_t)
        nbt = sf[start[twin[corner_v[ct]]] + kt]
        rows = np.r_[rows, c[left], ct]
        cols = np.r_[cols, nb[left], nbt]
        data = np.r_[data, weight[corner_v[c[left]]], weight[corner_v[ct]]]
    # duplicates (a face around both vertices of a pair) are summed, as vertex_normals sums
    return sp.csr_matrix((data, (rows, cols)), shape=(3 * m, m))


def corner_normals_grouped(V: np.ndarray, F: np.ndarray, groups) -> np.ndarray:
    """Per-corner normals of (V, F) summed over ``groups`` (from :func:`crease_groups`),
    area-weighted; (m, 3, 3) float64 unit normals, (0, 0, 1) where the sum vanishes."""
    return group_normals(V, F, groups).reshape(len(F), 3, 3)


def group_normals(V: np.ndarray, F: np.ndarray, groups) -> np.ndarray:
    """Area-weighted unit normals of groups of faces of (V, F).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    groups : (g, m) scipy.sparse.csr_matrix of ones
        Row i has a 1 in the column of every face of group i (rows of :func:`crease_groups`,
        or the shading vertices' rows of :func:`shading_vertices`).

    Returns
    -------
    (g, 3) float64
        Unit normals; (0, 0, 1) where the summed faces cancel or have no area.
    """
    F = np.asarray(F, dtype=np.int64)
    cross = _face_cross(V, F)  # unit normal times twice the area: the area weights
    acc = groups @ cross
    norm = np.sqrt(np.einsum("ij,ij->i", acc, acc))
    good = norm > 1e-300
    out = np.zeros_like(acc)
    out[:, 2] = 1.0  # (0, 0, 1) where the summed faces cancel or have no area
    out[good] = acc[good] / norm[good, None]
    return out


def shading_vertices(F: np.ndarray, groups) -> tuple[np.ndarray, np.ndarray, object]:
    """Merge the triangle corners that shade alike: one vertex per mesh vertex and group of
    faces it smooths over (several only along a crease), so that a renderer draws an indexed
    mesh of about as many vertices as the mesh has, instead of three per triangle.

    Two corners merge when they lie on the same vertex and their rows of ``groups`` hold the
    same faces (with the same weights, where there are any); their normals
    (:func:`group_normals` of those rows) are then the same sums in the same order, so the
    merged mesh shades bit for bit as the corners did. Pose-independent: computed once per
    model, reused for every posed frame.

    Parameters
    ----------
    F : (m, 3) int64
    groups : (3m, m) scipy.sparse.csr_matrix
        From :func:`crease_groups` (row 3·face + j: corner j of face).

    Returns
    -------
    src : (k,) int64
        The mesh vertex of each shading vertex (positions are ``V[src]``).
    tris : (m, 3) int64
        The triangles over the shading vertices, corner for corner as in F.
    rows : (k, m) scipy.sparse.csr_matrix
        Each shading vertex's group of faces (its normal is ``group_normals(V, F, rows)``).
    """
    F = np.asarray(F, dtype=np.int64)
    m = len(F)
    groups = groups.tocsr()
    if not groups.has_sorted_indices:
        groups = groups.sorted_indices()
    if m == 0:
        return np.zeros(0, np.int64), np.zeros((0, 3), np.int64), groups[:0]
    counts = np.diff(groups.indptr)
    # each corner's row as a key: its vertex, then its faces in order, padded with -1
    width = int(counts.max())
    weighted = bool(np.any(groups.data != 1.0))  # rim pairs' weights (crease_groups)
    key = np.full((3 * m, (2 if weighted else 1) * width + 1), -1, dtype=np.int64)
    key[:, 0] = F.ravel()
    slot = np.arange(groups.nnz) - np.repeat(groups.indptr[:-1], counts)
    key[np.repeat(np.arange(3 * m), counts), 1 + slot] = groups.indices
    if weighted:  # the same faces with other weights is another normal: the weights' bits join the key
        key[np.repeat(np.arange(3 * m), counts), 1 + width + slot] = np.ascontiguousarray(groups.data).view(np.int64)
    order = np.lexsort(key.T[::-1])  # by vertex, then faces (5x faster than np.unique(axis=0))
    sk = key[order]
    new = np.r_[True, np.any(sk[1:] != sk[:-1], axis=1)]
    inverse = np.empty(3 * m, dtype=np.int64)
    inverse[order] = np.cumsum(new) - 1
    first = order[new]
    return F.ravel()[first], inverse.reshape(m, 3), groups[first]
