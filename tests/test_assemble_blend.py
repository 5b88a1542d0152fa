"""Junction folds (issue 12, point 1): the dihedral measure, the seeded random creatures, and
the blended junction (``fillet`` + ``fair``, the default), which must keep every topological
guarantee of the plain sleeve and reach the issue's target: no dihedral angle above 90 degrees,
99.9% of them at most 45."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pytest
import shapely

from sketchforge_assemble import assemble_detailed
from sketchforge_assemble import diagnostics as dg
from sketchforge_assemble.testing import meshes_from_journal, random_creature

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_dihedral_angles_of_a_hinge():
    # two triangles sharing the edge (0,0,0)-(1,0,0), the second turned by 60 degrees about it
    a = np.radians(60)
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -np.cos(a), -np.sin(a)]], float)
    F = np.array([[0, 1, 2], [1, 0, 3]])
    assert dg.dihedral_angles(V, F) == pytest.approx([60.0])
    V[3] = [0.5, -1, 0]  # flat
    assert dg.dihedral_angles(V, F) == pytest.approx([0.0], abs=1e-6)


def _check_closed(res, meshes=None):
    """Closed, oriented, Euler characteristic 2 per group, no intersecting triangles; with
    ``meshes`` (the fillet) at most two pairs, each a face of one part crossing that part's
    own rim bridge within 4 edge lengths of one of its junction's ends (the fillet's known
    defect, see the README)."""
    V, F = res.mesh.V, res.mesh.F
    _, count = dg.edge_counts(F)
    assert np.all(count == 2)
    assert dg.is_consistently_oriented(F) and dg.signed_volume(V, F) > 0
    assert dg.euler_characteristics(F) == [2] * res.components
    pairs = dg.intersecting_pairs(V, F)
    if meshes is None:
        assert len(pairs) == 0
        return
    assert len(pairs) <= 2
    for a, b in pairs:
        layer = res.face_layer[a]
        assert res.face_layer[b] == layer and 2 in (res.face_kind[a], res.face_kind[b]), (a, b)
        m = meshes[layer]
        ends = m.V[m.junction[[0, -1]], :2]
        h = np.median(np.linalg.norm(m.V[m.F[:, 0], :2] - m.V[m.F[:, 1], :2], axis=1))
        c = V[F[a], :2].mean(axis=0)
        assert np.min(np.linalg.norm(ends - c, axis=1)) < 4 * h, (a, b)


@cache
def _example(name):
    return meshes_from_journal(EXAMPLES / f"{name}.json")


def test_random_creatures_are_deterministic_and_attach():
    doc = random_creature(3)
    assert doc == random_creature(3) and doc != random_creature(4)
    layers, meshes, closed = meshes_from_journal(doc)
    ids = [layer.id for layer in layers]
    n_limbs = sum(i.startswith("limb_") for i in ids)
    assert 2 <= n_limbs <= 6 and "head" in ids and "eye" in ids
    res = assemble_detailed(meshes, closed, names=ids)
    # head and every limb glue onto the body; the body and the eye are free parts
    assert sorted(ids[a.upper] for a in res.attachments) == sorted(["head"] + [i for i in ids if i.startswith("limb_")])
    assert {ids[a.lower] for a in res.attachments} == {"body"}
    _check_closed(res)


def _folds(res):
    d = dg.dihedral_angles(res.mesh.V, res.mesh.F)
    return float(d.max()), int(np.sum(d > 90)), float(np.mean(d <= 45))


def test_a_random_creature_without_room_for_a_head_is_refused():
    # seed 43's head chord lies in the band along the body's outline at every size: the
    # generator shrank it forever
    with pytest.raises(ValueError, match="no head fits"):
        random_creature(43)


@pytest.mark.parametrize("name", ["creature", "toucan"])
def test_junctions_blend_on_the_examples(name):
    layers, meshes, closed = _example(name)
    plain = assemble_detailed(meshes, closed, params={"fillet": 0.0})
    blended = assemble_detailed(meshes, closed)
    _check_closed(blended)
    assert not blended.warnings  # no junction fell back to the plain sleeve
    # measured: plain creature 179.5 degrees, 106 edges above 90; blended 49.8, 0 (99.994% <= 45);
    # toucan 178.9 -> 85.4 (99.94% <= 45), both faired in the narrow zone
    top0, over0, _ = _folds(plain)
    top, over, flat = _folds(blended)
    assert top0 > 170 and over0 > 40
    assert top <= 90 and over == 0 and flat >= 0.999
    # the narrow zone, widened (issue 34) only where it leaves a fold or too many creases: around
    # the ends of every junction (16 rings instead of 12, then 21) for the toucan's head over the
    # body, which then needs no wide zone near it (it did with 12)
    widened = {"creature": ("narrow", 12), "toucan": ("narrow", 21)}[name]
    assert (blended.solver["fair_zone"], blended.solver["fair_rings"]) == widened
    # and faired once: no further try for creases, none for a thinned limb (the neck try),
    # each of which costs the example creature another ~0.1 s against issue 12's 0.3 s
    if name == "creature":
        import sketchforge_assemble.assemble as asm

        calls = []
        real = asm._fair_rings
        try:
            asm._fair_rings = lambda *a, **k: calls.append(1) or real(*a, **k)
            assemble_detailed(meshes, closed)
        finally:
            asm._fair_rings = real
        assert len(calls) == 1
    # the blend only reshapes junctions: depth order and glue still hold
    assert blended.max_violation <= 1e-6 and blended.glue_error < 1e-3


@pytest.mark.parametrize("seed", [18, 29, 34])
def test_junctions_blend_on_random_creatures(seed):
    # seeds whose heads or limbs still folded above 90 degrees with fewer rings of fairing
    # around the whole seam (6 rings: 18 and 29; 10 rings: 34, a limb behind the body); the
    # full 30, and 29 held-out ones, are in benchmarks/bench_junctions.py
    _, meshes, closed = meshes_from_journal(random_creature(seed))
    res = assemble_detailed(meshes, closed)
    _check_closed(res)
    assert not res.warnings
    top, over, flat = _folds(res)
    assert top <= 90 and flat >= 0.999, (top, over, flat)


def test_fairing_is_local_and_keeps_what_rests_on_the_host():
    # Fairing moves only vertices near the junctions: the free eye on the toucan's head, 2.6
    # edge lengths from the beak's junction, keeps its faces and the head's front face under
    # it, so it still rests on the head at the depth solve's clearance (the head's back face
    # and the body further down are faired as usual).
    layers, meshes, closed = _example("toucan")
    ids = [layer.id for layer in layers]
    raw = assemble_detailed(meshes, closed, params={"fair": 0})
    res = assemble_detailed(meshes, closed)
    assert np.array_equal(raw.mesh.F, res.mesh.F)
    moved = np.any(raw.mesh.V != res.mesh.V, axis=1)
    eye = np.unique(res.mesh.F[res.face_layer == ids.index("eye")])
    assert not moved[eye].any()
    eye_mesh = meshes[ids.index("eye")]
    head_front = np.unique(res.mesh.F[(res.face_layer == ids.index("head")) & (res.face_kind == 0)])
    V = res.mesh.V[head_front]
    under = head_front[shapely.contains_xy(shapely.Polygon(eye_mesh.V[eye_mesh.boundary, :2]), V[:, 0], V[:, 1])]
    assert len(under) >= 10 and not moved[under].any()
    # the fairing reaches that far: without the eye the head's front there would move
    near = np.min(np.linalg.norm(res.mesh.V[head_front, None, :2] - eye_mesh.V[None, :, :2], axis=2), axis=1)
    assert moved[head_front[(near > 0.06) & (near < 0.1)]].any()
    # the eye's back face over the head's front face as the fairing left it: the lowest eye
    # vertex above its nearest head vertex, as without fairing
    def clearance(r):
        back = np.unique(r.mesh.F[(r.face_layer == ids.index("eye")) & (r.face_kind == 1)])
        d = np.linalg.norm(r.mesh.V[back, None, :2] - r.mesh.V[None, head_front, :2], axis=2)
        return np.min(r.mesh.V[back, 2] - r.mesh.V[head_front[np.argmin(d, axis=1)], 2])

    assert clearance(res) == pytest.approx(clearance(raw), abs=1e-12) and clearance(res) > 0
    # and it is local: what moves lies within the rings faired around the junctions' ends and 4
    # more, in edge lengths (h = 0.025), of a junction (measured: 0.42 with 16 rings, 0.60 with
    # 21), the rest of the model is bit-identical
    from sketchforge_assemble.blend import distance_to

    d = np.min([distance_to(raw.mesh.V[:, :2], m.V[m.junction, :2]) for m in meshes if len(m.junction)], axis=0)
    reach = (res.solver["fair_rings"] + 4) * 0.025
    assert moved.any() and d[moved].max() < reach and (d > reach).sum() > 500


def test_unsafe_fairing_falls_back_to_the_plain_sleeve(monkeypatch):
    # If the blended junction would cross itself, the model is still handed out, glued by the
    # plain sleeve (which never crosses itself), and the person is told why.
    import sketchforge_assemble.assemble as asm

    layers, meshes, closed = _example("creature")
    monkeypatch.setattr(asm, "fair_clear", lambda V, F, moved, *a, **k: (V, False, np.zeros(0, np.int64),
                                                                          np.zeros(len(V), bool)))
    res = assemble_detailed(meshes, closed)
    plain = assemble_detailed(meshes, closed, params={"fillet": 0.0})
    assert res.mesh.identical(plain.mesh)
    assert len(res.warnings) == 1 and "crossing itself" in res.warnings[0]


def test_fairing_safety_check_sees_a_crossing_and_a_flat_triangle():
    from sketchforge_assemble.fair import fairing_is_safe

    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, -0.5], [0.3, 0.2, 0.5], [0.2, 0.4, 0.5]], float)
    F = np.array([[0, 1, 2], [3, 4, 5]])
    moved = np.array([False, False, False, True, True, True])
    assert not fairing_is_safe(V, F, moved, 1.0)  # the second triangle pierces the first
    V[3:, 2] += 1.0
    assert fairing_is_safe(V, F, moved, 1.0)
    V[5] = V[3] + 0.5 * (V[4] - V[3])  # flat
    assert not fairing_is_safe(V, F, moved, 1.0)


@pytest.mark.parametrize("bad", [-1, 2.5, True, 51, "ten"])
def test_fair_parameter_is_checked(bad):
    from sketchforge.errors import ParameterError

    _, meshes, closed = _example("creature")
    with pytest.raises(ParameterError, match="'fair'"):
        assemble_detailed(meshes, closed, params={"fair": bad})


def test_fillet_starts_the_part_where_the_host_is():
    layers, meshes, closed = _example("creature")
    ids = [layer.id for layer in layers]
    res = assemble_detailed(meshes, closed)
    arm, body = ids.index("arm_front"), ids.index("body")
    V, F = res.mesh.V, res.mesh.F
    j = meshes[arm].V[meshes[arm].junction, :2]
    h = 0.03
    on_arm = np.unique(F[res.face_layer == arm])
    on_body = np.unique(F[(res.face_layer == body) & (res.face_kind == 0)])
    # arm vertices on its junction: within a few edge lengths above the body's front face
    # next to them (the fillet's height), never below it and never at the plane z = 0
    near = on_arm[np.min(np.linalg.norm(V[on_arm, None, :2] - j[None], axis=2), axis=1) < 1e-9]
    for v in near:
        d = np.linalg.norm(V[on_body, :2] - V[v, :2], axis=1)
        ring = on_body[(d > 0.3 * h) & (d < 1.5 * h)]
        assert np.min(V[ring, 2]) - 1.0 * h <= V[v, 2] <= np.max(V[ring, 2]) + 5.0 * h


def test_a_model_inside_the_fairing_rings_keeps_its_fillet(monkeypatch):
    # A small, coarse model: 50 rings cover all of it, so nothing would hold the fairing in
    # place (a singular system); it keeps the fillet's shape instead, closed and clean. (At 50
    # rings the body counts as thin, fair.far_weights, and its far face would hold the
    # fairing: that is checked at the end; here every host counts as thick.)
    import sketchforge_assemble.fair as fair
    from sketchforge_inflate import inflate_stroke

    t = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    a = np.radians(np.linspace(100, 400, 40))
    params = {"resolution": 0.08, "inflation": 1.0, "smoothing": 0.5}
    body = inflate_stroke(np.c_[0.6 * np.cos(t), 0.4 * np.sin(t)], closed=True, params=params)
    arm = inflate_stroke(np.c_[0.35 + 0.25 * np.cos(a), -0.2 + 0.25 * np.sin(a)], closed=False, params=params)
    fillet_only = assemble_detailed([body, arm], params={"fair": 0})
    with monkeypatch.context() as m:
        m.setattr(fair, "THIN_HOST", (0.0, 1e-9))
        whole = assemble_detailed([body, arm], params={"fair": 50})
    assert not whole.warnings and whole.mesh.identical(fillet_only.mesh)
    _check_closed(whole)
    faired = assemble_detailed([body, arm])  # 12 rings leave the body's far side to hold it
    assert not np.array_equal(faired.mesh.V, fillet_only.mesh.V)
    _check_closed(faired)
    held = assemble_detailed([body, arm], params={"fair": 50})  # the far face, not counted, holds it
    assert not held.warnings and not np.array_equal(held.mesh.V, fillet_only.mesh.V)
    _check_closed(held)


def test_narrow_fairing_keeps_the_parts_and_widens_only_where_a_fold_is_left(monkeypatch):
    # The default fairs 12 rings around each junction's ends and 7 along the rest of it, held
    # softly; the first blended default faired 14 rings around the whole seam, which refitted
    # heads and tails (a web between head and body, a leg thinned to a neck). A fold the narrow
    # zone leaves widens the zone of the junctions near it only (issue 34: widening every
    # junction for one fold pinched thin limbs elsewhere into necks).
    import sketchforge_assemble.assemble as asm
    import sketchforge_assemble.fair as fair
    from sketchforge_assemble.fair import hold_weights

    layers, meshes, closed = _example("creature")
    ids = [layer.id for layer in layers]
    raw = assemble_detailed(meshes, closed, params={"fair": 0})
    narrow = assemble_detailed(meshes, closed)
    assert narrow.solver["fair_zone"] == "narrow"
    # a fold left near the tail's junction (planted: the narrow zone leaves none here)
    tail = ids.index("tail")
    tail_v = np.unique(narrow.mesh.F[narrow.face_layer == tail])
    jx = meshes[tail].V[meshes[tail].junction[len(meshes[tail].junction) // 2], :2]
    seed = tail_v[np.argmin(np.linalg.norm(narrow.mesh.V[tail_v, :2] - jx, axis=1))]
    real = fair.fair_clear
    calls = []

    def planted(V, F, moved, A, h, hold=None, bend_limit=180.0, edges=None, ignore=None, scale=None):
        out = real(V, F, moved, A, h, hold, bend_limit, edges, ignore, scale)
        calls.append(bend_limit)
        return (out[0], out[1], np.array([seed]), out[3]) if len(calls) == 1 else out

    monkeypatch.setattr(asm, "fair_clear", planted)
    wide = assemble_detailed(meshes, closed)
    assert wide.solver["fair_zone"] == "narrow+wide" and not wide.warnings
    assert np.array_equal(wide.mesh.F, narrow.mesh.F)
    d_n = np.linalg.norm(narrow.mesh.V - raw.mesh.V, axis=1)
    d_w = np.linalg.norm(wide.mesh.V - raw.mesh.V, axis=1)
    assert np.sum(d_w > 0) > np.sum(d_n > 0)  # the tail's junction faired wider
    # ... and only there: the front legs and the head, far from the tail, are as the narrow zone left them
    h = 0.03
    for part in ("head", "leg_r", "arm_front"):
        v = np.unique(narrow.mesh.F[narrow.face_layer == ids.index(part)])
        far = v[np.linalg.norm(narrow.mesh.V[v, :2] - jx, axis=1) > 0.6]
        # (one solve over every moved vertex, whose zones touch through the body: the other
        # junctions move by a hundredth of an edge length at most, nothing a person sees)
        assert len(far) > 50 and np.abs(wide.mesh.V[far] - narrow.mesh.V[far]).max() < 0.01 * h, part
    p_n, m_n = np.percentile(d_n[d_n > 0], 95) / h, d_n.max() / h
    # measured on the creature: p95 3.5 edge lengths, max 14.3 (8.4 before issue 34's full-thickness
    # joins: the fairing now rounds the turn of a limb that arrives at its own thickness; 12.5
    # before the limb was held where it leaves its host: the head's seam over the body rises
    # 0.06 more, as the head beyond the body's outline keeps its thickness)
    assert p_n < 4.0 and m_n < 15.0, (p_n, m_n)
    # the widened fairing still meets the target
    top, over, flat = _folds(wide)
    assert top <= 90 and flat >= 0.999
    # the hold: none at the seam, growing outwards, and the zone's edge held at its full weight
    t = np.linspace(0.0, 1.0, 101)
    w = hold_weights(t)
    assert np.all(w[t <= 0.3] == 0.0) and np.all(np.diff(w) >= 0.0) and w[-1] > 0 and w[-1] == w.max()


def test_limb_hold_holds_a_limb_only_past_its_hosts_outline_and_away_from_the_seam():
    # fair.limb_hold (issue 34, point 5): zero over the host and at the seam, LIMB_HOLD well past
    # the outline, and rising without a jump in between (a decision continuous in the input)
    import shapely

    from sketchforge_assemble.fair import LIMB_HOLD, LIMB_RAMP, LIMB_SEAM_RINGS, limb_hold

    h = 0.05
    x = np.linspace(-0.5, 1.0, 301)
    V = np.c_[x, np.zeros_like(x), np.zeros_like(x)]
    F = np.c_[np.arange(len(x) - 2), np.arange(1, len(x) - 1), np.arange(2, len(x))]  # one layer's strip
    host = shapely.box(-1.0, -1.0, 0.0, 1.0)  # its outline at x = 0
    zone = np.ones(len(x), bool)
    far = np.full(len(x), LIMB_SEAM_RINGS + 1)
    w = limb_hold(V, F, np.zeros(len(F), np.int64), [(0, host, h)], zone, far)
    assert np.all(w[x <= 0] == 0) and np.allclose(w[x >= LIMB_RAMP * h], LIMB_HOLD)
    assert np.all(np.diff(w) >= 0) and np.max(np.diff(w)) < 0.1 * LIMB_HOLD  # smooth: 0.005 apart
    # at the seam nothing is held, wherever the seam lies; a layer that is not a limb, nothing
    assert np.all(limb_hold(V, F, np.zeros(len(F), np.int64), [(0, host, h)], zone, np.zeros(len(x), np.int64)) == 0)
    assert np.all(limb_hold(V, F, np.ones(len(F), np.int64), [(0, host, h)], zone, far) == 0)
    assert np.all(limb_hold(V, F, np.zeros(len(F), np.int64), [(0, host, h)], ~zone, far) == 0)


def test_a_shifted_limb_hold_starts_inside_the_outline_and_stays_continuous():
    # The neck try (issue 34, point 5: seed 16's tail) starts a thinned limb's hold NECK_SHIFT
    # edge lengths inside its host's outline: zero deeper than that, full LIMB_RAMP - NECK_SHIFT
    # edge lengths past the outline, monotone and without a step; no shift is the plain hold
    import shapely

    from sketchforge_assemble.fair import LIMB_HOLD, LIMB_RAMP, LIMB_SEAM_RINGS, NECK_SHIFT, limb_hold

    h = 0.05
    x = np.linspace(-0.5, 1.0, 301)
    V = np.c_[x, np.zeros_like(x), np.zeros_like(x)]
    F = np.c_[np.arange(len(x) - 2), np.arange(1, len(x) - 1), np.arange(2, len(x))]
    host = shapely.box(-1.0, -1.0, 0.0, 1.0)
    zone, far, layer = np.ones(len(x), bool), np.full(len(x), LIMB_SEAM_RINGS + 1), np.zeros(len(F), np.int64)
    plain = limb_hold(V, F, layer, [(0, host, h)], zone, far)
    np.testing.assert_array_equal(limb_hold(V, F, layer, [(0, host, h, 0.0)], zone, far), plain)
    w = limb_hold(V, F, layer, [(0, host, h, NECK_SHIFT)], zone, far)
    assert np.all(w[x <= -NECK_SHIFT * h] == 0) and np.all(w[(x < 0) & (x > -NECK_SHIFT * h + 1e-9)] > 0)
    assert np.allclose(w[x >= (LIMB_RAMP - NECK_SHIFT) * h + 1e-9], LIMB_HOLD)
    assert np.all(w >= plain) and np.all(np.diff(w) >= 0) and np.max(np.diff(w)) < 0.1 * LIMB_HOLD


def test_rim_pairs_share_where_the_rim_is_as_stitched_and_let_go_where_faired():
    # stitch.rim_share (issue 34): 1 for a rim pair as stitched, or moved whole (a free part
    # reseated); 0 once the fairing changed the vector across it by RIM_KEPT[1] edge lengths;
    # monotone and without a step in between (a decision continuous in the input)
    from sketchforge_assemble.stitch import RIM_KEPT, rim_share

    V0 = np.array([[0.0, 0.0, 0.1], [0.0, 0.0, -0.1]])
    pairs, h = np.array([[0, 1]]), np.array([0.05])
    assert rim_share(V0, V0, pairs, h)[0] == 1.0
    assert rim_share(V0, V0 + [0.3, -0.2, 0.5], pairs, h)[0] == 1.0  # moved whole
    w = []
    for d in np.linspace(0.0, 2.0 * RIM_KEPT[1], 81):
        V = V0.copy()
        V[0, 2] += d * h[0]
        w.append(rim_share(V0, V, pairs, h)[0])
    w = np.array(w)
    assert w[0] == 1.0 and w[-1] == 0.0 and np.all(np.diff(w) <= 0) and np.max(-np.diff(w)) < 0.1


def test_outline_distance_measures_past_the_outline_as_shapely_does_within_its_bound():
    # fair.outline_distance (the neck measure's, 6x faster than shapely.distance): never less
    # than the true distance, and at most spacing²/(8d) (spacing/2 at the outline) more, on
    # random star-shaped outlines with and without a hole
    import shapely

    from sketchforge_assemble.fair import outline_distance

    rng = np.random.default_rng(34)
    for trial in range(30):
        n = int(rng.integers(3, 200))
        t = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
        r = rng.uniform(0.5, 1.5, n)
        region = shapely.Polygon(np.c_[r * np.cos(t), r * np.sin(t)]).buffer(0)
        if trial % 3 == 0:
            region = region.difference(shapely.Point(0.0, 0.0).buffer(0.2))
        pts = rng.uniform(-2.0, 2.0, (400, 2))
        pts = pts[~shapely.contains_xy(region, pts[:, 0], pts[:, 1])]
        spacing = float(rng.uniform(0.005, 0.05))
        exact = shapely.distance(region, shapely.points(pts))
        d = outline_distance(region, pts, spacing)
        assert np.all(d >= exact - 1e-12)
        assert np.all(d - exact <= np.minimum(spacing / 2, spacing**2 / (8 * np.maximum(exact, 1e-12))) + 1e-12)


def test_reseat_moves_a_free_part_with_the_faces_it_rests_on_and_refuses_a_crossing():
    # fair.reseat: a free part resting on a faired face moves up by the most its support rose
    # (down by the least its support above sank); a move that would cross anything is refused
    from sketchforge_assemble.fair import reseat

    # layer 0: a flat square at z = 0 (two triangles); layer 1: a small triangle at z = 0.1 above it
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.4, 0.4, 0.1], [0.6, 0.4, 0.1], [0.5, 0.6, 0.1]], float)
    F = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6]])
    layer = np.array([0, 0, 1])
    below = np.array([1, 1, 1, 1, 0, 0, 0], bool)
    none = np.zeros(7, bool)
    V2 = V.copy()
    V2[:4, 2] += [0.02, 0.05, 0.03, 0.01]  # the support rose, by 0.05 at most
    out = reseat(V, V2, F, layer, [(1, below, none)])
    assert np.allclose(out[4:, 2], 0.15) and np.array_equal(out[:4], V2[:4])
    # faces above the part that rose by less (0.01) than those below it (0.05): pinched, refused
    assert reseat(V, V2, F, layer, [(1, below, below)]) is None
    # a part whose move would cross another face: refused
    V4 = V.copy()
    V4[:4, 2] += [0.0, 1.0, 0.0, 0.0]  # one corner (not under the part) lifted through its plane
    assert reseat(V, V4, F, layer, [(1, np.array([1, 0, 1, 1, 0, 0, 0], bool), none)]) is None
    # nothing to rest on: unchanged
    assert np.array_equal(reseat(V, V2, F, layer, [(1, none, none)]), V2)


def test_vertex_scale_marks_only_parts_meshed_finer_and_is_continuous():
    from sketchforge_assemble.fair import FINE_SHARE, vertex_scale

    # two triangles sharing the edge (1, 2): layer edge lengths per triangle
    F = np.array([[0, 1, 2], [1, 3, 2]], np.int64)
    assert vertex_scale(F, 4, np.array([1.0, 1.0])) is None  # parts meshed alike: fair as ever
    assert vertex_scale(F, 4, np.array([1.0, 0.9])) is None  # within FINE_SHARE: alike
    s = vertex_scale(F, 4, np.array([1.0, 0.4]))
    # the shared vertices count with the finer part, the coarse part's own vertex whole
    assert np.allclose(s, [1.0, 0.4 / FINE_SHARE, 0.4 / FINE_SHARE, 0.4 / FINE_SHARE])
    # continuous in the finer part's edge length through the threshold (no jump at FINE_SHARE)
    hs = np.linspace(0.5, 0.95, 451)
    ss = np.array([(vertex_scale(F, 4, np.array([1.0, x])) if x < FINE_SHARE else np.ones(4))[3] for x in hs])
    assert np.abs(np.diff(ss)).max() < 0.01


def test_fairing_at_one_scale_is_the_plain_fairing():
    # Inside a part of one edge length the scaled fairing must be the plain one (a part meshed
    # finer is faired the same as before; only the weights across a change of scale differ).
    from sketchforge_assemble.fair import adjacency, fair_seams

    layers, meshes, closed = meshes_from_journal(EXAMPLES / "drawn.json")
    res = assemble_detailed(meshes, closed)
    V, F = res.mesh.V, res.mesh.F
    A = adjacency(F, len(V))
    body = res.face_layer == int(np.argmax(np.bincount(res.face_layer)))  # the largest part
    moved = np.zeros(len(V), bool)
    moved[F[body].ravel()] = True
    moved[F[~body].ravel()] = False  # its own vertices only, away from its seams
    hold = np.full(len(V), 0.02)
    plain = fair_seams(V, F, moved, A, hold=hold)
    scaled = fair_seams(V, F, moved, A, hold=hold, scale=np.full(len(V), 0.37))
    assert not np.array_equal(plain, V)
    assert np.abs(scaled - plain).max() <= 1e-9 * np.abs(V).max()


def _slab(n=9, t=0.5):
    """A closed square slab of n x n vertices per face (unit spacing), front at z = t (face_kind
    0), back at -t (1), its rim bridged (2), all layer 0; and a tent of layer 1 glued on the
    front by the two middle vertices of its first row. Returns V, F, face_layer, face_kind,
    the two glued vertices."""
    idx = np.arange(n * n).reshape(n, n)
    xy = np.c_[np.tile(np.arange(n), n), np.repeat(np.arange(n), n)].astype(float)
    quads = np.c_[idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()]
    tri = np.r_[quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]
    V = np.r_[np.c_[xy, np.full(n * n, t)], np.c_[xy, np.full(n * n, -t)]]
    ring = np.r_[idx[0, :-1], idx[:-1, -1], idx[-1, :0:-1], idx[:0:-1, 0]]
    a, b = ring, np.roll(ring, -1)
    rim = np.r_[np.c_[b, a, a + n * n], np.c_[b, a + n * n, b + n * n]]
    g = idx[n // 2, n // 2], idx[n // 2, n // 2 + 1]
    apex = len(V)
    V = np.r_[V, [[n // 2 + 0.5, n // 2 - 0.5, t + 1.0]]]
    tent = np.array([[g[0], g[1], apex]])
    F = np.r_[tri, tri[:, ::-1] + n * n, rim, tent]
    layer = np.r_[np.zeros(len(F) - 1, np.int64), [1]]
    kind = np.r_[np.zeros(len(tri), np.int8), np.ones(len(tri), np.int8), np.full(len(rim), 2, np.int8), [0]]
    return V, F, layer, kind, np.array(g, np.int64)


def test_rings_around_a_thin_hosts_junction_stay_on_its_glued_face():
    from types import SimpleNamespace

    from sketchforge_assemble.fair import FAR_BLOCK, adjacency, glued_face_distance, rings_from

    V, F, layer, kind, glued = _slab()
    A = adjacency(F, len(V))
    att = [SimpleNamespace(upper=1, lower=0, side=1)]  # glued on the front (FRONT = 1)
    plain = glued_face_distance(A, F, layer, kind, att, {})(glued, 20)
    assert np.array_equal(plain, rings_from(A, glued, 20))
    kept = glued_face_distance(A, F, layer, kind, att, {(0, 1): FAR_BLOCK})(glued, 20)
    back = np.arange(81, 162)
    front = np.arange(81)
    # the front counts as before; the back, one rim edge away from the front's rim in the plain
    # count (4 + 1 rings from the middle), is out of reach
    assert np.array_equal(kept[front], plain[front])
    assert plain[back].min() <= 6 and kept[back].min() == 21


def test_far_weights_count_only_thin_hosts_and_are_continuous_in_their_thickness():
    from types import SimpleNamespace

    from sketchforge_assemble.fair import FAR_BLOCK, THIN_HOST, far_weights

    n = 21
    xy = np.c_[np.tile(np.arange(n), n), np.repeat(np.arange(n), n)].astype(float) * 0.1
    part = SimpleNamespace(xy=np.array([[1.0, 1.0], [1.2, 1.0]]), junction=np.array([0, 1]), h=0.1, n=2)
    att = [SimpleNamespace(upper=1, lower=0, side=1)]
    rings = 12

    def weight(thick_in_rings):
        # a host whose drawn thickness (twice its height) is thick_in_rings x rings x h
        host = SimpleNamespace(xy=xy, z=np.full(n * n, 0.5 * thick_in_rings * rings * 0.1), h=0.1, n=n * n)
        return far_weights([host, part], att, rings).get((0, 1), 1.0)

    assert weight(THIN_HOST[1] + 0.01) == 1.0 and weight(3.0) == 1.0
    assert weight(THIN_HOST[0] - 0.01) == FAR_BLOCK and weight(0.5) == FAR_BLOCK
    ts = np.linspace(THIN_HOST[0], THIN_HOST[1], 201)
    w = np.array([weight(t) for t in ts])
    assert np.all(np.diff(w) <= 0) and np.max(np.abs(np.diff(w))) < 0.02 * FAR_BLOCK


def _roof(slope: float, n: int = 9):
    """A grid over [-1, 1]² folded along x = 0 (z = slope·|x|), its columns on the fold:
    V (n², 3), F, and the (n²,) bool of the vertices on the fold. Its bend there is
    2·atan(slope) degrees, 0 everywhere else."""
    from sketchforge.geometry.mesh_edges import interior_edges

    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    V = np.c_[x.ravel(), y.ravel(), slope * np.abs(x.ravel())]
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]].astype(np.int64)
    return V, F, np.isclose(V[:, 0], 0.0), interior_edges(F)


def test_the_limb_hold_lets_go_at_a_crease_continuously_in_its_bend():
    """fair.crease_release (issue 34, point 5): the hold that keeps a limb's thickness past its
    host is let go where the stitched surface is creased, so the fairing can smooth the crease
    (seed 40's tail kept 9 edges over 45 degrees under the hold). 1 on smooth surface, 0 at a
    bend of 60 degrees or more, and no jump as the bend grows (a decision continuous in the
    drawing)."""
    from sketchforge_assemble.fair import CREASE_RELEASE, crease_release

    got = []
    for deg in np.arange(0.0, 91.0, 0.5):
        V, F, fold, edges = _roof(np.tan(np.radians(deg / 2)))
        r = crease_release(V, F, edges)
        assert np.all(r[~fold] == 1.0)  # flat away from the fold: held as before
        assert np.ptp(r[fold]) < 1e-12
        got.append(r[fold][0])
        at = fold & (V[:, 1] > 0)  # only some vertices asked for: the same there, 1 elsewhere
        assert np.array_equal(crease_release(V, F, edges, at=at)[at], r[at])
        assert np.all(crease_release(V, F, edges, at=at)[~at] == 1.0)
    got = np.array(got)
    lo, hi = CREASE_RELEASE
    bends = np.arange(0.0, 91.0, 0.5)
    assert np.all(got[bends <= lo - 0.5] == 1.0) and np.all(got[bends >= hi + 0.5] < 1e-9)
    assert np.all(np.diff(got) <= 1e-12) and np.max(np.abs(np.diff(got))) < 0.05
