"""Tests of the assemble plugin (issue 6) on multi-layer documents built from strokes.

The example documents in ``examples/`` are read as journals and every layer is inflated with
the real ``sketchforge_inflate.inflate_stroke``, then assembled.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import shapely
from assemble_shapes import arc as _arc
from assemble_shapes import ellipse as _ellipse
from assemble_shapes import inflate as _inflate

from sketchforge.document.layer import Layer
from sketchforge.errors import SketchforgeError
from sketchforge.geometry.locate import TriangleLocator
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.normals import face_normals
from sketchforge_assemble import BACK, FRONT, AttachmentError, DepthOrderError, assemble_detailed, assemble_meshes
from sketchforge_assemble import diagnostics as dg
from sketchforge_assemble.active_set import _active_set
from sketchforge_assemble.depth import solve_depth
from sketchforge_assemble.plugin import assemble_layers
from sketchforge_assemble.testing import meshes_from_journal

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@cache
def _inflated(name: str):
    return meshes_from_journal(EXAMPLES / f"{name}.json")


@cache
def _assembled(name: str, order: tuple | None = None):
    layers, meshes, closed = _inflated(name)
    idx = list(range(len(layers))) if order is None else list(order)
    res = assemble_detailed([meshes[i] for i in idx], [closed[i] for i in idx],
                            names=[layers[i].id for i in idx])
    return [layers[i] for i in idx], res


def _top_layer(res, x: float, y: float) -> int:
    """Layer hit first by a ray from +z down through (x, y)."""
    V, F = res.mesh.V, res.mesh.F
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    v0, v1 = b[:, :2] - a[:, :2], c[:, :2] - a[:, :2]
    v2 = np.array([x, y]) - a[:, :2]
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        l1 = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
        l2 = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
        hit = (np.abs(den) > 1e-14) & (l1 >= 0) & (l2 >= 0) & (l1 + l2 <= 1)
        z = (1 - l1 - l2) * a[:, 2] + l1 * b[:, 2] + l2 * c[:, 2]
    z[~hit] = -np.inf
    return int(res.face_layer[int(np.argmax(z))])


def _probe_point(layers, meshes, part: str, under: str):
    """A vertex of ``part`` well inside both ``part`` and ``under`` (deterministic)."""
    ids = [layer.id for layer in layers]
    m, u = meshes[ids.index(part)], meshes[ids.index(under)]
    region = shapely.Polygon(u.V[u.boundary, :2]).intersection(shapely.Polygon(m.V[m.boundary, :2]))
    core = region.buffer(-0.06)
    xy = m.V[:, :2]
    ok = shapely.contains_xy(core, xy[:, 0], xy[:, 1])
    assert ok.any(), f"{part} does not overlap {under} enough to probe"
    i = np.flatnonzero(ok)[np.argmax(m.V[ok, 2])]
    return float(xy[i, 0]), float(xy[i, 1])


# --- the assembled mesh is a closed, oriented, clean 2-manifold --------------------------------


@pytest.mark.parametrize("name", ["creature", "toucan", "separate"])
def test_examples_assemble_into_closed_oriented_manifolds(name):
    layers, res = _assembled(name)
    V, F = res.mesh.V, res.mesh.F
    _, count = dg.edge_counts(F)
    assert np.all(count == 2), "every edge must be shared by exactly two triangles"
    assert dg.is_consistently_oriented(F)
    assert dg.signed_volume(V, F) > 0, "triangles must face outwards"
    euler = dg.euler_characteristics(F)
    assert len(euler) == res.components, "one component per attached group / free part"
    assert euler == [2] * len(euler), "tree-shaped attachments give spheres"
    edges, _ = dg.edge_counts(F)
    h = np.median(np.linalg.norm(V[edges[:, 0]] - V[edges[:, 1]], axis=1))
    assert face_normals(V, F)[1].min() > 1e-3 * h * h, "no degenerate triangles"  # ~0.02 h² measured
    assert res.mesh.boundary.size == 0 and res.mesh.junction.size == 0
    assert res.max_violation <= 0.0, "every depth-order constraint holds"
    assert res.glue_error < 1e-5
    inter = dg.intersecting_pairs(V, F, res.face_layer)
    print(f"{name}: {len(V)} vertices, {len(F)} faces, {res.n_inequalities} depth rows "
          f"({res.n_active} active), {len(inter)} intersecting triangle pairs between layers")
    assert len(inter) == 0


def test_creature_attachments_follow_depth_order():
    layers, res = _assembled("creature")
    ids = [layer.id for layer in layers]
    got = {(ids[a.upper], ids[a.lower], a.side) for a in res.attachments}
    assert got == {
        ("head", "body", FRONT), ("arm_front", "body", FRONT),
        ("leg_l", "body", BACK), ("leg_r", "body", BACK),
        ("arm_back", "body", BACK), ("tail", "body", BACK),
    }
    assert res.components == 2  # the body group and the free eye


def test_toucan_chain_beak_head_body():
    layers, res = _assembled("toucan")
    ids = [layer.id for layer in layers]
    got = {(ids[a.upper], ids[a.lower], a.side) for a in res.attachments}
    assert ("beak", "head", FRONT) in got and ("head", "body", FRONT) in got
    assert ("tail", "body", BACK) in got and ("wing", "body", FRONT) in got
    assert res.components == 2  # bird and eye


def test_separate_layers_stay_separate():
    layers, res = _assembled("separate")
    assert res.attachments == []  # the open "moon" stroke has its junction over empty space
    assert res.components == len(layers) == 4
    assert res.n_inequalities == 0


# --- depth order as a user expects it --------------------------------------------------------


def test_ray_from_front_hits_the_part_in_front_first():
    layers, meshes, _ = _inflated("creature")
    ids = [layer.id for layer in layers]
    order_layers, res = _assembled("creature")
    x, y = _probe_point(layers, meshes, "arm_front", "body")
    assert ids[_top_layer(res, x, y)] == "arm_front"
    x, y = _probe_point(layers, meshes, "leg_l", "body")  # leg moved behind the body
    assert ids[_top_layer(res, x, y)] == "body"
    x, y = _probe_point(layers, meshes, "eye", "head")
    assert ids[_top_layer(res, x, y)] == "eye"


def _face_z(V, F, pts):
    """z of the triangulated surface (V, F) at each point (q, 2); NaN where no triangle is hit."""
    return TriangleLocator(V[:, :2], F).interpolate(V[:, 2], pts, nearest=False)


def _clearance(res, upper: int, lower: int) -> float:
    """Minimum of (back face of ``upper``) - (front face of ``lower``) over their overlap,
    measured like the vertex depth rows: at every vertex of either face, against the other face."""
    V, F = res.mesh.V, res.mesh.F
    back = F[(res.face_layer == upper) & (res.face_kind == 1)]
    front = F[(res.face_layer == lower) & (res.face_kind == 0)]
    vb, vf = np.unique(back), np.unique(front)
    c = np.r_[V[vb, 2] - _face_z(V, front, V[vb, :2]), _face_z(V, back, V[vf, :2]) - V[vf, 2]]
    c = c[np.isfinite(c)]
    assert len(c), "the two layers do not overlap"
    return float(c.min())


@pytest.mark.parametrize("name", ["creature", "toucan"])
def test_free_part_sits_on_the_layer_below(name):
    # A closed outline drawn over a layer (the eye on the head) is a free part; it must rest on
    # that layer, just clear of it, rather than float in front of it (visible from the side).
    layers, res = _assembled(name)
    ids = [layer.id for layer in layers]
    gap = res.solver["gap"]
    tol = 0.25 * gap
    clearance = _clearance(res, ids.index("eye"), ids.index("head"))
    print(f"{name}: eye clearance above the head {clearance:.5f} (gap {gap:.5f})")
    assert gap - tol <= clearance <= 2 * gap + tol
    assert set(res.solver["free_shift"]) == {ids.index("eye")}  # only the free part moved
    assert res.max_violation <= 0.0


@pytest.mark.parametrize("name", ["creature", "toucan"])
def test_overlapping_layers_keep_the_gap_in_the_assembled_mesh(name):
    # The depth rows checked on the output mesh itself, not through the solver's own rows: every
    # pair of overlapping layers not glued to each other keeps at least the gap between the
    # nearer layer's back face and the farther layer's front face.
    layers, res = _assembled(name)
    _, meshes, _ = _inflated(name)
    glued = {frozenset((a.upper, a.lower)) for a in res.attachments}
    polys = [shapely.Polygon(m.V[m.boundary, :2]) for m in meshes]
    gap = res.solver["gap"]
    checked = 0
    for k in range(len(layers)):
        for i in range(k):
            if frozenset((i, k)) in glued or polys[i].intersection(polys[k]).area <= 0:
                continue
            assert _clearance(res, k, i) >= gap * (1 - 1e-6), f"{layers[k].id} over {layers[i].id}"
            checked += 1
    assert checked >= 2  # e.g. the eye over the head, the front arm over a leg / the wing over the tail


def test_moving_a_layer_behind_flips_what_the_ray_sees():
    layers, meshes, _ = _inflated("creature")
    ids = [layer.id for layer in layers]
    a, b = ids.index("arm_front"), ids.index("body")
    order = [a] + [i for i in range(len(ids)) if i != a]  # move_layer arm_front -> index 0
    moved_layers, res = _assembled("creature", tuple(order))
    x, y = _probe_point(layers, meshes, "arm_front", "body")
    assert order[_top_layer(res, x, y)] == b
    arm = order.index(a)
    assert any(at.upper == arm and at.side == BACK for at in res.attachments)
    assert res.max_violation <= 0.0
    _, count = dg.edge_counts(res.mesh.F)
    assert np.all(count == 2)


# --- edge cases ------------------------------------------------------------------------------


def test_junction_spanning_two_layers_attaches_to_the_one_holding_most_of_it():
    # issue 34, point 3: an open stroke whose closing segment runs from inside `left` to inside
    # `right` is glued to the one that holds the longer stretch of it, and says so
    left = _inflate(_ellipse(-0.5, 0, 0.5, 0.4), True)
    right = _inflate(_ellipse(0.55, 0, 0.5, 0.4), True)
    part = _inflate(_arc(-0.05, -0.1, 0.4, 180, 360), False)
    assert part.junction.size
    res = assemble_detailed([left, right, part], names=["left", "right", "part"])
    assert [(a.upper, a.lower) for a in res.attachments] == [(2, 0)]  # left holds more of it
    first, last = res.attachments[0].keep
    assert 0 < last - first < len(part.junction) - 1
    assert len(res.notes) == 1 and "spans 'left' and 'right'" in res.notes[0] and "glued to 'left'" in res.notes[0]
    assert not res.warnings and res.free == []
    _, count = dg.edge_counts(res.mesh.F)
    assert np.all(count == 2) and len(dg.intersecting_pairs(res.mesh.V, res.mesh.F)) == 0
    # a junction with no stretch inside either (they are too far apart) is free, with a word
    far = _inflate(_ellipse(0.9, 0, 0.3, 0.4), True)
    res = assemble_detailed([left, far, _inflate(_arc(0.3, -0.1, 0.35, 180, 360), False)], names=["left", "far", "part"])
    assert res.attachments == [] and res.free == [2] and len(res.warnings) == 1 and "'part'" in res.warnings[0]
    with pytest.raises(AttachmentError, match="free part") as err:
        assemble_detailed([left, far, _inflate(_arc(0.3, -0.1, 0.35, 180, 360), False)],
                          names=["left", "far", "part"], params={"on_bad_junction": "raise"})
    assert isinstance(err.value, SketchforgeError)


def test_junction_partly_outside_the_layer_below_glues_the_stretch_inside():
    body = _inflate(_ellipse(0, 0, 0.6, 0.4), True)
    part = _inflate(_arc(0.45, 0.0, 0.35, 120, 420), False)  # closing segment pokes out of the body
    res = assemble_detailed([body, part], names=["body", "part"])
    assert [(a.upper, a.lower) for a in res.attachments] == [(1, 0)]
    first, last = res.attachments[0].keep
    J = part.V[part.junction[first:last + 1], :2]
    inside = shapely.contains_xy(shapely.Polygon(body.V[body.boundary, :2]), J[:, 0], J[:, 1])
    assert inside.all() and last - first < len(part.junction) - 1
    assert len(res.notes) == 1 and "runs off 'body'" in res.notes[0]
    _, count = dg.edge_counts(res.mesh.F)
    assert np.all(count == 2) and dg.euler_characteristics(res.mesh.F) == [2]


def test_layers_without_mesh_are_skipped_and_hook_returns_a_mesh():
    body = _inflate(_ellipse(0, 0, 0.6, 0.4), True)
    head = _inflate(_arc(0.55, 0.35, 0.3, 250, 560), False)
    res = assemble_detailed([None, body, head], [False, True, False])
    assert set(np.unique(res.face_layer)) == {1, 2}
    assert [(a.upper, a.lower, a.side) for a in res.attachments] == [(2, 1, FRONT)]
    layers = [Layer("b", "Body", mesh=body, closed=True), Layer("e", "Empty"), Layer("h", "Head", mesh=head)]
    mesh = assemble_layers(layers, {})
    assert isinstance(mesh, Mesh)
    assert np.array_equal(mesh.F, res.mesh.F) and np.array_equal(mesh.V, res.mesh.V)


def test_assembly_is_deterministic():
    layers, meshes, closed = _inflated("toucan")
    a = assemble_meshes(meshes, closed)
    b = assemble_meshes(meshes, closed)
    assert a.identical(b)


def test_active_set_matches_osqp_on_a_small_document():
    body = _inflate(_ellipse(0, 0, 0.6, 0.4), True, 0.08)
    arm = _inflate(_arc(0.35, -0.2, 0.25, 100, 400), False, 0.08)
    r1 = assemble_detailed([body, arm], params={"qp_solver": "osqp"})
    r2 = assemble_detailed([body, arm], params={"qp_solver": "active_set"})
    assert r1.max_violation <= 0 and r2.max_violation <= 1e-9  # the active set is exact up to round-off
    # OSQP is asked for half a gap of extra clearance, so the two differ by about that much
    assert np.abs(r1.mesh.V - r2.mesh.V).max() < 0.02


@cache
def _small_qp():
    """The depth QP (P, q, Aeq, beq, Ain, bin_) and OSQP's pad of the small body + arm document."""
    import sketchforge_assemble.depth as asm  # the assembly calls solve_depth through this module

    body = _inflate(_ellipse(0, 0, 0.6, 0.4), True, 0.08)
    arm = _inflate(_arc(0.35, -0.2, 0.25, 100, 400), False, 0.08)
    got, solve = {}, asm.solve_depth

    def spy(*args, **kw):
        got["qp"], got["pad"] = args[:6], kw["pad"]
        return solve(*args, **kw)

    asm.solve_depth = spy
    try:
        # the plain sleeve's QP: the blended junction's springs leave no depth row active here,
        # and these tests are about the active set's steps
        assemble_detailed([body, arm], params={"fillet": 0.0})
    finally:
        asm.solve_depth = solve
    return got["qp"], got["pad"]


