"""Cleaning a drawn open stroke, checked on strokes whose right answer is known by construction.

These tests come from mutants of sketchforge/geometry/strokes.py that the rest of the suite let
through. Each stroke here is built so that what the cleaning must give follows from the module's
own description (a hook is a turn sharper than HOOK_ANGLE at most HOOK_LENGTH edge lengths from
an end; a back-track is removed and its short side dropped; a crossing closes a loop, dropped
unless it joins the first and last fifths; a closed result repeats its first point) or from an
invariance (scaling a stroke and its edge length together, re-sampling a straight segment):

- drawn points are spaced more than a quarter edge apart, so thinning keeps them exactly and a
  test can ask for exact points (the ends, the vertices away from what was removed);
- corners and lengths use exact binary fractions and 3-4-5 triangles, so a boundary such as
  "at most HOOK_LENGTH edge lengths" is hit exactly;
- counts (hooks, spikes, loops) and the one-line messages are what callers show the user.
"""

import numpy as np
import pytest
import shapely
from test_strokes import _wave

from sketchforge.errors import SculptError
from sketchforge.geometry.contour import segment_crossings
from sketchforge.geometry.strokes import HOOK_LENGTH, clean_open_stroke

H = 0.03


# --------------------------------------------------------------------------- helpers


def _path(vertices, step):
    """The polyline through ``vertices`` with each side cut into equal pieces of about ``step``
    (the vertices themselves are kept exactly)."""
    V = np.asarray(vertices, dtype=float)
    out = [V[:1]]
    for a, b in zip(V[:-1], V[1:]):
        n = max(int(round(np.linalg.norm(b - a) / step)), 1)
        out.append(a + np.arange(1, n + 1)[:, None] / n * (b - a))
    return np.vstack(out)


def _simple(P, closed):
    """No two non-adjacent segments touch (the ring's closing point is not a crossing)."""
    Q = P[:-1] if closed else P
    pairs = segment_crossings(Q, closed=closed)
    return len(pairs) == 0


def _length(P):
    return float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())


def _has_rows(P, rows, tol=0.0):
    """Every row of ``rows`` is a point of ``P`` (within ``tol``)."""
    d = np.linalg.norm(np.asarray(rows)[:, None, :] - P[None, :, :], axis=2).min(axis=1)
    return bool((d <= tol).all())


def _off_path(P, drawn):
    """Largest distance from a point of P to the drawn polyline."""
    return float(shapely.distance(shapely.points(P), shapely.LineString(drawn)).max())


def _curl(at, radius, n=16, up=1.0):
    """A small closed curl starting and ending at ``at``: the pen circles once and goes on."""
    a = np.linspace(-np.pi / 2, 1.5 * np.pi, n)
    c = np.asarray(at) + [0.0, up * radius]
    return c + radius * np.column_stack([np.cos(a), up * np.sin(a)])


# --------------------------------------------------------------------------- a plain stroke


def test_a_plain_stroke_comes_back_as_drawn():
    # Points about 0.3 h apart, no turn sharper than a few degrees: nothing to thin, cut or drop.
    P = _wave()
    r = clean_open_stroke(P, H)
    assert (r.loops, r.hooks, r.spikes, r.closed) == (0, 0, 0, False)
    assert np.array_equal(r.points, P)
    assert r.points.dtype == np.float64 and r.points.flags.c_contiguous


@pytest.mark.parametrize("h", [0.4, 1.0])
def test_two_points_are_a_stroke(h):
    # The smallest stroke there is: two distinct points at least half an edge apart.
    r = clean_open_stroke([[0.0, 0.0], [1.0, 1.0]], h)
    assert np.array_equal(r.points, [[0.0, 0.0], [1.0, 1.0]])
    assert (r.loops, r.hooks, r.spikes, r.closed) == (0, 0, 0, False)


def test_the_shortest_accepted_stroke_is_half_an_edge():
    r = clean_open_stroke([[0.0, 0.0], [0.25, 0.0], [0.5, 0.0]], 1.0)
    assert _length(r.points) == 0.5
    r = clean_open_stroke([[0.0, 0.0], [0.75, 0.0], [1.0, 0.0]], 1.0)  # shorter than 1.5 h is fine
    assert _length(r.points) == 1.0
    with pytest.raises(SculptError, match=r"^the stroke is shorter than the resolution \(1\): draw a longer one$"):
        clean_open_stroke([[0.0, 0.0], [0.375, 0.0]], 1.0, error=SculptError)


