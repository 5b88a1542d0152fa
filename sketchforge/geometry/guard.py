"""The one gate between user-derived geometry and native code.

Triangle, libigl, OSQP and GEOS (through shapely) are C/C++ libraries. Handed a duplicated
vertex, crossing constrained segments, a face index out of range or a NaN they do not raise:
Triangle segfaults on a PSLG whose segments use a duplicated vertex, ``igl.cotmatrix``
segfaults on an out-of-range face, a zero-area triangle gives infinite cotangents, and a
vertex Triangle silently dropped leaves a zero row that makes the Laplacian singular. The
rule is therefore: **no unvalidated geometry reaches native code**. Every call into those
libraries goes through one of these functions first:

=========================================  ==========================================
native call                                guard
=========================================  ==========================================
``triangle.triangulate``                   :func:`pslg`
``igl.cotmatrix``, ``igl.massmatrix``      :func:`mesh`
``igl.min_quad_with_fixed_*``, scipy       :func:`sparse_system` (:func:`finite` for
sparse solves                              each right-hand side)
``osqp.OSQP.setup``                        :func:`qp`
scipy ``splu`` and LAPACK of a QP solved   :func:`objective`, :func:`constraints`
row by row (the dual active-set method)
shapely / GEOS                             :func:`polygon`, :func:`linestring` (build from
                                           coordinates), :func:`geometry` (check a built
                                           geometry), :func:`points` (raw coordinates)
=========================================  ==========================================

Conventions shared by every function:

- Inputs are array-likes; outputs are plain numpy arrays (or scipy sparse matrices, shapely
  geometries) in the dtype and memory layout the library wants, so the caller never casts
  again and passes exactly what was checked.
- ``what`` is a noun phrase naming the input for the message (``"the outline"``, ``"the
  junction of layer 'arm'"``); every failure is a :class:`~sketchforge.errors.GeometryError`
  (a :class:`~sketchforge.errors.SketchforgeError`, so the CLI and the app show it as one
  sentence) raised before anything native runs.
- Valid input passes through bit for bit: the only repairs are the documented ones (merging
  near-duplicate PSLG vertices, dropping degenerate and repeated segments, ``make_valid`` on
  polygons), so guarding a call never changes a result on clean data.
- Cost is O(n log n) with numpy and GEOS doing the loops (an R-tree over segments, a k-d tree
  over vertices): a few milliseconds on the 10k-vertex meshes of the inflate pipeline.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
import shapely
from scipy.spatial import cKDTree

from sketchforge.errors import GeometryError
from sketchforge.geometry.contour import MAX_COORDINATE, format_point

#: Default merge tolerance of :func:`pslg`, relative to the extent of its vertices. Far below
#: any resolution the inflate pipeline accepts, far above double rounding (1e-16): points
#: this close are one point that went through different arithmetic.
REL_TOL = 1e-9
#: A triangle counts as degenerate when twice its area is at most this times its longest
#: edge squared (its smallest angle is then below ~1e-12 rad and a cotangent above ~1e12).
AREA_TOL = 1e-12


def _coords(P, what: str, ncols: tuple[int, ...]) -> np.ndarray:
    """(k, c) float64 C-contiguous, c in ncols, finite, within ±MAX_COORDINATE."""
    try:
        A = np.asarray(P, dtype=np.float64)
    except (TypeError, ValueError):
        raise GeometryError(f"{what} must be an array of numbers, got {type(P).__name__}") from None
    if A.size == 0:
        A = A.reshape(0, ncols[0])
    if A.ndim != 2 or A.shape[1] not in ncols:
        cols = " or ".join(str(c) for c in ncols)
        raise GeometryError(f"{what} must be an array of shape (k, {cols}), got shape {A.shape}")
    if not np.isfinite(A).all():
        bad = int(np.flatnonzero(~np.isfinite(A).all(axis=1))[0])
        raise GeometryError(f"{what} has a point that is not a finite number (point {bad}: {A[bad].tolist()})")
    if A.size:
        top = float(np.abs(A).max())
        # Beyond this squared distances overflow (1e200² = inf) and GEOS and Triangle lose
        # every digit of the drawing; no drawing is that large.
        if top > MAX_COORDINATE:
            raise GeometryError(
                f"{what} has coordinates reaching {top:.3g}; they must lie within ±{MAX_COORDINATE:.0e} drawing units"
            )
    return np.ascontiguousarray(A)


def _indices(I, n: int, width: int | None, what: str, name: str) -> np.ndarray:
    """Integer array (k, width) (or (k,) for width None) with every entry in [0, n), int64."""
    try:
        A = np.asarray(I)
    except (TypeError, ValueError):  # ragged nested lists
        raise GeometryError(f"{what}: the {name} must be an array of integers") from None
    if A.size == 0:
        A = A.reshape((0,) if width is None else (0, width)).astype(np.int64)
    if A.dtype.kind not in "iu":
        # A float or bool index array is always a caller's bug; rounding it could pick the
        # wrong vertex silently.
        raise GeometryError(f"{what}: the {name} must be integers, got {A.dtype}")
    if (width is None and A.ndim != 1) or (width is not None and (A.ndim != 2 or A.shape[1] != width)):
        shape = "(k,)" if width is None else f"(k, {width})"
        raise GeometryError(f"{what}: the {name} must be an array of shape {shape}, got shape {A.shape}")
    if A.size and (A.min() < 0 or A.max() >= n):
        bad = int(A.min()) if A.min() < 0 else int(A.max())
        raise GeometryError(f"{what}: the {name} refer to point {bad}, outside 0..{n - 1}")
    return np.ascontiguousarray(A, dtype=np.int64)


# --- coordinates ----------------------------------------------------------------------------


def points(P, what: str) -> np.ndarray:
    """Coordinates that any native library can take.

    Parameters
    ----------
    P : (k, 2) array-like of float
    what : str
        Names the input in the message.

    Returns
    -------
    P : (k, 2) float64, C-contiguous, finite, every coordinate within ±MAX_COORDINATE
        (:data:`sketchforge.geometry.contour.MAX_COORDINATE`).

    Raises
    ------
    GeometryError
    """
    return _coords(P, what, (2,))


def finite(x, shape: tuple, what: str) -> np.ndarray:
    """A float64 array of exactly this shape with no NaN or infinity.

    For values that go into a solver after its matrix was checked (a right-hand side, the
    values at fixed vertices): one NaN there turns a whole solution into NaN.

    Parameters
    ----------
    x : array-like of float
    shape : tuple of int
        Required shape; axes of length 1 may be missing or extra ((n,) is accepted for (n, 1)
        and back), nothing else may differ.
    what : str

    Returns
    -------
    x : float64 C-contiguous array of shape ``shape``.
    """
    try:
        A = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise GeometryError(f"{what} must be an array of numbers, got {type(x).__name__}") from None
    shape = tuple(int(s) for s in shape)
    if A.shape != shape:
        # Only unit axes may differ ((n,) for (n, 1) and back): anything else is a mix-up.
        if A.squeeze().shape != tuple(s for s in shape if s != 1):
            raise GeometryError(f"{what} must have shape {shape}, got {A.shape}")
        A = A.reshape(shape)
    if not np.isfinite(A).all():
        bad = int(np.flatnonzero(~np.isfinite(A.ravel()))[0])
        raise GeometryError(f"{what} has a value that is not a finite number (entry {bad}: {A.ravel()[bad]})")
    return np.ascontiguousarray(A)


# --- Triangle -------------------------------------------------------------------------------


def tolerance(P, rel: float = REL_TOL) -> float:
    """``rel`` times the extent (larger side of the bounding box) of P (k, 2); 0 for no points.

    The merge distance :func:`pslg` uses when given ``tol=None``: relative, so that the same
    drawing at any scale merges the same points."""
    P = np.asarray(P, dtype=np.float64)
    if len(P) == 0:
        return 0.0
    return float(rel) * float(np.max(P.max(axis=0) - P.min(axis=0)))


def _check_tol(tol, what: str) -> float:
    try:
        t = float(tol)
    except (TypeError, ValueError):
        raise GeometryError(f"{what}: the merge tolerance must be a number, got {tol!r}") from None
    if not (np.isfinite(t) and t >= 0.0):
        raise GeometryError(f"{what}: the merge tolerance must be a finite number >= 0, got {tol!r}")
    return t


def _merge(P: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Merge the checked points P (n, 2) closer than ``tol`` (greedy in input order, see
    :func:`pslg`): returns the kept points Q (k, 2) in input order and ``index`` (n,) int64,
    ``Q[index[i]]`` being what point i became."""
    n = len(P)
    if n == 0:
        return P, np.zeros(0, np.int64)
    # Bit-identical copies first, with one sort: any number of copies costs O(n log n), and
    # the k-d tree below never sees a cluster of equal points (quadratically many pairs).
    # (A lexsort of the two columns: np.unique(axis=0) sorts a structured view, ~3x slower.)
    order = np.lexsort((P[:, 1], P[:, 0]))
    Ps = P[order]
    starts = np.flatnonzero(np.r_[True, np.any(Ps[1:] != Ps[:-1], axis=1)])
    first = np.minimum.reduceat(order, starts)  # earliest input index of each distinct point
    rep = np.empty(n, np.int64)
    rep[order] = np.repeat(first, np.diff(np.r_[starts, n]))
    if tol > 0.0:
        distinct = np.flatnonzero(rep == np.arange(n))  # ascending: input order
        D = P[distinct]
        tree = cKDTree(D, balanced_tree=False, compact_nodes=False)  # half the build time, same queries
        # Which points have a neighbour within tol at all (the nearest other point; the bound
        # is nudged up because it is strict and the ball query below is not).
        d, _ = tree.query(D, k=2, distance_upper_bound=np.nextafter(tol, np.inf))
        close = np.flatnonzero(np.isfinite(d[:, 1]))
        if len(close):
            # Only points with a close neighbour reach this loop: none on clean input. Each
            # kept point asks for its ball once and a merged point never asks, so a dense
            # cluster costs one query, not the quadratically many pairs query_pairs lists.
            owner = np.arange(len(D))
            taken = np.zeros(len(D), bool)
            for a in close:
                if taken[a]:
                    continue
                js = np.asarray(tree.query_ball_point(D[a], tol), dtype=np.int64)
                js = js[(js != a) & ~taken[js]]  # earlier ones are all taken already
                owner[js] = a
                taken[js] = True
            rep = distinct[owner[np.searchsorted(distinct, rep)]]
    keep = rep == np.arange(n)
    new = np.cumsum(keep) - 1
    return np.ascontiguousarray(P[keep]), new[rep].astype(np.int64)


