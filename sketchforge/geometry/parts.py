"""Where a newly drawn part goes, Monster Mash style: is its stroke closed, which parts does it
overlap (to draw it behind them), does its junction touch any part, and the partial redraw of
an outline by a stroke that starts and ends on it.

Every function takes plain arrays (drawing units, x right, y up) and is a function of them
alone, so a journal replays the same decisions.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely

from sketchforge.geometry import guard
from sketchforge.geometry.contour import prepare_outline


def stroke_closes(points, resolution: float) -> bool:
    """True when the stroke's own ends make it a closed outline: its ends are within the
    inflation's junction gap (JUNCTION_GAP_EDGES edge lengths) or it overshoots its start.
    The same rule the inflation applies to an open stroke, so what the panel shows is what the
    mesh and the assembly get.

    points : (n, 2) float64. Raises ContourError for a stroke that cannot be an outline."""
    return not prepare_outline(np.asarray(points, dtype=np.float64), float(resolution), closed=False).is_open


def _region(P: np.ndarray, what: str):
    return guard.polygon(np.asarray(P, dtype=np.float64), what)


def overlapped(points, outlines: Sequence) -> np.ndarray:
    """(k,) bool: which of the ``outlines`` (each (m, 2) float64, closed implicitly; None for
    a part without one) the region of ``points`` (closed by its chord) overlaps with positive
    area."""
    try:
        region = _region(points, "the stroke")
    except Exception:  # noqa: BLE001 - a degenerate stroke overlaps nothing; the inflation reports it
        return np.zeros(len(outlines), dtype=bool)
    out = np.zeros(len(outlines), dtype=bool)
    for k, P in enumerate(outlines):
        if P is None or len(P) < 3:
            continue
        try:
            other = _region(P, "a part's outline")
        except Exception:  # noqa: BLE001
            continue
        out[k] = region.intersection(other).area > 1e-9 * max(region.area, other.area)
    return out


def chord_touches(points, outlines: Sequence) -> bool:
    """True when the straight segment closing an open stroke (its junction, end to start)
    meets any of the ``outlines`` (each (m, 2) float64 or None) in more than a point."""
    P = np.asarray(points, dtype=np.float64)
    chord = shapely.LineString([P[-1], P[0]])
    for Q in outlines:
        if Q is None or len(Q) < 3:
            continue
        try:
            region = _region(Q, "a part's outline")
        except Exception:  # noqa: BLE001
            continue
        if chord.intersection(region).length > 1e-9 * max(chord.length, 1e-12):
            return True
    return False


def _arc(P: np.ndarray, closed: bool) -> np.ndarray:
    Q = np.vstack([P, P[:1]]) if closed else P
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(Q, axis=0), axis=1))])


def splice_outline(outline, closed: bool, stroke, tol: float) -> np.ndarray | None:
    """The outline with the stretch between the stroke's ends replaced by the stroke, or None
    when the stroke does not start and end on the outline.

    outline : (n, 2) float64, the part's drawn points (closed: the last joins the first).
    stroke : (k, 2) float64, both ends within ``tol`` of an outline point, at different points.
    Of a closed outline, the shorter of the two stretches between the ends is replaced (a
    vector drawing app's redraw of a bump); of an open one, the stretch between them.
    Returns (m, 2) float64."""
    P = np.asarray(outline, dtype=np.float64)
    S = np.asarray(stroke, dtype=np.float64)
    if len(P) < 3 or len(S) < 2:
        return None
    d0 = np.linalg.norm(P - S[0], axis=1)
    d1 = np.linalg.norm(P - S[-1], axis=1)
    i, j = int(np.argmin(d0)), int(np.argmin(d1))
    if d0[i] > tol or d1[j] > tol or i == j:
        return None
    if not closed:
        if i > j:
            i, j, S = j, i, S[::-1]
        return np.vstack([P[:i], S, P[j + 1 :]])
    n = len(P)
    s = _arc(P, True)
    total = s[-1]
    forward = (s[j] - s[i]) % total  # the stretch i -> j along the outline's order
    if forward <= total - forward:
        # replace i..j: the stroke (i -> j), then the kept stretch j+1 .. i-1
        kept = P[(np.arange(j + 1, j + 1 + (i - j - 1) % n)) % n]
        return np.vstack([S, kept])
    # replace j..i: the stroke reversed (j -> i), then the kept stretch i+1 .. j-1
    kept = P[(np.arange(i + 1, i + 1 + (j - i - 1) % n)) % n]
    return np.vstack([S[::-1], kept])


def part_at(point, outlines: Sequence) -> int:
    """Index of the frontmost of the ``outlines`` (back to front, each (m, 2) float64 or None)
    whose region contains ``point`` (2,), or -1."""
    p = shapely.Point(np.asarray(point, dtype=np.float64).reshape(2))
    for k in range(len(outlines) - 1, -1, -1):
        P = outlines[k]
        if P is None or len(P) < 3:
            continue
        try:
            if _region(P, "a part's outline").covers(p):
                return k
        except Exception:  # noqa: BLE001
            continue
    return -1
