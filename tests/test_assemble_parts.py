"""Pieces of the assembly checked against their definitions: the vertex adjacency, the fairing's
safety check (a property of the shape, so the same at any scale), what holds a free part near a
junction, the rim taper, the intersection counter's answer for every form of ``among``, and one
point locator per sheet per assembly."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
import shapely
from assemble_shapes import arc as _arc
from assemble_shapes import ellipse as _ellipse
from assemble_shapes import inflate as _inflate

from sketchforge_assemble import assemble_detailed
from sketchforge_assemble import diagnostics as dg
from sketchforge_assemble.fair import adjacency, fairing_is_safe, supports
from sketchforge_assemble.sheet import end_taper, unique_edges


@cache
def _scene():
    """An eye drawn *behind* the body (it settles onto the body's back face), the body and an
    arm glued to its front, assembled with the blended junction."""
    eye = _inflate(_ellipse(0.2, -0.1, 0.1, 0.08, 24), True, 0.03)
    body = _inflate(_ellipse(0, 0, 0.6, 0.4), True)
    arm = _inflate(_arc(0.35, -0.2, 0.25, 100, 400), False)
    return assemble_detailed([eye, body, arm], [True, False, False])


def test_adjacency_is_the_mesh_s_edges_both_ways():
    res = _scene()
    F, n = res.mesh.F, res.mesh.n_vertices
    A = adjacency(F, n)
    E = unique_edges(F)
    want = np.zeros((n, n), bool)
    want[E[:, 0], E[:, 1]] = want[E[:, 1], E[:, 0]] = True
    assert np.array_equal(A.toarray() != 0, want)
    assert np.all(A.data == 1.0)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_fairing_safety_is_the_same_at_any_scale(scale):
    # a flat sliver of area 1e-7 h² is unsafe, one of 1e-5 h² is not, whatever the drawing's units
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    F = np.array([[0, 1, 2], [1, 3, 2]])
    moved = np.ones(4, bool)
    h = 1.0
    assert fairing_is_safe(V * scale, F, moved, h * scale)
    for area, safe in ((1e-7, False), (1e-5, True)):
        W = V.copy()
        # vertex 3 moved to the middle of edge 1-2, off it by the height that gives triangle
        # 1-3-2 that area
        W[3] = W[1] + (W[2] - W[1]) * 0.5 + np.array([1.0, 1.0, 0.0]) / np.sqrt(2) * (2 * area / np.sqrt(2))
        assert fairing_is_safe(W * scale, F, moved, h * scale) is safe, (area, scale)
    assert not fairing_is_safe(np.where(np.arange(4)[:, None] == 3, np.nan, V), F, moved, h)


def test_a_free_part_behind_a_layer_is_held_by_that_layer_s_back_face():
    res = _scene()
    V, F = res.mesh.V, res.mesh.F
    eye_xy = _ellipse(0.2, -0.1, 0.1, 0.08, 24)
    footprint = shapely.Polygon(eye_xy).buffer(0.03)
    zone = np.ones(len(V), bool)
    held = supports(V, F, res.face_layer, res.face_kind, 0, footprint, zone)
    assert held.sum() > 5
    # the held vertices are the body's back face under the eye, and only those
    body_back = np.zeros(len(V), bool)
    body_back[F[(res.face_layer == 1) & (res.face_kind == 1)]] = True
    assert np.all(body_back[held])
    inside = shapely.contains_xy(footprint, V[:, 0], V[:, 1])
    assert np.all(inside[held])
    # nothing is held outside the zone the fairing would move
    assert not supports(V, F, res.face_layer, res.face_kind, 0, footprint, np.zeros(len(V), bool)).any()
    # a part over nothing in the zone holds nothing
    far = shapely.Point(5.0, 5.0).buffer(0.1)
    assert not supports(V, F, res.face_layer, res.face_kind, 0, far, zone).any()


def test_end_taper_runs_from_0_at_the_ends_to_1_from_the_radius_on():
    rng = np.random.default_rng(3)
    xy = rng.uniform(-1, 1, (500, 2))
    ends = np.array([[0.0, 0.0], [0.5, 0.5]])
    t = end_taper(xy, ends, 0.3)
    d = np.min(np.linalg.norm(xy[:, None] - ends[None], axis=2), axis=1)
    assert np.allclose(t, np.minimum(d / 0.3, 1.0), atol=1e-15)
    assert t.max() == 1.0 and t.min() >= 0.0
    assert np.all(end_taper(ends, ends, 0.3) == 0.0)


def test_intersecting_pairs_read_among_as_indices_or_as_a_mask():
    rng = np.random.default_rng(11)
    c = rng.uniform(0, 1, (300, 1, 3))
    V = (c + rng.normal(0, 0.08, (300, 3, 3))).reshape(-1, 3)
    F = np.arange(900).reshape(300, 3)
    mask = rng.random(300) < 0.3
    by_mask = dg.intersecting_pairs(V, F, among=mask)
    by_index = dg.intersecting_pairs(V, F, among=np.flatnonzero(mask))
    assert len(by_mask) > 10
    assert by_mask.tolist() == by_index.tolist()
    every = dg.intersecting_pairs(V, F)
    want = every[mask[every[:, 0]] | mask[every[:, 1]]]
    assert by_mask.tolist() == want.tolist()
    # none: still (0, 2) int64 index pairs
    none = dg.intersecting_pairs(V[:9] + np.arange(9)[:, None] * 10.0, F[:3])
    assert none.shape == (0, 2) and none.dtype == np.int64


def test_each_sheet_gets_one_point_locator_per_assembly(monkeypatch):
    # the fillets' springs and the depth rows share each sheet's locator (one build per sheet:
    # the build is most of a sheet's cost in the depth rows)
    import sketchforge.geometry.locate as locate

    built = []
    real = locate.TriangleLocator

    class Counting(real):
        def __init__(self, xy, F, *a, **k):
            built.append(len(xy))
            super().__init__(xy, F, *a, **k)

    monkeypatch.setattr(locate, "TriangleLocator", Counting)
    import sketchforge_assemble.depth_rows as depth_rows

    monkeypatch.setattr(depth_rows, "TriangleLocator", Counting)
    import sketchforge.plugin_api as api  # the blend's locator comes through the public API

    monkeypatch.setattr(api, "TriangleLocator", Counting)
    body = _inflate(_ellipse(0, 0, 0.6, 0.4), True)
    arm = _inflate(_arc(0.35, -0.2, 0.25, 100, 400), False)
    res = assemble_detailed([body, arm])
    assert res.solver["fair_zone"] is not None  # the blended junction: both used a locator
    assert len(built) == 2  # body and arm, once each


def test_the_fairing_solve_runs_on_libigl_and_agrees_with_superlu(monkeypatch):
    # SuperLU is only the fallback for a binding that fails: the fast path must work on its own
    # (a broken call into libigl would otherwise hide behind the fallback, 2x slower)
    import scipy.sparse as sp

    import sketchforge_assemble.fair as fair

    res = _scene()
    A = adjacency(res.mesh.F, res.mesh.n_vertices)
    Lg = sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A
    K = (Lg @ Lg + sp.eye(A.shape[0])).tocsc()
    rhs = np.random.default_rng(4).normal(size=(A.shape[0], 3))
    X_lu = fair.splu(K, permc_spec="COLAMD").solve(rhs)

    def no_fallback(*a, **k):
        raise AssertionError("the SuperLU fallback was used")

    monkeypatch.setattr(fair, "splu", no_fallback)
    X = fair._spd_solve(K, rhs)
    assert X.shape == rhs.shape
    assert np.abs(K @ X - rhs).max() <= 1e-9 * np.abs(rhs).max()
    assert np.abs(X - X_lu).max() <= 1e-9 * np.abs(X_lu).max()


def test_rings_count_edges_from_the_seed_like_a_breadth_first_search():
    from collections import deque

    from sketchforge_assemble.fair import rings_from

    res = _scene()
    F, n = res.mesh.F, res.mesh.n_vertices
    A = adjacency(F, n)
    seed = np.array([0, 7])
    got = rings_from(A, seed, 4)
    dist = np.full(n, 5)
    dist[seed] = 0
    todo = deque(seed.tolist())
    while todo:
        v = todo.popleft()
        for w in A.indices[A.indptr[v]:A.indptr[v + 1]]:
            if dist[w] > dist[v] + 1 and dist[v] + 1 <= 4:
                dist[w] = dist[v] + 1
                todo.append(w)
    assert np.array_equal(got, dist)
    assert got.dtype == np.int64 and set(np.unique(got)) == {0, 1, 2, 3, 4, 5}


def test_hold_weights_rise_smoothly_from_hold_start_to_the_zone_s_edge():
    from sketchforge_assemble.fair import HOLD_START, HOLD_WEIGHT, hold_weights

    t = np.linspace(0.0, 1.0, 101)
    w = hold_weights(t)
    assert np.all(w[t <= HOLD_START] == 0.0)
    assert w[-1] == pytest.approx(HOLD_WEIGHT, rel=1e-12)
    mid = HOLD_START + 0.5 * (1.0 - HOLD_START)
    assert hold_weights(np.array([mid]))[0] == pytest.approx(0.5 * HOLD_WEIGHT, rel=1e-12)
    assert np.all(np.diff(w) >= 0.0)


def test_fairing_builds_the_adjacency_it_is_not_given():
    from sketchforge_assemble.fair import fair_seams

    res = _scene()
    V, F = res.mesh.V, res.mesh.F
    moved = np.zeros(len(V), bool)
    moved[F[res.face_layer == 2].ravel()[:200]] = True  # part of the arm
    a = fair_seams(V, F, moved)
    b = fair_seams(V, F, moved, adjacency(F, len(V)))
    assert np.array_equal(a, b) and not np.array_equal(a, V)
