"""Depth order (thesis 4.7, last paragraph): shift the layers along z so that overlapping
layers do not interpenetrate and glued junctions meet.

Why a QP on heights and not ARAP. Every layer is a height field over the drawing plane and every
constraint is on z, so the unknown is one depth offset δ per planar vertex, shared by the
layer's front and back faces: the part's thickness 2z (its inflated shape) is kept exactly
and x, y, the outline the person drew, never move. ARAP would also move vertices in the
plane and needs a local/global loop with the active set inside each global step; here the
problem is one convex QP:

    minimise   Σ_layers  δᵀ(-L)δ + w δᵀMδ        (L cotangent Laplacian, M mass matrix)
    subject to glue rows     (equalities)  junction of a part = surface of the face below
               depth rows    (inequalities) back face of the nearer layer >= front face of
                             the farther one + gap, wherever the two overlap

The Dirichlet term lets a part move up or down as a whole for free and charges any tilt or
bend, so parts stay parallel to the drawing plane and bend only where a constraint needs it
(a thin-plate energy would leave tilts free, and the steep fold next to a junction would then
swing a whole arm far out of the plane). The small mass term ``w`` pulls parts towards the
drawing plane and makes the problem strictly convex.

Constraint sets, improving on the thesis. The thesis keeps only contour vertices and pairs each
with the *nearest* vertex below (C>= back contour of the upper layer over the front face below,
C<= front contour of the lower layer under the back face above). Contour-only rows let the
interior of a small part in front of a domed layer sink into it, and nearest-vertex rows are
off by up to half an edge on steep flanks. Here every vertex of one layer inside the other's
region is constrained, in both directions, against the exact point of the other face below or
above it (barycentric interpolation in the containing triangle, found with the core
:class:`~sketchforge.geometry.locate.TriangleLocator`, one per layer).

Solver (see :func:`solve_depth`). OSQP, asked for a little more clearance than required so
that its 1e-4 accuracy still leaves every row satisfied. If a row is still violated, a dual
active-set method (Goldfarb-Idnani, :func:`_active_set`) finishes from OSQP's active set; the
``"active_set"`` option runs it alone, from the glue rows. It adds the most violated row one
at a time and only if it is linearly independent of the working set (checked by the row's
pivot in the Cholesky factor of the working set's Schur complement), and a row leaves only
when its multiplier reaches zero along the step, so the working set never collects dependent
rows and the method ends without any anti-cycling rule. Measured on the creature (8k
unknowns, 12k rows, 177 active at the optimum): OSQP 0.4 s; the active set from OSQP's active
set about 1.5 s, from scratch about 2 s (430 steps), both to the same objective as a 1e-9 OSQP
solve. What OSQP is given (issue 12's speed work, see :func:`solve_without_free_parts` and
:func:`_osqp_screened`): the free parts are left out, each independent group of glued layers
is solved on its own, and only the rows within 3 gaps of an anchored glue-only solution go in
first (creature: 2 022 of 11 570 rows, 300 iterations in two rounds instead of 1675, CPU
~0.25 s instead of ~1.3 s; within 0.1-0.25 gaps of the exact optimum, as before). Monster
Mash's loop (every violated row becomes an equality row, rows with a negative multiplier
leave) is not used: it collects linearly dependent rows of touching faces, and then
a ridge hides the singular system and whether it ends at the optimum depends on round-off.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from scipy.linalg import cho_solve, cholesky, solve_triangular
from scipy.sparse.csgraph import connected_components

from sketchforge.plugin_api import TriangleLocator, guard, laplacian_and_mass

from .attach import FRONT, Attachment, lo_chain_index
from .cache import AssemblyCache, memo
from .errors import DepthOrderError
from .sheet import directed_edges


def _unique_edges(F: np.ndarray) -> np.ndarray:
    """:func:`.sheet.unique_edges` (the same array: (e, 2) int64, rows sorted, no repeats), with
    each edge packed into one int64 key: a 1-D unique instead of a row-wise one, ~10x faster."""
    E = np.sort(directed_edges(F), axis=1)
    n = int(F.max(initial=0)) + 1
    key = np.unique(E[:, 0] * n + E[:, 1])
    return np.c_[key // n, key % n].astype(np.int64)


class _Rows:
    """Accumulates sparse constraint rows  Σ coef·δ[col]  (op)  rhs."""

    def __init__(self):
        self.r, self.c, self.v, self.b, self.pair = [], [], [], [], []
        self.m = 0

    def add(self, cols: np.ndarray, coefs: np.ndarray, rhs: np.ndarray, pair=(-1, -1)) -> None:
        """cols, coefs (k, w); rhs (k,): k rows of w terms each; pair: (front, back) layers."""
        k, w = cols.shape
        self.pair.append(np.tile(pair, (k, 1)))
        self.r.append(np.repeat(np.arange(self.m, self.m + k), w))
        self.c.append(cols.ravel())
        self.v.append(coefs.ravel())
        self.b.append(rhs)
        self.m += k

    def add_block(self, other: _Rows, colmap, layers) -> None:
        """Append the rows of ``other`` (columns and pairs numbered within it) with each column
        c replaced by ``colmap(c)`` and each pair entry p by ``layers[p]``."""
        layers = np.asarray(layers)
        for r, c, v, b, pair in zip(other.r, other.c, other.v, other.b, other.pair):
            self.r.append(r + self.m)
            self.c.append(colmap(c))
            self.v.append(v)
            self.b.append(b)
            self.pair.append(layers[pair])
        self.m += other.m

    def matrix(self, n: int):
        if self.m == 0:
            return sp.csr_matrix((0, n)), np.zeros(0)
        A = sp.csr_matrix(
            (np.concatenate(self.v), (np.concatenate(self.r), np.concatenate(self.c))), shape=(self.m, n)
        )
        return A, np.concatenate(self.b)


def build_problem(sheets, offsets, front_off, back_off, attachments: list[Attachment], gap: float, reg: float,
                  stiffness: float = 20.0, glue_lift=None, springs=None, cache: AssemblyCache | None = None,
                  locators: dict | None = None):
    """Assemble the QP of the module docstring.

    Parameters
    ----------
    sheets : list of Sheet
        After junction insertion.
    offsets : (k+1,) int64
        Start of each sheet's block in the unknown vector δ.
    front_off, back_off : list of (n_i,) float64
        Fixed height of each face relative to δ: front z = δ + front_off, back z = δ - back_off
        (the layer's height plus the front/back margin).
    attachments : list of Attachment
    gap : float
        Clearance required between overlapping layers.
    reg : float
        Weight of the pull towards the drawing plane, relative to the drawing's size.
    stiffness : float
        Energy factor of a layer that other parts are glued to. A part bends to fit the layer
        it hangs from, never the other way round: drawing a leg behind a body must not dent or
        bump the body's front. (A stiff layer also stays locally planar at the slit, where the
        part folds away from it, so the two piecewise-linear faces do not cross between
        vertices.)
    glue_lift : list of (c,) float64, optional
        Per attachment, how far the part's facing junction chain lies off the face below,
        towards the part (the height of the blended junction's "+" lip and strip, see
        :mod:`.blend`); default 0.
    springs : list, optional
        Per attachment, soft rows ``(part_cols, host_cols, bary, weight, target)`` (sheet-local
        indices) added to the objective as  weight·(δ_part - Σ bary·δ_host - target)²
        (:func:`.blend.blend_junctions`).
    cache : AssemblyCache, optional
        Memo of each sheet's Laplacian, mass, edges, outline and locator and of each
        overlapping pair's depth rows (see :mod:`.cache`); the problem is bit-identical with
        or without it.
    locators : dict of int -> TriangleLocator, optional
        Point location per sheet index, filled as needed; pass the one
        :func:`.blend.blend_junctions` filled to build each sheet's locator once.

    Returns
    -------
    P : (N, N) csc, q (N,), Aeq (e, N), beq (e,), Ain (r, N), bin (r,), info : dict
    """
    N = int(offsets[-1])
    allxy = np.vstack([s.xy for s in sheets])
    diag = float(np.linalg.norm(allxy.max(0) - allxy.min(0))) or 1.0
    w = reg / diag**2
    blocks, blocks_m = [], []
    mesh_keys = [(s.xy, s.F, s.Fb) for s in sheets]
    for s, mk in zip(sheets, mesh_keys):
        # Every sheet's xy and F passed guard.mesh in the plane once, where they were made
        # (sheet_from_mesh, or insert_chains for a sheet with junctions cut in): not again.
        L, M = memo(cache, "laplacian", mk, lambda s=s: _sheet_operators(s))
        k = 1.0 + (stiffness if s.chains else 0.0)
        blocks.append((k * (-L) + w * M).tocsc())
        blocks_m.append(M)
    P = sp.block_diag(blocks, format="csc")
    q_springs = np.zeros(N)
    if springs:
        rows, cols, vals, wts, tgt = [], [], [], [], []
        m = 0
        for at, (pc, hc, bary, wt, target) in zip(attachments, springs):
            k = len(pc)
            r = np.arange(m, m + k)
            rows += [r, np.repeat(r, hc.shape[1])]
            cols += [offsets[at.upper] + pc, (offsets[at.lower] + hc).ravel()]
            vals += [np.ones(k), -bary.ravel()]
            wts.append(wt)
            tgt.append(target)
            m += k
        R = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m, N))
        wt, target = np.concatenate(wts), np.concatenate(tgt)
        P = (P + R.T @ sp.diags(wt) @ R).tocsc()
        q_springs = -(R.T @ (wt * target))

    eq, ineq = _Rows(), _Rows()
    glued: dict[tuple[int, int], list[np.ndarray]] = {}
    for a_i, at in enumerate(attachments):
        up, lo = sheets[at.upper], sheets[at.lower]
        j = up.junction
        c = lo.chains[lo_chain_index(attachments, a_i)]
        cols = np.c_[offsets[at.upper] + j, offsets[at.lower] + c]
        coefs = np.tile([1.0, -1.0], (len(j), 1))
        if at.side == FRONT:  # back chain of the part lies on the front face below
            rhs = front_off[at.lower][c] + back_off[at.upper][j]
        else:  # front chain of the part lies on the back face above
            rhs = -back_off[at.lower][c] - front_off[at.upper][j]
        if glue_lift is not None:
            rhs = rhs + (1.0 if at.side == FRONT else -1.0) * glue_lift[a_i]
        eq.add(cols, coefs, rhs)
        key = (min(at.upper, at.lower), max(at.upper, at.lower))
        glued.setdefault(key, [])
        glued[key].append(("u", at.upper, j))
        glued[key].append(("l", at.lower, c))

    polys = [memo(cache, "polygon", (s.xy, s.boundary, s.holes), s.polygon) for s in sheets]
    # once per sheet and face, not once per overlapping pair
    front_edges = [memo(cache, "edges", (s.F,), lambda s=s: _unique_edges(s.F)) for s in sheets]
    back_edges = [e if s.Fb is None else memo(cache, "edges", (s.Fb,), lambda s=s: _unique_edges(s.Fb))
                  for s, e in zip(sheets, front_edges)]
    # point location, once per sheet face that overlaps another (shared with the fillets' springs)
    locators: dict = {} if locators is None else locators

    def loc(i, side):
        return face_locator(locators, cache, sheets, i, side)

    def off_face(i, side):
        """1 for the vertices the face does not use: no depth row is written for them."""
        return (~sheets[i].on_face(side)).astype(np.float64)

    n_pairs = 0
    for i in range(len(sheets)):
        for k in range(i + 1, len(sheets)):
            if not polys[i].intersects(polys[k]):
                continue
            overlap = polys[i].intersection(polys[k])
            if overlap.area <= 0:
                continue
            n_pairs += 1
            skip = {i: np.zeros(sheets[i].n), k: np.zeros(sheets[k].n)}
            for _, layer, idx in glued.get((i, k), []):
                skip[layer][idx] = 1.0

            def rows(i=i, k=k, overlap=overlap, skip=skip):
                # Columns numbered within the pair (sheet i first, then k), so that the rows of
                # an unchanged pair are the same wherever the two sheets sit in δ. Layer i's
                # front face meets layer k's back face: each side's own triangulation.
                local = {i: 0, k: sheets[i].n}
                out = _Rows()
                fk, fi = sheets[k].face(-1), sheets[i].face(1)
                # C>=: vertices of the nearer layer k over layer i: back_k(v) - front_i(p) >= gap.
                _pair_rows(out, sheets, local, k, i, loc(i, 1), fi, np.maximum(skip[k], off_face(k, -1)), skip[i],
                           back_off[k], front_off[i], gap, +1)
                # C<=: vertices of layer i under layer k: back_k(p) - front_i(v) >= gap.
                _pair_rows(out, sheets, local, i, k, loc(k, -1), fk, np.maximum(skip[i], off_face(i, 1)), skip[k],
                           front_off[i], back_off[k], gap, -1)
                # and where their edges cross
                _crossing_rows(out, sheets, local, k, i, back_edges[k], front_edges[i], overlap, skip[k], skip[i],
                               back_off[k], front_off[i], gap)
                out.pair = [np.where(pr == i, 0, 1) for pr in out.pair]  # 0: sheet i, 1: sheet k
                return out

            block = memo(cache, "pair_rows", mesh_keys[i] + mesh_keys[k] + (
                sheets[i].boundary, sheets[i].holes, sheets[k].boundary, sheets[k].holes, skip[i], skip[k],
                front_off[i], back_off[k], sheets[i].h, sheets[k].h, float(gap)), rows)
            n_i = sheets[i].n

            def colmap(c, a=int(offsets[i]), b=int(offsets[k]) - n_i, n_i=n_i):
                return np.where(c < n_i, c + a, c + b)

            ineq.add_block(block, colmap, (i, k))
    Aeq, beq = eq.matrix(N)
    Ain, bin_ = ineq.matrix(N)
    # Rest depth of each layer: the constant offsets that stack the layers back to front
    # with every depth row satisfied (rows are  δ_front - δ_back >= rhs  for constant δ). The
    # mass term pulls towards this stack rather than towards the drawing plane, so away from
    # junctions the parts float clear of each other and only the rows near the glue become
    # active; pulling towards z = 0 instead pressed every overlap together and made thousands
    # of rows active. Free parts stacked this way hover over the layers they were drawn on
    # (those layers move in the solve); settle_free_parts lowers them afterwards.
    rest = np.zeros(len(sheets))  # (layers,)
    pairs = np.vstack(ineq.pair) if ineq.pair else np.zeros((0, 2), np.int64)
    for f in range(len(sheets)):
        mine = pairs[:, 0] == f
        if mine.any():
            rest[f] = max(0.0, float(np.max(rest[pairs[mine, 1]] + bin_[mine])))
    q = np.concatenate([-w * blocks_m[i] @ np.full(s.n, rest[i]) for i, s in enumerate(sheets)]) + q_springs
    return P, q, Aeq, beq, Ain, bin_, {"overlapping_pairs": n_pairs, "reg_weight": w, "rest_depth": rest.tolist()}


def _sheet_operators(s):
    """(L, M) of a sheet: its cotangent Laplacian and mass; with one triangulation per face
    (``Fb``), the mean of the two faces' operators, so every vertex of either face is in the
    energy and a sheet cut on one face only keeps the operators it always had."""
    L, M = laplacian_and_mass(s.xy, s.F, checked=True)
    if s.Fb is None:
        return L, M
    Lb, Mb = laplacian_and_mass(s.xy, s.Fb, checked=True)
    return ((L + Lb) * 0.5).tocsc(), ((M + Mb) * 0.5).tocsc()


def face_locator(locators: dict, cache, sheets, i: int, side: int) -> TriangleLocator:
    """The point locator of face ``side`` of sheet ``i``, made once (keyed by the face's
    triangulation: a sheet with one triangulation shares it between its faces)."""
    s = sheets[i]
    F = s.face(side)
    key = (i, 1 if F is s.F else -1)
    if key not in locators:
        locators[key] = memo(cache, "locator", (s.xy, F), lambda: TriangleLocator(s.xy, F))
    return locators[key]


def _pair_rows(rows, sheets, offsets, q, o, loc_o, F_o, skip_q, skip_o, off_q, off_o, gap, sign):
    """Rows for the vertices of sheet q lying over sheet o.

    sign=+1: q is in front (its back face, δ_q - off_q, must clear o's front face δ_o + off_o).
    sign=-1: q is behind (its front face δ_q + off_q must stay under o's back face δ_o - off_o).
    Row:  sign·(δ_q(v) - Σ bary·δ_o)  >=  gap' + off_q(v) + Σ bary·off_o,
    where gap' shrinks to 0 as the point nears glued junction vertices (the faces meet there).
    ``loc_o``: the :class:`~sketchforge.geometry.locate.TriangleLocator` of sheet o (a point on
    its outline, up to round-off, counts as inside).
    """
    sq = sheets[q]
    cand = np.flatnonzero(skip_q == 0)
    face, bary = loc_o.locate(sq.xy[cand])
    inside = face >= 0
    cand, tri, bary = cand[inside], F_o[face[inside]], bary[inside]
    if len(cand) == 0:
        return
    bary = np.clip(bary, 0.0, 1.0)  # a point of the triangle (barycentrics may be -1e-10 on edges)
    bary /= bary.sum(axis=1, keepdims=True)
    cols = np.c_[offsets[q] + cand, offsets[o] + tri]
    coefs = sign * np.c_[np.ones(len(cand)), -bary]
    g = gap * (1.0 - np.sum(bary * skip_o[tri], axis=1))
    rhs = g + off_q[cand] + np.sum(bary * off_o[tri], axis=1)
    rows.add(cols, coefs, rhs, (q, o) if sign > 0 else (o, q))


def _crossing_rows(rows, sheets, offsets, k, i, ek, ei, region, skip_k, skip_i, back_k, front_i, gap):
    """Rows where an edge of the nearer sheet k crosses an edge of sheet i in the plane.

    Vertex rows alone leave the two piecewise-linear faces free to cross inside a cell of their
    overlay, whose corners are the vertices of both meshes *and* these edge crossings; with
    rows at both, back_k - front_i >= gap holds on every overlay corner, so (being linear on
    each cell) everywhere: no intersection is left between vertices, even where both faces
    are steep (a junction near the outline of the layer below).
    Row: back_k(p) - front_i(p) >= gap' at the crossing p. ``ek``, ``ei``: the sheets'
    undirected edges (:func:`.sheet.unique_edges`).
    """
    from scipy.spatial import cKDTree

    sk, si = sheets[k], sheets[i]
    x0, x1, y0, y1 = region.bounds[0], region.bounds[2], region.bounds[1], region.bounds[3]

    def in_box(xy, e):
        m = 0.5 * (xy[e[:, 0]] + xy[e[:, 1]])
        pad = 2.0 * max(sk.h, si.h)
        return e[(m[:, 0] > x0 - pad) & (m[:, 0] < x1 + pad) & (m[:, 1] > y0 - pad) & (m[:, 1] < y1 + pad)]

    ek, ei = in_box(sk.xy, ek), in_box(si.xy, ei)
    if len(ek) == 0 or len(ei) == 0:
        return
    a, b = sk.xy[ek[:, 0]], sk.xy[ek[:, 1]]
    c, d = si.xy[ei[:, 0]], si.xy[ei[:, 1]]
    lk = np.linalg.norm(b - a, axis=1)
    li = np.linalg.norm(d - c, axis=1)
    tk, ti = cKDTree(0.5 * (a + b)), cKDTree(0.5 * (c + d))
    # every pair of edges whose midpoints are within the longest half-edges of each other (pairs
    # at distance 0 included), as arrays rather than Python lists, in a fixed order
    near = tk.sparse_distance_matrix(ti, 0.5 * (lk.max() + li.max()), output_type="ndarray")
    # two segments that cross have midpoints within half their summed lengths
    near = near[near["v"] <= 0.5 * (lk[near["i"]] + li[near["j"]]) * (1 + 1e-9)]
    order = np.lexsort((near["j"], near["i"]))
    pk, pi = near["i"][order].astype(np.int64), near["j"][order].astype(np.int64)
    if len(pk) == 0:
        return
    r, sv = b[pk] - a[pk], d[pi] - c[pi]
    den = r[:, 0] * sv[:, 1] - r[:, 1] * sv[:, 0]
    w = c[pi] - a[pk]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (w[:, 0] * sv[:, 1] - w[:, 1] * sv[:, 0]) / den
        t = (w[:, 0] * r[:, 1] - w[:, 1] * r[:, 0]) / den
    eps = 1e-9
    ok = (np.abs(den) > 1e-14) & (s > eps) & (s < 1 - eps) & (t > eps) & (t < 1 - eps)
    pk, pi, s, t = pk[ok], pi[ok], s[ok], t[ok]
    if len(pk) == 0:
        return
    A, B = ek[pk, 0], ek[pk, 1]
    C, D = ei[pi, 0], ei[pi, 1]
    cols = np.c_[offsets[k] + A, offsets[k] + B, offsets[i] + C, offsets[i] + D]
    coefs = np.c_[1 - s, s, -(1 - t), -t]
    glued = np.maximum((1 - s) * skip_k[A] + s * skip_k[B], (1 - t) * skip_i[C] + t * skip_i[D])
    rhs = (gap * (1.0 - glued) + (1 - s) * back_k[A] + s * back_k[B] + (1 - t) * front_i[C] + t * front_i[D])
    rows.add(cols, coefs, rhs, (k, i))


#: Memory the active-set method may hold (bytes): its cached columns P⁻¹cᵀ (8·N bytes per row
#: ever probed), the working-set buffer and the Schur factors. The creature needs ~20 MB; a
#: problem that would need more is not converging towards anything a person could use (a
#: planted sign error in the back glue once grew the assembly to 24 GB before the kernel killed
#: it), so it stops with a clear error instead.
MEMORY_BUDGET = 1 << 30


def solve_depth(P, q, Aeq, beq, Ain, bin_, method: str = "osqp", pad: float = 0.0, tol: float = 1e-10,
                max_iter: int | None = None, memory_budget: int = MEMORY_BUDGET):
    """Solve  min ½δᵀPδ + qᵀδ  s.t.  Aeq δ = beq,  Ain δ >= bin_.

    Parameters
    ----------
    P : (N, N) sparse, symmetric positive definite
    q : (N,) float64
    Aeq : (e, N) sparse, beq : (e,)
    Ain : (r, N) sparse, bin_ : (r,)
    method : {"osqp", "active_set"}
        "osqp" (default): OSQP to 1e-4 on the rows tightened by ``pad``, so that its residual
        still leaves every true row satisfied (measured on the creature: 1300 iterations,
        0.4 s, objective within 0.2% of a 1e-5 solve that needs 20000 iterations), given the
        rows near an anchored glue-only solution first (:func:`_osqp_screened`), its glue
        residual then closed to round-off (:func:`_polish_glue`); if some depth row is still
        violated, the dual active-set method (:func:`_active_set`) finishes from
        OSQP's active set; all that only when the glue-only optimum leaves some depth row
        violated (otherwise it is the exact answer, ``info["exact"]``: see the comment in the
        code). "active_set": the active-set method alone, from the equality rows.
    pad : float
        Extra clearance asked of OSQP (a fraction of the gap).
    tol : float
        Violation of a depth row that the active-set method accepts.
    max_iter : int, optional
        Safety net on the active-set steps (default: ten per row, at least 1000).
    memory_budget : int
        Bytes the active-set method may hold (default :data:`MEMORY_BUDGET`); OSQP is bounded
        by its 20000 iterations.

    Returns
    -------
    delta : (N,) float64
    info : dict
        ``osqp_iterations``, ``iterations`` (active-set steps, 0 if not needed), ``active``.

    Raises
    ------
    DepthOrderError
        The rows cannot all be satisfied, or the active-set method did not finish within
        ``max_iter`` steps or ``memory_budget`` bytes.
    GeometryError
        The problem has a NaN, an infinity outside the bounds or inconsistent shapes; checked
        before either solver runs, in the form that solver reads (:func:`guard.qp` for OSQP,
        :func:`guard.objective` and :func:`guard.constraints` for the active set alone).
    """
    what = "the depth-order problem"
    info = {"method": method, "osqp_iterations": 0, "iterations": 0}
    warm = np.zeros(0, np.int64)
    if method == "osqp":
        # OSQP takes the glue and depth rows as one matrix: the guard checks it in that form
        # (the active-set fallback below reads the same rows apart, as CSR).
        Ain, Aeq = sp.csr_matrix(Ain), sp.csr_matrix(Aeq)
        P, q, _, _, _ = guard.qp(P, q, sp.vstack([Aeq, Ain]).tocsc(), np.r_[beq, bin_ + pad],
                                 np.r_[beq, np.full(len(bin_), np.inf)], what)
        # The glue-only optimum first: where it satisfies every depth row, it is the QP's exact
        # optimum (no depth row is active) and no iterative solver is needed. Measured (issue 39,
        # benchmarks/bench_depth_qp.py, 10 QPs: the example creature, its 3-layer part, 8 seeded
        # random creatures): that held for all ten. OSQP at 1e-4 on the padded rows ended up to
        # 17 gaps from it on the creature (39 with polishing on, which is also slower); the
        # interior-point Clarabel and PIQP reach it within 1e-3 gap in 3x and 1.6x OSQP's time;
        # the active set alone exactly, in 6x. This solve costs about half an OSQP run (27 ms on
        # the creature, where OSQP took 57); where some row is active, OSQP and the active set
        # below take over as before.
        x = _equality_solution(P, q, Aeq, beq)
        if x is not None and (len(bin_) == 0 or np.min(Ain @ x - bin_) >= 0.0):
            info["exact"] = True
            info["active"] = int(np.sum(Ain @ x - bin_ <= pad + 1e-6)) if len(bin_) else 0
            return x, info
        x, y, osqp_info = _osqp_screened(P, q, Aeq, beq, Ain, bin_, pad)
        info.update(osqp_info)
        x = _polish_glue(x, Aeq, beq)
        if np.all(np.isfinite(x)) and (len(bin_) == 0 or np.min(Ain @ x - bin_) >= 0.0):
            info["active"] = int(np.sum(Ain @ x - bin_ <= pad + 1e-6)) if len(bin_) else 0
            return x, info
        if len(y) and np.all(np.isfinite(y)):
            # OSQP's multipliers of the rows >= are <= 0; strongest rows first
            warm = np.flatnonzero(y < -1e-9 * max(1.0, float(np.abs(y).max())))
            warm = warm[np.argsort(y[warm], kind="stable")]
    else:
        # The active-set method alone reads the glue and depth rows apart, row by row (CSR):
        # each kind is checked in that form, and nothing is stacked for OSQP.
        P, q = guard.objective(P, q, what)
        Aeq, beq, _ = guard.constraints(Aeq, beq, beq, P.shape[0], what, fmt="csr")
        Ain, bin_, _ = guard.constraints(Ain, bin_, None, P.shape[0], what, fmt="csr")
    if max_iter is None:
        max_iter = max(1000, 10 * (len(bin_) + len(beq)))
    x, it, active = _active_set(P, q, Aeq, beq, Ain, bin_, warm, tol, max_iter, memory_budget)
    info["iterations"] = it
    info["active"] = len(active)
    return x, info


#: Rows whose slack at the screening guess is below this many pads go to OSQP's first round
#: (see :func:`_osqp_screened`); 6 pads = 3 gaps.
SCREEN_PADS = 6.0
#: OSQP's absolute and relative tolerance (see :func:`solve_depth`).
EPS = 1e-4


#: How much harder the screening guess pulls towards the rest depths (see :func:`_screening_guess`).
ANCHOR = 1000.0


def _screening_guess(P, q, Aeq, beq):
    """(N,) the glue-only solution with the pull towards the rest depths ``ANCHOR`` times
    stronger, or None (see :func:`_equality_solution`).

    Why. The plain glue-only solution lets every part swing through the layer it hangs from
    (the creature: 4 532 of 11 570 rows violated there, 72 gaps off the optimum), so nearly
    half the rows look relevant. Anchored, the parts stay near their rest stack and only the
    rows near the junctions come close (creature: 2 022 rows, 300 iterations in two rounds
    instead of 475 in one). Only a guess: which rows go in first and where OSQP starts, never
    the answer. The pull's weight is read off P: the energy's only term that does not vanish
    on a constant offset is the mass term (Laplacian and springs are differences), so
    P·1 = w·M·1, and q = -w·M·rest on those rows.
    """
    d = np.maximum(np.asarray(P @ np.ones(P.shape[0])).ravel(), 0.0)
    Pa = (P + sp.diags(ANCHOR * d)).tocsc()
    qa = q + ANCHOR * np.where(d > 0, q, 0.0)
    if len(beq):
        # libigl's sparse LDLᵀ with the glue rows: half the time of SuperLU on the KKT matrix
        # (creature 17 vs 36 ms, same answer to 1e-13). P, q and the rows passed the guard in
        # solve_depth; the anchored P is P plus a non-negative diagonal.
        import igl

        try:
            x = np.asarray(igl.min_quad_with_fixed(Pa, qa[:, None], np.zeros(0, np.int64), np.zeros((0, 1)),
                                                   sp.csc_matrix(Aeq), np.asarray(beq, np.float64)[:, None],
                                                   True)).ravel()
        except (RuntimeError, ValueError, TypeError):  # failed factorisation, other binding: SuperLU
            x = None
        if x is not None and x.shape == (P.shape[0],) and np.all(np.isfinite(x)):
            return x
    return _equality_solution(Pa, qa, Aeq, beq)


def _equality_solution(P, q, Aeq, beq):
    """(N,) minimiser of ½δᵀPδ + qᵀδ subject to the glue rows alone (one sparse LU of the KKT
    matrix), or None when the glue rows make it singular (then nothing is screened)."""
    N = P.shape[0]
    try:
        if len(beq) == 0:
            return sla.splu(sp.csc_matrix(P), permc_spec="COLAMD").solve(-q)
        K = sp.bmat([[P, Aeq.T], [Aeq, None]], format="csc")
        x = sla.splu(K, permc_spec="COLAMD").solve(np.r_[-q, beq])[:N]
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        return None
    return x if np.all(np.isfinite(x)) else None


def _polish_glue(x, Aeq, beq):
    """(N,) x moved by the least amount (Euclidean) that makes every glue row hold to
    round-off: x - Aeqᵀ(Aeq Aeqᵀ)⁻¹(Aeq x - beq); x itself when there is nothing to do or the
    glue rows are dependent (the active set then judges them).

    Why. OSQP meets its rows only to its tolerance (1e-4, scaled): with the blended junction's
    lifted glue and springs the glue rows were left 1.3e-4 off on the creature (8e-8 with the
    plain sleeve). A glue row is one vertex of a part equal to a point of the face below, so
    its residual is a sub-micro step between what stitching then treats as one vertex: closing
    it exactly costs one tiny solve (e rows, two terms each, ~60 on the creature) where
    tightening OSQP would cost iterations on every row. The move is of the residual's size,
    far below the ``pad`` of clearance OSQP leaves on each depth row, and the caller still
    checks every depth row afterwards.
    """
    if len(beq) == 0 or not np.all(np.isfinite(x)):
        return x
    Aeq = sp.csr_matrix(Aeq)
    r = Aeq @ x - beq
    try:
        lam = sla.splu(sp.csc_matrix(Aeq @ Aeq.T), permc_spec="NATURAL").solve(r)
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        return x
    if not np.all(np.isfinite(lam)):
        return x
    return x - Aeq.T @ lam


def _osqp_screened(P, q, Aeq, beq, Ain, bin_, pad, rounds: int = 6):
    """OSQP on the rows that can matter, grown until every row holds.

    Why. Of the ~11k depth rows of the creature fewer than 200 are active at the optimum, and
    OSQP's cost per iteration (and, measured, its iteration count) grows with the rows it
    carries. The rows whose slack at an anchored glue-only solution (:func:`_screening_guess`)
    is below ``SCREEN_PADS`` pads go to the first round, from that solution; any other row that
    the round's answer leaves closer than that joins and OSQP runs again, warm-started. A
    solution of fewer rows that satisfies all of them solves the whole problem (the rows left
    out are inactive), so the answer is the same QP's, to OSQP's accuracy; the caller still
    checks every row. Without ``pad`` (no scale to screen with) every row goes in at once.

    Returns
    -------
    x : (N,) float64, y : (r,) float64
        OSQP's answer and its multipliers of the depth rows (0 on rows never given to it).
    info : dict
        ``osqp_iterations`` (all rounds), ``osqp_status``, ``osqp_rounds``, ``osqp_rows``.
    """
    import osqp

    r = len(bin_)
    x0 = _screening_guess(P, q, Aeq, beq) if pad > 0 and r else None
    if x0 is None:
        use = np.ones(r, bool)
    else:
        use = Ain @ x0 - bin_ < SCREEN_PADS * pad
    Pu = sp.triu(P).tocsc()
    y_all = np.zeros(r)
    y_eq = np.zeros(len(beq))
    info = {"osqp_iterations": 0, "osqp_rounds": 0}
    x = x0
    for _ in range(rounds):
        rows = np.flatnonzero(use)
        A = sp.vstack([Aeq, Ain[rows]]).tocsc()
        solver = osqp.OSQP()
        solver.setup(P=Pu, q=q, A=A, l=np.r_[beq, bin_[rows] + pad], u=np.r_[beq, np.full(len(rows), np.inf)],
                     verbose=False, eps_abs=EPS, eps_rel=EPS, polishing=False, max_iter=20000,
                     adaptive_rho_interval=25)
        if x is not None:
            solver.warm_start(x=x, y=np.r_[y_eq, y_all[rows]])
        # a status other than "solved" is handled by the caller (feasibility check, then the active set)
        res = solver.solve(raise_error=False)
        info["osqp_iterations"] += int(res.info.iter)
        info["osqp_rounds"] += 1
        info["osqp_status"] = str(res.info.status)
        info["osqp_rows"] = int(len(rows))
        x = np.asarray(res.x)
        y = np.asarray(res.y)
        y_eq = y[:len(beq)]
        y_all = np.zeros(r)
        y_all[rows] = y[len(beq):]
        if not np.all(np.isfinite(x)) or r == 0:
            break
        grow = ~use & (Ain @ x - bin_ < SCREEN_PADS * pad)
        if not grow.any():
            break
        use |= grow
    return x, y_all, info


class _WorkingSet:
    """Working set of the active-set method in range-space form.

    P is factorised once; row c of the working set keeps z = P⁻¹cᵀ (computed once per row that
    ever enters, in ``cache``) and G = C P⁻¹ Cᵀ is held as its Cholesky factor L alone (G itself
    is never solved with), grown by one row and column per added row: the new pivot
    g_pp - |L⁻¹g|² is the squared distance (in the
    P⁻¹ metric) of the row from the span of the working set, so a row that is linearly
    dependent on the set shows up as a pivot at round-off level and is never added. The z of
    the rows in the set live in the columns ``slot`` of one buffer (a row that leaves frees its
    column, nothing is copied), so x = x0 + Z λ is one product over the buffer.
    """

    def __init__(self, lu, Aeq, Ain, x0, beq, bin_, budget=MEMORY_BUDGET):
        self.lu, self.Aeq, self.Ain = lu, Aeq, Ain
        self.budget = budget
        self.x0 = x0
        self.eq_cx0, self.in_cx0 = Aeq @ x0, Ain @ x0
        self.beq, self.bin_ = beq, bin_
        self.cache: dict[int, np.ndarray] = {}  # row key -> P⁻¹cᵀ; keys: depth row r >= 0, glue row i -> -1 - i
        self.keys: list[int] = []
        self.slot: list[int] = []
        self.free: list[int] = []
        self.Z = np.zeros((len(x0), 16))
        self.used = 0  # columns of Z ever used
        self.L = np.zeros((0, 0))

    @property
    def m(self):
        return len(self.keys)

    def check_budget(self, new_columns: int = 0, z_columns: int | None = None, m: int | None = None) -> None:
        """Refuse to grow past the memory budget (before allocating, so nothing is ever
        half-grown): cached and buffered columns of N floats, and the m×m factor L."""
        n = len(self.x0)
        z_columns = self.Z.shape[1] if z_columns is None else z_columns
        m = self.m if m is None else m
        need = 8 * n * (len(self.cache) + new_columns + z_columns) + 8 * m * m
        if need > self.budget:
            raise DepthOrderError(
                f"The depth-order solve stopped: it needed {need / 2**20:.0f} MB, over its budget of "
                f"{self.budget / 2**20:.0f} MB ({len(self.cache) + new_columns} rows in play); the layers are "
                "glued and stacked in a way it cannot resolve. Reorder or redraw the parts."
            )

    def row(self, key):
        A, r = (self.Ain, key) if key >= 0 else (self.Aeq, -1 - key)
        s, e = A.indptr[r], A.indptr[r + 1]
        return A.indices[s:e], A.data[s:e]

    def z(self, keys):
        """P⁻¹cᵀ of each row (one solve for all the missing ones)."""
        ins = [k for k in keys if k >= 0 and k not in self.cache]
        eqs = [-1 - k for k in keys if k < 0 and k not in self.cache]
        self.check_budget(new_columns=len(ins) + len(eqs))
        for A, rows, key in ((self.Ain, ins, lambda r: r), (self.Aeq, eqs, lambda i: -1 - i)):
            if rows:
                Zn = self.lu.solve(A[rows].T.toarray())
                for c, r in enumerate(rows):
                    self.cache[key(r)] = Zn[:, c]
        return [self.cache[k] for k in keys]

    def spread(self, v):
        """(m,) coefficients of the rows in the set -> (used,) coefficients of Z's columns."""
        out = np.zeros(self.used)
        out[self.slot] = v
        return out

    def probe(self, key):
        """For a row c not in the set: z = P⁻¹cᵀ, r = G⁻¹ C z, the pivot c z - (C z)ᵀ G⁻¹ (C z), c z,
        and l = L⁻¹ C z (to add the row)."""
        (zp,) = self.z([key])
        cols, vals = self.row(key)
        cz = float(vals @ zp[cols])
        if self.m == 0:
            return zp, np.zeros(0), cz, cz, np.zeros(0)
        g = vals @ self.Z[cols][:, self.slot]  # C P⁻¹ cᵀ (P symmetric)
        l = solve_triangular(self.L, g, lower=True, check_finite=False)
        r = solve_triangular(self.L, l, lower=True, trans="T", check_finite=False)
        return zp, r, cz - float(l @ l), cz, l

    def add(self, key, zp, l, piv):
        m = self.m
        full = not self.free and self.used == self.Z.shape[1]
        self.check_budget(z_columns=self.Z.shape[1] * (2 if full else 1), m=m + 1)
        if self.free:
            j = self.free.pop()
        else:
            if self.used == self.Z.shape[1]:
                self.Z = np.concatenate([self.Z, np.zeros_like(self.Z)], axis=1)
            j = self.used
            self.used += 1
        self.Z[:, j] = zp
        L = np.zeros((m + 1, m + 1))
        L[:m, :m] = self.L
        L[m, :m] = l
        L[m, m] = np.sqrt(piv)
        self.L = L
        self.keys.append(key)
        self.slot.append(j)

    def remove(self, j):
        """Drop the j-th row of the set. The factor keeps its leading block; only the trailing
        block is refactorised (L33 L33ᵀ + l l ᵀ, with l the dropped column below the diagonal)."""
        m = self.m
        self.free.append(self.slot.pop(j))
        del self.keys[j]
        keep = np.r_[0:j, j + 1:m]
        L = self.L[np.ix_(keep, keep)]
        if j < m - 1:
            l = self.L[j + 1:, j]
            T = self.L[j + 1:, j + 1:]
            L[j:, j:] = cholesky(T @ T.T + np.outer(l, l), lower=True, check_finite=False)
        self.L = L

    def minimiser(self):
        """x minimising the energy with every row of the set an equality, and its multipliers."""
        if self.m == 0:
            return self.x0.copy(), np.zeros(0)
        k = np.asarray(self.keys)
        # Each kind of row indexes only its own arrays: with no glue rows (or no depth rows)
        # the other array is empty, and np.where would index it anyway (IndexError).
        ins = k >= 0
        i, e = k[ins], -1 - k[~ins]
        rhs = np.empty(len(k))
        rhs[ins] = self.bin_[i] - self.in_cx0[i]
        rhs[~ins] = self.beq[e] - self.eq_cx0[e]
        lam = cho_solve((self.L, True), rhs, check_finite=False)
        return self.x0 + self.Z[:, :self.used] @ self.spread(lam), lam


def _active_set(P, q, Aeq, beq, Ain, bin_, warm, tol, max_iter, memory_budget=MEMORY_BUDGET):
    """Dual active-set method (Goldfarb & Idnani 1983) in range-space form.

    Why a dual method. A primal active-set method needs a feasible start, which is exactly what
    is missing when OSQP leaves a row violated. The dual method starts from any minimiser of
    the energy on a working set W of independent rows with multipliers >= 0 (the equality rows
    alone, or OSQP's active set cleaned up below) and keeps that true while it adds the most
    violated row p: it moves x along z = P⁻¹(c_pᵀ - Cᵀr) (r = G⁻¹ C P⁻¹ c_pᵀ), which keeps the
    rows of W tight, and lowers their multipliers by t·r while p's grows by t. The step is the
    smaller of the full step that makes p tight (then p joins W) and the partial step at which
    the first multiplier of W reaches 0 (that row leaves W and the step continues). A row p
    linearly dependent on W (Schur pivot at round-off level relative to c_p P⁻¹ c_pᵀ) is never
    added: only multipliers move (a pure dual step) until a row of W leaves; if none can leave,
    W already implies c_p x <= its current value and the rows are infeasible (up to round-off:
    a violation at round-off level is accepted). For a strictly convex QP the dual objective
    strictly increases, so no working set repeats and the method ends in finitely many steps,
    with no anti-cycling rule.

    Warm start. OSQP's active rows (strongest multiplier first) enter W while independent
    (pivot check); then the row with the most negative multiplier leaves, one at a time, until
    all are >= 0: a valid start for the dual method.

    Returns
    -------
    x : (N,) float64, steps : int, active : (a,) int64 depth rows in the final working set.
    """
    lu = sla.splu(sp.csc_matrix(P), permc_spec="COLAMD")
    x0 = lu.solve(-q)
    W = _WorkingSet(lu, Aeq, Ain, x0, beq, bin_, memory_budget)
    dep = 1e-10  # relative pivot below which a row counts as dependent on the working set
    scale = 1.0 + float(np.abs(bin_).max(initial=0.0)) + float(np.abs(beq).max(initial=0.0))

    def try_add(key):
        zp, _, piv, cz, l = W.probe(key)
        if piv > dep * cz:
            W.add(key, zp, l, piv)

    W.z([-1 - i for i in range(len(beq))] + [int(k) for k in warm])
    for i in range(len(beq)):
        try_add(-1 - i)
    n_eq = W.m
    for k in warm:
        try_add(int(k))
    x, lam = W.minimiser()
    while W.m > n_eq and lam[n_eq:].min() < 0.0:
        W.remove(n_eq + int(np.argmin(lam[n_eq:])))
        x, lam = W.minimiser()
    if len(beq) and np.max(np.abs(Aeq @ x - beq)) > 1e-8 * scale:
        raise DepthOrderError("The glue rows of the layers contradict each other.")

    in_set = np.zeros(len(bin_), bool)
    in_set[[k for k in W.keys if k >= 0]] = True
    skipped = np.zeros(len(bin_), bool)
    steps = 0
    while True:
        slack = Ain @ x - bin_ if len(bin_) else np.zeros(0)
        slack[in_set | skipped] = np.inf
        p = int(np.argmin(slack)) if len(slack) else -1
        if p < 0 or slack[p] >= -tol:
            break
        s_p = float(slack[p])
        while True:
            steps += 1
            if steps > max_iter:
                raise DepthOrderError("The depth-order solve did not converge; reorder or redraw the parts.")
            zp, r, piv, cz, l = W.probe(p)
            dependent = piv <= dep * cz
            # partial step: the first depth row of W whose multiplier reaches 0 (equality rows have
            # free multipliers)
            ri = r[n_eq:]
            pos = np.flatnonzero(ri > 1e-14 * max(1.0, float(np.abs(r).max(initial=0.0))))
            t1, k1 = np.inf, -1
            if len(pos):
                ratios = np.maximum(lam[n_eq:][pos], 0.0) / ri[pos]
                j = int(np.argmin(ratios))
                t1, k1 = float(ratios[j]), n_eq + int(pos[j])
            t2 = np.inf if dependent else -s_p / piv
            if not np.isfinite(t1) and not np.isfinite(t2):
                # W implies c_p x <= its value now: infeasible, unless the gap is round-off
                if s_p < -1e-9 * scale:
                    raise DepthOrderError(
                        "The depth order of the layers could not be satisfied (the layers are glued and "
                        "stacked in a way that leaves no room); reorder or redraw the parts."
                    )
                skipped[p] = True
                break
            t = min(t1, t2)
            lam = lam - t * r  # (p's own multiplier, t so far, is recomputed when p joins W)
            if not dependent:
                # x moves by t·P⁻¹(c_pᵀ - Cᵀr) here, but nothing reads it before the full step
                # recomputes it from W: p, independent of W, stays so as rows leave, so this
                # loop ends in a full step. Only p's slack is tracked.
                s_p += t * piv
            if t2 <= t1:  # full step: p joins W; x and λ afresh (no drift from the updates)
                W.add(p, zp, l, piv)
                in_set[p] = True
                x, lam = W.minimiser()
                lam[n_eq:] = np.maximum(lam[n_eq:], 0.0)
                break
            in_set[W.keys[k1]] = False  # partial step: the blocking row leaves, p is tried again
            lam = np.delete(lam, k1)
            W.remove(k1)
    if not np.all(np.isfinite(x)):
        raise DepthOrderError("The depth-order solve produced non-finite heights.")
    return x, steps, np.array([k for k in W.keys if k >= 0], np.int64)


def solve_without_free_parts(P, q, Aeq, beq, Ain, bin_, offsets, free, rest, method: str = "osqp",
                             pad: float = 0.0, cache: AssemblyCache | None = None):
    """:func:`solve_depth` with the free parts left out of the QP, then placed at their rest
    depth (:func:`settle_free_parts` lowers them afterwards, as it would after a solve of
    the whole problem).

    Why. A free part has no glue row, so only its small mass term fixes its depth: it was the
    worst-conditioned direction of the QP (the creature's eye alone: 1675 OSQP iterations
    with it, 1125 without; random creatures 2-4x fewer) and its answer was thrown away by
    the settling anyway. Exact: with every free part at its rest depth (where its own energy
    is least, a constant offset) and every row touching it satisfied, the glued parts'
    solution and the free parts' rest depths together meet the optimality conditions of the
    whole QP (the free parts' rows are inactive, their multipliers 0). When some free part
    at rest would cross a layer that the glue moved, that is not so: the part is then lifted
    out as a whole (:func:`_lift_free_parts`; a sticker on what it was drawn on, which does
    not move for it), and only if no single shift clears it does it join the QP of the group
    it touches, which is solved again (the other groups are not).

    Parameters
    ----------
    P, q, Aeq, beq, Ain, bin_ : as :func:`solve_depth`
    offsets : (k+1,) int64
        Start of each sheet's block in δ.
    free : iterable of int
        Sheets without an attachment either way (no glue row touches them).
    rest : (k,) float64
        Rest depth of each sheet (the constant its mass term pulls towards, see
        :func:`build_problem`).
    method, pad : as :func:`solve_depth`
    cache : AssemblyCache, optional
        Memo of the glued parts' solve, keyed by their whole QP: editing a free part (an eye)
        re-places it without solving again.

    Returns
    -------
    x : (N,) float64
    info : dict
        :func:`solve_depth`'s (iterations and rows summed over the groups), with ``groups``
        (independent QPs solved), ``free_lifted`` ({part: shift} of the free parts lifted out
        of a layer whole) and ``free_in_solve`` (the free parts that had to join the QP);
        OSQP's ``active`` is counted over every depth row.
    """
    N = P.shape[0]
    free = sorted(free)
    P, Aeq, Ain = sp.csc_matrix(P), sp.csr_matrix(Aeq), sp.csr_matrix(Ain)
    k = len(offsets) - 1
    layer_of = np.repeat(np.arange(k), np.diff(offsets))  # (N,) sheet of each unknown
    eq_lo, eq_hi = _row_layers(Aeq, layer_of)
    in_lo, in_hi = _row_layers(Ain, layer_of)
    # A group's solve is reused when a free part joins another group: through the cache, or
    # within this call by its members (its rows are then the same: a free part that joined
    # and touches it would be one of them).
    local: dict[tuple, tuple] = {}
    out = np.zeros(k, bool)  # free parts left out of the QP
    out[free] = True
    lifted: dict[int, float] = {}
    while True:
        x = np.zeros(N)
        info = {"method": method, "osqp_iterations": 0, "iterations": 0, "groups": 0}
        touch = out[in_lo] | out[in_hi]  # depth rows of a free part left out
        # Independent groups: sheets in the QP linked by a glue or depth row. Each is its own
        # QP (in one problem they would not interact), solved and cached on its own, so
        # editing one creature of a crowd re-solves only that creature.
        links = np.r_[eq_lo, in_lo[~touch]], np.r_[eq_hi, in_hi[~touch]]
        n_grp, group = connected_components(sp.coo_matrix((np.ones(len(links[0])), links), shape=(k, k)),
                                            directed=False)
        for g in range(n_grp):
            members = np.flatnonzero((group == g) & ~out)
            if len(members) == 0:
                continue
            cols = np.flatnonzero(np.isin(layer_of, members))
            er = np.flatnonzero(np.isin(eq_lo, members))
            ir = np.flatnonzero(~touch & np.isin(in_lo, members))
            sub = (P[cols][:, cols], q[cols], Aeq[er][:, cols], beq[er], Ain[ir][:, cols], bin_[ir])
            try:
                if cache is None:
                    if tuple(members) not in local:
                        local[tuple(members)] = solve_depth(*sub, method=method, pad=pad)
                    xg, gi = local[tuple(members)]
                else:
                    xg, gi = _memo_solve(cache, sub, method, pad)
            except DepthOrderError:
                squeezed = [int(f) for f in free if not out[f] and f in members]
                if not squeezed:
                    raise
                # a free part drawn where there is no room for it (between two layers glued
                # together, or onto a twin): it, not the glued model, is what cannot be placed
                raise DepthOrderError("there is no room for it between the layers it is drawn between; move it "
                                      "in depth (Page Up / Page Down) or aside", layers=squeezed, free=True) from None
            x[cols] = xg
            info["groups"] += 1
            for key in ("osqp_iterations", "iterations", "osqp_rounds", "osqp_rows", "active"):
                if key in gi:
                    info[key] = info.get(key, 0) + gi[key]
            if "osqp_status" in gi and info.get("osqp_status", "solved") == "solved":
                info["osqp_status"] = gi["osqp_status"]
        for f in np.flatnonzero(out):
            x[offsets[f]:offsets[f + 1]] = rest[f]
        if not touch.any():
            break
        lifted = _lift_free_parts(x, Ain, bin_, offsets, out, in_lo, in_hi, touch, pad)
        bad = np.flatnonzero(touch)[Ain[touch] @ x - bin_[touch] < 0.0]
        if len(bad) == 0:
            break
        # a free part at rest would cross a layer the glue moved, and no shift of it as a whole
        # clears every row (squeezed between two layers, or crossing another free part): it
        # joins the QP of what it touches (the other groups' solves come back from the cache)
        out[np.r_[in_lo[bad], in_hi[bad]]] = False
    info["free_lifted"] = {int(f): v for f, v in lifted.items() if out[f]}
    info["free_in_solve"] = [int(f) for f in free if not out[f]]
    if free and len(bin_) and info.get("iterations", 0) == 0:  # OSQP's count, as in solve_depth
        info["active"] = int(np.sum(Ain @ x - bin_ <= pad + 1e-6))
    return x, info


def _lift_free_parts(x, Ain, bin_, offsets, out, in_lo, in_hi, touch, pad):
    """Shift each free part left out of the QP (``out`` (k,) bool) as a whole, in place in x
    (N,), by the smallest amount that gives every depth row it has with a solved layer a slack
    of at least ``pad``, if one exists and a row is violated; returns {part: shift}.

    Why. The glue can move a layer past a free part's rest depth (the blended creature: the
    head, glued to the body, ends up in front of the eye drawn on it). Solving the whole group
    again with the part in it cost a second QP, as long as the first, to come out with the part
    nearly where a rigid shift puts it: the layers it is drawn on are stiffer than it and its
    own energy is shift-free. So a free part is placed like a sticker, as
    :func:`settle_free_parts` places it afterwards, and no glued layer moves for it. Only a part
    that no single shift can clear (held from both sides) joins the QP.

    A shift t of the part's block changes the slack of a row by t·d, d the row's sum of
    coefficients over the part's columns (+1 where the part is the nearer layer, -1 where it is
    the farther; see :func:`settle_free_parts`).
    """
    lifted: dict[int, float] = {}
    rows_all = np.flatnonzero(touch)
    for f in np.flatnonzero(out):
        mine = rows_all[((in_lo[rows_all] == f) & ~out[in_hi[rows_all]])
                        | ((in_hi[rows_all] == f) & ~out[in_lo[rows_all]])]
        if len(mine) == 0:
            continue
        a, b = int(offsets[f]), int(offsets[f + 1])
        A = Ain[mine]
        slack = A @ x - bin_[mine]
        if slack.min() >= 0.0:
            continue
        d = np.asarray(A[:, a:b].sum(axis=1)).ravel()
        up, down = d > 0.5, d < -0.5
        lo = float(np.max((pad - slack[up]) / d[up], initial=-np.inf))
        hi = float(np.min((slack[down] - pad) / -d[down], initial=np.inf))
        if lo > hi:
            continue  # held from both sides: the QP decides
        t = min(max(0.0, lo), hi)
        x[a:b] += t
        lifted[int(f)] = t
    return lifted


def _row_layers(A, layer_of):
    """(first, last) sheet touched by each row of A (CSR, every row with an entry): (r,) int64 twice."""
    if A.shape[0] == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    lay = layer_of[A.indices]
    starts = A.indptr[:-1]
    if np.any(np.diff(A.indptr) == 0):
        raise ValueError("a constraint row without coefficients")
    return np.minimum.reduceat(lay, starts), np.maximum.reduceat(lay, starts)


def _memo_solve(cache, sub, method, pad):
    """:func:`solve_depth` of ``sub`` = (P, q, Aeq, beq, Ain, bin_) through the cache, keyed by
    the whole problem; the info returned is a copy (the cached one is shared)."""
    key = tuple(a for m in sub for a in ((m.data, m.indices, m.indptr, m.shape) if sp.issparse(m) else (m,)))
    x, info = memo(cache, "depth_solve", key + (method, float(pad)), lambda: solve_depth(*sub, method=method, pad=pad))
    return x, dict(info)


def settle_free_parts(x, Ain, bin_, offsets, free, pad: float = 0.0):
    """Lower each free part rigidly onto the layers below it (or raise one that has layers
    only in front of it onto them), after the solve.

    Why. The rest depth that the mass term pulls towards (see :func:`build_problem`) stacks
    the layers from the *rest* depths of the layers below, but those layers move in the solve
    (a head glued to a body sits where the body puts it, not at its own rest), so a free part
    (a closed outline such as an eye, its own component) ends up hovering far above what it
    was drawn on: about 80 gaps in front of the head in ``examples/creature.json``, plain to
    see from the side. A user expects it to sit on that layer like a sticker, just clear of it.

    How, and why not re-derive the rest depth and solve again. A free part has no glue rows
    and its offsets appear in depth rows only, so shifting its block of δ by a constant -s
    changes nothing but those rows' slacks, each by exactly -s·d, where d is the row's sum of
    coefficients over the part's columns: +1 on rows where the part is the nearer layer (they
    tighten), -1 where it is the farther one (they loosen: moving down only gets further from
    what lies in front of it). The largest s that keeps every row satisfied is therefore the
    part's minimum slack over its "nearer" rows, exact and in one matrix-vector product; the
    part keeps its shape (its Dirichlet energy is unchanged) and no glued layer moves. A
    second solve with re-derived rest depths would cost another OSQP run, could move the glued
    layers too (their rest depths depend on the free part's rows), and would only be as exact
    as OSQP's 1e-4 residual. Parts are settled back to front, each with the slacks left by the
    previous ones, so a free part over another free part lands on it after it has landed.

    Parameters
    ----------
    x : (N,) float64
        Solution of :func:`solve_depth`.
    Ain : (r, N) sparse, bin_ : (r,)
        Depth rows  Ain δ >= bin_.
    offsets : (k+1,) int64
        Start of each sheet's block in δ.
    free : iterable of int
        Sheets that are free parts (no attachment either way).
    pad : float
        Clearance above the required one left on the tightest row: the same extra clearance
        the solver is asked for, so that the part ends as close to the layer below as the
        glued parts' active rows are and no row is left at exactly zero slack (round-off).

    Returns
    -------
    x : (N,) float64
        A copy with the free parts lowered.
    shift : dict int -> float
        How far each free part that has a layer below it was lowered (0 when its tightest row
        already has at most ``pad`` slack); a free part with layers only in front of it is
        raised onto them instead (a negative shift). Parts overlapping nothing stay put.
    """
    x = np.array(x, dtype=np.float64, copy=True)
    shift: dict[int, float] = {}
    if len(bin_) == 0:
        return x, shift
    Ain = sp.csr_matrix(Ain)
    for f in sorted(free):
        a, b = int(offsets[f]), int(offsets[f + 1])
        d = np.asarray(Ain[:, a:b].sum(axis=1)).ravel()  # +1 nearer, -1 farther, 0 not involved
        below = d > 0.5
        if below.any():
            slack = Ain[below] @ x - bin_[below]
            s = max(0.0, float(np.min((slack - pad) / d[below])))
            x[a:b] -= s
            shift[f] = s
            continue
        # Nothing below: a part drawn behind a layer and over nothing else rises onto that
        # layer's back face from behind instead of staying at the drawing plane, far behind a
        # layer that the glue moved forwards (the same rows, their signs flipped).
        above = d < -0.5
        if above.any():
            slack = Ain[above] @ x - bin_[above]
            s = max(0.0, float(np.min((slack - pad) / -d[above])))
            x[a:b] += s
            shift[f] = -s
    return x, shift
