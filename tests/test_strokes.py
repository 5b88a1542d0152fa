"""Cleaning a drawn stroke (loops, hooks, back-tracking) and throwing random polylines at the
sculpt entry points: never a crash, either a result or one clear line (issue 16, point 1)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tests_support import examples

from sketchforge.errors import SculptError, SketchforgeError
from sketchforge.geometry.contour import segment_crossings
from sketchforge.geometry.strokes import clean_open_stroke
from sketchforge_isophote_tool import sculpt
from sketchforge_isophote_tool.testing import LIGHT, inflated

H = 0.03


def _wave(n=120):
    t = np.linspace(0.0, 1.0, n)
    return np.column_stack([t, 0.15 * np.sin(4 * t)])


def _simple(P, closed):
    Q = P[:-1] if closed else P
    pairs = segment_crossings(Q, closed=closed)
    if closed:
        pairs = pairs[~((pairs[:, 0] == 0) & (pairs[:, 1] == len(Q) - 1))]
    return len(pairs) == 0


def test_a_small_loop_is_dropped_and_the_path_kept():
    P = _wave()
    k = 60
    centre = P[k] + [0.0, 0.04]
    a = np.linspace(-np.pi / 2, 1.5 * np.pi, 30)
    drawn = np.vstack([P[:k], centre + 0.04 * np.column_stack([np.cos(a), np.sin(a)]), P[k:]])
    r = clean_open_stroke(drawn, H)
    assert r.loops == 1 and not r.closed and _simple(r.points, False)
    # every cleaned point lies on the intended wave (within jitter of the thinning)
    from shapely import LineString, distance, points

    assert distance(points(r.points), LineString(P)).max() < 0.2 * H
    assert np.allclose(r.points[0], P[0]) and np.allclose(r.points[-1], P[-1])


def test_a_hook_at_the_end_is_cut():
    P = _wave()
    hook = P[-1] + np.array([[-0.02, -0.03], [-0.035, -0.06]])  # a sharp flick back as the pen lifts
    r = clean_open_stroke(np.vstack([P, hook]), H)
    assert r.hooks + r.spikes >= 1
    assert np.linalg.norm(r.points[-1] - P[-1]) < 0.5 * H


def test_back_tracking_is_removed():
    P = _wave()
    k = 60
    out = P[k] + np.linspace(0, 1, 8)[:, None] * [0.0, 0.2]
    back = P[k] + np.linspace(1, 0, 8)[:, None] * [0.004, 0.2]
    r = clean_open_stroke(np.vstack([P[:k], out, back, P[k:]]), H)
    assert r.spikes >= 1
    assert np.abs(r.points[:, 1]).max() < 0.15 + 0.1 * H  # the spike (up to 0.35) is gone


def test_a_closed_curve_with_overlapping_ends_stays_closed():
    a = np.linspace(0, 2.3 * np.pi, 200)
    r = clean_open_stroke(0.5 * np.column_stack([np.cos(a), np.sin(a)]), H)
    assert r.closed and np.array_equal(r.points[0], r.points[-1])
    assert _simple(r.points, True)
    length = np.linalg.norm(np.diff(r.points, axis=0), axis=1).sum()
    assert abs(length - np.pi) < 0.05  # the whole circle, the overlap gone


def test_near_duplicates_and_collinear_runs_are_harmless():
    P = _wave(40)
    dup = np.repeat(P, 3, axis=0) + np.tile([[0, 0], [1e-13, 0], [0, -1e-13]], (40, 1))
    r = clean_open_stroke(dup, H)
    assert _simple(r.points, False) and (np.linalg.norm(np.diff(r.points, axis=0), axis=1) > 0).all()
    line = np.column_stack([np.linspace(0, 1, 50), np.zeros(50)])
    r = clean_open_stroke(np.vstack([line, line[::-1]]), H)  # there and back along one line
    assert _simple(r.points, r.closed)


@pytest.mark.parametrize(
    "bad,msg",
    [([[0, 0]], "at least 2"), ([[0, 0], [np.inf, 0]], "finite"), ("abc", "pairs"), ([[1e300, 0], [0, 0]], "within")],
)
def test_bad_strokes_raise_the_callers_error(bad, msg):
    with pytest.raises(SculptError, match=msg):
        clean_open_stroke(bad, H, error=SculptError)


# --- property-based -----------------------------------------------------------------------------


def _polyline(draw):
    """Random polylines with what hands and scripts produce: loops, spikes, exact and 1e-12
    duplicates, collinear runs."""
    n = draw(st.integers(2, 40))
    steps = np.array(draw(st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1)), min_size=n, max_size=n)))
    scale = draw(st.sampled_from([0.002, 0.03, 0.2]))
    P = np.cumsum(steps * scale, axis=0)
    kind = draw(st.sampled_from(["plain", "dup", "near", "collinear", "spike", "loop"]))
    if kind == "dup":
        P = np.repeat(P, 2, axis=0)
    elif kind == "near":
        P = np.repeat(P, 2, axis=0) + np.tile([[0.0, 0.0], [1e-12, -1e-12]], (len(P), 1))
    elif kind == "collinear":
        P = np.vstack([P, P[-1] + np.linspace(0, 1, 10)[:, None] * [0.1, 0.0], P[-1] + [0.05, 0.0]])
    elif kind == "spike" and len(P) > 2:
        k = len(P) // 2
        P = np.vstack([P[: k + 1], P[k] + [0.0, 0.3], P[k:]])
    elif kind == "loop" and len(P) > 2:
        k = len(P) // 2
        a = np.linspace(0, 2 * np.pi, 12)
        P = np.vstack([P[: k + 1], P[k] + 0.03 * np.column_stack([np.cos(a) - 1, np.sin(a)]), P[k:]])
    return P


@settings(max_examples=examples(150), deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_any_polyline_cleans_to_a_simple_one_or_a_clear_error(data):
    P = _polyline(data.draw)
    try:
        r = clean_open_stroke(P, H, error=SculptError)
    except SculptError as exc:
        assert str(exc) and "\n" not in str(exc)
        return
    assert _simple(r.points, r.closed)
    assert np.isfinite(r.points).all() and len(r.points) >= 2


@pytest.fixture(scope="module")
def layer():
    return inflated("ellipse", 0.04)


def _band_ring(mesh, band):
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.isophote import band_around, picked_isophote
    from sketchforge_isophote_tool.layerdata import layer_data

    ld = layer_data(mesh, LIGHT, LAMBERTIAN)
    geom = band_around(ld, picked_isophote(ld, [0.2, 0.1])[1], band)
    poly = max(getattr(geom, "geoms", [geom]), key=lambda g: g.area)
    return np.asarray(poly.exterior.coords)


@settings(
    max_examples=examples(60),
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(st.data())
def test_any_polyline_through_sculpt_gives_a_result_or_one_line(layer, data):
    """Random polylines placed over the layer (some on the band's edge, some off the layer):
    the edit either applies (finite heights, contour at 0) or raises a SketchforgeError."""
    band = data.draw(st.sampled_from([0.05, 0.3, 1.5]))
    if data.draw(st.booleans()):
        P = _polyline(data.draw)
        anchor = data.draw(st.sampled_from([(0.2, 0.1), (0.1, 0.35), (0.95, 0.0), (-1.5, 0.0), (0.45, 0.38)]))
        P = P - P.mean(axis=0) + np.array(anchor)
    else:
        # Points exactly on the band's edge (its own vertices), a run of them, maybe jittered.
        ring = _band_ring(layer, band)
        k0 = data.draw(st.integers(0, len(ring) - 2))
        k1 = data.draw(st.integers(k0 + 1, min(k0 + 60, len(ring) - 1)))
        P = ring[k0 : k1 + 1] + data.draw(st.sampled_from([0.0, 1e-12, 1e-3])) * np.sin(np.arange(k1 - k0 + 1))[:, None]
    try:
        r = sculpt(layer, LIGHT, [0.2, 0.1], band, P)
    except SketchforgeError as exc:
        assert str(exc) and "\n" not in str(exc)
        return
    z = r.mesh.V[:, 2]
    assert np.isfinite(z).all() and (z >= 0).all() and (z[layer.boundary] == 0).all()