# --------------------------------------------------------------------------- messages


def test_messages_name_the_input_and_say_what_is_wrong():
    with pytest.raises(SculptError, match=r"^the stroke needs at least 2 distinct points$"):
        clean_open_stroke([[1.0, 2.0], [1.0, 2.0]], H, error=SculptError)
    with pytest.raises(SculptError, match=r"^the outline needs at least 2 distinct points$"):
        clean_open_stroke([[1.0, 2.0]], H, error=SculptError, what="outline")
    # Validation is the caller's too: its message names the input the caller's way.
    with pytest.raises(SculptError, match=r"^the outline has a point that is not a finite number"):
        clean_open_stroke([[0.0, 0.0], [np.nan, 1.0]], H, error=SculptError, what="outline")
    with pytest.raises(SculptError, match=r"^the stroke has a point that is not a finite number"):
        clean_open_stroke([[0.0, 0.0], [np.nan, 1.0]], H, error=SculptError)
    # Two points 1e-12 apart are one point for the cleaning (round-off, not drawing).
    with pytest.raises(SculptError, match=r"^the isophote is shorter than the resolution \(0\.03\): draw a longer one$"):
        clean_open_stroke([[0.0, 0.0], [1e-12, 0.0]], H, error=SculptError, what="isophote")


def test_a_closed_triangle_with_long_sides_leaves_nothing():
    # The pen comes back exactly to where it started, but the first and last sides are longer
    # than a fifth of the stroke: the crossing closes a loop that is dropped, and nothing is left.
    with pytest.raises(SculptError, match=r"^nothing of the stroke is left after removing its loops and hooks: draw a plain curve$"):
        clean_open_stroke([[0, 0], [4, 0], [0, 3], [0, 0]], 0.5, error=SculptError)


def test_nothing_left_after_a_loop_and_a_hook():
    # The same triangle, then a flick down and back up as the pen lifts: the flick is a hook,
    # the triangle a dropped loop, and what is left (0.2 long) is under half an edge.
    P = [[0, 0], [4, 0], [0, 3], [0, 0], [0.0, -0.2], [0.0, -0.05]]
    with pytest.raises(SculptError, match=r"^nothing of the stroke is left after removing its loops and hooks"):
        clean_open_stroke(P, 0.5, error=SculptError)
    # Without the triangle the hook alone is cut and the rest is kept.
    r = clean_open_stroke(_path([[0, 3], [0, 0]], 0.25).tolist() + P[-2:], 0.5)
    assert r.hooks == 1 and np.array_equal(r.points[-1], [0.0, -0.2])


# --------------------------------------------------------------------------- hooks


@pytest.mark.parametrize("h", [1.0, 4.0 / 3.0])
def test_a_hook_at_each_end_is_cut_at_its_turn(h):
    # A straight stroke along y = 0 with a 127 degree flick at each end (3-4-5 triangles, so the
    # turns are exact); each flick is 1.25 long, well inside HOOK_LENGTH edge lengths. (With
    # h = 4/3 the chords that measure the turn are exactly 1 long.)
    base = _path([[0, 0], [10, 0]], 0.5)
    P = np.vstack([[[0.75, 1.0]], base, [[9.25, 1.0]]])
    r = clean_open_stroke(P, h)
    assert (r.hooks, r.spikes, r.loops) == (2, 0, 0)
    assert np.array_equal(r.points, base)


def test_a_hook_exactly_hook_length_long_is_cut():
    # "At most HOOK_LENGTH edge lengths from the end": a 3-4-5 flick of length exactly 3 h.
    h = 5.0 / 3.0
    assert HOOK_LENGTH * h == 5.0
    base = _path([[0, 0], [12, 0]], 1.0)
    r = clean_open_stroke(np.vstack([base, [[9.0, 4.0]]]), h)
    assert r.hooks == 1 and np.array_equal(r.points, base)


