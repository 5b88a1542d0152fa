"""Clean a hand-drawn open stroke the way a drawing app would.

A redrawn isophote is an open stroke drawn quickly: it may curl into a small loop, cross
itself (an offset curve drawn around a tight bend makes a "swallowtail"), end with a hook
where the pen lifted, or run back over itself for a moment. Downstream code (quadrature along
the stroke, GEOS clipping, and any triangulation) wants a simple polyline, so
:func:`clean_open_stroke` returns one:

1. validation: an (n, 2) array of finite numbers within ±MAX_COORDINATE, ≥ 2 distinct points;
2. thinning to about one point per quarter edge length (bin means, O(n): tablet noise and
   near-duplicates go; see :func:`sketchforge.geometry.contour.decimate`);
3. hooks: a turn sharper than HOOK_ANGLE within HOOK_LENGTH edge lengths of an end cuts
   that end off at the turn;
4. back-tracking: where the stroke turns back (sharper than SPIKE_ANGLE) and runs over its own
   path, the excursion out and back is removed;
5. loops: every self-crossing closes a loop; the loop is dropped and the path continues from
   the crossing point — unless the crossing joins the stroke's first and last fifths (as
   :func:`sketchforge.geometry.contour.prepare_outline` trims a closing overshoot): then the
   person drew a closed curve with overlapping ends, the loop is kept as a closed stroke and
   the overlapping tails are dropped.

Every step is a function of the drawn points alone (no iteration whose count depends on
round-off): the same stroke always gives the same polyline.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sketchforge.geometry.contour import decimate, intersection_point, segment_crossings, validate_stroke

#: Turning angle (degrees, chords over one edge length each side) above which a turn near an
#: end is a hook.
HOOK_ANGLE = 100.0
#: A hook is at most this many edge lengths from the end it cuts off.
HOOK_LENGTH = 3.0
#: Turning angle (degrees) above which the stroke is taken to double back on itself.
SPIKE_ANGLE = 150.0
#: A self-crossing between the first and the last this fraction of the stroke closes it (a
#: closed curve drawn with overlapping ends), as contour.OVERSHOOT_FRACTION does for outlines.
OVERLAP_FRACTION = 0.2
#: Most loops resolved in one stroke (each pass removes at least one segment, so this only
#: bounds the work on pathological scribbles).
MAX_LOOPS = 200


@dataclass(frozen=True)
class CleanStroke:
    """A cleaned stroke.

    Attributes
    ----------
    points : (k, 2) float64
        The polyline; a closed one repeats its first point at the end.
    closed : bool
    loops, hooks, spikes : int
        How many of each were removed (for messages and tests).
    """

    points: np.ndarray
    closed: bool
    loops: int = 0
    hooks: int = 0
    spikes: int = 0


def _arclength(P: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])


def _at(P: np.ndarray, s: np.ndarray, t) -> np.ndarray:
    """Points at arc lengths t along P (s = its arc lengths)."""
    t = np.asarray(t, dtype=np.float64)
    return np.stack([np.interp(t, s, P[:, 0]), np.interp(t, s, P[:, 1])], axis=-1)


def _turns(P: np.ndarray, window: float) -> np.ndarray:
    """Turning angle (degrees) at each interior point of an open polyline, from the chords to
    the points ``window`` back and ahead along it (0 at the ends)."""
    s = _arclength(P)
    back = _at(P, s, np.maximum(s - window, 0.0))
    ahead = _at(P, s, np.minimum(s + window, s[-1]))
    u, v = P - back, ahead - P
    nu, nv = np.linalg.norm(u, axis=1), np.linalg.norm(v, axis=1)
    cos = np.einsum("ij,ij->i", u, v) / np.maximum(nu * nv, 1e-300)
    ang = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    ang[(nu == 0) | (nv == 0)] = 0.0
    return ang


def _cut_hooks(P: np.ndarray, h: float) -> tuple[np.ndarray, int]:
    """Cut each end back to its last sharp turn within HOOK_LENGTH edge lengths of it."""
    n_hooks = 0
    for _ in range(2):  # the head, then (reversed) the tail
        s = _arclength(P)
        if s[-1] > 2 * HOOK_LENGTH * h:
            ang = _turns(P, 0.75 * h)
            near = np.nonzero((s <= HOOK_LENGTH * h) & (ang > HOOK_ANGLE))[0]
            if len(near):
                k = int(near[np.argmax(ang[near])])
                P = P[k:]
                n_hooks += 1
        P = P[::-1]
    return P, n_hooks


def _remove_spikes(P: np.ndarray, h: float) -> tuple[np.ndarray, int]:
    """Remove out-and-back excursions: at a turn sharper than SPIKE_ANGLE, the points at equal
    arc length before and after the turn stay close while the stroke retraces its path; the
    whole retraced stretch goes."""
    n = 0
    for _ in range(MAX_LOOPS):
        s = _arclength(P)
        L = s[-1]
        if len(P) < 3 or L < 2 * h:
            break
        ang = _turns(P, 0.5 * h)
        cand = np.nonzero(ang > SPIKE_ANGLE)[0]
        if not len(cand):
            break
        k = int(cand[np.argmax(ang[cand])])
        # Retrace length: largest t with |P(s_k - t') - P(s_k + t')| small for all t' <= t.
        tmax = min(s[k], L - s[k])
        t = np.linspace(0.0, tmax, max(int(np.ceil(tmax / (0.25 * h))), 1) + 1)
        gap = np.linalg.norm(_at(P, s, s[k] - t) - _at(P, s, s[k] + t), axis=1)
        bad = np.nonzero(gap > np.maximum(0.75 * h, 0.5 * t))[0]
        T = t[bad[0] - 1] if len(bad) else tmax
        if T >= tmax - 1e-9 * max(L, 1.0):
            # It retraces to an end: what lies beyond the turn on the short side is a hook.
            P = P[k:] if s[k] <= L - s[k] else P[: k + 1]
        else:
            a, b = s[k] - T, s[k] + T
            P = np.vstack([P[s < a], _at(P, s, [a, b]), P[s > b]])
        P = P[np.concatenate([[True], np.linalg.norm(np.diff(P, axis=0), axis=1) > 0])]
        n += 1
    return P, n


def _resolve_loops(P: np.ndarray) -> tuple[np.ndarray, bool, int]:
    """Drop every loop closed by a self-crossing (or keep the loop and drop the tails when
    the loop is most of the stroke). Returns (points, closed, loops removed)."""
    closed = False
    n = 0
    for _ in range(MAX_LOOPS):
        Q = P[:-1] if closed else P
        pairs = segment_crossings(Q, closed=closed)
        if closed:
            # The ring's closing point is where the first and last segments meet, not a crossing.
            nseg = len(Q)
            pairs = pairs[~((pairs[:, 0] == 0) & (pairs[:, 1] == nseg - 1))]
        if not len(pairs):
            break
        i = int(pairs[0, 0])
        j = int(pairs[pairs[:, 0] == i][:, 1].max())  # outermost loop starting at segment i
        R = np.vstack([Q, Q[:1]]) if closed else Q
        x = intersection_point(R[i], R[i + 1], R[j], R[j + 1])
        loop = np.vstack([x[None], R[i + 1 : j + 1], x[None]])
        rest = np.vstack([R[: i + 1], x[None], R[j + 1 :]])
        s = _arclength(R)
        overlap = s[i + 1] <= OVERLAP_FRACTION * s[-1] and s[j] >= (1.0 - OVERLAP_FRACTION) * s[-1]
        if not closed and overlap:
            P, closed = loop, True
        else:
            P = rest
        P = P[np.concatenate([[True], np.linalg.norm(np.diff(P, axis=0), axis=1) > 0])]
        n += 1
        if len(P) < (4 if closed else 2):
            break
    return P, closed, n


def clean_open_stroke(points, h: float, error=ValueError, what: str = "stroke") -> CleanStroke:
    """Validate and clean a drawn open stroke (see the module docstring).

    Parameters
    ----------
    points : (n, 2) array-like of float
        The stroke as drawn.
    h : float
        The length scale (an edge length of the mesh it is drawn on), > 0.
    error : exception class
        Raised, with a one-line message, for input that is not a usable stroke.
    what : str
        How the message names the input.

    Returns
    -------
    CleanStroke
        A polyline without self-crossings, consecutive points distinct.
    """
    P = validate_stroke(points, error, what)
    if len(P):
        P = P[np.concatenate([[True], np.any(np.diff(P, axis=0) != 0, axis=1)])]
    if len(P) < 2:
        raise error(f"the {what} needs at least 2 distinct points")
    scale = float(np.abs(P).max(initial=0.0))
    # Thinning bins by arc length; far-apart points keep their own bins. Near-duplicates
    # (1e-12 apart) merge, so they can neither make zero-length segments nor fake crossings.
    P = decimate(P, 0.25 * h)
    P = P[np.concatenate([[True], np.linalg.norm(np.diff(P, axis=0), axis=1) > 1e-9 * max(scale, h)])]
    if len(P) < 2:
        raise error(f"the {what} is shorter than the resolution ({h:.3g}): draw a longer one")
    P, hooks = _cut_hooks(P, h)
    P, spikes = _remove_spikes(P, h)
    P, closed, loops = _resolve_loops(P)
    if len(P) < 2 or _arclength(P)[-1] < 0.5 * h:
        if loops + hooks + spikes:
            raise error(f"nothing of the {what} is left after removing its loops and hooks: draw a plain curve")
        raise error(f"the {what} is shorter than the resolution ({h:.3g}): draw a longer one")
    return CleanStroke(np.ascontiguousarray(P), closed, loops, hooks, spikes)