def _osqp_reference(P, q, Aeq, beq, Ain, bin_, pad=0.0, eps=1e-9):
    import osqp

    s = osqp.OSQP()
    s.setup(P=sp.triu(P).tocsc(), q=q, A=sp.vstack([Aeq, Ain]).tocsc(), l=np.r_[beq, bin_ + pad],
            u=np.r_[beq, np.full(len(bin_), np.inf)], verbose=False, eps_abs=eps, eps_rel=eps,
            polishing=eps < 1e-6, max_iter=200000)
    return s.solve(raise_error=False)


def _qp_variant(variant):
    """The small QP as built, with its rows perturbed at round-off level, or with every depth row
    twice (one copy slightly tighter, so the working set must swap twins)."""
    (P, q, Aeq, beq, Ain, bin_), pad = _small_qp()
    Ain = sp.csr_matrix(Ain, copy=True)
    rng = np.random.default_rng(int(variant[-1]) if variant[-1].isdigit() else 0)
    if variant.startswith("perturbed"):
        Ain.data *= 1 + 1e-15 * rng.standard_normal(Ain.nnz)
        bin_ = bin_ * (1 + 1e-15 * rng.standard_normal(len(bin_)))
        q = q * (1 + 1e-15 * rng.standard_normal(len(q)))
    elif variant == "duplicated":
        Ain = sp.vstack([Ain, Ain[::-1]]).tocsr()
        bin_ = np.r_[bin_, bin_[::-1] + 1e-7]
    return P, q, Aeq, beq, Ain, bin_, pad