def test_a_stroke_no_longer_than_two_hooks_is_left_as_drawn():
    # A V turning 127 degrees 5 from its start: the turn is within HOOK_LENGTH of that end, but
    # the stroke is no longer than 2 HOOK_LENGTH (the second one exactly), so it is a V, not a hook.
    for V, h in [([[3.0, 4.0], [0.0, 0.0], [5.0, 0.0]], 2.0), ([[3.0, 4.0], [0.0, 0.0], [7.0, 0.0]], 2.0)]:
        V = np.array(V)
        assert _length(V) <= 2 * HOOK_LENGTH * h
        r = clean_open_stroke(V, h)
        assert (r.hooks, r.spikes, r.loops) == (0, 0, 0)
        assert np.array_equal(r.points, V)


def test_a_hook_is_cut_however_the_rest_is_sampled():
    # The same stroke with its last straight side drawn as one segment or as many: the hook at the
    # start (4 long, within HOOK_LENGTH = 4.5 of the end) is cut either way.
    h = 1.5
    hook = [[2.4, 3.2], [0.0, 0.0]]
    one = np.array(hook + [[1.0, 0.0], [2.0, 0.0], [3.0, 0.0], [6.5, 0.0]])
    many = np.vstack([one[:-1], [[4.2, 0.0], [5.4, 0.0], [6.5, 0.0]]])
    for P in (one, many):
        r = clean_open_stroke(P, h)
        assert r.hooks == 1 and np.array_equal(r.points, P[1:])


def test_a_flourish_of_two_sharp_turns_is_cut_at_the_sharper():
    # The stroke runs along y = 0 to (10, 0), turns 140 degrees, goes 1.5 h, turns 110 degrees
    # and goes 1 h: both turns are hooks within HOOK_LENGTH of the end; the whole flourish goes.
    h = 1.0
    base = _path([[0, 0], [10, 0]], 0.5)
    a1, a2 = np.radians(140.0), np.radians(250.0)
    p1 = base[-1] + 1.5 * np.array([np.cos(a1), np.sin(a1)])
    p2 = p1 + 1.0 * np.array([np.cos(a2), np.sin(a2)])
    r = clean_open_stroke(np.vstack([base, p1, p2]), h)
    assert r.hooks == 1 and np.array_equal(r.points, base)


# --------------------------------------------------------------------------- back-tracking


def test_an_interior_back_track_leaves_the_line_it_was_drawn_on():
    # Along y = 0, up 2 h and straight back down, then on: the excursion goes, the rest of the
    # line stays: every point on y = 0, the ends and the line's drawn points kept.
    h = 1.0
    left, right = _path([[0, 0], [6, 0]], 0.5), _path([[6, 0], [12, 0]], 0.5)
    up = _path([[6, 0], [6, 2]], 0.5)
    P = np.vstack([left, up[1:], up[-2::-1], right[1:]])
    r = clean_open_stroke(P, h)
    assert (r.spikes, r.hooks, r.loops) == (1, 0, 0)
    assert np.all(r.points[:, 1] == 0.0)
    assert np.array_equal(r.points[0], P[0]) and np.array_equal(r.points[-1], P[-1])
    far = np.vstack([left, right])
    # Removing the excursion costs the line at most h/2 either side of its root.
    far = far[np.abs(far[:, 0] - 6.0) >= 0.5 * h]
    assert _has_rows(r.points, far)
    assert _simple(r.points, False)


def test_two_back_tracks_are_two_spikes():
    h = 1.0
    seg = [_path([[0, 0], [5, 0]], 0.5)]
    for x0 in (5.0, 12.0):
        up = _path([[x0, 0], [x0, 2.5]], 0.5)
        seg += [up[1:], up[-2::-1], _path([[x0, 0], [x0 + 7.0 if x0 == 5.0 else 17.0, 0]], 0.5)[1:]]
    r = clean_open_stroke(np.vstack(seg), h)
    assert (r.spikes, r.hooks, r.loops) == (2, 0, 0)
    assert np.all(r.points[:, 1] == 0.0)


