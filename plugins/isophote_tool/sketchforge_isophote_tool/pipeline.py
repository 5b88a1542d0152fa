"""The isophote edit as a pure function: ``sculpt(mesh, light, pick, band, stroke) -> SculptResult``.

This module is the sculpt *host*: it does what every sculpt solver shares and hands the rest
to the named solver (``sketchforge_sculpt_solvers``; the built-in ``gauss_newton`` in
:mod:`.gauss_newton`, the thesis' ``strips`` in the ``strips`` plugin).

1. pick -> isovalue c (0 in shadow), the isophote through the pick, band = isophote ⊕ disk
   (:mod:`.isophote`)
2. stroke: loops, hooks and back-tracking removed, smoothed, resampled, clipped to the band
   (:mod:`.stroke`, :mod:`sketchforge.geometry.strokes`); where an isophote is promised (the
   stroke inside the band and outside the rim margin) and how far it is now
3. the solver: a :class:`~sketchforge.plugins.sculpt_problem.SculptProblem` in, the height
   change δz out (the thesis' 4.3–4.6: regions, shading, heights)
4. the host's checks, the same for every solver: heights >= 0 and 0 on the rim, finite, and
   never worse: if the isophote ends farther from the stroke than it started, the best
   partial edit is kept (half, a quarter of the change); if none is closer, the edit is
   refused with what to draw instead (:mod:`.fidelity`), or as already done when the stroke
   lies within the shading's resolution of the isophote; a change of more than
   :data:`MAX_CHANGE` of the peak is scaled down to it first. A band narrower than one edge
   length, and a stroke whose moving part lies only in the rim margin, are refused before
   any solve.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
from scipy.spatial import cKDTree

from sketchforge.plugin_api import (
    LAMBERTIAN,
    LRUCache,
    Mesh,
    NothingToDoError,
    ParameterError,
    PluginError,
    ReflectanceModel,
    SculptError,
    SculptProblem,
    SculptSolution,
    SketchforgeError,
    SolverError,
    band_radius,
)

from .creases import crease_bounds
from .fidelity import honoured_samples, isophote_lines, mean_distance
from .isophote import band_around, picked_isophote
from .layerdata import LayerData, layer_data, vertex_shading
from .shading import bary_rows, shading_change
from .stroke import clip_to_band, prepare_stroke, resample_polyline, stroke_samples

#: Partial edits tried, in order, when the full one would leave the isophote farther from the
#: stroke than before.
FALLBACK_FRACTIONS = (0.5, 0.25)
#: Distances below this many edge lengths are below what first-order vertex normals resolve:
#: a stroke within it of the isophote asks for no change where it runs (its "moving part" is
#: the rest).
RESOLUTION_EDGES = 0.25
#: The largest height change an edit may make, as a fraction of the layer's peak: a larger one
#: is scaled down to it (and then halved, quartered, as any edit that overshoots), and refused
#: with the figure if no scaled version brings the isophote closer.
MAX_CHANGE = 0.6


@dataclass
class SculptResult:
    """Outcome of one isophote edit.

    Attributes
    ----------
    mesh : Mesh
        Same V order (only z changed), same F, boundary, junction.
    changed : (n,) bool
        Vertices whose height changed.
    c : float
        The isovalue.
    isophote : shapely LineString
        The selected isophote.
    band : shapely geometry
    stroke : shapely (Multi)LineString
        The cleaned stroke clipped to the band.
    dE : (n,) float64
        The shading change the solver aimed at (zeros if it reports none).
    before, after : float
        Mean distance from the stroke to the isophote before and after, in drawing units.
    fraction : float
        1 for the full edit; 0.5 or 0.25 when only part of it brought the isophote closer.
    timings : dict[str, float]
        Seconds per step.
    params : dict
        The solver's complete parameters.
    layer : LayerData
        The layer before the edit (for :meth:`characteristics`).
    band_radius : float
    reach : float
        How far from the stroke heights could change (the solver's answer; the band radius
        plus the ring for ``gauss_newton``).
    solver : str
        The sculpt solver that made it.
    solution : SculptSolution
        What the solver returned (its regions, curves and numbers).
    ignored_length, ignored_fraction : float
        Length (drawing units) and share of the cleaned stroke that was not used: outside the
        band, or in pieces inside it shorter than half an edge length. The person is told
        (:meth:`describe`), since drawing outside the band changes nothing there.
    bounded_from : float
        0, or the largest height change of the solver's full answer as a fraction of the peak
        when it was over :data:`MAX_CHANGE` and the edit was scaled down (the person is told).
    """

    mesh: Mesh
    changed: np.ndarray
    c: float
    isophote: Any  # shapely geometries (untyped)
    band: Any
    stroke: Any
    dE: np.ndarray
    before: float
    after: float
    fraction: float = 1.0
    timings: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    layer: Any = field(default=None, repr=False)  # the LayerData it was solved on
    band_radius: float = 0.0
    reach: float = 0.0
    solver: str = "gauss_newton"
    solution: Any = field(default=None, repr=False)  # the solver's SculptSolution
    ignored_length: float = 0.0
    ignored_fraction: float = 0.0
    bounded_from: float = 0.0

    @property
    def options(self) -> dict:
        """The solver's parameters (the name before solvers were named)."""
        return self.params

    def _region(self, name: str):
        got = getattr(self.solution, name, None) if self.solution is not None else None
        return got() if callable(got) else got

    @property
    def edit_zone(self):
        """Where the shading changes (shapely; built on request, for display): the solver's
        own region, or the band within one band radius of the stroke."""
        own = self._region("shading_region")
        return own if own is not None else self.band.intersection(self.stroke.buffer(self.band_radius))

    @property
    def support(self):
        """Where heights may change, inside the layer (shapely): the solver's own region, or
        the stroke's neighbourhood of radius :attr:`reach`."""
        own = self._region("height_region")
        return own if own is not None else self.stroke.buffer(self.reach).intersection(self.layer.outline)

    def new_isophotes(self) -> list:
        """The isophote E = c on the edited surface (polylines (k, 2) within the support), for
        display: where the redrawn isophote actually landed."""
        pd = self.layer.planar
        E, _, _ = vertex_shading(pd, self.mesh.V[:, 2], self.layer.light, self.layer.model)
        near = shapely.intersection(isophote_lines(pd, E, self.c), self.support)
        return [np.asarray(g.coords) for g in getattr(near, "geoms", [near]) if g.geom_type == "LineString" and not g.is_empty]

    def describe(self) -> str:
        """One line for the person: how far the isophote was and is from the stroke, and what
        of the stroke was ignored."""
        if self.bounded_from:
            part = (f" ({self.fraction:.0%} of the change: the whole of it would have changed heights by "
                    f"{self.bounded_from:.0%} of the peak, at most {MAX_CHANGE:.0%} is allowed)")
        else:
            part = "" if self.fraction == 1.0 else f" ({self.fraction:.0%} of the change: the whole of it overshot)"
        text = f"isophote {self.before / self.h:.1f} → {self.after / self.h:.1f} edge lengths from the stroke{part}"
        # Less than half an edge length left out is the clipping's own rounding at the ends.
        if self.ignored_length >= 0.5 * self.h:
            text += (f"; {self.ignored_fraction:.0%} of the stroke ({self.ignored_length:.3g} drawing units) lay outside "
                     "the band and was ignored")
        return text

    @property
    def h(self) -> float:
        """The layer's edge length (fidelity is best read in edge lengths)."""
        return self.layer.h

    def characteristics(self, n: int = 15) -> list:
        """Curves to show with "show characteristics" (polylines (k, 2)): the solver's own
        (the strips it integrated), or base characteristics through the stroke, traced on
        request (see :mod:`.characteristics`)."""
        own = getattr(self.solution, "curves", None)
        if own:
            return [np.asarray(c, dtype=np.float64) for c in own]
        from .characteristics import base_characteristics

        pieces = [np.asarray(g.coords) for g in getattr(self.stroke, "geoms", [self.stroke])]
        return base_characteristics(self.layer, pieces, self.reach, n)