class PslgError(GeometryError):
    """A :func:`pslg` refusal that also says which input is at fault, so that a caller that
    put the graph together from several sources (an outline and the junctions cut into it)
    can name the right one.

    Attributes
    ----------
    points : tuple of int
        Indices into the ``vertices`` given of the stray points (a point on a segment that
        does not end there); empty otherwise. A point that absorbed near-duplicates is named
        by the first of them.
    segments : tuple of int
        Rows of the ``segments`` given that the message is about (the segment a point lies
        on; the two segments that cross); empty when the graph as a whole is refused.
    at : (2,) float64 or None
        Where, in drawing units (the point that the message names).
    """

    def __init__(self, message: str, points=(), segments=(), at=None):
        super().__init__(message)
        self.points = tuple(int(i) for i in points)
        self.segments = tuple(int(i) for i in segments)
        self.at = None if at is None else np.array(at, dtype=np.float64)


def pslg(vertices, segments, tol, *, what: str = "the outline", return_index: bool = False):
    """A planar straight-line graph that Triangle can take without undefined behaviour.

    Triangle's behaviour on an invalid PSLG is undefined: segments that use a duplicated vertex
    segfault it (on some runs; a singular Laplacian on others), and with ``Y`` or ``q`` crossing
    segments change the boundary the caller relies on. This merges near-duplicate vertices
    into one shared table, remaps the segments, drops the ones that became degenerate or
    repeated, and refuses what cannot be repaired without guessing the drawing's intent.

    Parameters
    ----------
    vertices : (n, 2) array-like of float
    segments : (s, 2) array-like of int, or None
        Constrained segments, indices into ``vertices``.
    tol : float or None
        Merge distance (drawing units): vertices closer than this become one (see below), and
        no vertex may lie closer than this to a segment it is not an end of. None:
        :func:`tolerance` of the vertices (1e-9 of the extent). 0 merges exactly equal
        vertices only.
    what : str
        Names the input in messages.
    return_index : bool
        Also return ``index`` (n,) int64: input vertex i is output vertex ``index[i]``. A
        caller whose vertices must all survive (Triangle's output numbered like its input)
        compares ``len(tri["vertices"])`` with n and finds the merged ones here.

    Returns
    -------
    tri : dict
        ``vertices`` (k, 2) float64 C-contiguous, the kept vertices in input order with their
        exact input coordinates; ``segments`` (s', 2) int32 C-contiguous (only when there is
        one: Triangle rejects an empty segment list). Pass it to ``triangle.triangulate`` as
        is. With ``p`` and segments that enclose nothing, Triangle returns no ``triangles``
        key: check for it.
    index : (n,) int64
        Only with ``return_index``.

    Raises
    ------
    GeometryError
        Non-finite or huge coordinates; segment indices that are not integers or out of range;
        fewer than 3 distinct vertices or all on one line (Triangle fails or returns nothing).
    PslgError
        Two segments that cross or overlap; a vertex within ``tol`` of the inside of a segment
        it does not end (the error names them, see :class:`PslgError`).

    Notes
    -----
    Merging is greedy in input order: a vertex that no earlier kept vertex lies within ``tol``
    of is kept, and takes every later unmerged vertex within ``tol`` of it. So kept vertices
    are more than ``tol`` apart, every merged vertex is within ``tol`` of the vertex it became
    (no chain of close vertices drifts further), and the kept one is the first of its group.
    """
    V = points(vertices, f"{what}")
    S0 = _indices(np.zeros((0, 2), np.int64) if segments is None else segments, len(V), 2, what, "segment indices")
    tol = tolerance(V) if tol is None else _check_tol(tol, what)
    Q, index = _merge(V, tol)
    if len(Q) < 3:
        raise GeometryError(f"{what} has {len(Q)} distinct points; triangulating needs at least 3")
    _check_not_collinear(Q, tol, what)

    S = index[S0]
    rows = np.flatnonzero(S[:, 0] != S[:, 1])  # the others became zero-length when their ends merged
    if len(rows):
        # A segment given twice (either direction) constrains nothing more; keep the first.
        _, first = np.unique(np.sort(S[rows], axis=1), axis=0, return_index=True)
        rows = rows[np.sort(first)]
    S = S[rows]
    _check_segments(Q, S, tol, what, index, rows)

    out = {"vertices": Q}
    if len(S):
        out["segments"] = np.ascontiguousarray(S, dtype=np.int32)
    return (out, index) if return_index else out


