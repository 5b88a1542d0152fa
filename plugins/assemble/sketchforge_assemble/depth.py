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
above it (barycentric interpolation in the containing triangle, found with libigl's AABB tree).

Solver (see :func:`solve_depth`). OSQP, asked for a little more clearance than required so
that its 1e-4 accuracy still leaves every row satisfied; Monster Mash's active-set loop
(violated rows become equality rows, rows with a negative multiplier leave) is the fallback
and the ``"active_set"`` option. Measured on the creature (8k unknowns, 12k rows, ~190 active
at the optimum): the loop from an empty set adds thousands of nearly dependent rows of
touching faces and takes minutes; OSQP takes 0.4 s. igl.min_quad_with_fixed returns no
multipliers and refactorises per working set, so the loop uses one scipy factorisation of the
energy in range-space form instead.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla
import shapely
import igl

from sketchforge.geometry.laplacian import laplacian_and_mass

from .attach import FRONT, Attachment, lo_chain_index
from .errors import DepthOrderError
from .sheet import Sheet, unique_edges


def locate(sheet: Sheet, pts: np.ndarray):
    """Point location in a sheet.

    Parameters
    ----------
    sheet : Sheet
    pts : (q, 2) float64

    Returns
    -------
    inside : (q,) bool
        Whether the point lies in (or on) the sheet's triangulation.
    tri : (q, 3) int64
        Vertices of the containing triangle (meaningful where ``inside``).
    bary : (q, 3) float64
        Barycentric coordinates in that triangle.
    """
    V3 = np.c_[sheet.xy, np.zeros(sheet.n)]
    P3 = np.c_[pts, np.zeros(len(pts))]
    d2, I, _ = igl.point_mesh_squared_distance(P3, V3, sheet.F)
    tri = sheet.F[I]
    a, b, c = (sheet.xy[tri[:, k]] for k in range(3))
    v0, v1, v2 = b - a, c - a, pts - a
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    l1 = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
    l2 = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
    bary = np.clip(np.c_[1.0 - l1 - l2, l1, l2], 0.0, 1.0)
    bary /= bary.sum(axis=1, keepdims=True)
    inside = d2 <= (1e-9 * sheet.h) ** 2
    return inside, tri, bary


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

    def matrix(self, n: int):
        if self.m == 0:
            return sp.csr_matrix((0, n)), np.zeros(0)
        A = sp.csr_matrix(
            (np.concatenate(self.v), (np.concatenate(self.r), np.concatenate(self.c))), shape=(self.m, n)
        )
        return A, np.concatenate(self.b)


def build_problem(sheets, offsets, front_off, back_off, attachments: list[Attachment], gap: float, reg: float,
                  stiffness: float = 20.0):
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

    Returns
    -------
    P : (N, N) csc, q (N,), Aeq (e, N), beq (e,), Ain (r, N), bin (r,), info : dict
    """
    N = int(offsets[-1])
    allxy = np.vstack([s.xy for s in sheets])
    diag = float(np.linalg.norm(allxy.max(0) - allxy.min(0))) or 1.0
    w = reg / diag**2
    blocks, blocks_m = [], []
    for s in sheets:
        L, M = laplacian_and_mass(s.xy, s.F)
        k = 1.0 + (stiffness if s.chains else 0.0)
        blocks.append((k * (-L) + w * M).tocsc())
        blocks_m.append(M)
    P = sp.block_diag(blocks, format="csc")

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
        eq.add(cols, coefs, rhs)
        key = (min(at.upper, at.lower), max(at.upper, at.lower))
        glued.setdefault(key, [])
        glued[key].append(("u", at.upper, j))
        glued[key].append(("l", at.lower, c))

    polys = [s.polygon() for s in sheets]
    edges = [unique_edges(s.F) for s in sheets]  # once per sheet, not once per overlapping pair
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
            # C>=: vertices of the nearer layer k over layer i: back_k(v) - front_i(p) >= gap.
            _pair_rows(ineq, sheets, offsets, k, i, polys[i], skip[k], skip[i], back_off[k], front_off[i], gap, +1)
            # C<=: vertices of layer i under layer k: back_k(p) - front_i(v) >= gap.
            _pair_rows(ineq, sheets, offsets, i, k, polys[k], skip[i], skip[k], front_off[i], back_off[k], gap, -1)
            # and where their edges cross
            _crossing_rows(ineq, sheets, offsets, k, i, edges[k], edges[i], overlap, skip[k], skip[i],
                           back_off[k], front_off[i], gap)
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
    q = np.concatenate([-w * blocks_m[i] @ np.full(s.n, rest[i]) for i, s in enumerate(sheets)])
    return P, q, Aeq, beq, Ain, bin_, {"overlapping_pairs": n_pairs, "reg_weight": w, "rest_depth": rest.tolist()}


def _pair_rows(rows, sheets, offsets, q, o, poly_o, skip_q, skip_o, off_q, off_o, gap, sign):
    """Rows for the vertices of sheet q lying over sheet o.

    sign=+1: q is in front (its back face, δ_q - off_q, must clear o's front face δ_o + off_o).
    sign=-1: q is behind (its front face δ_q + off_q must stay under o's back face δ_o - off_o).
    Row:  sign·(δ_q(v) - Σ bary·δ_o)  >=  gap' + off_q(v) + Σ bary·off_o,
    where gap' shrinks to 0 as the point nears glued junction vertices (the faces meet there).
    """
    sq, so = sheets[q], sheets[o]
    cand = np.flatnonzero((skip_q == 0) & shapely.contains_xy(poly_o.buffer(1e-9 * so.h), sq.xy[:, 0], sq.xy[:, 1]))
    if len(cand) == 0:
        return
    inside, tri, bary = locate(so, sq.xy[cand])
    cand, tri, bary = cand[inside], tri[inside], bary[inside]
    if len(cand) == 0:
        return
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
    pairs = tk.query_ball_tree(ti, r=0.5 * (lk.max() + li.max()))
    pk = np.repeat(np.arange(len(ek)), [len(p) for p in pairs])
    pi = np.fromiter((j for p in pairs for j in p), dtype=np.int64, count=len(pk))
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


def _kkt_solve(P, q, C, d, gamma=1e-11):
    """Solve  min ½xᵀPx + qᵀx  s.t. Cx = d ; returns x and multipliers λ (Px + q = Cᵀλ).

    A tiny negative (2,2) block keeps the system solvable when rows repeat.
    """
    n, m = P.shape[0], C.shape[0]
    K = sp.bmat([[P, C.T], [C, -gamma * sp.eye(m)]], format="csc")
    sol = sla.splu(K, permc_spec="COLAMD").solve(np.r_[-q, d])
    return sol[:n], sol[n:]


def solve_depth(P, q, Aeq, beq, Ain, bin_, method: str = "osqp", pad: float = 0.0, tol: float = 1e-10,
                max_iter: int = 500):
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
        0.4 s, objective within 0.2% of a 1e-5 solve that needs 20000 iterations); if some row is still violated, the active-set
        loop finishes from OSQP's active set. "active_set": Monster Mash's loop alone.
    pad : float
        Extra clearance asked of OSQP (a fraction of the gap).

    Returns
    -------
    delta : (N,) float64
    info : dict
        ``osqp_iterations``, ``iterations`` (active-set loop, 0 if not needed), ``active``.
    """
    Ain = sp.csr_matrix(Ain)
    Aeq = sp.csr_matrix(Aeq)
    info = {"method": method, "osqp_iterations": 0, "iterations": 0}
    active = np.zeros(len(bin_), bool)
    if method == "osqp":
        import osqp

        solver = osqp.OSQP()
        solver.setup(P=sp.triu(P).tocsc(), q=q, A=sp.vstack([Aeq, Ain]).tocsc(),
                     l=np.r_[beq, bin_ + pad], u=np.r_[beq, np.full(len(bin_), np.inf)], verbose=False,
                     eps_abs=1e-4, eps_rel=1e-4, polishing=False, max_iter=20000,
                     adaptive_rho_interval=25)
        # a status other than "solved" is handled below (feasibility check, then the loop)
        res = solver.solve(raise_error=False)
        info["osqp_iterations"] = int(res.info.iter)
        info["osqp_status"] = str(res.info.status)
        x = np.asarray(res.x)
        if np.all(np.isfinite(x)) and (len(bin_) == 0 or np.min(Ain @ x - bin_) >= 0.0):
            info["active"] = int(np.sum(Ain @ x - bin_ <= pad + 1e-6)) if len(bin_) else 0
            return x, info
        y = res.y[len(beq):]
        if np.all(np.isfinite(y)):
            active = y < -1e-9 * max(1.0, float(np.abs(y).max(initial=0.0)))
    x, it, active = _active_set(P, q, Aeq, beq, Ain, bin_, active, tol, max_iter)
    info["iterations"] = it
    info["active"] = int(active.sum())
    return x, info


def _active_set(P, q, Aeq, beq, Ain, bin_, active, tol, max_iter):
    """Monster Mash's active-set loop, in range-space form.

    P (block diagonal, one block per layer) is factorised once; the working set W gives
    x = x0 + P⁻¹Cᵀλ with (C P⁻¹ Cᵀ) λ = d - C x0 (C = equality rows + W), a dense system the
    size of W; P⁻¹cᵀ is computed once per row that ever enters W. Violated rows join W and
    rows whose multiplier is negative leave (a row that left three times stays, against
    cycling). Measured: fine from a good guess, but from scratch the many nearly dependent
    rows of touching faces make it add thousands of rows, hence the OSQP seed.
    """
    N = P.shape[0]
    lu = sla.splu(sp.csc_matrix(P), permc_spec="COLAMD")
    x0 = lu.solve(-q)
    Zeq = lu.solve(Aeq.T.toarray()) if Aeq.shape[0] else np.zeros((N, 0))
    cache: dict[int, np.ndarray] = {}
    removed = np.zeros(len(bin_), np.int64)
    x = x0
    for it in range(1, max_iter + 1):
        idx = np.flatnonzero(active)
        new = [r for r in idx if r not in cache]
        if new:
            Znew = lu.solve(Ain[new].T.toarray())
            for c, r in enumerate(new):
                cache[r] = Znew[:, c]
        C = sp.vstack([Aeq, Ain[idx]]).tocsr()
        x = x0
        lam = np.zeros(0)
        if C.shape[0]:
            Z = np.column_stack([Zeq] + [cache[r] for r in idx])
            G = np.asarray(C @ Z)
            G = 0.5 * (G + G.T)
            # rows can repeat (a vertex pair seen from both layers): a tiny ridge keeps G solvable
            G[np.diag_indices_from(G)] += 1e-12 * max(1.0, float(np.abs(np.diag(G)).max()))
            lam = np.linalg.solve(G, np.r_[beq, bin_[idx]] - C @ x0)
            x = x0 + Z @ lam
        slack = Ain @ x - bin_ if len(bin_) else np.zeros(0)
        viol = (~active) & (slack < -tol)
        lam_in = lam[len(beq):]
        neg = (lam_in < -1e-9 * max(1.0, float(np.abs(lam_in).max(initial=0.0)))) & (removed[idx] < 3)
        if not viol.any() and not neg.any():
            break
        removed[idx[neg]] += 1
        active[idx[neg]] = False
        # Add only the worst violations: adding every violated row at once (as Monster Mash
        # does) makes neighbouring, nearly dependent rows enter together and then leave again.
        if viol.any():
            worst = float(-slack[viol].min())
            active |= viol & (slack <= -0.5 * worst)
    else:
        raise DepthOrderError(
            "The depth order of the layers could not be satisfied (the layers are glued and "
            "stacked in a way that leaves no room); reorder or redraw the parts."
        )
    if not np.all(np.isfinite(x)):
        raise DepthOrderError("The depth-order solve produced non-finite heights.")
    return x, it, active


def settle_free_parts(x, Ain, bin_, offsets, free, pad: float = 0.0):
    """Lower each free part rigidly onto the layers below it, after the solve.

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
        already has at most ``pad`` slack). Parts over nothing are left where they are.
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
        if not below.any():
            continue
        slack = Ain[below] @ x - bin_[below]
        s = max(0.0, float(np.min((slack - pad) / d[below])))
        x[a:b] -= s
        shift[f] = s
    return x, shift