_PICKS = LRUCache(8, name="picks")


def _pick(ld: LayerData, pick, r: float):
    """(c, isophote, band, in_band) for a pick, in_band (n,) bool the vertices inside the band;
    cached: redrawing the stroke for the same pick (the app's live preview does it on every
    throttled mouse move) skips the isophote and band."""
    p = np.asarray(pick, dtype=np.float64).reshape(-1)
    key = (id(ld), p.tobytes(), r)

    def make():
        c, iso = picked_isophote(ld, pick)
        band_geom = band_around(ld, iso, r)
        shapely.prepare(band_geom)
        in_band = shapely.contains_xy(band_geom, ld.V2[:, 0], ld.V2[:, 1])
        in_band.setflags(write=False)
        return ld, c, iso, band_geom, in_band

    hit = _PICKS.get_or_make(key, make)
    if hit[0] is not ld:  # an id reused by a newer LayerData: recompute
        hit = make()
    return hit[1:]


def smoothstep(t: np.ndarray) -> np.ndarray:
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def distance_to(pieces: list[np.ndarray], P: np.ndarray, h: float, upper: float) -> np.ndarray:
    """Distance (k,) from points P (k, 2) to the stroke pieces, capped at ``upper``: the nearest
    of samples every h/8 along them (within h/64 of the exact distance; a minimum of
    continuous functions, so continuous in the stroke)."""
    S = np.concatenate([resample_polyline(p, 0.125 * h) for p in pieces])
    d, _ = cKDTree(S).query(P, distance_upper_bound=upper)
    return np.minimum(d, upper)