@pytest.mark.parametrize("start", ["empty", "osqp"])
@pytest.mark.parametrize("variant", ["as_built", "perturbed1", "perturbed2", "perturbed3", "duplicated"])
def test_active_set_is_exact_and_robust_to_round_off(variant, start):
    # The dual active set adds one row at a time and only rows independent of the working set,
    # so 1e-15 changes of the rows (or repeated rows) cannot change the working set it ends on.
    P, q, Aeq, beq, Ain, bin_, pad = _qp_variant(variant)
    if start == "empty":
        x, info = solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set")
        assert info["iterations"] > 0
    else:  # the fallback path: from the active set of OSQP's padded solve
        y = _osqp_reference(P, q, Aeq, beq, Ain, bin_, pad, eps=1e-4).y[len(beq):]
        warm = np.flatnonzero(y < -1e-9 * np.abs(y).max())
        x, _, _ = _active_set(P, q, Aeq, beq, Ain, bin_, warm[np.argsort(y[warm])], 1e-10, 1000)
    xr = _osqp_reference(P, q, Aeq, beq, Ain, bin_).x
    f, fr = 0.5 * x @ (P @ x) + q @ x, 0.5 * xr @ (P @ xr) + q @ xr
    assert abs(f - fr) <= 1e-5 * abs(fr), (f, fr)
    assert np.max(bin_ - Ain @ x) <= 1e-9
    assert np.max(np.abs(Aeq @ x - beq)) <= 1e-9
    assert np.abs(x - xr).max() < 1e-5


