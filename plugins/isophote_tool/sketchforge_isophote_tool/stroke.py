"""The redrawn isophote: cleaned, smoothed, resampled, clipped to the band, and sampled for
the line integral that pins the new shading to it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sketchforge.plugin_api import SculptError, clean_open_stroke, guard, validate_stroke

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
    """Clean (loops, hooks, back-tracking: :func:`sketchforge.geometry.strokes.clean_open_stroke`),
    resample at spacing h/2 and smooth a drawn stroke.

    Parameters
    ----------
    stroke : (k, 2) array-like
    h : float
        Mesh edge length.
    smooth_iters : int
        Passes of (1/4, 1/2, 1/4) smoothing after resampling (ends fixed on an open stroke):
        removes hand jitter below the mesh resolution.

    Returns
    -------
    (j, 2) float64
        A simple polyline; a closed one (a whole isophote redrawn) repeats its first point.

    Raises
    ------
    SculptError
        Not a list of finite points, fewer than 2 distinct points, longer than
        ``MAX_STROKE_SAMPLES`` half edge lengths, or nothing left after cleaning.
    """
    P = guard_length(stroke, h)
    clean = clean_open_stroke(P, h, error=SculptError)
    P = resample_polyline(clean.points, 0.5 * h)
    for _ in range(smooth_iters):
        if clean.closed:
            ring = P[:-1]
            ring = 0.25 * np.roll(ring, 1, axis=0) + 0.5 * ring + 0.25 * np.roll(ring, -1, axis=0)
            P = np.vstack([ring, ring[:1]])
        else:
            P[1:-1] = 0.25 * P[:-2] + 0.5 * P[1:-1] + 0.25 * P[2:]
    return P


def guard_length(stroke, h: float) -> np.ndarray:
    """The stroke as finite (k, 2) float64 points, refusing one too long to resample."""
    P = validate_stroke(stroke, SculptError, "stroke")
    length = float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum()) if len(P) > 1 else 0.0
    if length > MAX_STROKE_SAMPLES * 0.5 * h:
        raise SculptError(
            f"the stroke is {length:.3g} drawing units long, too long for a layer of edge length "
            f"{h:.3g} (at most {MAX_STROKE_SAMPLES * 0.5 * h:.3g}): draw it over the layer"
        )
    return P


def clip_to_band(P: np.ndarray, band, h: float) -> list[np.ndarray]:
    """Pieces (each (k, 2)) of the stroke inside the band; pieces shorter than h/2 dropped.

    Raises
    ------
    SculptError
        If no part of the stroke lies inside the band.
    """
    line = guard.linestring(P, "the stroke")
    inter = line.intersection(band)
    pieces = []
    for g in getattr(inter, "geoms", [inter]):
        if g.geom_type == "LineString" and not g.is_empty and g.length >= 0.5 * h:
            pieces.append(resample_polyline(np.asarray(g.coords), 0.5 * h))
    if not pieces:
        raise SculptError("the stroke has no part inside the band around the picked isophote: draw it inside the dashed band")
    return pieces


@dataclass
class StrokeSamples:
    """Quadrature of a line integral along the stroke pieces: ∫ f ds ≈ Σ w_k f(P_k).

    Attributes
    ----------
    P : (k, 2) float64
        Two Gauss points per segment of every piece.
    w : (k,) float64
        Their weights (half the segment length each).
    """

    P: np.ndarray
    w: np.ndarray


def stroke_samples(pieces: list[np.ndarray]) -> StrokeSamples:
    """Two-point Gauss quadrature on every segment of the pieces: exact for the squared
    residual of a linear field along a segment, and the points move continuously with the
    stroke (no sample appears or vanishes as it is redrawn a hair differently)."""
    g = 0.5 / np.sqrt(3.0)
    pts, wts = [], []
    for P in pieces:
        seg = np.diff(P, axis=0)
        half = 0.5 * np.linalg.norm(seg, axis=1)
        for t in (0.5 - g, 0.5 + g):
            pts.append(P[:-1] + t * seg)
            wts.append(half)
    return StrokeSamples(np.concatenate(pts), np.concatenate(wts))