@dataclass
class HostData:
    """What the built-in solvers read beyond the :class:`SculptProblem` (``host_data``): the
    layer's cached operators and the stroke's quadrature, so nothing is computed twice."""

    layer: LayerData
    pieces: list
    samples: object  # StrokeSamples
    B: object  # (k, n) barycentric rows of the samples
    sample_rim_weight: np.ndarray  # (k,) the rim fade of the samples with the layer's margin
    honoured: np.ndarray


def _slopes(ld: LayerData):
    """(p, q, E, R_p, R_q) at the vertices of a layer, once per LayerData."""
    got = getattr(ld, "_slopes_cache", None)
    if got is None:
        from sketchforge.plugin_api import evaluate_pq, slopes_from_heights

        pd = ld.planar
        p, q = slopes_from_heights(pd.Gp, pd.Gq, ld.z)
        E, Rp, Rq = evaluate_pq(ld.model, p, q, ld.light)
        got = (p, q, E, Rp, Rq)
        ld._slopes_cache = got
    return got


def _moves_only_in_margin(pd, pieces: list[np.ndarray], iso, honoured: np.ndarray, h: float) -> bool:
    """Whether the stroke asks for a move only inside the rim margin: outside it, where an
    isophote is promised, it runs within the resolution of the isophote (mean distance), while
    inside the margin some of it is farther. Such a stroke is refused like one drawn entirely
    there (it once got "lies on the isophote already" from one solver, and from the other a
    change of 9% of the peak that barely moved the isophote). The stroke's own smoothing
    carries a little of the move out of the margin, hence the mean, not each point."""
    if mean_distance(honoured, iso) > RESOLUTION_EDGES * h:
        return False
    P = np.concatenate(pieces)
    off = shapely.distance(shapely.points(P), iso) > RESOLUTION_EDGES * h
    return bool(np.any(off & (pd.rim_distance(P) < pd.margin_at(P))))