@pytest.mark.parametrize("at", ["head", "tail"])
def test_a_back_track_to_an_end_keeps_the_long_side(at):
    # The stroke runs 12 h along y = 0 and at one end doubles back 4 h over itself (too far from
    # the end to be a hook): the doubled-back stretch is dropped, the stroke ends at the turn.
    h = 1.0
    base = _path([[0, 0], [12, 0]], 0.5)
    back = _path([[12, 0], [8, 0.05]], 0.5)[1:]
    P = np.vstack([base, back])
    if at == "head":
        P = P[::-1].copy()
    r = clean_open_stroke(P, h)
    assert (r.spikes, r.hooks, r.loops) == (1, 0, 0)
    want = base if at == "tail" else base[::-1]
    assert np.array_equal(r.points, want)


@pytest.mark.parametrize("h", [1.0, 0.5])
def test_there_and_back_is_one_pass(h):
    # Out and straight back to the start: one pass over the segment is left. (With h = 1 the
    # stroke is exactly 2 h long, the shortest in which back-tracking is looked for.)
    r = clean_open_stroke([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]], h)
    assert r.spikes == 1 and _length(r.points) == 1.0 and len(r.points) == 2


def test_a_short_sharp_v_is_left_as_drawn():
    # Shorter than 2 h, a sharp V is detail at the resolution, not back-tracking.
    V = np.array([[0.0, 0.1], [0.75, 0.0], [0.0, 0.0]])
    r = clean_open_stroke(V, 1.0)
    assert (r.spikes, r.hooks, r.loops) == (0, 0, 0) and np.array_equal(r.points, V)


# --------------------------------------------------------------------------- loops


def _curly_line(xs, h=1.0, length=16.0, radius=1.0):
    """y = 0 from 0 to ``length`` (points h/2 apart) with a curl of ``radius`` drawn at each x in
    ``xs``; returns (stroke, the line's own points)."""
    line = _path([[0, 0], [length, 0]], 0.5 * h)
    parts, last = [], 0
    for x in xs:
        k = int(np.flatnonzero(line[:, 0] == x)[0])
        parts += [line[last:k], _curl(line[k], radius)[:-1]]
        last = k
    parts.append(line[last:])
    return np.vstack(parts), line


@pytest.mark.parametrize("xs", [[1.5], [14.5], [8.0], [4.0, 12.0]])
def test_curls_are_dropped_and_the_line_kept(xs):
    # A curl near either end lies within the stroke's first or last fifth but does not join the
    # two: the stroke stays open. Whatever is left lies on the drawn path, and the line's own
    # points away from the curls are all there, unmoved.
    P, line = _curly_line(xs)
    r = clean_open_stroke(P, 1.0)
    assert not r.closed and (r.loops, r.hooks, r.spikes) == (len(xs), 0, 0)
    assert _simple(r.points, False)
    assert np.array_equal(r.points[0], line[0]) and np.array_equal(r.points[-1], line[-1])
    assert _off_path(r.points, P) < 1e-12
    assert np.abs(r.points[:, 1]).max() < 1e-12
    away = line[np.min(np.abs(line[:, :1] - np.array(xs)[None, :]), axis=1) > 0]
    assert _has_rows(r.points, away)


def test_a_stroke_that_ends_on_itself_loses_the_loop_and_keeps_distinct_points():
    # The pen stops exactly on the path drawn earlier (at a drawn point): the loop goes, the path
    # ends there, and no point is repeated.
    P = _path([[-2, 0], [4, 0], [4, 2], [2, 2], [2, 0]], 0.5)
    r = clean_open_stroke(P, 1.0)
    assert (r.loops, r.closed) == (1, False)
    assert np.array_equal(r.points, P[: int(np.flatnonzero(P[:, 0] == 2.0)[0]) + 1])
    assert (np.linalg.norm(np.diff(r.points, axis=0), axis=1) > 0).all()


