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

Modules. This one runs the solve (:func:`solve_without_free_parts`: groups of glued layers,
free parts left out and settled afterwards); :mod:`.depth_rows` builds the energy and the
rows (:func:`build_problem`); :mod:`.depth_qp` solves one QP (:func:`solve_depth`: OSQP,
screening, glue polish) and :mod:`.active_set` is the dual active-set method it falls back on.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .cache import AssemblyCache, memo
from .depth_qp import solve_depth
from .depth_rows import build_problem, face_locator
from .errors import DepthOrderError

# build_problem, face_locator and solve_depth live in depth_rows and depth_qp; they stay
# importable from here, where the assembly and other code have always found them.
__all__ = ["build_problem", "face_locator", "settle_free_parts", "solve_depth", "solve_without_free_parts"]


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
        info: dict[str, Any] = {"method": method, "osqp_iterations": 0, "iterations": 0, "groups": 0}
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
