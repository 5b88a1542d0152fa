"""Slit rings: an outline that runs out to an inner ring and back along a narrow channel (a
hole drawn as part of the outline) is refused, while two parts that merely come close (a
horse's hooves, the ends of a C) are not (issue 30). Used by
:func:`sketchforge.geometry.contour.prepare_outline`, which re-exports every name."""

from __future__ import annotations

import numpy as np
import shapely
from scipy.spatial import cKDTree

from sketchforge.errors import ContourError
from sketchforge.geometry.polyline import _arclength, format_point, signed_area

#: Two stretches of an outline far apart along it but closer than SLIT_WIDTH_EDGES edge
#: lengths, or than SLIT_WIDTH_FRACTION of the size (square root of the area) of the loop they
#: cut off, pinch it; a pinch that cuts the ring into one loop inside the other is a candidate
#: slit ring. The search radius is capped at SLIT_MAX_EDGES edge lengths to keep the search
#: O(n log n).
SLIT_WIDTH_EDGES = 0.5
SLIT_WIDTH_FRACTION = 0.15
SLIT_MAX_EDGES = 8.0
#: A candidate is a slit ring only when the stroke runs out and back along a channel: its two
#: walls stay within a width w of each other along a length of at least SLIT_CHANNEL_ASPECT·w
#: and SLIT_CHANNEL_LENGTH·r, where r is the inscribed radius of the loop beyond (the hole the
#: user meant) and w at most r / SLIT_HOLE_FATNESS. Two parts that merely come close (a horse's
#: hooves, the ends of a C) have round walls that part again within about sqrt(radius · gap):
#: no channel. Measured (issue 30): the concatenated and hand-drawn rings of
#: tests/test_silhouettes.py have channels of 1.07-5.3 r; hooves and C ends 0.005-0.0005 apart
#: at most 0.59 r, the scikit-image horse none at all.
SLIT_CHANNEL_ASPECT = 3.0
SLIT_HOLE_FATNESS = 3.0
SLIT_CHANNEL_LENGTH = 0.8


def _segment_distances(a, b, c, d) -> np.ndarray:
    """Distances (m,) between segments ab and cd, each (m, 2): 0 where they touch or cross.

    GEOS' exact distance, as segment_crossings uses GEOS for its test. A hand-written version
    read the orientation signs of nearly collinear segments, which are round-off, and gave 0 for
    1 in 10^4 disjoint segments on one line."""
    return shapely.distance(shapely.linestrings(np.stack([a, b], axis=1)),
                            shapely.linestrings(np.stack([c, d], axis=1)))


def _ring_points(Q, s, at) -> np.ndarray:
    """Points (len(at), 2) at arc lengths ``at`` (any real, taken modulo the length) along the
    closed ring Q (k + 1, 2, first point repeated) whose cumulative arc length is ``s``."""
    at = np.mod(at, s[-1])
    return np.column_stack([np.interp(at, s, Q[:, 0]), np.interp(at, s, Q[:, 1])])


def _ring_stretch(Q, s, a: float, b: float) -> np.ndarray:
    """The ring's polyline from arc length a to b (a < b, b - a < the ring's length)."""
    total = s[-1]
    shift = np.floor(a / total) * total
    a, b = a - shift, b - shift
    S = np.concatenate([s[:-1], s[:-1] + total])
    X = np.vstack([Q[:-1], Q[:-1]])
    inside = (S > a) & (S < b)
    return np.vstack([_ring_points(Q, s, [a]), X[inside], _ring_points(Q, s, [b])])


def _channel_length(Q, s, m: int, n: int, hole_radius: float, h: float) -> float:
    """Length of the longest channel through the pinch between segments m and n (m < n) of the
    ring Q (k + 1, 2; arc lengths s): the longest stretch of one wall around the pinch whose
    points all lie within w of the other wall, with w <= hole_radius / SLIT_HOLE_FATNESS and
    the stretch at least SLIT_CHANNEL_ASPECT·w long. 0 when there is none.

    Every quantity is a distance or a length, so the result moves continuously with the
    outline (no step depends on which side of a threshold a round-off falls)."""
    total = s[-1]
    la = shapely.linestrings([Q[m], Q[m + 1]])
    lb = shapely.linestrings([Q[n], Q[n + 1]])
    pa, pb = np.asarray(shapely.shortest_line(la, lb).coords)
    sa = s[m] + float(np.linalg.norm(pa - Q[m]))
    sb = s[n] + float(np.linalg.norm(pb - Q[n]))
    inside = sb - sa
    # The walls end well before they meet each other again round either loop; a channel
    # longer than twice the hole's radius says no more than one of that length.
    reach = min(0.45 * min(inside, total - inside), 2.0 * hole_radius)
    if not reach > 0.0:
        return 0.0
    step = max(min(0.25 * h, reach / 50.0), reach / 400.0)
    count = int(reach / step)
    t = np.arange(-count, count + 1) * step
    wall = shapely.LineString(_ring_stretch(Q, s, sb - reach, sb + reach))
    sep = shapely.distance(shapely.points(_ring_points(Q, s, sa + t)), wall)
    # The widest separation met going out from the pinch on each side; the longest window
    # whose widest separation is at most w is then a pair of sorted look-ups, for every w.
    left = np.maximum.accumulate(sep[count::-1])
    right = np.maximum.accumulate(sep[count:])
    w = np.unique(np.concatenate([left, right]))
    w = w[w <= hole_radius / SLIT_HOLE_FATNESS]
    if not len(w):
        return 0.0
    length = (np.searchsorted(left, w, side="right") - 1 + np.searchsorted(right, w, side="right") - 1) * step
    ok = length >= SLIT_CHANNEL_ASPECT * w
    return float(length[ok].max()) if ok.any() else 0.0