def build_problem(ld: LayerData, c: float, pick, iso, band_geom, in_band: np.ndarray, r: float, pieces: list,
                  honoured: np.ndarray, before: float, reference: Mesh | None = None) -> SculptProblem:
    """The :class:`SculptProblem` of an edit on layer ``ld`` (services bound to its data; its
    crease bounds relative to the layer as inflated, ``reference``, when given)."""
    crease_bound, jump_bound = crease_bounds(reference, ld.light, ld.model)
    pd, h = ld.planar, ld.h
    samples = stroke_samples(pieces)
    ds_rim = pd.rim_distance(samples.P)
    m_s = np.minimum(pd.margin_at(samples.P), pd.margin)
    w_rim = smoothstep(ds_rim / np.maximum(m_s, 1e-300)) if pd.margin > 0 else np.ones(len(ds_rim))
    B = bary_rows(pd, samples.P)

    def shading(z):
        return vertex_shading(pd, z, ld.light, ld.model)

    def change(free, weights):
        return shading_change(pd, ld.E, free, B, weights, c)

    def after(z):
        E, _, _ = vertex_shading(pd, z, ld.light, ld.model)
        return mean_distance(honoured, isophote_lines(pd, E, c))

    return SculptProblem(
        V=ld.mesh.V, F=pd.F, is_rim=pd.is_contour, light=ld.light, model=ld.model, E=ld.E, h=h, c=float(c),
        pick=np.asarray(pick, np.float64).reshape(2), isophote=np.asarray(iso.coords, np.float64)[:, :2],
        band=band_geom, band_radius=r, in_band=in_band,
        stroke=pieces, samples=samples.P, sample_weights=samples.w * w_rim, d_rim=pd.d_rim,
        rim_margin=np.minimum(pd.margin_v, pd.margin), outline=pd.outline, Q=pd.Q, before=before,
        _slopes=lambda: _slopes(ld), _shading=shading, _shading_change=change, _distance_after=after,
        _locate=lambda P: pd.locator.locate(P), _distance_to_stroke=lambda P, u: distance_to(pieces, P, h, u),
        host_data=HostData(ld, pieces, samples, B, w_rim, honoured), crease_bound=crease_bound, jump_bound=jump_bound,
    )


@dataclass
class PreparedStroke:
    """One redrawn isophote, ready for a solver: the pick's isovalue ``c``, isophote ``iso``
    and band (``band``, ``in_band`` (n,) bool, ``radius``), the cleaned stroke clipped to the
    band (``pieces``, ``stroke_geom``), the samples where an isophote is promised
    (``honoured``), the mean distance from them to the isophote now (``before``) and how much
    of the drawn stroke was left out (``ignored`` of ``drawn``, drawing units)."""

    c: float
    iso: Any  # shapely geometries (untyped)
    band: Any
    in_band: np.ndarray
    radius: float
    pieces: list
    stroke_geom: object
    honoured: np.ndarray
    before: float
    ignored: float
    drawn: float


def _prepare(ld: LayerData, pick, r: float, stroke) -> PreparedStroke:
    """Pick, band and stroke of one isophote edit on ``ld`` (band radius ``r``). Raises
    SculptError for a band narrower than one edge length, a stroke with no part inside the band,
    or one whose moving part lies only within the rim margin."""
    pd, h = ld.planar, ld.h
    if r < h:
        # Narrower than one edge length the band holds no vertex to change across it: the edit
        # would do nothing visible.
        raise SculptError(f"the band ({r:.3g}) is narrower than one edge length of this layer ({h:.3g}): "
                          f"widen it to at least {h:.3g}")
    c, iso, band_geom, in_band = _pick(ld, pick, r)
    cleaned = prepare_stroke(stroke, h)
    pieces = clip_to_band(cleaned, band_geom, h)
    drawn = float(np.sum(np.linalg.norm(np.diff(cleaned, axis=0), axis=1)))
    used = float(sum(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)) for p in pieces))
    ignored = max(0.0, drawn - used)
    stroke_geom = shapely.MultiLineString(pieces) if len(pieces) > 1 else shapely.LineString(pieces[0])
    honoured = honoured_samples(pd, pieces, band_geom)
    if len(honoured) == 0 or _moves_only_in_margin(pd, pieces, iso, honoured, h):
        local = float(np.max(np.minimum(pd.margin_at(np.concatenate(pieces)), pd.margin)))
        raise SculptError(
            f"the stroke runs within the rim margin ({local:.2g} from the outline here), where the surface "
            "turns vertical and cannot follow a redrawn isophote: draw it further inside the shape"
        )
    before = mean_distance(honoured, iso)
    return PreparedStroke(c, iso, band_geom, in_band, r, pieces, stroke_geom, honoured, before, ignored, drawn)