def _check_not_collinear(Q: np.ndarray, tol: float, what: str) -> None:
    # Triangle raises on fewer than 3 vertices and returns no triangles for collinear ones;
    # both would surface as a KeyError or ValueError far from the cause.
    C = Q - Q.mean(axis=0)
    w, v = np.linalg.eigh(C.T @ C)
    width = float(np.max(np.abs(C @ v[:, 0])))  # distance from the best-fit line
    extent = float(np.max(np.abs(C @ v[:, 1])))
    if width <= max(tol, 1e-13 * extent):
        raise GeometryError(f"{what}: all its points lie on one straight line, so it encloses no area")


def _check_segments(Q: np.ndarray, S: np.ndarray, tol: float, what: str, index: np.ndarray,
                    rows: np.ndarray) -> None:
    """Refuse touching, overlapping and crossing segments. ``index`` (input vertex -> Q) and
    ``rows`` (S -> input segment row) translate what is refused back to the caller's input."""
    if len(S) == 0:
        return
    lines = shapely.linestrings(np.stack([Q[S[:, 0]], Q[S[:, 1]]], axis=1))
    tree = shapely.STRtree(lines)
    # Vertex on a segment it does not end. Merged vertices are more than tol apart, so a
    # vertex within tol of a segment but not one of its ends is near its inside. This also
    # catches every overlap (two collinear segments from one vertex: the shorter one's far end
    # lies on the longer one), every T-junction and every near miss within tol (the closest
    # points of two disjoint segments include an end of one of them).
    pts = shapely.points(Q)
    if tol > 0.0:
        vi, sj = tree.query(pts, predicate="dwithin", distance=tol)
    else:
        vi, sj = tree.query(pts, predicate="intersects")
    bad = (S[sj, 0] != vi) & (S[sj, 1] != vi)
    if bad.any():
        k = int(np.argmax(bad))
        a, b = Q[S[sj[k], 0]], Q[S[sj[k], 1]]
        first = int(np.argmax(index == vi[k]))  # the kept vertex is the first of its group
        raise PslgError(
            f"{what} has a point at {format_point(Q[vi[k]])} on the segment from {format_point(a)} to {format_point(b)}, which does not "
            f"end there (closer than {tol:.3g})",
            points=(first,), segments=(rows[sj[k]],), at=Q[vi[k]],
        )
    # Proper crossings: segments that share no vertex and intersect.
    i, j = tree.query(lines, predicate="intersects")
    m = i < j
    i, j = i[m], j[m]
    share = (S[i, 0] == S[j, 0]) | (S[i, 0] == S[j, 1]) | (S[i, 1] == S[j, 0]) | (S[i, 1] == S[j, 1])
    i, j = i[~share], j[~share]
    if len(i):
        x = shapely.get_coordinates(shapely.intersection(lines[i[0]], lines[j[0]])).mean(axis=0)
        raise PslgError(f"{what} has two segments that cross near {format_point(x)}", segments=(rows[i[0]], rows[j[0]]),
                        at=x)


