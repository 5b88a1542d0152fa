"""How far the isophote is from the stroke: before an edit, after it, and after part of it.

The measure the issue asks for, used by the pipeline (an edit may never end farther from the
stroke than it started), the tests and ``benchmarks/bench_sculpt_corpus.py``: the mean
distance from samples of the stroke to the isophote E = c, over the samples the edit promises
to honour (inside the band, outside the rim margin).
"""

from __future__ import annotations

import numpy as np
import shapely

from sketchforge.plugin_api import isophotes

from .layerdata import PlanarData


def isophote_lines(pd: PlanarData, E: np.ndarray, c: float):
    """Every component of E = c on the layer, as one shapely MultiLineString (maybe empty)."""
    lines = [L for L in isophotes(pd.V2, pd.F, E, c)[0] if len(L) > 1]
    return shapely.MultiLineString(lines) if lines else shapely.MultiLineString()


def mean_distance(P: np.ndarray, geom) -> float:
    """Mean distance (float) from points P (k, 2) to a shapely geometry; inf if it is empty."""
    if geom.is_empty or len(P) == 0:
        return float("inf")
    return float(shapely.distance(shapely.points(P), geom).mean())


def honoured_samples(pd: PlanarData, pieces: list[np.ndarray], band) -> np.ndarray:
    """Points (k, 2) every h/2 along the stroke pieces that lie inside the band and outside
    the rim margin: where an edit promises to put the isophote."""
    P = np.concatenate(pieces) if pieces else np.zeros((0, 2))
    if len(P) == 0:
        return P
    inside = shapely.contains_xy(band, P[:, 0], P[:, 1])
    d = pd.rim_distance(P)
    return P[inside & (d >= pd.margin_at(P))]


def beside_distance(lines, stroke, radius: float, h: float) -> float:
    """Mean distance from the isophote's points beside the stroke to the stroke: the other
    direction of the fidelity measure. Points within ``radius`` of the stroke whose nearest
    stroke point is not one of its ends count; an isophote that moved onto the stroke gives a
    small value, one that stayed where it was (the stroke met only by a new little loop)
    a large one. 0 when no point is beside the stroke.

    Parameters
    ----------
    lines : shapely (Multi)LineString
        The isophote, e.g. from :func:`isophote_lines`.
    stroke : shapely (Multi)LineString
    radius : float
    h : float
        Edge length (sampling step h/4; ends within 2h do not count as beside).
    """
    P = shapely.get_coordinates(shapely.segmentize(lines, 0.25 * h)) if not lines.is_empty else np.zeros((0, 2))
    if len(P) == 0:
        return 0.0
    pts = shapely.points(P)
    d = shapely.distance(pts, stroke)
    parts = getattr(stroke, "geoms", [stroke])
    ends = shapely.MultiPoint([p for g in parts for p in (g.coords[0], g.coords[-1])])
    beside = (d < radius) & (shapely.distance(pts, ends) > d + 2.0 * h)
    return float(d[beside].mean()) if beside.any() else 0.0
