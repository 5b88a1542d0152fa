"""Checks of assembled meshes written apart from the assembler (issue 34, point 7): they share
no code with ``sketchforge_assemble`` (whose own ``diagnostics`` the fairing uses), so a bug
there cannot hide itself here. Used by the tests and by ``benchmarks/bench_creatures.py``.

All functions take plain arrays: ``V`` (n, 3) float64, ``F`` (m, 3) int64.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree


def _edges(F: np.ndarray):
    """(undirected edges (e, 2) sorted, the two faces of each (e, 2) with -1 where missing,
    how many faces each edge has (e,))."""
    E = np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    face = np.repeat(np.arange(len(F)), 3)
    key, inv, count = np.unique(E, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    order = np.argsort(inv, kind="stable")
    first = np.r_[0, np.cumsum(count)[:-1]]
    pair = np.full((len(key), 2), -1, np.int64)
    pair[:, 0] = face[order[first]]
    two = count >= 2
    pair[two, 1] = face[order[first[two] + 1]]
    return key, pair, count


def boundary_edges(F: np.ndarray) -> int:
    """Edges that do not have exactly two triangles (open or non-manifold edges)."""
    return int(np.sum(_edges(F)[2] != 2))


def components(F: np.ndarray, n: int) -> int:
    """Connected components of the triangles (vertices joined by edges), unused vertices not
    counted."""
    E = F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    A = coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(n, n))
    _, label = connected_components(A, directed=False)
    return int(len(np.unique(label[np.unique(F)])))


def dihedral(V: np.ndarray, F: np.ndarray):
    """(edges (e, 2), angle (e,) degrees between the normals of the two triangles of each
    interior edge: 0 flat, 180 folded onto itself)."""
    key, pair, count = _edges(F)
    ok = count == 2
    key, pair = key[ok], pair[ok]
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    cos = np.clip(np.sum(n[pair[:, 0]] * n[pair[:, 1]], axis=1), -1.0, 1.0)
    return key, np.degrees(np.arccos(cos))


def _segment_hits_triangle(P0, P1, A, B, C, eps=1e-12):
    """(k,) bool: the segment P0-P1 passes through the inside of triangle ABC (Möller-Trumbore
    on the segment's line, the hit strictly inside the segment and the triangle)."""
    d = P1 - P0
    e1, e2 = B - A, C - A
    p = np.cross(d, e2)
    det = np.sum(e1 * p, axis=1)
    scale = np.linalg.norm(d, axis=1) * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
    ok = np.abs(det) > eps * np.maximum(scale, 1e-300)  # parallel (coplanar) pairs are not counted
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = P0 - A
    u = np.sum(s * p, axis=1) * inv
    q = np.cross(s, e1)
    v = np.sum(d * q, axis=1) * inv
    t = np.sum(e2 * q, axis=1) * inv
    tiny = 1e-9
    return ok & (u > tiny) & (v > tiny) & (u + v < 1 - tiny) & (t > tiny) & (t < 1 - tiny)


def self_intersections(V: np.ndarray, F: np.ndarray) -> int:
    """Pairs of triangles (sharing no vertex) of which one has an edge passing through the
    other's inside. Candidates: triangles whose bounding spheres (centroid, farthest corner)
    overlap, found with a k-d tree."""
    T = V[F]
    c = T.mean(axis=1)
    r = np.linalg.norm(T - c[:, None, :], axis=2).max(axis=1)
    pairs = cKDTree(c).query_pairs(2.0 * float(r.max()), output_type="ndarray")
    if len(pairs) == 0:
        return 0
    a, b = pairs[:, 0], pairs[:, 1]
    near = np.linalg.norm(c[a] - c[b], axis=1) <= r[a] + r[b]
    a, b = a[near], b[near]
    share = np.zeros(len(a), bool)
    for i in range(3):
        for j in range(3):
            share |= F[a, i] == F[b, j]
    a, b = a[~share], b[~share]
    hit = np.zeros(len(a), bool)
    for X, Y in ((a, b), (b, a)):
        for i, j in ((0, 1), (1, 2), (2, 0)):
            hit |= _segment_hits_triangle(V[F[X, i]], V[F[X, j]], V[F[Y, 0]], V[F[Y, 1]], V[F[Y, 2]])
    return int(hit.sum())


def seam_zone(V: np.ndarray, F: np.ndarray, face_layer: np.ndarray, radius: float) -> np.ndarray:
    """(n,) bool: the vertices within ``radius`` (3D) of a seam, where triangles of two
    different layers share an edge (a glued junction; free parts share none)."""
    key, pair, count = _edges(F)
    two = count == 2
    seam = key[two & (face_layer[np.maximum(pair[:, 0], 0)] != face_layer[np.maximum(pair[:, 1], 0)])]
    out = np.zeros(len(V), bool)
    if len(seam) == 0:
        return out
    pts = np.unique(seam.ravel())
    d, _ = cKDTree(V[pts]).query(V, distance_upper_bound=radius)
    return np.isfinite(d)


def junction_angles(V: np.ndarray, F: np.ndarray, face_layer: np.ndarray, radius: float) -> np.ndarray:
    """Dihedral angles (degrees) of the interior edges with both ends within ``radius`` of a
    glued junction's seam (see :func:`seam_zone`)."""
    key, ang = dihedral(V, F)
    zone = seam_zone(V, F, face_layer, radius)
    return ang[zone[key[:, 0]] & zone[key[:, 1]]]


def thickness(V: np.ndarray, F: np.ndarray, face_layer: np.ndarray, face_kind: np.ndarray, layer: int,
              xy: np.ndarray) -> np.ndarray:
    """(k,) float64: how thick the part ``layer`` of the assembled mesh is at the drawing-plane
    points ``xy`` (k, 2): its front face's height there minus its back face's (face_kind 0 and
    1 of that layer, located by brute force), NaN where a face is missing."""
    out = []
    for kind in (0, 1):
        tri = F[(face_layer == layer) & (face_kind == kind)]
        T = V[tri]
        z = np.full(len(xy), np.nan if kind == 0 else np.nan)
        if len(T):
            a, b, c = T[:, 0, :2], T[:, 1, :2], T[:, 2, :2]
            det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
            good = np.abs(det) > 1e-14
            tree = cKDTree(T[:, :, :2].mean(axis=1))
            reach = float(np.linalg.norm(T[:, :, :2] - T[:, :, :2].mean(axis=1)[:, None], axis=2).max())
            for i, p in enumerate(xy):
                cand = np.array(tree.query_ball_point(p, reach), dtype=np.int64)
                cand = cand[good[cand]] if len(cand) else cand
                if not len(cand):
                    continue
                d = det[cand]
                l1 = ((b[cand, 1] - c[cand, 1]) * (p[0] - c[cand, 0]) + (c[cand, 0] - b[cand, 0]) * (p[1] - c[cand, 1])) / d
                l2 = ((c[cand, 1] - a[cand, 1]) * (p[0] - c[cand, 0]) + (a[cand, 0] - c[cand, 0]) * (p[1] - c[cand, 1])) / d
                l3 = 1 - l1 - l2
                inside = (l1 >= -1e-9) & (l2 >= -1e-9) & (l3 >= -1e-9)
                if inside.any():
                    zz = l1 * T[cand, 0, 2] + l2 * T[cand, 1, 2] + l3 * T[cand, 2, 2]
                    z[i] = zz[inside].max() if kind == 0 else zz[inside].min()
        out.append(z)
    return out[0] - out[1]


def limb_depth_ratio(V, F, face_layer, face_kind, layer: int, part_region, host_region, h: float,
                     grid: int = 60) -> float:
    """How thick a limb is just outside its host's outline, relative to mid-limb (issue 34,
    point 5): on a grid of points of the part's region outside the host (shapely polygons in
    the drawing plane), the largest thickness among those within 2 ``h`` of the host's
    outline, over the largest among those at 40-60% of the farthest point's distance from
    it. NaN when the part hardly leaves its host."""
    import shapely

    out = part_region.difference(host_region)
    if out.is_empty or out.area <= 0:
        return float("nan")
    x0, y0, x1, y1 = out.bounds
    gx, gy = np.meshgrid(np.linspace(x0, x1, grid), np.linspace(y0, y1, grid))
    P = np.c_[gx.ravel(), gy.ravel()]
    P = P[shapely.contains_xy(out.buffer(-0.25 * h), P[:, 0], P[:, 1])]
    if len(P) < 8:
        return float("nan")
    d = shapely.distance(host_region, shapely.points(P))
    D = float(d.max())
    if D < 6 * h:
        return float("nan")
    t = thickness(V, F, face_layer, face_kind, layer, P)
    near = (d <= 2 * h) & np.isfinite(t)
    mid = (d >= 0.4 * D) & (d <= 0.6 * D) & np.isfinite(t)
    if not near.any() or not mid.any():
        return float("nan")
    return float(t[near].max() / t[mid].max())


def own_layer_depth_ratio(V: np.ndarray, F: np.ndarray, part_region, host_region, h: float) -> float:
    """:func:`limb_depth_ratio` of a layer's own front surface V (n, 3), F (m, 3) alone, with
    its mirror image as the back: what the part's drawing gives, whatever the assembly does
    (under 0.8 where the part is drawn narrower where it leaves its host)."""
    m = len(F)
    kind = np.r_[np.zeros(m, np.int64), np.ones(m, np.int64)]
    return limb_depth_ratio(np.r_[V, V * np.array([1.0, 1.0, -1.0])], np.r_[F, F[:, ::-1] + len(V)],
                            np.zeros(2 * m, np.int64), kind, 0, part_region, host_region, h)


def edge_length(V: np.ndarray, F: np.ndarray) -> float:
    """Median length in the drawing plane of the first edge of every triangle F (m, 3) of V (n, 3)."""
    return float(np.median(np.linalg.norm(V[F[:, 0], :2] - V[F[:, 1], :2], axis=1)))


def layers_edge_length(meshes) -> float:
    """The edge length of most of a model's surface: over the triangles of every layer mesh
    (``.V`` (n, 3), ``.F`` (m, 3)) pooled, the median by area of the length in the drawing plane
    of each one's first edge. Not the median of each layer's own (:func:`edge_length`): the
    inflater meshes narrow parts (a beak, an eye) finer, and a model's measuring radius should
    not shrink because its eye is meshed finer; by area, a finer part weighs what it did."""
    length, area = [], []
    for m in meshes:
        P = m.V[m.F][:, :, :2]
        length.append(np.linalg.norm(P[:, 0] - P[:, 1], axis=1))
        d1, d2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
        area.append(0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]))
    length, area = np.concatenate(length), np.concatenate(area)
    order = np.argsort(length, kind="stable")
    cum = np.cumsum(area[order])
    return float(length[order][np.searchsorted(cum, 0.5 * cum[-1])])


