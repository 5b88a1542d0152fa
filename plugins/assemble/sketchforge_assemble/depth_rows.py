"""The depth-order QP's terms (thesis 4.7): the Dirichlet-plus-mass energy of every layer's
offsets, the glue rows (equalities: a part's junction on the face below) and the depth rows
(inequalities: back face of the nearer layer >= front face of the farther one + gap, wherever
the two overlap). :func:`build_problem` assembles them; :mod:`.depth` says why a QP on heights
and why these constraint sets, :mod:`.depth_qp` solves it.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sketchforge.plugin_api import TriangleLocator, laplacian_and_mass

from .attach import FRONT, Attachment, lo_chain_index
from .cache import AssemblyCache, memo
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
                  locators: dict | None = None, operators: dict | None = None):
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
    operators : dict, optional
        (L, M) of sheets with one triangulation (``Fb`` None) already made in this assembly,
        keyed by ``(id(xy), id(F))`` of the live arrays (:func:`.assemble._attach_sheets`
        makes a glued part's for its full thickness; a part that hosts nothing keeps its
        arrays, so its operators are not made twice).

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
        known = operators.get((id(s.xy), id(s.F))) if operators and s.Fb is None else None
        L, M = known if known is not None else memo(cache, "laplacian", mk, lambda s=s: _sheet_operators(s))
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