# --- libigl -----------------------------------------------------------------------------------


def mesh(V, F, what: str = "the mesh", *, planar: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """A triangle mesh that libigl's cotangent Laplacian and mass matrix can take.

    Parameters
    ----------
    V : (n, 2) or (n, 3) array-like of float
        A planar mesh (the drawing plane) or a surface.
    F : (m, 3) array-like of int
    what : str
    planar : bool
        Measure areas in the drawing plane (the first two columns) also for an (n, 3) V: a
        height field z(x, y), whose operators are built on its planar mesh, must have no
        triangle that is flat *in the plane* (a vertical one has a fine 3D area).

    Returns
    -------
    V : (n, 2) or (n, 3) float64, C-contiguous (the columns given).
    F : (m, 3) int64, C-contiguous: the only index dtype the igl bindings accept.

    Raises
    ------
    GeometryError
        Non-finite or huge coordinates; F not integer, not (m, 3) or out of range (igl reads
        out of bounds: a segfault); a triangle of zero area, measured where V lives (in the
        drawing plane for (n, 2) or with ``planar``: cotangents there are infinite).
    """
    V = _coords(V, f"{what}", (2, 3))
    F = _indices(F, len(V), 3, what, "triangle indices")
    dims = 2 if planar else V.shape[1]
    if len(F):
        # One gather per coordinate into (m, 3) blocks, corners taken relative to corner 0:
        # a third of the time of gathering (m, 3)-row blocks per corner on a 40k-vertex mesh.
        u, w = [], []
        for d in range(dims):
            X = np.take(np.ascontiguousarray(V[:, d]), F)
            X -= X[:, :1]
            u.append(X[:, 1])
            w.append(X[:, 2])
        if dims == 2:
            area2 = np.abs(u[0] * w[1] - u[1] * w[0])
        else:
            area2 = np.sqrt((u[1] * w[2] - u[2] * w[1]) ** 2 + (u[2] * w[0] - u[0] * w[2]) ** 2
                            + (u[0] * w[1] - u[1] * w[0]) ** 2)
        longest = np.maximum(np.maximum(sum(x * x for x in u), sum(x * x for x in w)),
                             sum((y - x) ** 2 for x, y in zip(u, w)))
        flat = area2 <= AREA_TOL * longest
        if flat.any():
            k = int(np.argmax(flat))
            where = "in the drawing plane " if dims == 2 else ""
            raise GeometryError(
                f"{what} has a triangle of zero area {where}(triangle {k}, near {format_point(V[F[k, 0]])}); "
                "its cotangent weights would be infinite"
            )
    return V, F


class System(NamedTuple):
    """Output of :func:`sparse_system`.

    A : (n, n) scipy.sparse.csc_matrix float64
    fixed : (f,) int64 sorted unique, or None
    """

    A: sp.csc_matrix
    fixed: np.ndarray | None


def _finite_sparse(A, what: str, role: str, fmt: str = "csc"):
    """A as a float64 sparse matrix in format ``fmt`` ("csc" or "csr") with finite entries, or
    GeometryError naming ``role`` of ``what``."""
    try:
        M = (sp.csr_matrix if fmt == "csr" else sp.csc_matrix)(A, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{what}: {role} is not a numeric 2-D array ({exc})") from None
    if not np.isfinite(M.data).all():
        raise GeometryError(f"{what}: {role} has an entry that is not a finite number")
    return M


def sparse_system(A, what: str = "the linear system", *, fixed=None) -> System:
    """A sparse system matrix that igl.min_quad_with_fixed or a scipy solver can take.

    Each right-hand side is checked where it is used, with :func:`finite`.

    Parameters
    ----------
    A : (n, n) sparse or dense array-like of float
    what : str
    fixed : (f,) array-like of int, optional
        Rows/columns whose values are prescribed (``min_quad_with_fixed``'s ``known``); they
        are eliminated, so only the other rows must be non-empty.

    Returns
    -------
    System
        ``(A, fixed)`` as CSC float64 and sorted unique int64 (or None).

    Raises
    ------
    GeometryError
        A not square or with a non-finite entry; fixed indices out of range (igl reads out of
        bounds); a free row of A that is all zeros (a vertex no triangle uses, e.g. a duplicate
        Triangle dropped): the system is singular.
    """
    M = _finite_sparse(A, what, "the matrix")
    n = M.shape[0]
    if M.shape != (n, n):
        raise GeometryError(f"{what}: the matrix must be square, got shape {M.shape}")
    free = np.ones(n, bool)
    if fixed is not None:
        fixed = np.unique(_indices(np.asarray(fixed).ravel(), n, None, what, "fixed indices"))
        free[fixed] = False
    if n and free.any():
        rowsum = abs(M) @ np.ones(n)
        empty = free & (rowsum == 0.0)
        if empty.any():
            raise GeometryError(
                f"{what}: row {int(np.argmax(empty))} of the matrix is all zeros (a vertex no triangle uses?), "
                "so the system is singular"
            )
    return System(M, fixed)


# --- OSQP -------------------------------------------------------------------------------------


def qp(P, q, A, l, u, what: str = "the quadratic program"):
    """A QP  min ½xᵀPx + qᵀx  s.t.  l <= Ax <= u  that OSQP can take.

    :func:`objective` and :func:`constraints` together, for a solver that takes all rows as
    one matrix (OSQP).

    Parameters
    ----------
    P : (N, N) sparse or dense array-like of float
        OSQP reads its upper triangle only (the caller passes ``sp.triu(P)``).
    q : (N,) array-like of float
    A : (m, N) sparse or dense array-like of float
    l, u : (m,) array-like of float
        Bounds; -inf in ``l`` and +inf in ``u`` mean no bound.
    what : str

    Returns
    -------
    P : (N, N) csc float64, q : (N,) float64, A : (m, N) csc float64, l, u : (m,) float64

    Raises
    ------
    GeometryError
        Shapes that do not match; NaN anywhere; infinity outside the bounds (or +inf as a
        lower bound, -inf as an upper one: no x satisfies them); some l > u.
    """
    P, q = objective(P, q, what)
    A, l, u = constraints(A, l, u, P.shape[0], what)
    return P, q, A, l, u


def objective(P, q, what: str = "the quadratic program"):
    """The objective ½xᵀPx + qᵀx of a QP: P (N, N) square with finite entries (returned as
    CSC float64, what SuperLU and OSQP take), q (N,) finite float64. Raises GeometryError."""
    P = _finite_sparse(P, what, "the objective matrix")
    N = P.shape[0]
    if P.shape != (N, N):
        raise GeometryError(f"{what}: the objective matrix must be square, got shape {P.shape}")
    return P, finite(q, (N,), f"the linear term of {what}")


def constraints(A, l, u, n: int, what: str = "the quadratic program", *, fmt: str = "csc"):
    """Constraint rows  l <= Ax <= u  over ``n`` unknowns.

    Parameters
    ----------
    A : (m, n) sparse or dense array-like of float
    l, u : (m,) array-like of float, or None for no bound on that side
        -inf in ``l`` and +inf in ``u`` mean no bound on that row.
    n : int
    what : str
    fmt : {"csc", "csr"}
        Sparse format of the returned A: CSC for OSQP, CSR for a method that reads rows.

    Returns
    -------
    A : (m, n) float64 in ``fmt``, l, u : (m,) float64 (None where None was given)

    Raises
    ------
    GeometryError
        A with a non-finite entry or not n columns; bounds of the wrong length, NaN, +inf as a
        lower bound or -inf as an upper one (no x satisfies them), some l > u.
    """
    A = _finite_sparse(A, what, "the constraint matrix", fmt)
    if A.shape[1] != n:
        raise GeometryError(f"{what}: the constraint matrix has {A.shape[1]} columns for {n} unknowns")
    m = A.shape[0]
    bounds: list[np.ndarray | None] = []
    for name, x in (("lower", l), ("upper", u)):
        if x is None:
            bounds.append(None)
            continue
        try:
            x = np.ascontiguousarray(np.asarray(x, dtype=np.float64).reshape(-1))
        except (TypeError, ValueError):
            raise GeometryError(f"{what}: the {name} bounds must be numbers") from None
        if len(x) != m:
            raise GeometryError(f"{what}: {len(x)} {name} bounds for {m} constraint rows")
        if np.isnan(x).any():
            raise GeometryError(f"{what}: a bound is not a number (NaN)")
        bounds.append(x)
    l, u = bounds
    if (l is not None and np.isposinf(l).any()) or (u is not None and np.isneginf(u).any()):
        raise GeometryError(f"{what}: a lower bound is +inf or an upper bound is -inf, so no point satisfies it")
    if l is not None and u is not None and (l > u).any():
        k = int(np.argmax(l > u))
        raise GeometryError(f"{what}: row {k} has lower bound {l[k]:.6g} above its upper bound {u[k]:.6g}")
    return A, l, u


# --- GEOS (shapely) ---------------------------------------------------------------------------


def geometry(g, what: str = "the shape"):
    """A shapely geometry that GEOS operations can take.

    Parameters
    ----------
    g : shapely.Geometry
    what : str

    Returns
    -------
    shapely.Geometry
        ``g`` itself when valid. An invalid Polygon (a self-touching or self-crossing outline)
        is repaired with ``shapely.make_valid`` and only its polygonal parts are kept (a
        Polygon, a MultiPolygon, or an empty Polygon): collapsed slivers that make_valid
        returns as lines would otherwise surprise every caller that expects an area. An
        invalid MultiPolygon (overlapping parts) is the union of its parts, each repaired so.

    Raises
    ------
    GeometryError
        Not a geometry; a coordinate that is not finite or beyond ±MAX_COORDINATE (GEOS has
        no NaN semantics and overflows on huge ones); an invalid geometry of another kind (a
        line with fewer than 2 distinct points).
    """
    if not isinstance(g, shapely.Geometry):
        raise GeometryError(f"{what} must be a shapely geometry, got {type(g).__name__}")
    xy = shapely.get_coordinates(g)
    _coords(xy, what, (2,))
    if g.is_empty or g.is_valid:
        return g
    if g.geom_type == "MultiPolygon":
        # make_valid reads a twice-covered overlap of two parts as outside (even-odd: their
        # symmetric difference); a person who drew two overlapping parts means their union
        union = shapely.union_all([geometry(p, what) for p in g.geoms])
        return union if not union.is_empty else shapely.Polygon()  # not an empty collection
    if g.geom_type == "Polygon":
        fixed = shapely.make_valid(g)
        parts = [p for p in shapely.get_parts(fixed) if p.geom_type in ("Polygon", "MultiPolygon")]
        if not parts:
            return shapely.Polygon()
        return parts[0] if len(parts) == 1 else shapely.union_all(parts)
    raise GeometryError(f"{what} is not a valid {g.geom_type} ({shapely.is_valid_reason(g)})")


def polygon(P, what: str = "the outline"):
    """A valid polygonal region from an outline's coordinates.

    Parameters
    ----------
    P : (k, 2) array-like of float
        The ring, either orientation, closing point optional.
    what : str

    Returns
    -------
    shapely Polygon or MultiPolygon (see :func:`geometry`; possibly empty when the outline
    encloses no area).

    Raises
    ------
    GeometryError
        Non-finite or huge coordinates, fewer than 3 distinct points (shapely cannot even
        build the ring).
    """
    P = points(P, what)
    if len(np.unique(P, axis=0)) < 3:
        raise GeometryError(f"{what} has fewer than 3 distinct points, so it encloses no area")
    return geometry(shapely.Polygon(P), what)


def linestring(P, what: str = "the line"):
    """A valid shapely LineString from a polyline's coordinates.

    Parameters
    ----------
    P : (k, 2) array-like of float
    what : str

    Returns
    -------
    shapely.LineString

    Raises
    ------
    GeometryError
        Non-finite or huge coordinates, fewer than 2 distinct points.
    """
    P = points(P, what)
    if len(P) < 2 or not np.any(P != P[0]):
        raise GeometryError(f"{what} has fewer than 2 distinct points")
    return shapely.LineString(P)
