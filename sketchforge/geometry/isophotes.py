"""Isophotes (curves of equal intensity) of a vertex field on a triangle mesh.

Marching triangles on the piecewise-linear interpolant of E: a triangle whose vertices lie on
both sides of c holds one straight segment between two edge points found by exact linear
interpolation (thesis 4.1). Segments are chained through shared edges into ordered polylines.

A vertex with E == c exactly counts as above c (a symbolic perturbation of c downwards), so
every crossed edge has one vertex strictly below and one at or above c, each triangle holds at
most one segment, and the chains never branch. Where a vertex sits exactly on c, consecutive
edge points coincide; the duplicates are removed.
"""

from __future__ import annotations

import numpy as np

from sketchforge.errors import SculptError
from sketchforge.geometry.locate import TriangleLocator, interpolate


def isophotes(
    V: np.ndarray, F: np.ndarray, E: np.ndarray, c: float
) -> tuple[list[np.ndarray], np.ndarray]:
    """The level set E = c as ordered polylines.

    Parameters
    ----------
    V : (n, d) float64, d >= 2
        Vertex positions; the first two columns are the drawing plane (used for orientation).
        Pass (n, 2) for curves in the plane or (n, 3) for curves on the surface.
    F : (m, 3) int64
    E : (n,) float64
        Values at vertices.
    c : float
        The isovalue.

    Returns
    -------
    polylines : list of (k, d) float64
        One per connected component, in a deterministic order (by first triangle index). Each
        runs with the brighter side (E > c) on its left in the drawing plane, so a closed curve
        around a bright spot is counter-clockwise. A closed curve repeats its first point at the
        end; an open one starts and ends on the mesh boundary (the rim).
    closed : (len(polylines),) bool
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    E = np.asarray(E, dtype=np.float64)
    c = float(c)
    if not np.isfinite(c):
        raise ValueError(f"the isovalue must be finite, got {c}")
    n = len(V)
    above = E >= c
    A = above[F]
    s = A.sum(axis=1)
    crossing = np.nonzero((s == 1) | (s == 2))[0]
    if len(crossing) == 0:
        return [], np.zeros(0, dtype=bool)
    Fc = F[crossing]
    Ac = A[crossing]
    sc = s[crossing]
    rows = np.arange(len(crossing))
    # The odd vertex out: the lone vertex above (s == 1) or the lone one below (s == 2).
    odd = np.where(sc == 1, np.argmax(Ac, axis=1), np.argmin(Ac, axis=1))
    vo = Fc[rows, odd]
    v1 = Fc[rows, (odd + 1) % 3]
    v2 = Fc[rows, (odd + 2) % 3]
    P2 = V[:, :2]
    e1, e2 = P2[v1] - P2[vo], P2[v2] - P2[vo]
    ccw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] >= 0
    # In a counter-clockwise triangle with its lone vertex above c, going from edge (vo, v1) to
    # edge (vo, v2) keeps that vertex on the left; each flip (lone vertex below, clockwise
    # winding) reverses the direction.
    forward = (sc == 1) == ccw
    key1 = np.minimum(vo, v1) * n + np.maximum(vo, v1)
    key2 = np.minimum(vo, v2) * n + np.maximum(vo, v2)
    start = np.where(forward, key1, key2)
    end = np.where(forward, key2, key1)

    # Edge points, one per crossed edge, by linear interpolation from the lower end.
    keys = np.unique(np.concatenate([start, end]))
    a, b = keys // n, keys % n
    lo = np.where(above[a], b, a)
    hi = np.where(above[a], a, b)
    t = (c - E[lo]) / (E[hi] - E[lo])  # E[hi] >= c > E[lo], so the denominator is > 0
    pts = V[lo] + t[:, None] * (V[hi] - V[lo])
    # A vertex exactly on c must give the same point from all its edges, bit for bit, so that
    # the duplicates it creates can be recognised and removed.
    on_c = E[hi] == c
    pts[on_c] = V[hi[on_c]]
    si = np.searchsorted(keys, start)
    ei = np.searchsorted(keys, end)

    # Successor of each segment: the one starting on the edge where it ends.
    S = len(si)
    first_at = np.full(len(keys), -1, dtype=np.int64)
    first_at[si] = np.arange(S)
    succ = first_at[ei]
    has_pred = np.zeros(S, dtype=bool)
    has_pred[succ[succ >= 0]] = True

    visited = np.zeros(S, dtype=bool)
    chains: list[tuple[int, list[int], bool]] = []
    succ_l = succ.tolist()
    for seed in list(np.nonzero(~has_pred)[0]) + list(range(S)):
        if visited[seed]:
            continue
        chain = [int(seed)]
        visited[seed] = True
        j = succ_l[seed]
        closed = False
        while j >= 0:
            if j == seed:
                closed = True
                break
            if visited[j]:  # only on a mesh with inconsistent or overlapping triangles
                break
            visited[j] = True
            chain.append(j)
            j = succ_l[j]
        chains.append((int(seed), chain, closed))
    chains.sort(key=lambda ch: min(ch[1]))

    polylines: list[np.ndarray] = []
    flags: list[bool] = []
    for _, chain, closed in chains:
        idx = np.concatenate([[si[chain[0]]], ei[chain]])
        line = pts[idx]
        keep = np.ones(len(line), dtype=bool)
        keep[1:] = np.any(line[1:] != line[:-1], axis=1)
        line = line[keep]
        if len(line) < (4 if closed else 2):
            continue  # a curve shrunk to a point where a vertex sits exactly on c
        polylines.append(line)
        flags.append(closed)
    return polylines, np.array(flags, dtype=bool)


def isovalue_at(mesh, E: np.ndarray, point, locator: TriangleLocator | None = None) -> float:
    """The isovalue picked at a point of the drawing plane.

    Parameters
    ----------
    mesh : Mesh
    E : (n,) float64
        Signed intensity at the mesh's vertices.
    point : (2,) float64
    locator : TriangleLocator, optional
        A prebuilt locator for ``mesh`` (saves rebuilding it on every pick).

    Returns
    -------
    float
        E interpolated at the point; 0.0 for a pick in shadow (E < 0), which selects the rim of
        the self-shadowed region (thesis 2.3.1).

    Raises
    ------
    SculptError
        If the point is not one finite (x, y) or is outside the mesh.
    """
    P = np.asarray(point, dtype=np.float64).reshape(-1)
    if P.shape != (2,) or not np.isfinite(P).all():
        raise SculptError(f"the pick must be one finite point [x, y], got {P.tolist()}")
    P = P.reshape(1, 2)
    loc = locator if locator is not None else TriangleLocator(mesh.V, mesh.F)
    face, bary = loc.locate(P)
    if face[0] < 0:
        raise SculptError("the pick is outside the layer: click on the shape to choose an isophote")
    value = float(interpolate(E, mesh.F, face, bary)[0])
    return max(value, 0.0)


def _point_polyline_distance(line: np.ndarray, p: np.ndarray) -> float:
    line = line[:, :2]
    if len(line) == 1:
        return float(np.hypot(*(line[0] - p)))
    a, b = line[:-1], line[1:]
    d = b - a
    dd = np.einsum("ij,ij->i", d, d)
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    q = a + t[:, None] * d
    return float(np.sqrt(np.min(np.einsum("ij,ij->i", q - p, q - p))))


def select_isophote(polylines: list[np.ndarray], point) -> int:
    """Index of the polyline nearest to a point (distance in the drawing plane).

    Parameters
    ----------
    polylines : list of (k, d) float64
        As returned by :func:`isophotes`.
    point : (2,) float64

    Returns
    -------
    int
        Ties go to the lower index.

    Raises
    ------
    SculptError
        If there is no polyline.
    """
    if len(polylines) == 0:
        raise SculptError("there is no isophote at this value on the layer")
    p = np.asarray(point, dtype=np.float64).reshape(2)
    dist = [_point_polyline_distance(np.asarray(line, dtype=np.float64), p) for line in polylines]
    return int(np.argmin(dist))