def test_active_set_swaps_a_row_for_a_dependent_tighter_copy():
    # Started from the optimal working set, every row gets a copy 1e-6 tighter: each copy is
    # violated and linearly dependent on its twin, so it may not join next to it; a pure dual
    # step moves the multiplier over and the twin leaves.
    P, q, Aeq, beq, Ain, bin_, _ = _qp_variant("as_built")
    n = len(bin_)
    _, _, act = _active_set(P, q, Aeq, beq, Ain, bin_, np.zeros(0, np.int64), 1e-10, 1000)
    A2, b2 = sp.vstack([Ain, Ain]).tocsr(), np.r_[bin_, bin_ + 1e-6]
    x2, _, act2 = _active_set(P, q, Aeq, beq, A2, b2, act, 1e-10, 1000)
    # every original row left for its tighter copy (the optimum's working set is unique only
    # up to nearly dependent rows, so it is compared by size, and the answer to 1e-12 below)
    assert np.all(act2 >= n) and len(act2) == len(act)
    xr, _, _ = _active_set(P, q, Aeq, beq, Ain, bin_ + 1e-6, np.zeros(0, np.int64), 1e-10, 1000)
    assert np.abs(x2 - xr).max() < 1e-12
    assert np.max(b2 - A2 @ x2) <= 1e-9