def _overlapping_circle(curl_at=None, turns=1.15, n=160, r0=1.0):
    """A near-circle drawn ``turns`` times round, its radius r0 at the middle and 5 % less at both
    ends (so the overlapping ends cross once), with a small outward curl at angle curl_at."""
    a = np.linspace(0.0, 2 * np.pi * turns, int(n * turns))
    rad = r0 * (1.0 - 0.05 * (2 * a / a[-1] - 1) ** 2)
    P = np.column_stack([rad * np.cos(a), rad * np.sin(a)])
    if curl_at is None:
        return P, P
    k = int(np.argmin(np.abs(a - curl_at)))
    d = P[k] / np.linalg.norm(P[k])
    t = np.linspace(0, 2 * np.pi, 14)[1:-1]
    # A curl drawn outward: out along d, round, back through the circle.
    c = P[k] + 0.12 * d
    curl = c + 0.12 * (np.cos(t)[:, None] * -d + np.sin(t)[:, None] * np.array([-d[1], d[0]]))
    return np.vstack([P[: k + 1], curl, P[k:]]), P


@pytest.mark.parametrize("curl_at", [None, np.pi, 0.35, 2 * np.pi - 0.2])
def test_a_closed_curve_with_overlapping_ends_is_kept_closed(curl_at):
    # The ends cross in the first and last fifths: a closed curve. The ring keeps every drawn
    # point of the circle that is not in the overlapping tails or the curl, repeats its first
    # point at the end, and has no crossing left (a curl on it is a loop of its own).
    P, circle = _overlapping_circle(curl_at)
    h = 0.05
    r = clean_open_stroke(P, h)
    assert r.closed and np.array_equal(r.points[0], r.points[-1])
    assert r.loops == (1 if curl_at is None else 2)
    assert _simple(r.points, True)
    assert _off_path(r.points, P) < 1e-12
    # The ring runs from the crossing of the ends (its first point) once round: every drawn point
    # of the circle strictly between the crossing's two passes is on it.
    ang = np.arctan2(circle[:, 1], circle[:, 0]) % (2 * np.pi)
    line = shapely.LineString(circle)
    s = shapely.line_locate_point(line, shapely.points(circle))
    half = len(circle) // 2
    first = shapely.line_locate_point(shapely.LineString(circle[: half + 1]), shapely.Point(r.points[0]))
    last = s[half] + shapely.line_locate_point(shapely.LineString(circle[half:]), shapely.Point(r.points[0]))
    keep = (s > first + 1e-9) & (s < last - 1e-9)
    if curl_at is not None:
        keep &= np.abs((ang - curl_at + np.pi) % (2 * np.pi) - np.pi) > 0.3
    assert _has_rows(r.points, circle[keep])
    assert abs(_length(r.points) - 2 * np.pi * 0.98) < 0.05


# --------------------------------------------------------------------------- invariance


def _busy_stroke():
    """A wave with flicks at its ends, a back-track and a curl (for H = 0.03)."""
    P = _wave()
    k, m = 40, 80
    out = P[k] + np.linspace(0, 1, 8)[:, None] * [0.0, 0.2]
    back = P[k] + np.linspace(1, 0, 8)[:, None] * [0.004, 0.2]
    a = np.linspace(-np.pi / 2, 1.5 * np.pi, 30)
    curl = P[m] + [0.0, 0.04] + 0.04 * np.column_stack([np.cos(a), np.sin(a)])
    head = P[0] + np.array([[0.035, -0.06], [0.02, -0.03]])
    tail = P[-1] + np.array([[-0.02, -0.03], [-0.035, -0.06]])
    return np.vstack([head, P[:k], out, back, P[k:m], curl, P[m:], tail])


@pytest.mark.parametrize("c", [2e-7, 1e-6, 1.0 / 3.0, 7.0, 2e4])
def test_scaling_the_stroke_and_the_edge_together_scales_the_result(c):
    # Every length in the cleaning is in edge lengths: drawing c times larger on a mesh with
    # c times longer edges gives the same polyline, c times larger.
    P = _busy_stroke()
    ref = clean_open_stroke(P, H)
    assert min(ref.hooks, ref.spikes, ref.loops) >= 1  # every kind of cleaning takes part
    r = clean_open_stroke(c * P, c * H)
    assert (r.hooks, r.spikes, r.loops, r.closed) == (ref.hooks, ref.spikes, ref.loops, ref.closed)
    assert r.points.shape == ref.points.shape
    assert np.allclose(r.points / c, ref.points, rtol=0, atol=1e-9)
