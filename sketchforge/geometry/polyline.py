"""Small helpers on drawn polylines and rings (numpy, (k, 2) float64): the shoelace area,
arclength, the validation of a stroke's numbers, thinning, segment crossings (an R-tree of
segments) and the point where two segments meet. :mod:`sketchforge.geometry.contour` builds
its outlines from them (and re-exports every name)."""

from __future__ import annotations

import numpy as np
import shapely

from sketchforge.errors import ContourError

#: Coordinates beyond this (drawing units) are refused: squared distances of 1e200 overflow,
#: and no drawing is that large.
MAX_COORDINATE = 1e9


def signed_area(P) -> float:
    """Shoelace area of the closed ring P (k, 2); positive when counter-clockwise."""
    P = np.asarray(P, dtype=np.float64)
    x, y = P[:, 0], P[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _arclength(P) -> np.ndarray:
    """Cumulative length along the polyline P (k, 2) -> (k,), starting at 0."""
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])


def format_point(p) -> str:
    """A point (2,) as "(x, y)" with 4 significant digits, for messages."""
    return f"({p[0]:.4g}, {p[1]:.4g})"


def validate_stroke(points, error=ContourError, what: str = "stroke") -> np.ndarray:
    """A drawn stroke as an (n, 2) float64 array, or ``error`` saying in one line what is wrong
    (the outline of a layer, a redrawn isophote: ``what`` names it)."""
    try:
        P = np.array(points, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise error(f"the {what} must be a list of [x, y] number pairs ({exc})") from None
    if P.ndim != 2 or P.shape[1] != 2:
        raise error(f"the {what} must be a list of [x, y] pairs, got an array of shape {P.shape}")
    if not np.all(np.isfinite(P)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(P), axis=1))[0])
        raise error(f"the {what} has a point that is not a finite number (point {bad}: {P[bad].tolist()})")
    if P.size and np.max(np.abs(P)) > MAX_COORDINATE:
        raise error(
            f"the {what}'s coordinates reach {np.max(np.abs(P)):.3g}; they must lie within "
            f"±{MAX_COORDINATE:.0e} drawing units"
        )
    return P


def decimate(P, spacing: float) -> np.ndarray:
    """Thin a polyline to about one point per ``spacing`` of length, in O(n), keeping both ends.

    Points are binned by arc length and each bin is replaced by its mean: near duplicates
    vanish and dense tablet noise is averaged rather than sampled (rounding corners by at most
    spacing/2). A noisy stroke's arc length overstates its real length, so thinning repeats
    (each pass O(n)) until the count settles.

    P (n, 2) float64 -> (m, 2) float64.
    """
    if len(P) < 3 or spacing <= 0:
        return P
    for _ in range(4):
        # Arc length of a 5-point moving average: noise between samples inflates the raw
        # length several times over, which would make the bins far too small.
        c = np.cumsum(np.vstack([np.zeros((1, 2)), P]), axis=0)
        w = min(5, len(P))
        smooth = np.vstack([P[: w // 2], (c[w:] - c[:-w]) / w, P[len(P) - (w - 1 - w // 2) :]])
        s = _arclength(smooth)
        if not s[-1] / spacing < 2.0**53:  # bins finer than float resolution (a 1e-300 spacing)
            break
        bucket = np.floor(s / spacing).astype(np.int64)
        starts = np.flatnonzero(np.concatenate([[True], bucket[1:] > bucket[:-1]]))
        if len(starts) > 0.9 * len(P):
            break
        counts = np.diff(np.concatenate([starts, [len(P)]]))
        Q = np.add.reduceat(P, starts, axis=0) / counts[:, None]
        # The stroke's ends stay where they were drawn (they define the junction).
        Q = np.vstack([P[:1], Q[1:-1], P[-1:]]) if len(Q) > 2 else np.vstack([P[:1], P[-1:]])
        if len(Q) < 3:
            break
        P = Q
    # A bin edge can split a cluster of near-duplicates into two means a hair apart, which would
    # make a zig-zag that touches itself: drop points too close to their predecessor.
    d = np.linalg.norm(np.diff(P, axis=0), axis=1)
    keep = np.concatenate([[True], d >= 0.25 * spacing])
    keep[-1] = True
    P = P[keep]
    if len(P) > 2 and np.linalg.norm(P[-1] - P[-2]) < 0.25 * spacing:
        P = np.delete(P, -2, axis=0)
    return P


def segment_crossings(P, closed: bool) -> np.ndarray:
    """Pairs of non-adjacent segments of the polyline that touch or cross, O(n log n).

    Parameters
    ----------
    P : (k, 2) float64
    closed : bool
        Include the closing segment P[-1] -> P[0] (index k-1).

    Returns
    -------
    pairs : (c, 2) int64, segment i runs from P[i] to P[i+1]; i < j; sorted.
    """
    Q = np.vstack([P, P[:1]]) if closed else P
    nseg = len(Q) - 1
    if nseg < 3:
        return np.zeros((0, 2), dtype=np.int64)
    segs = shapely.linestrings(np.stack([Q[:-1], Q[1:]], axis=1))
    tree = shapely.STRtree(segs)
    i, j = tree.query(segs, predicate="intersects")
    keep = (j > i + 1) & ~(closed & (i == 0) & (j == nseg - 1))
    pairs = np.column_stack([i[keep], j[keep]]).astype(np.int64)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def intersection_point(a, b, c, d) -> np.ndarray:
    """Where segment ab meets segment cd. If they are parallel (collinear and overlapping): the
    midpoint of a and d, which lies in the overlap when the segments run end to end and
    otherwise near it, not the overlap's midpoint."""
    r, s = b - a, d - c
    den = r[0] * s[1] - r[1] * s[0]
    if abs(den) < 1e-300:
        return 0.5 * (a + d)
    t = ((c[0] - a[0]) * s[1] - (c[1] - a[1]) * s[0]) / den
    return a + min(max(t, 0.0), 1.0) * r
