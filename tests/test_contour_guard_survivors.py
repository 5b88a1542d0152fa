"""Contour helpers and the native-code guard, checked where mutation testing found the suite blind.

These tests come from mutants of sketchforge/geometry/contour.py and guard.py that the rest of
the suite did not kill. Each checks a property a caller relies on, computed independently of
the code under test:

- ``_segment_distances`` (what the slit-ring check measures a channel's width with) against
  GEOS' exact segment-to-segment distance, on random segments at several scales;
- ``intersection_point`` (where an error message says a stroke crosses itself) lies on both
  segments, also for a segment 1e-300 long and for nearly parallel, nearly touching ones;
- ``clean_contour``'s defaults and its ``smooth=False`` (points stay on the drawn polygon);
- the messages the guard's refusals show the user name the input, the part at fault and the
  row, and what it returns has the documented shapes and dtypes.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import shapely

from sketchforge.errors import GeometryError
from sketchforge.geometry import guard
from sketchforge.geometry.contour import (
    _segment_distances,
    clean_contour,
    intersection_point,
    prepare_outline,
    resample_outline,
)


def _one_sentence(exc: BaseException) -> str:
    msg = str(exc)
    assert msg.strip() and "\n" not in msg and "None" not in msg, repr(msg)
    return msg


def _point_to_segment(p, a, b) -> float:
    """Exact (GEOS) distance from point p to segment ab."""
    return shapely.Point(p).distance(shapely.LineString([a, b]) if np.any(a != b) else shapely.Point(a))


# --- _segment_distances ------------------------------------------------------------------------


@pytest.mark.parametrize("scale", [1e-3, 1.0, 250.0])
def test_segment_distances_match_the_exact_distance_between_segments(scale):
    # Random segments give every case: crossing (0), one end nearest the other segment's
    # inside, ends nearest each other (projections before the start and past the end), and
    # segments whose lines cross outside one of them. Small scales matter: a squared length
    # below 1 must not be treated as 1.
    rng = np.random.default_rng(7)
    m = 400
    a, b, c, d = (scale * (rng.random((m, 2)) + [3.0, -2.0]) for _ in range(4))
    got = _segment_distances(a, b, c, d)
    want = np.array([shapely.LineString([a[k], b[k]]).distance(shapely.LineString([c[k], d[k]])) for k in range(m)])
    assert got.shape == (m,)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12 * scale)
    # Both kinds of pair are there, or the comparison above would prove little.
    assert (want == 0).sum() > 20 and (want > 0.05 * scale).sum() > 100


def test_segment_distance_is_zero_exactly_where_segments_cross_and_symmetric():
    # A plus sign: the segments cross in their middles, every end is 1 from the other segment.
    a, b = np.array([[-1.0, 0.0]]), np.array([[1.0, 0.0]])
    c, d = np.array([[0.0, -1.0]]), np.array([[0.0, 1.0]])
    assert _segment_distances(a, b, c, d).tolist() == [0.0]
    # Lines crossing outside one segment (a "T" that stops short): the gap, not 0.
    for dy in (0.25, 2.0):
        c2, d2 = np.array([[0.0, dy]]), np.array([[0.0, dy + 3.0]])
        assert _segment_distances(a, b, c2, d2).tolist() == pytest.approx([dy])
        assert _segment_distances(c2, d2, a, b).tolist() == pytest.approx([dy])
    # Segments side by side, offset along their direction: the nearest ends decide.
    e, f = np.array([[2.0, 0.5]]), np.array([[4.0, 0.5]])
    assert _segment_distances(a, b, e, f)[0] == pytest.approx(np.hypot(1.0, 0.5))
    # Touching pairs (an end on the other segment's inside, a shared end, collinear overlap):
    # 0, with no divide-by-zero or invalid-value warning on the way (the house rule of
    # test_contour: warnings from numpy on valid strokes are bugs).
    T = [((0.0, 1.0), (0.0, 0.0), (-1.0, 0.0), (1.0, 0.0)),
         ((0.0, -1.0), (0.0, 0.0), (-1.0, 0.0), (1.0, 0.0)),
         ((0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (-1.0, 0.0)),
         ((0.0, 0.0), (1.0, 1.0), (1.0, 1.0), (2.0, 0.0)),
         ((0.0, 0.0), (2.0, 2.0), (1.0, 1.0), (3.0, 3.0))]
    p, q, r, s = (np.array(x) for x in zip(*T))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _segment_distances(p, q, r, s).tolist() == [0.0] * len(T)
        assert _segment_distances(r, s, p, q).tolist() == [0.0] * len(T)
    # Translated and rotated copies: the same distances.
    rng = np.random.default_rng(3)
    P = rng.random((50, 4, 2))
    base = _segment_distances(P[:, 0], P[:, 1], P[:, 2], P[:, 3])
    th = 0.7
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    Q = P @ R.T + [123.0, -45.0]
    np.testing.assert_allclose(_segment_distances(Q[:, 0], Q[:, 1], Q[:, 2], Q[:, 3]), base, atol=1e-9)


# --- intersection_point ------------------------------------------------------------------------


def test_intersection_point_is_the_crossing_of_two_crossing_segments():
    rng = np.random.default_rng(11)
    for _ in range(200):
        X = rng.uniform(-50, 50, 2)
        u, v = rng.normal(size=2), rng.normal(size=2)
        if abs(u[0] * v[1] - u[1] * v[0]) < 0.1 * np.linalg.norm(u) * np.linalg.norm(v):
            continue  # well-conditioned crossings only: the answer is then known to 1e-9
        ta, tc = rng.uniform(0.1, 0.9, 2)
        a, b = X - ta * u, X + (1 - ta) * u
        c, d = X - tc * v, X + (1 - tc) * v
        np.testing.assert_allclose(intersection_point(a, b, c, d), X, atol=1e-9)
        np.testing.assert_allclose(intersection_point(c, d, a, b), X, atol=1e-9)


def test_intersection_point_with_a_vanishingly_short_segment_is_still_the_crossing():
    # A unit segment crossed in its middle by one 1e-300 long: the cross product of their
    # directions is exactly 1e-300, not zero, so they are not parallel.
    h = 1e-300
    a, b = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    c, d = np.array([0.5, -h / 2]), np.array([0.5, h / 2])
    np.testing.assert_allclose(intersection_point(a, b, c, d), [0.5, 0.0], atol=1e-12)


def test_intersection_point_of_nearly_parallel_touching_segments_lies_on_both():
    # Almost parallel and almost touching (1e-17 apart): the supporting lines meet half a unit
    # past b, but the answer must still be a point of segment ab close to segment cd.
    a, b = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    c, d = np.array([0.5, 1e-17]), np.array([1.5, 0.0])
    x = intersection_point(a, b, c, d)
    assert _point_to_segment(x, a, b) < 1e-12
    assert _point_to_segment(x, c, d) < 1e-12


# --- clean_contour -----------------------------------------------------------------------------


def test_clean_contour_treats_a_stroke_as_open_by_default():
    # Three quarters of a circle, counter-clockwise: the ends are 14 edge lengths apart, so
    # by default the closing segment is the junction, a straight run from the end to the start.
    th = np.radians(np.linspace(45.0, 315.0, 200))
    P = 10.0 * np.c_[np.cos(th), np.sin(th)]
    c = clean_contour(P, 1.0)
    assert len(c.junction) >= 10
    J = c.points[c.junction]
    np.testing.assert_allclose(J[:, 0], 10.0 * np.cos(np.radians(45.0)), atol=1e-9)
    assert {tuple(np.round(J[0], 9)), tuple(np.round(J[-1], 9))} == {tuple(np.round(P[-1], 9)), tuple(np.round(P[0], 9))}
    assert len(clean_contour(P, 1.0, closed=True).junction) == 0


def test_clean_contour_without_smoothing_keeps_every_point_on_the_drawn_polygon():
    # A regular 12-gon (turns of 30 degrees: no corners) with edges far longer than the
    # thinning spacing: nothing is thinned away, so unsmoothed resampling puts every point on
    # its sides; smoothing rounds it off by hundredths.
    th = np.linspace(0.0, 2 * np.pi, 12, endpoint=False)
    P = 10.0 * np.c_[np.cos(th), np.sin(th)]
    ring = shapely.LinearRing(P)

    def off(points):
        return max(ring.distance(shapely.Point(p)) for p in points)

    raw = clean_contour(P, 1.0, closed=True, smooth=False)
    assert off(raw.points) < 1e-9
    np.testing.assert_array_equal(raw.points, resample_outline(prepare_outline(P, 1.0, True), smooth=False).points)
    assert off(clean_contour(P, 1.0, closed=True).points) > 1e-3


# --- guard: merge tolerance --------------------------------------------------------------------

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
SQUARE_SEGS = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])


@pytest.mark.parametrize("tol, words", [
    ("fine", "the square: the merge tolerance must be a number, got 'fine'"),
    (-1e-6, "the square: the merge tolerance must be a finite number >= 0, got -1e-06"),
    (np.inf, "the square: the merge tolerance must be a finite number >= 0, got inf"),
    (np.nan, "the square: the merge tolerance must be a finite number >= 0, got nan"),
])
def test_pslg_refuses_a_merge_tolerance_that_is_not_a_finite_non_negative_number(tol, words):
    with pytest.raises(GeometryError) as err:
        guard.pslg(SQUARE, SQUARE_SEGS, tol, what="the square")
    assert _one_sentence(err.value) == words
    # 0 and positive tolerances are fine.
    for ok in (0, 0.0, 1e-3):
        assert guard.pslg(SQUARE, SQUARE_SEGS, ok)["vertices"].shape == (4, 2)


# --- guard: QP parts ---------------------------------------------------------------------------


def _message(fn, *args, **kwargs) -> str:
    with pytest.raises(GeometryError) as err:
        fn(*args, **kwargs)
    return _one_sentence(err.value)


def test_objective_messages_name_the_program_and_the_objective_matrix():
    assert _message(guard.objective, np.diag([1.0, np.nan]), [0.0, 0.0]) == (
        "the quadratic program: the objective matrix has an entry that is not a finite number")
    assert _message(guard.objective, np.diag([1.0, np.inf]), [0.0, 0.0], "the depth QP") == (
        "the depth QP: the objective matrix has an entry that is not a finite number")
    assert _message(guard.objective, np.ones((2, 3)), [0.0, 0.0], "the depth QP") == (
        "the depth QP: the objective matrix must be square, got shape (2, 3)")
    assert _message(guard.objective, np.ones((3, 2)), [0.0, 0.0]) == (
        "the quadratic program: the objective matrix must be square, got shape (3, 2)")


def test_constraints_messages_name_the_program_the_matrix_the_side_and_the_row():
    A = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    assert _message(guard.constraints, np.array([[np.nan, 0.0]]), None, None, 2) == (
        "the quadratic program: the constraint matrix has an entry that is not a finite number")
    assert _message(guard.constraints, A, None, None, 3) == (
        "the quadratic program: the constraint matrix has 2 columns for 3 unknowns")
    assert _message(guard.constraints, A, None, [1.0, 2.0], 2, "the QP") == (
        "the QP: 2 upper bounds for 3 constraint rows")
    assert _message(guard.constraints, A, [0.0, 0.0, 0.0], ["a", "b", "c"], 2, "the QP") == (
        "the QP: the upper bounds must be numbers")
    assert _message(guard.constraints, A, ["x", 0.0, 0.0], None, 2, "the QP") == (
        "the QP: the lower bounds must be numbers")
    # The first row whose lower bound is above its upper bound; a row with l == u is fine.
    assert _message(guard.constraints, A, [0.0, 1.0, 5.0], [0.0, 2.0, 3.0], 2, "the QP") == (
        "the QP: row 2 has lower bound 5 above its upper bound 3")


def test_constraints_return_flat_float64_bounds_whatever_their_input_shape_and_dtype():
    A = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    M, l, u = guard.constraints(A, np.array([[0], [-1], [2]]), [1, 2, 3], 2)
    assert M.format == "csc" and M.dtype == np.float64
    for x, want in ((l, [0.0, -1.0, 2.0]), (u, [1.0, 2.0, 3.0])):
        assert x.shape == (3,) and x.dtype == np.float64 and x.flags.c_contiguous
        assert x.tolist() == want


def test_qp_messages_name_the_program_in_every_part():
    P, q = np.eye(2), np.zeros(2)
    A = np.array([[1.0, 0.0], [0.0, 1.0]])
    assert _message(guard.qp, P, q, A[:, :1], None, None) == (
        "the quadratic program: the constraint matrix has 1 columns for 2 unknowns")
    assert _message(guard.qp, P, q, A[:, :1], None, None, "the depth QP") == (
        "the depth QP: the constraint matrix has 1 columns for 2 unknowns")
    assert _message(guard.qp, P, q, A, [3.0, 0.0], [1.0, 1.0], what="the depth QP") == (
        "the depth QP: row 0 has lower bound 3 above its upper bound 1")
    assert _message(guard.qp, np.diag([np.nan, 1.0]), q, A, None, None) == (
        "the quadratic program: the objective matrix has an entry that is not a finite number")


# --- guard: linestring, PslgError --------------------------------------------------------------


def test_linestring_takes_two_distinct_points_and_names_the_line_when_refusing():
    line = guard.linestring([[0.0, 0.0], [3.0, 4.0]])
    assert line.length == pytest.approx(5.0)
    assert guard.linestring([[1.0, 1.0], [1.0, 1.0], [2.0, 1.0]]).length == pytest.approx(1.0)
    assert _message(guard.linestring, [[1.0, 2.0], [1.0, 2.0], [1.0, 2.0]]) == "the line has fewer than 2 distinct points"
    assert _message(guard.linestring, [[1.0, 2.0]], "the isophote") == "the isophote has fewer than 2 distinct points"
    assert _message(guard.linestring, [[0.0, 0.0], [np.nan, 1.0]], "the isophote") == (
        "the isophote has a point that is not a finite number (point 1: [nan, 1.0])")


def test_pslg_error_location_is_float64_or_none():
    e = guard.PslgError("the outline has two segments that cross", segments=(1, 3), at=(2, 5))
    assert isinstance(e, GeometryError) and str(e) == "the outline has two segments that cross"
    assert e.segments == (1, 3) and e.points == ()
    assert e.at.dtype == np.float64 and e.at.tolist() == [2.0, 5.0]
    assert guard.PslgError("the outline is refused").at is None


def test_disjoint_segments_on_one_line_are_never_called_crossing():
    # The orientation signs of nearly collinear segments are round-off noise: before they were
    # read with a tolerance, 1 in 10^4 disjoint collinear pairs got distance 0 (this one did).
    a = np.array([[1.2522676343404942, -6.591828446920562]])
    b = np.array([[5.5751778734472515, -4.2090648830639275]])
    c = np.array([[5.649393156458938, -4.168157840710419]])
    d = np.array([[8.408149429654678, -2.6475470563676016]])
    exact = shapely.LineString([a[0], b[0]]).distance(shapely.LineString([c[0], d[0]]))
    assert exact > 0.08
    assert _segment_distances(a, b, c, d)[0] == pytest.approx(exact, rel=1e-9)
    rng = np.random.default_rng(11)
    for scale in (1e-3, 1.0, 250.0):
        n = 5000
        p0 = rng.uniform(-5, 5, (n, 2)) * scale
        u = rng.normal(size=(n, 2))
        u /= np.linalg.norm(u, axis=1)[:, None]
        t = np.sort(rng.uniform(0, 10, (n, 4)), axis=1) * scale  # a-b then c-d along the line
        A, B, C, D = (p0 + t[:, k : k + 1] * u for k in range(4))
        ref = shapely.distance(shapely.linestrings(np.stack([A, B], 1)), shapely.linestrings(np.stack([C, D], 1)))
        got = _segment_distances(A, B, C, D)
        assert np.abs(got - ref).max() <= 1e-12 * scale * 10


# --- guard.geometry / guard.polygon ------------------------------------------------------------


def test_geometry_names_the_shape_and_what_it_got_instead_of_a_geometry():
    with pytest.raises(GeometryError) as info:
        guard.geometry([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert _one_sentence(info.value) == "the shape must be a shapely geometry, got list"
    with pytest.raises(GeometryError) as info:
        guard.geometry(np.zeros((3, 2)), "the hole")
    assert _one_sentence(info.value) == "the hole must be a shapely geometry, got ndarray"


def test_an_overlapping_multipolygon_is_repaired_to_the_union_of_its_parts():
    # Two parts that overlap, handed over as one MultiPolygon, are invalid for GEOS. What was
    # drawn is both parts: the repair is their union. (make_valid alone reads the twice-covered
    # overlap as outside, a hole where the parts overlap.)
    a = shapely.box(0.0, 0.0, 2.0, 2.0)
    b = shapely.box(1.0, 1.0, 3.0, 3.0)
    g = shapely.MultiPolygon([a, b])
    assert not g.is_valid
    fixed = guard.geometry(g, "the parts")
    assert fixed.is_valid and fixed.geom_type == "Polygon"
    assert shapely.symmetric_difference(fixed, shapely.union(a, b)).area < 1e-12
    assert fixed.area == pytest.approx(7.0, abs=1e-12) and fixed.contains(shapely.Point(1.5, 1.5))
    # a part that is itself a bow tie is repaired as a lone one is, then joined to the rest
    bow = shapely.Polygon([(5.0, 0.0), (7.0, 2.0), (7.0, 0.0), (5.0, 2.0)])
    both = guard.geometry(shapely.MultiPolygon([a, bow]), "the parts")
    assert both.is_valid and both.area == pytest.approx(4.0 + guard.geometry(bow).area, abs=1e-12)
    assert guard.geometry(bow).area == pytest.approx(2.0, abs=1e-12)
    # parts that all collapse to lines leave an empty Polygon, as a lone collapsed part does
    flat = shapely.Polygon([(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (1.0, 0.0)])
    gone = guard.geometry(shapely.MultiPolygon([flat, flat]), "the parts")
    assert gone.geom_type == "Polygon" and gone.is_empty


def test_an_invalid_ring_is_refused_with_the_reason_geos_gives():
    ring = shapely.LinearRing([(0.0, 0.0), (2.0, 2.0), (2.0, 0.0), (0.0, 2.0)])  # a bow tie
    assert not ring.is_valid
    with pytest.raises(GeometryError) as info:
        guard.geometry(ring, "the rim")
    msg = _one_sentence(info.value)
    assert msg.startswith("the rim is not a valid LinearRing (") and "Self-intersection" in msg


def test_polygon_names_the_outline_by_default_and_the_caller_s_name_otherwise():
    with pytest.raises(GeometryError) as info:
        guard.polygon([[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]])
    assert _one_sentence(info.value).startswith("the outline has fewer than 3 distinct points")
    with pytest.raises(GeometryError) as info:
        guard.polygon([[0.0, 0.0], [np.nan, 1.0], [1.0, 0.0]], "the wing")
    assert _one_sentence(info.value).startswith("the wing has a point that is not a finite number")


def test_random_overlapping_parts_repair_to_their_union():
    # 60 seeded MultiPolygons of 2-4 random star-shaped parts (some self-crossing): the repair is
    # valid, covers every part, and has the area of the union of the parts repaired alone.
    rng = np.random.default_rng(2026)
    for _ in range(60):
        parts = []
        for _ in range(int(rng.integers(2, 5))):
            n = int(rng.integers(4, 9))
            t = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
            if rng.random() < 0.3:
                rng.shuffle(t)  # a self-crossing part
            r = rng.uniform(0.3, 1.0, n)
            c = rng.uniform(-1.0, 1.0, 2)
            parts.append(shapely.Polygon(np.c_[c[0] + r * np.cos(t), c[1] + r * np.sin(t)]))
        g = shapely.MultiPolygon(parts)
        fixed = guard.geometry(g, "the parts")
        assert fixed.is_valid and fixed.geom_type in ("Polygon", "MultiPolygon")
        alone = shapely.union_all([guard.geometry(p) for p in parts])
        assert fixed.area == pytest.approx(alone.area, rel=1e-9, abs=1e-12)
        assert all(guard.geometry(p).difference(fixed).area < 1e-9 for p in parts)
