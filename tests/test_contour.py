"""Stroke cleaning: validation, thinning, overshoot, junction, orientation, resampling."""

import time
import warnings

import numpy as np
import pytest
from inflate_shapes import circle, figure_eight, star

from sketchforge.errors import ContourError
from sketchforge.geometry.contour import (
    JUNCTION_GAP_EDGES,
    clean_contour,
    prepare_outline,
    segment_crossings,
    signed_area,
)

H = 0.05


def _edges(P):
    return np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)


def test_either_orientation_gives_the_same_counter_clockwise_outline():
    a = clean_contour(circle(), H, closed=True)
    b = clean_contour(circle(clockwise=True), H, closed=True)
    assert signed_area(a.points) > 0 and signed_area(b.points) > 0
    assert signed_area(a.points) == pytest.approx(signed_area(b.points), rel=1e-3)
    assert signed_area(a.points) == pytest.approx(np.pi, rel=5e-3)


def test_resampled_evenly_at_the_target_edge_length():
    c = clean_contour(circle(n=57), H, closed=True)
    e = _edges(c.points)
    assert np.all(np.abs(e - H) < 0.1 * H)
    assert len(c.junction) == 0


def test_duplicates_and_near_duplicates_are_dropped():
    P = circle(n=200)
    noisy = np.repeat(P, 3, axis=0)
    noisy[1::3] += 1e-9
    c = clean_contour(noisy, H, closed=True)
    assert np.min(_edges(c.points)) > 0.5 * H
    assert len(c.points) == len(clean_contour(P, H, closed=True).points)


def test_hand_jitter_is_smoothed_without_shrinking():
    rng = np.random.default_rng(7)
    # Tablet-like: samples every h/16, radial noise of a tenth of an edge.
    P = circle(n=2000)
    jitter = 0.1 * H * rng.standard_normal(len(P))
    c = clean_contour(P * (1.0 + jitter)[:, None], H, closed=True)
    r = np.linalg.norm(c.points, axis=1)
    assert r.std() < 0.4 * jitter.std()
    assert abs(r.mean() - 1.0) < 0.002
    assert len(c.corners) == 0


def test_sharp_corners_are_kept_exactly():
    P, corners = star()
    c = clean_contour(P, H, closed=True)
    for corner in corners:
        assert np.min(np.linalg.norm(c.points - corner, axis=1)) < 1e-12


def test_open_stroke_keeps_its_closing_segment_as_junction():
    # A "C" drawn clockwise, ends far apart (gap 0.59 > 2 edges).
    P = circle(n=300, turns=(2 * np.pi - 0.6) / (2 * np.pi), start=0.3, clockwise=True)
    c = clean_contour(P, H, closed=False)
    J = c.junction
    assert len(J) >= 3
    # Consecutive along the counter-clockwise ring, ends = the stroke's ends.
    assert np.all((np.diff(J) % len(c.points)) == 1)
    ends = {tuple(np.round(P[0], 12)), tuple(np.round(P[-1], 12))}
    assert {tuple(np.round(c.points[J[0]], 12)), tuple(np.round(c.points[J[-1]], 12))} == ends
    # Straight: every junction vertex on the chord x = cos(0.3).
    assert np.abs(c.points[J, 0] - np.cos(0.3)).max() < 1e-12
    assert signed_area(c.points) > 0


def test_closed_flag_makes_the_whole_outline_free():
    P = circle(n=300, turns=(2 * np.pi - 0.6) / (2 * np.pi), start=0.3)
    assert len(clean_contour(P, H, closed=True).junction) == 0


def test_nearly_meeting_ends_make_no_junction():
    gap = 0.5 * JUNCTION_GAP_EDGES * H  # angle ≈ gap on the unit circle
    P = circle(n=300, turns=(2 * np.pi - gap) / (2 * np.pi))
    o = prepare_outline(P, H, closed=False)
    assert not o.is_open
    assert len(clean_contour(P, H).junction) == 0


def test_closing_overshoot_is_trimmed():
    P = circle(n=440, turns=1.12, start=0.0)
    c = clean_contour(P, H, closed=False)
    assert len(c.junction) == 0
    assert len(segment_crossings(c.points, closed=True)) == 0
    assert signed_area(c.points) == pytest.approx(np.pi, rel=5e-3)


def test_stroke_of_100k_points_is_thinned_quickly():
    rng = np.random.default_rng(1)
    P = circle(n=100_000) + 1e-4 * rng.standard_normal((100_000, 2))
    t0 = time.perf_counter()
    o = prepare_outline(P, 0.03, closed=True)
    elapsed = time.perf_counter() - t0
    # Thinned to about 4 points per edge length; an O(n²) cleaning would take minutes.
    assert len(o.points) < 5 * 2 * np.pi / 0.03
    assert elapsed < 3.0


@pytest.mark.parametrize(
    "points, message",
    [
        ([[0, 0], [1, 1]], "at least 3"),
        ([[0, 0], [1, 1], [0, 0], [1, 1], [1, 1]], "at least 3"),
        ([[0, 0], [1, 0], [2, 0], [0.5, 0]], "straight line"),
        ([[0, 0], [1, 0], [np.nan, 1]], "finite"),
        ([[0, 0], [1, 0], [np.inf, 1]], "finite"),
        ([[0, 0], [1e200, 0], [0, 1e200]], "must lie within"),
        ([[0, 0], [1], [0, 1]], "pairs"),
        (np.zeros((4, 3)), "pairs"),
    ],
)
def test_bad_strokes_get_clear_errors(points, message):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow or invalid-value warnings on the way
        with pytest.raises(ContourError, match=message):
            clean_contour(points, H)


def test_figure_eight_is_rejected():
    with pytest.raises(ContourError, match="crosses itself"):
        clean_contour(figure_eight(), H, closed=True)


def test_closing_line_that_crosses_the_stroke_is_rejected():
    # A hook whose last leg sits between the start and the end: the closing line cuts it.
    C = np.array([[0, 0], [0, 2], [3, 2], [3, -1], [1, -1], [1, 1], [2, 1]], dtype=float)
    P = np.vstack([C[i] + (C[i + 1] - C[i]) * t for i in range(len(C) - 1) for t in np.linspace(0, 1, 20, endpoint=False)] + [C[-1:]])
    with pytest.raises(ContourError, match="closing the stroke"):
        clean_contour(P, H, closed=False)