def _run_solver(solver, problem: SculptProblem, full: dict, provider, n: int):
    """``solver.solve(problem, full)`` as (SculptSolution, dz (n,) float64): a solver's bug is
    a PluginError naming it, a wrong shape too, non-finite heights a SolverError."""
    try:
        answer = solver.solve(problem, full)
    except SketchforgeError:
        raise
    except Exception as exc:  # noqa: BLE001 - a solver's bug: named, never a crash of the app
        who = f" of plugin {provider!r}" if provider else ""
        raise PluginError(f"the sculpt solver {solver.name!r}{who} failed: {type(exc).__name__}: {exc}") from exc
    solution = answer if isinstance(answer, SculptSolution) else SculptSolution(np.asarray(answer))
    dz = np.asarray(solution.dz, dtype=np.float64)
    if dz.shape != (n,):
        raise PluginError(f"the sculpt solver {solver.name!r} returned heights of shape {dz.shape}; the layer has "
                          f"{n} vertices")
    if not np.isfinite(dz).all():
        raise SolverError(f"the sculpt solver {solver.name!r} produced non-finite heights; the layer was left unchanged")
    return solution, dz


def change_bound(ld: LayerData, dz: np.ndarray) -> tuple[float, float]:
    """The largest height change of ``dz`` (n,) off the rim as a fraction of the layer's peak,
    and the scale (<= 1) that brings it to :data:`MAX_CHANGE` (1 when it is within)."""
    peak = float(ld.z.max())
    largest = float(np.abs(np.where(ld.planar.is_contour, 0.0, dz)).max(initial=0.0)) / max(peak, 1e-300)
    return largest, (min(1.0, MAX_CHANGE / largest) if largest > 0.0 else 1.0)


def bound_note(largest: float) -> str:
    """The figure a refusal of a scaled-down edit gives (``largest``: see :func:`change_bound`)."""
    return f" (the full edit would change heights by {largest:.0%} of the peak; at most {MAX_CHANGE:.0%} is applied)"


def _default_solver():
    from .gauss_newton import GAUSS_NEWTON

    return GAUSS_NEWTON


def solver_params(solver, params) -> dict:
    """``solver``'s complete parameters for ``params``, its own check's error named."""
    try:
        return solver.check_params(dict(params or {}))
    except SketchforgeError as exc:
        raise ParameterError(f"sculpt solver {solver.name!r}: {exc}") from None