def test_active_set_reports_infeasible_rows():
    P, q, Aeq, beq, Ain, bin_, _ = _qp_variant("as_built")
    Ain = sp.vstack([Ain, -Ain[:1]]).tocsr()  # row 0 >= b0 and row 0 <= b0 - gap
    bin_ = np.r_[bin_, -bin_[0] + 0.01]
    with pytest.raises(DepthOrderError, match="could not be satisfied"):
        solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set")
    with pytest.raises(DepthOrderError, match="could not be satisfied"):
        solve_depth(P, q, Aeq, beq, Ain, bin_, method="osqp")


# --- the intersection counter itself ---------------------------------------------------------


def test_intersection_counter_on_hand_made_triangles():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0],           # flat triangle
                  [0.2, 0.2, -1], [0.3, 0.2, 1], [0.2, 0.3, 1],  # pierces it
                  [5, 5, 5], [6, 5, 5], [5, 6, 5]], float)       # far away
    F = np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8]])
    assert dg.intersecting_pairs(V, F).tolist() == [[0, 1]]
    assert len(dg.intersecting_pairs(V, F, np.array([0, 0, 1]))) == 0  # same group: not counted
    F2 = np.array([[0, 1, 2], [0, 4, 5]])  # shares a vertex: neighbours are skipped
    assert len(dg.intersecting_pairs(V, F2)) == 0


@pytest.mark.parametrize("scale", [(1.0, 1.0, 1.0), (1.0, 3.0, 0.2)])
@pytest.mark.parametrize("big", [64, 4, 1])
def test_box_pairs_are_exactly_the_overlapping_boxes(big, scale):
    # the broad phase of the intersection counter (and of the fairing's safety check) must
    # miss no overlapping pair and report each once, big boxes (tested directly) included;
    # also in a flat, long cloud (a model is thin in z), where the grid has unequal sides
    rng = np.random.default_rng(7)
    lo = rng.random((300, 3)) * scale
    hi = lo + rng.random((300, 3)) ** 3 * 0.5 * np.asarray(scale)
    hi[:3] = lo[:3] + 0.9  # a few big ones
    among = rng.random(300) < 0.3
    for sel in (None, among, np.flatnonzero(among)):
        got = dg.box_pairs(lo, hi, sel, big=big)
        mark = np.ones(300, bool) if sel is None else among
        i, j = np.triu_indices(300, 1)
        hit = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1) & (mark[i] | mark[j])
        assert got.tolist() == np.c_[i[hit], j[hit]].tolist()


