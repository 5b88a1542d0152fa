"""The isophote edit as a pure function: ``sculpt(mesh, light, pick, band, stroke) -> SculptResult``.

Pipeline (thesis 4.3–4.6; what differs from the thesis and why is said in each module):

1. pick -> isovalue c (0 in shadow), the isophote through the pick, band = isophote ⊕ disk
   (:mod:`.isophote`)
2. stroke: loops, hooks and back-tracking removed, smoothed, resampled, clipped to the band
   (:mod:`.stroke`, :mod:`sketchforge.geometry.strokes`)
3. zones, all by distance to the stroke d_s (continuous in every input):
   edit zone   band ∩ {d_s < band radius}: where the shading may change (4.3's B•*);
   support U   {d_s < band radius + ring}: the vertices whose height may change; ring = rim
               margin + 2 edge lengths, so no vertex farther than band + margin + 2h from the
               stroke ever moves (4.3's M•, kept local: see :mod:`.heights`)
4. the shading change δE in the edit zone, E = c on the stroke (:mod:`.shading`, 4.4)
5. heights: Gauss–Newton on R(p, q) = E_old + δE over U (:mod:`.heights`, 4.5–4.6)
6. never worse: if the isophote ends farther from the stroke than it started, the best
   partial edit is kept (half, a quarter of the change); if none is closer, the edit is
   refused with what to draw instead (:mod:`.fidelity`).
"""

from __future__ import annotations

import time
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
import shapely
from scipy.spatial import cKDTree

from sketchforge.errors import NothingToDoError, SculptError, SolverError
from sketchforge.geometry.band import band_radius
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge.plugins.registry import ReflectanceModel

from .fidelity import honoured_samples, isophote_lines, mean_distance
from .heights import GN_STEPS, solve_heights
from .isophote import band_around, picked_isophote
from .layerdata import LayerData, cached, layer_data, vertex_shading
from .shading import bary_rows, shading_change
from .stroke import clip_to_band, prepare_stroke, resample_polyline, stroke_samples

#: Options of :func:`sculpt`; lengths "in edge lengths" are multiples of the mean edge length h.
DEFAULT_OPTIONS = {
    "smoothness": 1.0,  # α: weight of the squared Laplacian of the height change, in units of h²
    "ring": None,  # width of the ring around the edit zone where heights return to the old ones; None: rim margin + 2h
    "ring_weight": 0.1,  # data weight at the outer edge of the ring (1 in the edit zone)
    "rim_margin": None,  # drawing units; None: max(3h, 0.12·size), less where the layer is thin
    "steps": GN_STEPS,  # Gauss–Newton steps
    "stroke_weight": 20.0,  # weight of E = c along the stroke in the height solve, against a band of width h
    "never_worse": True,  # fall back to a partial edit, or refuse, rather than end farther from the stroke
}