def drawn_tips(mesh, turn: float = 50.0) -> np.ndarray:
    """(k, 2) float64: the sharp corners drawn on a layer's outline (``mesh.V`` (n, 3),
    ``mesh.boundary`` its outline loop, ``mesh.junction`` the junction's vertices, skipped):
    the outline vertices where it turns by more than ``turn`` degrees between the points one
    edge length (:func:`edge_length`) behind and ahead along it. A beak's tip, a claw."""
    B = mesh.V[mesh.boundary, :2]
    k = len(B)
    if k < 3:
        return np.zeros((0, 2))
    h = edge_length(mesh.V, mesh.F)
    ring = np.vstack([B, B[:1]])
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(ring, axis=0), axis=1))]
    total = s[-1]

    def at(t):
        t = np.mod(t, total)
        j = np.clip(np.searchsorted(s, t, side="right") - 1, 0, k - 1)
        a = (t - s[j]) / np.maximum(s[j + 1] - s[j], 1e-300)
        return ring[j] * (1 - a)[:, None] + ring[j + 1] * a[:, None]

    u, v = B - at(s[:k] - h), at(s[:k] + h) - B
    cos = np.sum(u * v, axis=1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-300)
    sharp = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) > turn
    sharp &= ~np.isin(mesh.boundary, mesh.junction)
    return B[sharp]


def at_drawn_tips(V: np.ndarray, F: np.ndarray, face_layer: np.ndarray, tips, radius: float) -> np.ndarray:
    """(e,) bool over :func:`dihedral`'s edges: both triangles of the edge on one layer, and
    the edge's midpoint within ``radius`` (in the drawing plane) of one of that layer's drawn
    tips (``tips[k]``: :func:`drawn_tips` of layer k). Such an edge bends with the part's own
    drawn corner, present in the layer as inflated, not with a junction."""
    key, pair, count = _edges(F)
    ok = count == 2
    key, pair = key[ok], pair[ok]
    la, lb = face_layer[pair[:, 0]], face_layer[pair[:, 1]]
    out = np.zeros(len(key), bool)
    mid = V[key].mean(axis=1)[:, :2]
    for k, T in enumerate(tips):
        sel = np.flatnonzero((la == k) & (lb == k))
        if len(T) == 0 or len(sel) == 0:
            continue
        d, _ = cKDTree(np.asarray(T)).query(mid[sel], distance_upper_bound=radius)
        out[sel[np.isfinite(d)]] = True
    return out