def _refuse_slit_ring(P, h: float) -> None:
    """Refuse an outer and an inner ring concatenated into one stroke (an "O" or "&" drawn in
    one go): the ring then runs out along a thin channel, round the hole and back, and would
    inflate into a ring with a slit. Drawn holes go in the ``holes`` field instead.

    Parts of a simple outline that only come close (legs, the ends of a C: closer than the
    resolution, even) are no slit ring: the stroke must run out and back along a channel
    (see SLIT_CHANNEL_ASPECT), so such an outline is inflated.

    P (k, 2) float64, the thinned ring; h the edge length. Raises ContourError."""
    k = len(P)
    if k < 8:
        return
    Q = np.vstack([P, P[:1]])
    size = np.sqrt(abs(signed_area(P)))
    reach = max(SLIT_WIDTH_EDGES * h, min(SLIT_WIDTH_FRACTION * size, SLIT_MAX_EDGES * h))
    # Candidate pairs by segment midpoints (a k-d tree: GEOS' dwithin query took a second on
    # a 4k-point outline), then exact segment distances on the few left.
    a, b = Q[:-1], Q[1:]
    half = 0.5 * float(np.max(np.linalg.norm(b - a, axis=1)))
    pairs = cKDTree(0.5 * (a + b)).query_pairs(reach + 2.0 * half, output_type="ndarray")
    if not len(pairs):
        return
    i, j = np.sort(pairs, axis=1).T
    s = _arclength(Q)
    total = s[-1]
    along = np.abs(s[j] - s[i])
    # Neighbours along a smooth stretch are close in both senses; a pinch joins stretches that
    # are close across but far apart along the ring.
    keep = np.minimum(along, total - along) > max(4.0 * h, 4.0 * reach)
    if not keep.any():
        return
    cand = np.column_stack([i[keep], j[keep]])
    dist = _segment_distances(a[cand[:, 0]], b[cand[:, 0]], a[cand[:, 1]], b[cand[:, 1]])
    near = dist <= reach
    cand, dist = cand[near], dist[near]
    # The closest pair first: a pinch is where the channel is narrowest. A bounded number of
    # candidates keeps a wiggly stroke O(n log n).
    order = np.argsort(dist, kind="stable")[:16]
    for (m, n), d in zip(cand[order], dist[order]):
        inner, outer = P[m + 1 : n + 1], np.vstack([P[n + 1 :], P[: m + 1]])
        if len(inner) < 3 or len(outer) < 3:
            continue
        pa, pb = shapely.Polygon(inner).buffer(0), shapely.Polygon(outer).buffer(0)
        if pa.is_empty or pb.is_empty:
            continue
        big, hole = (pa, pb) if pa.area >= pb.area else (pb, pa)
        if d > max(SLIT_WIDTH_EDGES * h, SLIT_WIDTH_FRACTION * np.sqrt(hole.area)):
            continue
        # The smaller loop must lie inside the larger one (the hole inside the ring). Its
        # representative point is strictly inside it; the larger loop's can fall in the hole.
        if not big.contains(hole.representative_point()):
            continue
        radius = float(shapely.length(shapely.maximum_inscribed_circle(hole, 1e-3 * np.sqrt(hole.area))))
        if _channel_length(Q, s, int(m), int(n), radius, h) >= SLIT_CHANNEL_LENGTH * radius:
            x = 0.5 * (Q[m] + Q[n + 1])
            raise ContourError(
                f"the outline runs out to an inner ring and back along a slit near {format_point(x)}: "
                "draw the hole as a hole (the 'holes' field of set_contour, or Alt+drag in the app), "
                "not as part of the outline"
            )