def test_intersections_checked_in_two_threads_are_the_same_pairs(monkeypatch):
    # a soup of small random triangles, many crossing: the two-thread split of a large
    # ``among`` (its halves left and right of the median x) gives exactly the one-thread answer
    rng = np.random.default_rng(11)
    c = rng.random((3000, 3))
    V = (c[:, None, :] + 0.04 * rng.standard_normal((3000, 3, 3))).reshape(-1, 3)
    F = np.arange(9000).reshape(-1, 3)
    among = rng.random(3000) < 0.7
    one = dg._intersecting_pairs(V, F, None, 200_000, among)
    assert len(one) > 100
    monkeypatch.setattr(dg, "SPLIT_FROM", 10)
    monkeypatch.setattr(dg.os, "cpu_count", lambda: 2)
    for sel in (among, np.flatnonzero(among)):
        two = dg.intersecting_pairs(V, F, among=sel)
        assert two.dtype == np.int64 and two.tolist() == one.tolist()
    assert dg.intersecting_pairs(V, F, among=np.zeros(0, np.int64)).shape == (0, 2)  # nothing asked for
    # called from one of the pool's own threads it does the work there (waiting for the pool
    # from inside it could deadlock), with the same answer
    got = dg._pool().submit(dg.intersecting_pairs, V, F, None, 200_000, among).result(timeout=60)
    assert got.tolist() == one.tolist()


def test_a_loop_of_attachments_is_a_clear_error_or_a_free_part():
    # two parts, each with its junction (the closing chord) inside the other: A glued behind
    # B, B glued in front of A, which would glue a sleeve onto itself
    a = _inflate(_arc(-0.3, 0.0, 0.5, 40, 320), False)
    b = _inflate(_arc(0.3, 0.0, 0.5, 220, 500), False)
    assert a.junction.size and b.junction.size
    with pytest.raises(AttachmentError, match=r"loop \('b' -> 'a' -> 'b'") as err:
        assemble_detailed([a, b], names=["a", "b"], params={"on_bad_junction": "raise"})
    assert isinstance(err.value, SketchforgeError)
    res = assemble_detailed([a, b], names=["a", "b"])  # the default: the part closing the loop is free
    assert len(res.attachments) == 1 and len(res.warnings) == 1 and "loop" in res.warnings[0]
    _, count = dg.edge_counts(res.mesh.F)
    assert np.all(count == 2) and dg.euler_characteristics(res.mesh.F) == [2]
    assert dg.is_consistently_oriented(res.mesh.F) and dg.signed_volume(res.mesh.V, res.mesh.F) > 0


def test_free_part_behind_a_layer_settles_onto_its_back():
    # A disc drawn behind the creature's head, where the head reaches past the body: only the
    # head overlaps it, from the front. The head is glued onto the body's front, far from the
    # drawing plane, so the disc would stay behind it at its rest depth; it must rise to sit
    # just behind the head, like a sticker on the head's back.
    layers, meshes, closed = _inflated("creature")
    ids = [layer.id for layer in layers]
    head, body = meshes[ids.index("head")], meshes[ids.index("body")]
    spot = shapely.Polygon(head.V[head.boundary, :2]).difference(
        shapely.Polygon(body.V[body.boundary, :2]).buffer(0.05)).buffer(-0.05)
    c = spot.representative_point()
    disc = _inflate(_ellipse(c.x, c.y, 0.04, 0.04, n=16), True, res=0.015)
    res = assemble_detailed([disc] + list(meshes), [True] + list(closed), names=["disc"] + ids)
    assert res.solver["free_shift"][0] < 0  # raised
    V, F = res.mesh.V, res.mesh.F
    front = V[np.unique(F[(res.face_layer == 0) & (res.face_kind == 0)])]
    back = res.face_layer == 1 + ids.index("head")
    Vh = V[np.unique(F[back & (res.face_kind == 1)])]
    # clearance: the head's back face above each disc front vertex (nearest head back vertex)
    d = np.linalg.norm(front[:, None, :2] - Vh[None, :, :2], axis=2)
    above = Vh[np.argmin(d, axis=1), 2] - front[:, 2]
    gap = res.solver["gap"]
    print(f"disc clearance behind the head {np.min(above):.4f} (gap {gap:.4f}), "
          f"raised by {-res.solver['free_shift'][0]:.3f}")
    assert res.max_violation <= 0.0
    assert -0.5 * gap <= np.min(above) <= 0.02  # nearest vertices, not the exact point above