#: Partial edits tried, in order, when the full one would leave the isophote farther from the
#: stroke than before.
FALLBACK_FRACTIONS = (0.5, 0.25)
#: Distances below this many edge lengths are below what first-order vertex normals resolve:
#: an edit that ends within it of the stroke is not "farther", whatever it started from.
RESOLUTION_EDGES = 0.25


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
        The shading change at the vertices (the target of the height solve is E + dE).
    before, after : float
        Mean distance from the stroke to the isophote before and after, in drawing units.
    fraction : float
        1 for the full edit; 0.5 or 0.25 when only part of it brought the isophote closer.
    timings : dict[str, float]
        Seconds per step.
    options : dict
    layer : LayerData
        The layer before the edit (for :meth:`characteristics`).
    band_radius : float
    reach : float
        Band radius plus ring: the farthest a changed vertex can be from the stroke.
    ignored_length, ignored_fraction : float
        Length (drawing units) and share of the cleaned stroke that was not used: outside the
        band, or in pieces inside it shorter than half an edge length. The person is told
        (:meth:`describe`), since drawing outside the band changes nothing there.
    """

    mesh: Mesh
    changed: np.ndarray
    c: float
    isophote: object
    band: object
    stroke: object
    dE: np.ndarray
    before: float
    after: float
    fraction: float = 1.0
    timings: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)
    layer: object = field(default=None, repr=False)
    band_radius: float = 0.0
    reach: float = 0.0
    ignored_length: float = 0.0
    ignored_fraction: float = 0.0

    @property
    def edit_zone(self):
        """Where the shading changes: the band within one band radius of the stroke (shapely;
        built on request, for display)."""
        return self.band.intersection(self.stroke.buffer(self.band_radius))

    @property
    def support(self):
        """Where heights may change: the edit zone and its ring, inside the layer (shapely)."""
        return self.stroke.buffer(self.reach).intersection(self.layer.outline)

    def new_isophotes(self) -> list:
        """The isophote E = c on the edited surface (polylines (k, 2) within the support), for
        display: where the redrawn isophote actually landed."""
        pd = self.layer.planar
        E, _, _ = vertex_shading(pd, self.mesh.V[:, 2], self.layer.light, self.layer.model)
        near = shapely.intersection(isophote_lines(pd, E, self.c), self.support)
        return [np.asarray(g.coords) for g in getattr(near, "geoms", [near]) if g.geom_type == "LineString" and not g.is_empty]

    def describe(self) -> str:
        """One line for the person: how far the isophote was and is from the stroke."""
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
        """Base characteristics through the stroke (polylines (k, 2)), for display; traced on
        request, not during the edit (see :mod:`.characteristics`)."""
        from .characteristics import base_characteristics

        pieces = [np.asarray(g.coords) for g in getattr(self.stroke, "geoms", [self.stroke])]
        return base_characteristics(self.layer, pieces, self.reach, n)


def _options(options: dict | None) -> dict:
    opts = dict(DEFAULT_OPTIONS)
    if options:
        unknown = set(options) - set(DEFAULT_OPTIONS)
        if unknown:
            raise SculptError(f"unknown sculpt options: {sorted(unknown)}; known: {sorted(DEFAULT_OPTIONS)}")
        opts.update(options)
    for key in ("smoothness", "ring_weight", "stroke_weight"):
        v = float(opts[key])
        if not (np.isfinite(v) and v >= 0):
            raise SculptError(f"the sculpt option {key!r} must be a number >= 0, got {opts[key]!r}")
    for key in ("ring", "rim_margin"):
        if opts[key] is not None:
            try:
                v = float(opts[key])
            except (TypeError, ValueError, OverflowError):
                v = float("nan")
            if not (np.isfinite(v) and v >= 0):
                raise SculptError(f"the sculpt option {key!r} must be a number >= 0 (drawing units) or None, got {opts[key]!r}")
    if not (isinstance(opts["steps"], (int, np.integer)) and 1 <= opts["steps"] <= 50):
        raise SculptError(f"the sculpt option 'steps' must be an integer in 1..50, got {opts['steps']!r}")
    return opts


_PICKS: "OrderedDict[tuple, tuple]" = OrderedDict()


def _pick(ld: LayerData, pick, r: float):
    """(c, isophote, band) for a pick, cached: redrawing the stroke for the same pick (the
    app's live preview does it on every throttled mouse move) skips the isophote and band."""
    p = np.asarray(pick, dtype=np.float64).reshape(-1)
    key = (id(ld), p.tobytes(), r)

    def make():
        c, iso = picked_isophote(ld, pick)
        band_geom = band_around(ld, iso, r)
        shapely.prepare(band_geom)
        return ld, c, iso, band_geom

    hit = cached(_PICKS, key, make)
    if hit[0] is not ld:  # an id reused by a newer LayerData: recompute
        hit = make()
    return hit[1:]


def _smoothstep(t: np.ndarray) -> np.ndarray:
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _distance_to(pieces: list[np.ndarray], P: np.ndarray, h: float, upper: float) -> np.ndarray:
    """Distance (k,) from points P (k, 2) to the stroke pieces, capped at ``upper``: the nearest
    of samples every h/8 along them (within h/64 of the exact distance; a minimum of
    continuous functions, so continuous in the stroke)."""
    S = np.concatenate([resample_polyline(p, 0.125 * h) for p in pieces])
    d, _ = cKDTree(S).query(P, distance_upper_bound=upper)
    return np.minimum(d, upper)


def sculpt(
    mesh: Mesh,
    light,
    pick,
    band: float,
    stroke,
    model: ReflectanceModel = LAMBERTIAN,
    options: dict | None = None,
) -> SculptResult:
    """Redraw the isophote through ``pick`` along ``stroke``; recompute the heights it affects.

    Parameters
    ----------
    mesh : Mesh
        The layer's front surface (z >= 0, z = 0 on ``mesh.boundary``).
    light : (3,) float64
        Unit light direction in the drawing plane (z = 0).
    pick : (2,) float64
        A point on the layer; its shading (0 in shadow) is the isovalue c.
    band : float
        Radius of the band around the isophote (drawing units, > 0).
    stroke : (k, 2) float64
        The redrawn isophote; parts outside the band are ignored.
    model : ReflectanceModel
        Solver-side reflectance (any registered model).
    options : dict or None
        Overrides of :data:`DEFAULT_OPTIONS`.

    Returns
    -------
    SculptResult

    Raises
    ------
    SculptError
        Invalid pick, band or stroke, or a stroke the surface cannot follow (the message says
        what to draw instead).
    NothingToDoError
        The stroke lies on the isophote already.
    SolverError
        A solver produced non-finite values.
    """
    opts = _options(options)
    r = band_radius(band)
    light = np.asarray(light, np.float64).reshape(3)
    T: dict = {}
    t0 = time.perf_counter()
    ld = layer_data(mesh, light, model)
    pd, h = ld.planar, ld.h
    margin = pd.margin if opts["rim_margin"] is None else float(opts["rim_margin"])
    T["layer"] = time.perf_counter() - t0

    t = time.perf_counter()
    c, iso, band_geom = _pick(ld, pick, r)
    cleaned = prepare_stroke(stroke, h)
    pieces = clip_to_band(cleaned, band_geom, h)
    drawn = float(np.sum(np.linalg.norm(np.diff(cleaned, axis=0), axis=1)))
    used = float(sum(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)) for p in pieces))
    ignored = max(0.0, drawn - used)
    stroke_geom = shapely.MultiLineString(pieces) if len(pieces) > 1 else shapely.LineString(pieces[0])
    honoured = honoured_samples(pd, pieces, band_geom)
    if len(honoured) == 0:
        local = float(np.max(np.minimum(pd.margin_at(np.concatenate(pieces)), margin)))
        raise SculptError(
            f"the stroke runs within the rim margin ({local:.2g} from the outline here), where the surface "
            "turns vertical and cannot follow a redrawn isophote: draw it further inside the shape"
        )
    before = mean_distance(honoured, iso)
    T["stroke"] = time.perf_counter() - t

    t = time.perf_counter()
    ring = margin + 2.0 * h if opts["ring"] is None else float(opts["ring"])
    interior = ~pd.is_contour
    d_s = _distance_to(pieces, pd.V2, h, r + ring)
    in_band = shapely.contains_xy(band_geom, pd.V2[:, 0], pd.V2[:, 1])
    free_E = in_band & (d_s < r) & interior
    U = (d_s < r + ring) & interior
    margin_v = np.minimum(pd.margin_v, margin)
    rim = _smoothstep(pd.d_rim / np.maximum(margin_v, 1e-300)) if margin > 0 else np.ones(len(pd.V2))
    w0 = float(opts["ring_weight"])
    w = rim * (w0 + (1.0 - w0) * (1.0 - _smoothstep((d_s - r) / max(ring, 1e-300))))
    samples = stroke_samples(pieces)
    ds_rim = pd.rim_distance(samples.P)
    m_s = np.minimum(pd.margin_at(samples.P), margin)
    w_s = _smoothstep(ds_rim / np.maximum(m_s, 1e-300)) if margin > 0 else np.ones(len(ds_rim))
    T["zones"] = time.perf_counter() - t

    t = time.perf_counter()
    B = bary_rows(pd, samples.P)
    dE = shading_change(pd, ld.E, free_E, B, samples.w * w_s, c)
    T["shading"] = time.perf_counter() - t

    t = time.perf_counter()
    dz = solve_heights(
        ld, ld.E + dE, U, w, float(opts["smoothness"]), int(opts["steps"]),
        (B, samples.w * w_s), c, float(opts["stroke_weight"]),
    )
    T["heights"] = time.perf_counter() - t

    t = time.perf_counter()
    fraction, z, after = 1.0, None, np.inf
    for frac in (1.0,) + (FALLBACK_FRACTIONS if opts["never_worse"] else ()):
        zf = np.maximum(ld.z + frac * dz, 0.0)  # heights >= 0 by contract
        zf[pd.is_contour] = 0.0
        Ef, _, _ = vertex_shading(pd, zf, light, model)
        af = mean_distance(honoured, isophote_lines(pd, Ef, c))
        if z is None or af < after:
            fraction, z, after = frac, zf, af
        if not opts["never_worse"] or af <= max(before, RESOLUTION_EDGES * h):
            break
    T["check"] = time.perf_counter() - t
    if opts["never_worse"] and after > max(before, RESOLUTION_EDGES * h):
        raise SculptError(
            f"the surface cannot take this shading here: every version of the edit left the isophote farther "
            f"from the stroke ({after / h:.1f} edge lengths) than it was ({before / h:.1f}); draw the new "
            "isophote closer to the old one, or further from the rim"
        )
    if not np.isfinite(z).all():
        raise SolverError("the edit produced non-finite heights; the layer was left unchanged")
    changed = z != ld.z
    if not changed.any():
        raise NothingToDoError("the stroke lies on the isophote already: nothing to change")
    new_mesh = mesh.with_heights(z)
    T["total"] = time.perf_counter() - t0
    return SculptResult(
        new_mesh, changed, c, iso, band_geom, stroke_geom, dE, before, after, fraction, T, opts, ld, r, r + ring,
        ignored, ignored / drawn if drawn > 0 else 0.0,
    )