def sculpt(
    mesh: Mesh,
    light,
    pick,
    band: float,
    stroke,
    model: ReflectanceModel = LAMBERTIAN,
    solver=None,
    params: dict | None = None,
    never_worse: bool = True,
    provider: str | None = None,
    reference: Mesh | None = None,
) -> SculptResult:
    """Redraw the isophote through ``pick`` along ``stroke``; recompute the heights it affects.

    Parameters
    ----------
    mesh : Mesh
        The layer's front surface (z >= 0, z = 0 on ``mesh.boundary``).
    light : (3,) float64
        Unit direction towards the light (z >= 0).
    pick : (2,) float64
        A point on the layer; its shading (0 in shadow) is the isovalue c.
    band : float
        Radius of the band around the isophote (drawing units, > 0).
    stroke : (k, 2) float64
        The redrawn isophote; parts outside the band are ignored (and reported).
    model : ReflectanceModel
        Solver-side reflectance (any registered model).
    solver : SculptSolver or None
        The sculpt solver (None: the built-in ``gauss_newton``).
    params : dict or None
        The solver's parameters (it checks them: unknown keys are refused).
    never_worse : bool
        Keep a partial edit, or refuse, rather than end farther from the stroke.
    provider : str or None
        The solver's plugin, for the message if it fails.
    reference : Mesh or None
        The layer as inflated, before any edit: the solver is asked to keep the creases it
        leaves within a bound relative to that layer's (:func:`.creases.crease_bounds`), so a
        chain of edits does not crease a finely meshed layer more than a coarse one. None: a
        fixed bound of 30 degrees.

    Returns
    -------
    SculptResult

    Raises
    ------
    SculptError
        Invalid pick, band or stroke, or a stroke the surface cannot follow (the message says
        what to draw instead).
    ParameterError
        A parameter the solver refuses (named).
    NothingToDoError
        The stroke lies on the isophote already.
    SolverError
        A solver produced non-finite values.
    PluginError
        The solver failed with an error that is not a SketchforgeError (a bug).
    """
    solver = _default_solver() if solver is None else solver
    full = solver_params(solver, params)
    r = band_radius(band)
    light = np.asarray(light, np.float64).reshape(3)
    T: dict = {}
    t0 = time.perf_counter()
    ld = layer_data(mesh, light, model)
    pd, h = ld.planar, ld.h
    T["layer"] = time.perf_counter() - t0

    t = time.perf_counter()
    e = _prepare(ld, pick, r, stroke)
    c, iso, band_geom, in_band, pieces, honoured, before = e.c, e.iso, e.band, e.in_band, e.pieces, e.honoured, e.before
    ignored, drawn, stroke_geom = e.ignored, e.drawn, e.stroke_geom
    problem = build_problem(ld, c, pick, iso, band_geom, in_band, r, pieces, honoured, before, reference)
    T["stroke"] = time.perf_counter() - t

    t = time.perf_counter()
    solution, dz = _run_solver(solver, problem, full, provider, len(pd.V2))
    # The solver's own stages (zones, shading, heights...) beside the host's.
    T.update({(k if k not in ("layer", "stroke", "solve", "check", "total") else f"solver.{k}"): float(v)
              for k, v in solution.info.get("timings", {}).items()})
    T["solve"] = time.perf_counter() - t

    t = time.perf_counter()
    largest, scale = change_bound(ld, dz)
    fraction, z, after = scale, None, np.inf
    for frac in (scale,) + (tuple(scale * f for f in FALLBACK_FRACTIONS) if never_worse else ()):
        zf = np.maximum(ld.z + frac * dz, 0.0)  # heights >= 0 by contract
        zf[pd.is_contour] = 0.0
        af = problem.distance_after(zf)
        if z is None or af < after:
            fraction, z, after = frac, zf, af
        if not never_worse or af <= before:
            break
    T["check"] = time.perf_counter() - t
    if never_worse and after > before:
        if before <= RESOLUTION_EDGES * h:
            # A stroke within the resolution of the isophote: no version of the edit may leave
            # it farther (the tolerance once let an edit through that moved heights by 24% of
            # the peak and took the isophote from 0.11 to 0.16 edge lengths).
            raise NothingToDoError(f"the stroke lies on the isophote already ({before / h:.2f} edge lengths from it, "
                                   "within what the shading resolves): nothing to change")
        bound = bound_note(largest) if scale < 1.0 else ""
        raise SculptError(
            f"the surface cannot take this shading here: every version of the edit left the isophote farther "
            f"from the stroke ({after / h:.1f} edge lengths) than it was ({before / h:.1f}){bound}; draw the new "
            "isophote closer to the old one, or further from the rim"
        )
    if not np.isfinite(z).all():
        raise SolverError("the edit produced non-finite heights; the layer was left unchanged")
    changed = z != ld.z
    if not changed.any():
        raise NothingToDoError("the stroke lies on the isophote already: nothing to change")
    new_mesh = mesh.with_heights(z)
    T["total"] = time.perf_counter() - t0
    dE = np.zeros(len(z)) if solution.dE is None else np.asarray(solution.dE, dtype=np.float64)
    reach = float(solution.info.get("reach", r))
    return SculptResult(
        new_mesh, changed, c, iso, band_geom, stroke_geom, dE, before, after, fraction, T, full, ld, r, reach,
        solver.name, solution, ignored, ignored / drawn if drawn > 0 else 0.0, largest if scale < 1.0 else 0.0,
    )
