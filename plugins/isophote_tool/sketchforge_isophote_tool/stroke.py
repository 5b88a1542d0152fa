"""Clean a redrawn isophote stroke: validate, smooth, resample, clip to the band."""

from __future__ import annotations

import numpy as np
import shapely

from sketchforge.errors import SculptError

#: Most points of a resampled stroke (spacing h/2): ~50 000 edge lengths, far beyond any drawn
#: stroke. A journal entry with a far-off point would otherwise allocate without bound (a point
#: at 1e9 asked for ~600 GiB).
MAX_STROKE_SAMPLES = 100_000


def _arc_lengths(P: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])


def even_parameters(P: np.ndarray, spacing: float) -> np.ndarray:
    """Arc lengths of evenly spaced points along a polyline P (n, 2), at most ``spacing``
    apart, both ends included."""
    L = _arc_lengths(P)[-1]
    return np.linspace(0.0, L, max(int(np.ceil(L / spacing)), 1) + 1)


def polyline_at(P: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Points (k, 2) at arc lengths t along a polyline P (n, 2)."""
    s = _arc_lengths(P)
    return np.column_stack([np.interp(t, s, P[:, 0]), np.interp(t, s, P[:, 1])])


def resample_polyline(P: np.ndarray, spacing: float) -> np.ndarray:
    """Evenly spaced points (k, 2) along a polyline P (n, 2), ends kept."""
    return polyline_at(P, even_parameters(P, spacing))


def prepare_stroke(stroke, h: float, smooth_iters: int = 3) -> np.ndarray:
    """Validate, smooth and resample a stroke at spacing h/2.

    Parameters
    ----------
    stroke : (k, 2) array-like
    h : float
        Mesh edge length.
    smooth_iters : int
        Passes of (1/4, 1/2, 1/4) smoothing with fixed ends, after resampling: removes hand
        jitter below the mesh resolution without moving the ends.

    Raises
    ------
    SculptError
        Fewer than 2 distinct points, non-finite values, or a stroke longer than
        ``MAX_STROKE_SAMPLES`` half edge lengths.
    """
    try:
        P = np.asarray(stroke, np.float64)
    except (TypeError, ValueError):
        raise SculptError("the stroke must be a list of [x, y] points") from None
    if P.ndim != 2 or P.shape[1] != 2:
        raise SculptError(f"the stroke must be a list of [x, y] points, got shape {P.shape}")
    if not np.isfinite(P).all():
        raise SculptError("the stroke has non-finite coordinates")
    keep = np.concatenate([[True], np.linalg.norm(np.diff(P, axis=0), axis=1) > 1e-12])
    P = P[keep]
    if len(P) < 2:
        raise SculptError("the stroke needs at least 2 distinct points")
    length = _arc_lengths(P)[-1]
    if length > MAX_STROKE_SAMPLES * 0.5 * h:
        raise SculptError(
            f"the stroke is {length:.3g} drawing units long, too long for a layer of edge length "
            f"{h:.3g} (at most {MAX_STROKE_SAMPLES * 0.5 * h:.3g}): draw it over the layer"
        )
    P = resample_polyline(P, 0.5 * h)
    for _ in range(smooth_iters):
        P[1:-1] = 0.25 * P[:-2] + 0.5 * P[1:-1] + 0.25 * P[2:]
    return P


def clip_to_band(P: np.ndarray, band, h: float) -> list[np.ndarray]:
    """Pieces (each (k, 2)) of the stroke inside the band; pieces shorter than h/2 dropped.

    Raises
    ------
    SculptError
        If no part of the stroke lies inside the band.
    """
    inter = shapely.LineString(P).intersection(band)
    pieces = []
    for g in getattr(inter, "geoms", [inter]):
        if g.geom_type == "LineString" and not g.is_empty and g.length >= 0.5 * h:
            pieces.append(resample_polyline(np.asarray(g.coords), 0.5 * h))
    if not pieces:
        raise SculptError("the stroke has no part inside the band around the picked isophote")
    return pieces
