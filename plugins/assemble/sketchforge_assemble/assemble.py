"""Layers -> one closed, outward-oriented 2-manifold mesh (thesis 3.2 and 4.7).

Pipeline: planar sheets (:mod:`.sheet`) -> attachments (:mod:`.attach`) -> junctions cut into
the faces below (:mod:`.remesh`) -> fillets at the junctions (:mod:`.blend`) -> depth QP
(:mod:`.depth`) -> faces, slits and rim bridges (:mod:`.stitch`) -> the junctions faired
(:mod:`.fair`). With an :class:`~.cache.AssemblyCache`, the per-layer and per-pair steps,
each group's solve and the fairing are reused when their inputs are bit-identical (:mod:`.cache`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from sketchforge.plugin_api import LimitError, ParameterError
from sketchforge.plugin_api import Mesh

from .attach import Attachment, find_attachments
from .blend import blend_junctions
from .cache import AssemblyCache, memo
from .depth import build_problem, settle_free_parts, solve_without_free_parts
from .fair import fair_seams, fairing_is_fit, hold_weights, seam_zone, supports, wide_zone
from .remesh import insert_chains
from .sheet import sheet_from_mesh, taper
from .stitch import build_mesh

#: Assembly options. ``margin``: front/back separation at the rim, in edge lengths of the
#: layer (thesis 4.7's "small margin"); ``gap``: clearance between overlapping layers, in
#: median edge lengths; ``reg``: pull of the parts towards the drawing plane (relative, see
#: :mod:`.depth`); ``stiffness``: how much stiffer a layer with parts glued to it is than
#: the parts (see :func:`.depth.build_problem`); ``solver``: "osqp" (a dual active set finishes
#: if a row is left violated) or "active_set" (the active set alone, see
#: :func:`.depth.solve_depth`); ``on_bad_junction``: "raise" or "free"; ``fillet``: width, in edge
#: lengths of the part, of the blended junction of :mod:`.blend` (0 keeps the plain sleeve, which
#: folds by up to 180 degrees where a part meets its host); ``fair``: how many rings of edges
#: around the ends of every blended junction :mod:`.fair` smooths (60% of that along the rest
#: of it; 0: none; only with ``fillet`` > 0). Where that leaves a fold or a crossing, 1.4 ×
#: ``fair`` rings around the whole junction are smoothed instead; a blended junction that would
#: still cross itself falls back to the plain sleeve, with a warning.
#: The narrow fairing may leave a bend of at most this many degrees over one edge (issue 12: a
#: bend over 90 degrees is a fold); more, and the wide zone is faired instead (see above).
MAX_BEND = 90.0

DEFAULT_PARAMS: Mapping[str, object] = {
    "margin": 0.1,
    "gap": 0.1,
    "reg": 1.0,
    "stiffness": 20.0,
    "qp_solver": "osqp",
    "on_bad_junction": "raise",
    "fillet": 4.0,
    "fair": 12,
}


@dataclass(frozen=True, eq=False)
class AssemblyResult:
    """The assembled mesh and what it took to make it.

    Attributes
    ----------
    mesh : Mesh
        Closed, outward-oriented; ``boundary``/``junction`` empty.
    face_layer : (m,) int64
        Index (in the input list) of the layer each triangle comes from.
    face_kind : (m,) int8
        0 front face, 1 back face, 2 rim bridge.
    attachments : list of Attachment
        In input indices.
    components : int
        Connected components (one per group of attached parts, one per free part).
    n_equalities, n_inequalities, n_active : int
        Glue rows, depth-order rows, and the depth rows active at the answer: within half the
        gap (+1e-6) of binding, counted the same way whichever solver ran.
    max_violation : float
        Largest violation of any depth-order row (0 when all hold).
    glue_error : float
        Largest residual of a glue row (the glued vertices are shared, so this only measures
        the solver's accuracy, never a crack).
    warnings : list of str
    timings : dict of str -> float
        Seconds per stage.
    """

    mesh: Mesh
    face_layer: np.ndarray
    face_kind: np.ndarray
    attachments: list
    components: int
    n_equalities: int
    n_inequalities: int
    n_active: int
    max_violation: float
    glue_error: float = 0.0
    warnings: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    solver: dict = field(default_factory=dict)


#: Most work an assembly takes on: for every pair of layers whose bounding boxes overlap, the
#: smaller one's vertex count, summed (each such vertex gets depth rows against the other
#: layer). Parts stacked on each other make it grow with the square of their number, and the
#: depth QP faster still (issue 30: 10 copies of a 4.9k-vertex layer in place, 221k, took
#: 2.8 s; 20, 0.93M, 8.4 s; 40, 3.8M, 73 s; 3000 ran past any patience). The example creature
#: needs 6.1k (about 70k at the benchmark's finest resolution, 93k vertices), the toucan 2.9k,
#: a crowd of 38 layers of random creatures 16k.
MAX_OVERLAP_WORK = 1_000_000


def overlap_work(meshes: Sequence[Mesh]) -> tuple[int, int]:
    """(pairs of layers whose bounding boxes overlap, the work :data:`MAX_OVERLAP_WORK`
    bounds) for these meshes, in O(layers²) on their bounding boxes only."""
    if len(meshes) < 2:
        return 0, 0
    lo = np.array([m.V[:, :2].min(axis=0) for m in meshes])
    hi = np.array([m.V[:, :2].max(axis=0) for m in meshes])
    n = np.array([m.n_vertices for m in meshes], dtype=np.int64)
    over = np.all((lo[:, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[:, None, :]), axis=2)
    i, j = np.nonzero(np.triu(over, k=1))
    return int(len(i)), int(np.minimum(n[i], n[j]).sum())


def _check_overlap_work(meshes: Sequence[Mesh]) -> None:
    pairs, work = overlap_work(meshes)
    if work > MAX_OVERLAP_WORK:
        raise LimitError(
            f"assembling these {len(meshes)} layers would keep {pairs:,} overlapping pairs of layers apart "
            f"({work:,} vertex rows; the limit is {MAX_OVERLAP_WORK:,}): parts are stacked on top of each "
            "other, so hide, move or remove some of them"
        )


def _sheet(cache: AssemblyCache | None, k: int, name: str, mesh: Mesh, free: bool):
    """:func:`.sheet.sheet_from_mesh` through the cache (keyed by the mesh's arrays)."""
    sheet = memo(cache, "sheet", (mesh.V, mesh.F, mesh.boundary, mesh.junction, tuple(mesh.holes), free),
                 lambda: sheet_from_mesh(k, name, mesh, free))
    return sheet.evolve(layer=k, name=name)


def _params(params) -> dict:
    """The assembly's complete parameters: defaults filled in, unknown keys refused (the
    ``check_params`` of the ``depth_qp`` assembler)."""
    known = set(DEFAULT_PARAMS)
    unknown = sorted(str(k) for k in (params or {}) if k not in known)
    if unknown:
        raise ParameterError(f"unknown assembly parameter {unknown[0][:60]!r} (known: {', '.join(sorted(known))})")
    p = dict(DEFAULT_PARAMS)
    p.update(params or {})
    if not (isinstance(p["fillet"], (int, float)) and np.isfinite(p["fillet"]) and p["fillet"] >= 0):
        raise ParameterError(f"assembly parameter 'fillet' must be a number >= 0, got {p['fillet']!r}")
    if not (isinstance(p["fair"], (int, np.integer)) and not isinstance(p["fair"], bool) and 0 <= p["fair"] <= 50):
        raise ParameterError(f"assembly parameter 'fair' must be a whole number of rings from 0 to 50, got {p['fair']!r}")
    for key in ("margin", "gap", "reg", "stiffness"):
        if not (isinstance(p[key], (int, float)) and np.isfinite(p[key]) and p[key] > 0):
            raise ParameterError(f"assembly parameter '{key}' must be a positive number, got {p[key]!r}")
    if p["qp_solver"] not in ("osqp", "active_set"):
        raise ParameterError(f"assembly parameter 'qp_solver' must be 'osqp' or 'active_set', got {p['qp_solver']!r}")
    if p["on_bad_junction"] not in ("raise", "free"):
        raise ParameterError("assembly parameter 'on_bad_junction' must be 'raise' or 'free'")
    return p


def assemble_detailed(meshes: Sequence[Mesh | None], closed: Sequence[bool] | None = None,
                      params=None, names: Sequence[str] | None = None,
                      cache: AssemblyCache | None = None) -> AssemblyResult:
    """Assemble layer meshes, back to front, and report diagnostics.

    Parameters
    ----------
    meshes : list of Mesh or None
        Front surfaces of the layers, back to front (later = in front). ``None`` is skipped.
    closed : list of bool, optional
        True marks a free part (its junction, if any, is ignored). Default: all False, so a
        mesh with a junction attaches.
    params : dict, optional
        See :data:`DEFAULT_PARAMS`.
    names : list of str, optional
        Layer names used in error messages (default "layer 0", ...).
    cache : AssemblyCache, optional
        Keeps per-layer sheets, junction cuts, operators, per-pair depth rows and the glued
        parts' solve between calls, so that re-assembling after one layer changed redoes only
        what depends on it (see :mod:`.cache`). The result is bit-identical with or without.

    Returns
    -------
    AssemblyResult
    """
    p = _params(params)
    t0 = time.perf_counter()
    timings = {}
    n_in = len(meshes)
    closed = [False] * n_in if closed is None else list(closed)
    names = [f"layer {i}" for i in range(n_in)] if names is None else list(names)
    keep = [i for i, m in enumerate(meshes) if m is not None and m.n_faces > 0]
    if not keep:
        raise ParameterError("there is no layer with a mesh to assemble")
    knames = [names[i] for i in keep]
    _check_overlap_work([meshes[i] for i in keep])  # before any work, so a refusal is quick
    sheets = [_sheet(cache, k, knames[k], meshes[i], bool(closed[i])) for k, i in enumerate(keep)]

    attachments, warnings = find_attachments(sheets, knames, p["on_bad_junction"])
    attached = {a.upper for a in attachments}
    for u in range(len(sheets)):
        if u not in attached and len(sheets[u].junction):
            # junction over empty space, or a bad one with on_bad_junction="free": a free part
            # whose whole outline is a rim
            sheets[u] = sheets[u].evolve(junction=np.zeros(0, np.int64))
    timings["attach"] = time.perf_counter() - t0

    t = time.perf_counter()
    for lo in sorted({a.lower for a in attachments}):
        mine = [a for a in attachments if a.lower == lo]
        chains = [sheets[a.upper].xy[sheets[a.upper].junction] for a in mine]
        s = sheets[lo]
        cut = memo(cache, "remesh", (s.xy, s.z, s.F, s.boundary, s.junction, s.holes, s.h, chains),
                   lambda: insert_chains(s, chains, knames, [a.upper for a in mine]))
        sheets[lo] = cut.evolve(layer=lo, name=knames[lo])
    timings["remesh"] = time.perf_counter() - t

    t = time.perf_counter()
    offs = []
    for s in sheets:
        offs.append(s.z + p["margin"] * s.h * taper(s))
    front_off, back_off = list(offs), list(offs)
    lips = glue = springs = None
    locators: dict = {}  # per sheet, for the fillets' springs and the depth rows alike
    if p["fillet"] > 0 and attachments:
        lips, glue, springs = blend_junctions(sheets, attachments, front_off, back_off, p["fillet"],
                                              locators=locators)
    offsets = np.r_[0, np.cumsum([s.n for s in sheets])]
    gap = p["gap"] * float(np.median([s.h for s in sheets]))
    P, q, Aeq, beq, Ain, bin_, pinfo = build_problem(sheets, offsets, front_off, back_off, attachments, gap,
                                                    p["reg"], p["stiffness"], glue, springs, cache=cache,
                                                    locators=locators)
    timings["constraints"] = time.perf_counter() - t

    t = time.perf_counter()
    pad = 0.5 * gap
    # Free parts (no attachment either way) are left out of the QP and sit on what lies below
    # them instead of floating at their rest depth; glued layers do not move (see
    # depth.solve_without_free_parts and depth.settle_free_parts).
    in_att = {a.upper for a in attachments} | {a.lower for a in attachments}
    free = [i for i in range(len(sheets)) if i not in in_att]
    x, sinfo = solve_without_free_parts(P, q, Aeq, beq, Ain, bin_, offsets, free, pinfo["rest_depth"],
                                        method=p["qp_solver"], pad=pad, cache=cache)
    sinfo = dict(sinfo)  # the cached solve's info is shared
    sinfo.update(pinfo)
    sinfo["gap"] = gap
    x, shift = settle_free_parts(x, Ain, bin_, offsets, free, pad)
    sinfo["free_shift"] = {keep[i]: v for i, v in shift.items()}
    # Counted at the settled answer, the same way for both solvers: the active set's own count
    # (its working set) knows nothing of the rows a free part came to rest on.
    sinfo["active"] = int(np.sum(Ain @ x - bin_ <= pad + 1e-6)) if len(bin_) else 0
    timings["solve"] = time.perf_counter() - t
    viol = 0.0
    if len(bin_):
        viol = max(viol, float(np.max(bin_ - Ain @ x, initial=0.0)))
    glue_error = float(np.max(np.abs(Aeq @ x - beq), initial=0.0))

    t = time.perf_counter()
    delta = [x[offsets[k]:offsets[k + 1]] for k in range(len(sheets))]
    V, F, face_layer, face_kind, seam, ends = build_mesh(sheets, attachments, delta, front_off, back_off, lips)
    timings["stitch"] = time.perf_counter() - t
    fair_zone = None
    if lips is not None and p["fair"] > 0:
        t = time.perf_counter()
        rings = int(p["fair"])
        A, reach = seam_zone(F, len(V), seam, ends, rings)
        wide = wide_zone(A, seam, rings)
        # A free part resting on a face near a junction keeps the face under it as it was
        # solved (fairing it away would leave the part floating, or sunk into it).
        held = np.zeros(len(V), bool)
        for k in sorted(set(range(len(sheets))) - in_att):
            held |= supports(V, F, face_layer, face_kind, k, sheets[k].polygon().buffer(sheets[k].h), wide)
        h_med = float(np.median([s.h for s in sheets]))

        def faired(V=V, A=A, reach=reach, wide=wide, held=held):
            spent = {"fair": 0.0, "fair_check": 0.0}

            def attempt(moved, hold, bend_limit):
                t1 = time.perf_counter()
                V2 = fair_seams(V, F, moved, A, hold=hold)
                t2 = time.perf_counter()
                ok = fairing_is_fit(V2, F, moved, A, h_med, bend_limit)
                spent["fair"] += t2 - t1
                spent["fair_check"] += time.perf_counter() - t2
                return V2, ok

            # The narrow zone, held softly; where it leaves a fold or a crossing, the wide one
            # (a bend it leaves is still far below the plain sleeve's, so only a crossing or a
            # flat triangle there falls back to the plain sleeve).
            V2, ok = attempt((reach < 1.0) & ~held, hold_weights(reach), MAX_BEND)
            zone = "narrow"
            if not ok:
                V2, ok = attempt(wide & ~held, None, 180.0)
                zone = "wide"
            timings.update(spent)
            return V2, ok, zone

        # Through the cache by the stitched mesh itself: an undo, or an edit that leaves every
        # junction's rings as they were, skips the fairing's solves and checks.
        V, safe, fair_zone = memo(cache, "fair", (V, F, seam, ends, held, rings, h_med), faired)
        V = V.copy()  # the cached array stays as it was, whatever the caller does to the mesh
        timings.setdefault("fair", time.perf_counter() - t)
        timings.setdefault("fair_check", 0.0)
        if not safe:
            # The blended junction would cross itself (or flatten a triangle): the plain
            # sleeve never does, so the model is still handed out, with its folds, and why.
            plain = assemble_detailed(meshes, closed, {**p, "fillet": 0.0}, names, cache=cache)
            plain.warnings.append("a junction could not be blended without the surface crossing itself; "
                                  "its parts are glued with a plain fold (assembly parameter 'fillet')")
            return plain
    sinfo["fair_zone"] = fair_zone
    timings["total"] = time.perf_counter() - t0

    # components: one per group of attached parts
    parent = list(range(len(sheets)))

    def root(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a in attachments:
        parent[root(a.upper)] = root(a.lower)
    n_comp = len({root(i) for i in range(len(sheets))})
    keep_arr = np.array(keep)
    return AssemblyResult(
        mesh=Mesh(V, F),
        face_layer=keep_arr[face_layer],
        face_kind=face_kind,
        attachments=[Attachment(keep[a.upper], keep[a.lower], a.side) for a in attachments],
        components=n_comp,
        n_equalities=int(len(beq)),
        n_inequalities=int(len(bin_)),
        n_active=int(sinfo.get("active", 0)),
        max_violation=viol,
        glue_error=glue_error,
        warnings=warnings,
        timings=timings,
        solver=sinfo,
    )


def assemble_meshes(meshes: list[Mesh], closed: list[bool] | None = None, params=None) -> Mesh:
    """Assemble layer meshes (back to front) into one closed, outward-oriented mesh.

    See :func:`assemble_detailed` for the parameters; this returns only the mesh.
    """
    return assemble_detailed(meshes, closed, params).mesh
