"""Regions of an edit (thesis 4.3, fig. 4.5-4.6): S•, B•, B•*, M•.

S•   cells between neighbouring sampled region strips that the stroke crosses, merged (every
     cell between the first and the last crossed one of an inflow arc).
B•   band ∩ S•.
B•*  B• ∩ Ω* (Ω*: the layer minus the rim margin).
M•   S• cut along the part of ∂B• that strips cross inward; the piece holding the stroke,
     clipped to Ω* (heights in the rim margin never change).
     Computed without a fragile ``split``: S• \\ B• falls into components; a component is
     downstream (part of M•) when the strips' net flux through its shared boundary with B•
     goes from B• into it. M• = B• ∪ downstream components, the piece holding the stroke.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import shapely

from sketchforge.errors import NothingToDoError
from sketchforge.plugins.registry import ReflectanceModel

from .gaps import StripGaps, insert_strips
from .layerdata import LayerData
from .strips import contour_runs, cyclic_runs, flow, integrate_region_strips, ring_points

#: Refinement rounds for the seeding of region strips.
MAX_REFINE = 5


@dataclass
class Regions:
    """Everything the region step computes, for display and tests (shapely geometries).

    Attributes
    ----------
    strips : list of (k, 2) float64
        All sampled region strips.
    S, B, B_star, M : shapely geometry
        S•, B•, B•*, M•.
    omega_star : shapely geometry
        Ω*, the layer minus the rim margin.
    entry : list of (k, 2) float64
        Polylines of ∂M• where strips enter M• (the cut curve; seeds of step 4.5).
    max_gap : float
        Largest distance between neighbouring strips inside S• near the band, after seeding.
    """

    strips: list = field(default_factory=list)
    S: object = None
    B: object = None
    B_star: object = None
    M: object = None
    omega_star: object = None
    entry: list = field(default_factory=list)
    max_gap: float = 0.0


def _cell(a: np.ndarray, b: np.ndarray):
    ring = np.concatenate([a, b[::-1]])
    if len(ring) < 3:
        return shapely.Polygon()
    poly = shapely.Polygon(ring)
    if not poly.is_valid:
        poly = shapely.make_valid(poly)
        parts = [g for g in getattr(poly, "geoms", [poly]) if g.geom_type in ("Polygon", "MultiPolygon")]
        poly = shapely.unary_union(parts) if parts else shapely.Polygon()
    return poly


def clean(geom, h: float):
    """Drop slivers left by polygon unions: holes and parts smaller than h² (shapely geometry)."""
    parts = []
    for p in _polygons(geom):
        holes = [r for r in p.interiors if shapely.Polygon(r).area >= h * h]
        q = shapely.Polygon(p.exterior, holes)
        if q.area >= 0.5 * h * h:
            parts.append(q)
    if not parts:
        return shapely.Polygon()
    return parts[0] if len(parts) == 1 else shapely.MultiPolygon(parts)


def compute_regions(
    ld: LayerData,
    light: np.ndarray,
    model: ReflectanceModel,
    band,
    stroke,
    margin: float,
    max_gap: float,
    timings: dict | None = None,
) -> Regions:
    """Sample region strips, refine them near the stroke, and build S•, B•, B•*, M•.

    Parameters
    ----------
    ld : LayerData
    light : (3,) float64
    model : ReflectanceModel
    band : shapely geometry
    stroke : shapely (Multi)LineString
        The stroke, already clipped to the band.
    margin : float
        Rim margin (Ω* = layer minus this margin).
    max_gap : float
        Target largest distance between neighbouring strips inside S• (≈ 2 edge lengths).
    timings : dict or None
        If given, the seconds spent integrating region strips are added under "strips".

    Raises
    ------
    NothingToDoError
        If no strip region holds the stroke.
    """
    h = ld.h
    omega_star = ld.omega_star(margin)
    runs = contour_runs(ld, light, model, spacing=0.5 * h)
    if not runs:
        raise NothingToDoError("no characteristic strip enters the layer under this light")
    coords = np.asarray(ld.outline.exterior.coords)
    zone = band.buffer(h).intersection(omega_star)
    gaps_of = StripGaps(zone)
    cell_memo: dict = {}  # (id, id) of two neighbouring strips -> (cell, hits stroke, refs)

    # Seeds per run: arc-length parameters, sorted. Strips start a quarter edge inside the
    # contour so their first sample lies in the layer.
    run_t = []
    for t0, t1 in runs:
        n = max(int(np.ceil((t1 - t0) / h)), 1)
        run_t.append(np.linspace(t0, t1, n + 1))

    def integrate(ts):
        t_ = time.perf_counter()
        P, n_in = ring_points(coords, ts)
        out = integrate_region_strips(ld, light, model, P + 0.25 * h * n_in, margin)
        if timings is not None:
            timings["strips"] = timings.get("strips", 0.0) + time.perf_counter() - t_
        return out

    flat = np.concatenate(run_t)
    all_strips = integrate(flat)
    run_s, k = [], 0
    for t in run_t:
        run_s.append(all_strips[k : k + len(t)])
        k += len(t)

    shapely.prepare(stroke)

    def crossed_range(strips_):
        # Cells between strips already paired in an earlier round are reused: only the
        # cells next to inserted strips are new.
        cells, hits, new = [], [], []
        for i in range(len(strips_) - 1):
            a, b = strips_[i], strips_[i + 1]
            m = cell_memo.get((id(a), id(b)))
            if m is None:
                new.append(i)
                cells.append(_cell(a, b))
                hits.append(False)
            else:
                cells.append(m[0])
                hits.append(m[1])
        if new:
            geoms = np.array([cells[i] for i in new], dtype=object)
            inter = shapely.intersects(stroke, geoms) & ~shapely.is_empty(geoms)
            for i, x in zip(new, inter):
                hits[i] = bool(x)
                cell_memo[(id(strips_[i]), id(strips_[i + 1]))] = (cells[i], hits[i], strips_[i], strips_[i + 1])
        return cells, np.nonzero(hits)[0]

    worst = 0.0
    S_parts = []
    for r in range(len(runs)):
        t, st = run_t[r], run_s[r]
        for _ in range(MAX_REFINE + 1):
            cells, hit = crossed_range(st)
            if len(hit) == 0:
                break
            a, b = max(hit.min() - 1, 0), min(hit.max() + 1, len(cells) - 1)
            gaps = gaps_of([(st[i], st[i + 1]) for i in range(a, b + 1)])
            bad = np.nonzero((gaps > max_gap) & (np.diff(t)[a : b + 1] > 1e-3 * h))[0] + a
            worst = max(worst, float(gaps[(hit.min() - a) : (hit.max() - a + 1)].max(initial=0.0)))
            if len(bad) == 0 or _ == MAX_REFINE:
                break
            new_t = 0.5 * (t[bad] + t[bad + 1])
            t, st = insert_strips(t, st, new_t, integrate(new_t))
            worst = 0.0
        run_t[r], run_s[r] = t, st
        if len(hit):
            S_parts.extend(cells[hit.min() : hit.max() + 1])
    strips = [s for st in run_s for s in st]
    if not S_parts:
        raise NothingToDoError("the stroke crosses no characteristic strip (it lies outside the region strips cover)")
    S = clean(shapely.unary_union(S_parts), h)
    B = clean(band.intersection(S), h)
    B_star = clean(B.intersection(omega_star), h)
    M = _impacted(ld, light, model, S, B, stroke, omega_star)
    entry = entry_curves(ld, light, model, M, omega_star)
    return Regions(strips, S, B, B_star, M, omega_star, entry, worst)


def _rings(poly):
    poly = shapely.geometry.polygon.orient(poly, 1.0)  # exterior CCW, holes CW: left = inward
    return [np.asarray(poly.exterior.coords)] + [np.asarray(r.coords) for r in poly.interiors]


def _polygons(g):
    return [p for p in getattr(g, "geoms", [g]) if p.geom_type == "Polygon" and not p.is_empty]


def _impacted(ld, light, model, S, B, stroke, omega_star):
    h = ld.h
    D = S.difference(B)
    keep = [B]
    Bb = B.boundary
    for C in _polygons(D):
        flux = 0.0
        for coords in _rings(C):
            L = float(np.sum(np.linalg.norm(np.diff(coords, axis=0), axis=1)))
            n = max(int(np.ceil(L / (0.25 * h))), 8)
            P, n_in = ring_points(coords, (np.arange(n) + 0.5) * (L / n))
            shared = shapely.distance(shapely.points(P), Bb) < 1e-6 * h
            if shared.any():
                d = flow(ld, light, model, P[shared])
                flux += float(np.einsum("ij,ij->i", d, n_in[shared]).sum())
        if flux > 0:  # strips go from B• into C: C is downstream, its heights change
            keep.append(C)
    # Clipped to Ω*: heights in the rim margin are not recomputed (thesis 4.3: near ∂Ω small
    # shading changes mean large height changes; no strip runs there).
    Mfull = clean(shapely.unary_union(keep).intersection(omega_star), h)
    pieces = _polygons(Mfull)
    if not pieces:
        raise NothingToDoError("the impacted region is empty")
    lengths = [p.intersection(stroke).length for p in pieces]
    return pieces[int(np.argmax(lengths))]


def entry_curves(ld, light, model, M, omega_star, min_cos: float = 0.2) -> list[np.ndarray]:
    """Polylines of ∂M• where strips enter M• (cosine to the inward normal > min_cos).

    The threshold drops the sides of M•, which are strips (tangent flow) up to sampling noise.
    """
    h = ld.h
    out = []
    for coords in _rings(M):
        L = float(np.sum(np.linalg.norm(np.diff(coords, axis=0), axis=1)))
        n = max(int(np.ceil(L / (0.25 * h))), 8)
        P, n_in = ring_points(coords, np.arange(n) * (L / n))
        d = flow(ld, light, model, P)
        # M• lies in Ω*, so this includes the parts of ∂Ω* where strips enter M• from the rim
        # margin (4.5: the part of ∂Ω overlapping ∂S• is an initial curve too).
        ok = np.einsum("ij,ij->i", d, n_in) > min_cos
        if ok.all():
            out.append(np.concatenate([P, P[:1]]))
            continue
        # Runs of consecutive entering samples, wrapping around the ring.
        start, runs = cyclic_runs(ok)
        out.extend(P[(start + np.arange(k0, k1)) % n] for k0, k1 in runs if k1 - k0 >= 2)
    return out
