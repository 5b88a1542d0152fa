"""Several isophotes redrawn in one edit: ``sculpt_many(mesh, light, edits) -> JointSculptResult``.

Beyond the thesis (ch. 4 redraws one isophote at a time). Redrawing two isophotes one after
the other lets the second edit undo the first: measured on the seeded corpus, the second
edit pulled the first isophote back off its stroke (1.15 edge lengths from it, against 0.3
for a single edit). Here every stroke enters one solve:

1. each stroke as a single edit would take it (:func:`.pipeline._prepare`): its pick, isovalue
   c_i, isophote, band, the stroke cleaned and clipped to its band, how far it is now; a band
   narrower than one edge length, or a stroke whose moving part lies only in the rim margin,
   is refused as a single edit would refuse it, naming the stroke;
2. strokes that contradict each other are refused in one line: two strokes of isophotes of
   different values that cross (no surface has two brightnesses at one point);
3. one problem for the solver (a :class:`~sketchforge.plugins.sculpt_problem.SculptProblem`
   with ``parts``, one per isophote): the union of the bands, every stroke's samples, each
   asking for its own value (``sample_values``); only solvers with ``several_isophotes`` get
   one, any other is refused in one line naming it;
4. the host's checks per stroke, as for a single edit: heights >= 0 and 0 on the rim; a joint
   change of more than :data:`.pipeline.MAX_CHANGE` of the peak scaled down to it (each
   solve's); and never worse, per stroke with today's half-and-quarter rule: when a stroke's
   isophote would end farther from it than it started (no tolerance: a stroke within the
   shading's resolution of its isophote may not end farther either), the other strokes are
   asked for half, then a quarter of their change (their samples ask for E + f·(c_i − E)) and
   the edit is solved again; then that stroke itself for half, then a quarter; if it is still
   worse the edit is refused, naming that stroke (and the bound's figure when the change was
   scaled down). (Measured on the corpus: asking the others for less saved half of the pairs
   the full solve could not take, asking the stroke itself for less none: the others' change
   is what pulls it off.)

An edit of one stroke is exactly :func:`.pipeline.sculpt` (bit for bit).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import shapely

from sketchforge.plugin_api import (
    LAMBERTIAN,
    Mesh,
    NothingToDoError,
    ReflectanceModel,
    SculptError,
    SculptProblem,
    SolverError,
    band_radius,
)

from .layerdata import layer_data
from .pipeline import (
    FALLBACK_FRACTIONS,
    MAX_CHANGE,
    RESOLUTION_EDGES,
    HostData,
    SculptResult,
    _default_solver,
    _prepare,
    _run_solver,
    bound_note,
    build_problem,
    change_bound,
    sculpt,
    solver_params,
)
from .shading import shading_change
from .stroke import StrokeSamples

#: Most isophotes one edit redraws (each adds a band and a stroke to one solve).
MAX_ISOPHOTES = 16
#: Isovalues closer than this are one brightness: their strokes may cross (two pieces of the
#: same isophote, or isophotes of one value meeting at a saddle).
SAME_VALUE = 1e-6
#: Solves a joint edit may take before it is refused (the first, then the fallbacks).
MAX_ROUNDS = 6


def one_at_a_time(solver_name: str, count: int) -> str:
    """The refusal of a joint edit by a solver without ``several_isophotes``."""
    return (f"the sculpt solver {solver_name!r} redraws one isophote per edit, and this edit redraws {count}: "
            "apply the strokes one at a time, or choose a solver that takes several (such as 'gauss_newton')")


@dataclass
class JointSculptResult:
    """Outcome of a joint edit.

    Attributes
    ----------
    mesh : Mesh
        The edited layer (same V order, only z changed).
    changed : (n,) bool
    parts : list of SculptResult
        One per stroke, in order: its isovalue ``c``, ``isophote``, ``band``, ``stroke``,
        ``before`` / ``after`` (drawing units), ``fraction`` (1, or 0.5 / 0.25 when only part
        of that stroke's change was asked for, times the bound's scale when the joint change
        was scaled down) and ``bounded_from`` (as for a single edit: 0, or the largest height
        change of the last solve's full answer, a fraction of the peak, when it was over
        :data:`.pipeline.MAX_CHANGE`); all share ``mesh``.
    timings : dict[str, float]
    solver : str
    rounds : int
        Solves run (1, or more when a stroke's change was reduced).
    """

    mesh: Mesh
    changed: np.ndarray
    parts: list
    timings: dict = field(default_factory=dict)
    solver: str = "gauss_newton"
    rounds: int = 1

    @property
    def layer(self):
        return self.parts[0].layer

    @property
    def h(self) -> float:
        return self.parts[0].h

    @property
    def c(self) -> list[float]:
        return [p.c for p in self.parts]

    @property
    def params(self) -> dict:
        return self.parts[0].params

    @property
    def edit_zone(self):
        return shapely.union_all([p.edit_zone for p in self.parts])

    @property
    def support(self):
        return shapely.union_all([p.support for p in self.parts])

    def new_isophotes(self) -> list:
        """Each stroke's isophote as it now runs near it (polylines (k, 2))."""
        return [line for p in self.parts for line in p.new_isophotes()]

    def characteristics(self, n: int = 15) -> list:
        return [line for p in self.parts for line in p.characteristics(max(3, n // len(self.parts)))]

    @property
    def bounded_from(self) -> float:
        """0, or the largest height change of the full joint answer (fraction of the peak) when
        it was over :data:`.pipeline.MAX_CHANGE` and the edit was scaled down."""
        return self.parts[0].bounded_from

    def describe(self) -> str:
        """One line: how far each isophote was and is from its stroke."""
        bits = []
        for i, p in enumerate(self.parts, start=1):
            part = "" if p.fraction == 1.0 else f" ({p.fraction:.0%} of its change)"
            bits.append(f"{i}: {p.before / p.h:.1f} → {p.after / p.h:.1f}{part}")
        text = f"{len(self.parts)} isophotes, edge lengths from their strokes " + ", ".join(bits)
        if self.bounded_from:
            text += (f"; the whole change would have changed heights by {self.bounded_from:.0%} of the peak, "
                     f"at most {MAX_CHANGE:.0%} is allowed")
        ignored = [(i, p) for i, p in enumerate(self.parts, start=1) if p.ignored_length >= 0.5 * p.h]
        if ignored:
            text += "; outside their bands and ignored: " + ", ".join(
                f"{p.ignored_fraction:.0%} of stroke {i}" for i, p in ignored)
        return text


def check_contradictions(prepared: list) -> None:
    """Refuse strokes that ask for two brightnesses at one point: strokes of isophotes whose
    values differ (by more than SAME_VALUE) that cross. One line naming both."""
    geoms = [p.stroke_geom for p in prepared]
    for i in range(len(prepared)):
        for j in range(i + 1, len(prepared)):
            a, b = prepared[i], prepared[j]
            if abs(a.c - b.c) > SAME_VALUE and geoms[i].intersects(geoms[j]):
                raise SculptError(
                    f"strokes {i + 1} and {j + 1} cross, but they redraw isophotes of different brightness "
                    f"(n·l = {a.c:.3f} and {b.c:.3f}), which can never meet: redraw one of them so that they do not cross"
                )


def joint_problem(ld, parts: list[SculptProblem], fractions: list[float]) -> SculptProblem:
    """The :class:`SculptProblem` of several isophotes on layer ``ld``: ``parts`` the single
    problems (:func:`.pipeline.build_problem`), ``fractions`` (one per part) the share of each
    stroke's change asked for (1: E = c_i along it)."""
    pd, h = ld.planar, ld.h
    hds = [p.host_data for p in parts]
    B = sp.vstack([hd.B for hd in hds]).tocsr()
    values = []
    for p, hd, f in zip(parts, hds, fractions):
        if f == 1.0:
            values.append(np.full(len(p.samples), p.c))
        else:  # part of the change only: E + f (c - E) at its samples
            E_s = hd.B @ ld.E
            values.append(E_s + f * (p.c - E_s))
    values = np.concatenate(values)
    samples = StrokeSamples(np.concatenate([hd.samples.P for hd in hds]), np.concatenate([hd.samples.w for hd in hds]))
    rim_w = np.concatenate([hd.sample_rim_weight for hd in hds])
    pieces = [piece for p in parts for piece in p.stroke]
    honoured = np.concatenate([hd.honoured for hd in hds])
    counts = np.array([len(hd.honoured) for hd in hds], dtype=np.float64)

    def change(free, weights):
        return shading_change(pd, ld.E, free, B, weights, values)

    def after(z):
        return float(np.dot([p.distance_after(z) for p in parts], counts) / counts.sum())

    def to_stroke(P, upper):
        return np.min([p.distance_to_stroke(P, upper) for p in parts], axis=0)

    first = parts[0]
    return SculptProblem(
        V=first.V, F=first.F, is_rim=first.is_rim, light=first.light, model=first.model, E=first.E, h=h, c=first.c,
        pick=first.pick, isophote=first.isophote, band=shapely.union_all([p.band for p in parts]),
        band_radius=max(p.band_radius for p in parts), in_band=np.logical_or.reduce([p.in_band for p in parts]),
        stroke=pieces, samples=samples.P, sample_weights=np.concatenate([p.sample_weights for p in parts]),
        d_rim=first.d_rim, rim_margin=first.rim_margin, outline=first.outline, Q=first.Q,
        before=float(np.dot([p.before for p in parts], counts) / counts.sum()),
        _slopes=first._slopes, _shading=first._shading, _shading_change=change, _distance_after=after,
        _locate=first._locate, _distance_to_stroke=to_stroke,
        host_data=HostData(ld, pieces, samples, B, rim_w, honoured),
        parts=tuple(parts), _sample_values=values, crease_bound=first.crease_bound, jump_bound=first.jump_bound,
    )


def _refuse(prepared: list, afters: list[float], worse: list[int], h: float, bound: str) -> None:
    """Refuse a joint edit whose fallbacks are spent with strokes ``worse`` still ending farther
    from their isophotes (``afters``, drawing units): as already done when every stroke lies
    within the shading's resolution of its isophote (a single edit's rule), else naming the
    stroke that lost most, with ``bound`` (the bound's figure, or "")."""
    tolerance = RESOLUTION_EDGES * h
    if all(e.before <= tolerance for e in prepared):
        raise NothingToDoError("every stroke lies on its isophote already (within what the shading resolves), and "
                               "this edit would leave one farther from it: nothing to change")
    i = max(worse, key=lambda k: afters[k] - prepared[k].before)
    e = prepared[i]
    if e.before <= tolerance:
        raise SculptError(
            f"stroke {i + 1} (isophote n·l = {e.c:.3f}) lies on its isophote already ({e.before / h:.2f} edge lengths "
            f"from it), and every version of the edit left it farther ({afters[i] / h:.2f}){bound}; draw the other "
            "strokes further from it, or apply them without it"
        )
    raise SculptError(
        f"stroke {i + 1} (isophote n·l = {e.c:.3f}): every version of the edit left its isophote "
        f"farther from it ({afters[i] / h:.1f} edge lengths) than it was ({e.before / h:.1f}){bound}; draw it "
        "closer to the old isophote or further from the rim, or apply it on its own"
    )


def sculpt_many(
    mesh: Mesh,
    light,
    edits,
    model: ReflectanceModel = LAMBERTIAN,
    solver=None,
    params: dict | None = None,
    never_worse: bool = True,
    provider: str | None = None,
    reference: Mesh | None = None,
) -> JointSculptResult:
    """Redraw several isophotes of one layer in one solve (see the module docstring).

    Parameters
    ----------
    mesh : Mesh
    light : (3,) float64
        Unit direction towards the light (z >= 0).
    edits : sequence of (pick (2,), band float, stroke (k, 2))
        One per isophote, in order (messages number them from 1).
    model, solver, params, never_worse, provider, reference
        As for :func:`.pipeline.sculpt`.

    Raises
    ------
    SculptError
        No stroke or too many; a solver that takes one isophote per edit; a stroke a single
        edit would refuse (named: "stroke 2: ..."); strokes that cross with different values;
        a stroke whose isophote every version of the edit leaves farther from it.
    NothingToDoError
        Every stroke lies on its isophote already (within the shading's resolution, and every
        version of the edit leaves one farther; or the edit changes nothing).
    """
    solver = _default_solver() if solver is None else solver
    edits = list(edits)
    if not edits:
        raise SculptError("an edit of several isophotes needs at least one stroke")
    if len(edits) > MAX_ISOPHOTES:
        raise SculptError(f"one edit redraws at most {MAX_ISOPHOTES} isophotes, this one {len(edits)}: apply them in parts")
    if len(edits) > 1 and not getattr(solver, "several_isophotes", False):
        raise SculptError(one_at_a_time(solver.name, len(edits)))
    if len(edits) == 1:
        pick, band, stroke = edits[0]
        r = sculpt(mesh, light, pick, band, stroke, model, solver, params, never_worse, provider, reference)
        return JointSculptResult(r.mesh, r.changed, [r], dict(r.timings), r.solver, 1)
    full = solver_params(solver, params)
    light = np.asarray(light, np.float64).reshape(3)
    T: dict = {}
    t0 = time.perf_counter()
    ld = layer_data(mesh, light, model)
    pd, h = ld.planar, ld.h
    prepared, parts = [], []
    for i, (pick, band, stroke) in enumerate(edits, start=1):
        try:
            e = _prepare(ld, pick, band_radius(band), stroke)
        except SculptError as exc:
            raise SculptError(f"stroke {i}: {exc}") from None
        prepared.append(e)
        parts.append(build_problem(ld, e.c, pick, e.iso, e.band, e.in_band, e.radius, e.pieces, e.honoured, e.before,
                                   reference))
    check_contradictions(prepared)
    T["strokes"] = time.perf_counter() - t0

    fractions = [1.0] * len(parts)
    steps = (1.0,) + FALLBACK_FRACTIONS
    rounds = 0
    while True:
        rounds += 1
        t = time.perf_counter()
        problem = joint_problem(ld, parts, fractions)
        solution, dz = _run_solver(solver, problem, full, provider, len(pd.V2))
        T[f"solve.{rounds}"] = time.perf_counter() - t
        largest, scale = change_bound(ld, dz)
        z = np.maximum(ld.z + scale * dz, 0.0)  # heights >= 0 by contract
        z[pd.is_contour] = 0.0
        afters = [p.distance_after(z) for p in parts]
        # No tolerance (as for a single edit): a stroke within the shading's resolution of its
        # isophote may not end farther from it either.
        worse = [i for i, (e, a) in enumerate(zip(prepared, afters)) if a > e.before]
        if not never_worse or not worse:
            break
        # A stroke whose isophote ends farther than it started is mostly pulled off by the
        # others (on the corpus, asking the others for less saved half of such pairs, asking
        # it for less none): the others give up half, then a quarter of their change first,
        # then that stroke itself (today's rule for one isophote).
        others = [i for i in range(len(parts)) if i not in worse and fractions[i] != steps[-1]]
        mine = [i for i in worse if fractions[i] != steps[-1]]
        if rounds >= MAX_ROUNDS or not (others or mine):
            _refuse(prepared, afters, worse, h, bound_note(largest) if scale < 1.0 else "")
        for i in others or mine:
            fractions[i] = steps[steps.index(fractions[i]) + 1]
    if not np.isfinite(z).all():
        raise SolverError("the edit produced non-finite heights; the layer was left unchanged")
    changed = z != ld.z
    if not changed.any():
        raise NothingToDoError("every stroke lies on its isophote already: nothing to change")
    new_mesh = mesh.with_heights(z)
    T["total"] = time.perf_counter() - t0
    dE = np.zeros(len(z)) if solution.dE is None else np.asarray(solution.dE, dtype=np.float64)
    reach = float(solution.info.get("reach", max(e.radius for e in prepared)))
    bounded = largest if scale < 1.0 else 0.0
    results = [
        SculptResult(new_mesh, changed, e.c, e.iso, e.band, e.stroke_geom, dE, e.before, a, f * scale, T, full, ld,
                     e.radius, reach, solver.name, solution, e.ignored, e.ignored / e.drawn if e.drawn > 0 else 0.0,
                     bounded)
        for e, a, f in zip(prepared, afters, fractions)
    ]
    return JointSculptResult(new_mesh, changed, results, T, solver.name, rounds)
