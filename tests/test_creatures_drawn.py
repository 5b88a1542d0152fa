"""Creatures drawn as people draw them (issue 34, point 7): a small seeded subset of the
Monster-Mash-style corpus (``sketchforge_assemble.drawn``; the full set runs in
``benchmarks/bench_creatures.py``), assembled and checked by ``tests/mesh_checks.py``, which
shares no code with the assembler."""

from __future__ import annotations

import mesh_checks as mc
import numpy as np
import pytest

from sketchforge.geometry import guard
from sketchforge_assemble import BACK, FRONT, assemble_detailed
from sketchforge_assemble.drawn import KINDS, drawn_creature
from sketchforge_assemble.testing import meshes_from_journal


def _assembled(seed):
    layers, meshes, closed = meshes_from_journal(drawn_creature(seed))
    names = [l.name for l in layers]
    return layers, meshes, closed, names, assemble_detailed(meshes, closed, names=names)


def _joins_fold_free(seed, min_ratio):
    """Issue 34's joins on the creature of ``seed``, by mesh_checks alone: no junction edge (within
    8 edge lengths of a seam) over 90 degrees, 99.9% at most 45, a closed mesh with nothing
    crossing, every limb at least ``min_ratio`` of its mid-limb depth just outside its host, or
    at least 0.9 of its own inflated layer's ratio where it is drawn narrower there. Returns the
    assembly result."""
    layers, meshes, closed, names, res = _assembled(seed)
    V, F = res.mesh.V, res.mesh.F
    ang = mc.junction_angles(V, F, res.face_layer, 8 * mc.layers_edge_length(meshes))
    assert ang.max() <= 90.0 and np.mean(ang <= 45) >= 0.999, (ang.max(), np.mean(ang <= 45))
    assert mc.self_intersections(V, F) == 0 and mc.boundary_edges(F) == 0
    thin = {names[k]: (r, own) for k, (r, own) in _limb_ratios(meshes, res).items() if r < min(min_ratio, 0.9 * own)}
    assert not thin, thin
    return res


def test_the_generator_draws_every_kind_deterministically_as_the_app_places_strokes():
    docs = [drawn_creature(s) for s in range(3)]
    assert docs[0] == drawn_creature(0) and docs[0] != drawn_creature(3)
    kinds = {KINDS[s % 3] for s in range(3)}
    assert kinds == set(KINDS)
    for doc in docs:
        adds = [e for e in doc["journal"] if e["command"] == "add_layer"]
        contours = [e for e in doc["journal"] if e["command"] == "set_contour"]
        assert 9 <= len(adds) <= 13
        assert any("index" in e for e in adds)  # some parts drawn behind (right button)
        assert sum(not e["closed"] for e in contours) >= 6  # heads, limbs, tails: open strokes


@pytest.mark.parametrize("seed", [0, 1, 2, 5])
def test_drawn_creatures_assemble_whole_closed_and_without_crossings(seed):
    layers, meshes, closed, names, res = _assembled(seed)
    V, F = res.mesh.V, res.mesh.F
    # every open part is glued (none of this subset has a junction that cannot be)
    parts = [i for i, l in enumerate(layers) if not l.closed and len(l.mesh.junction)]
    assert sorted(a.upper for a in res.attachments) == parts and res.free == [] and res.left_out == []
    # one closed surface per group: checked apart from the assembler
    assert mc.boundary_edges(F) == 0
    assert mc.components(F, len(V)) == len(layers) - len(res.attachments)
    assert mc.self_intersections(V, F) == 0
    # the depth order of the drawing: a part drawn behind its host hangs on its back face
    for a in res.attachments:
        assert a.side == (FRONT if a.lower < a.upper else BACK)


def test_near_and_far_legs_hang_on_the_two_faces_of_the_body_where_their_junctions_overlap():
    # a quadruped: each far leg (right button) overlaps its near leg, their junctions overlap or
    # cross on the body; they are glued to its back and front faces and never conflict
    layers, meshes, closed, names, res = _assembled(0)
    side = {names[a.upper]: (names[a.lower], a.side) for a in res.attachments}
    for leg in ("front", "hind"):
        assert side[f"{leg} near"] == ("body", FRONT) and side[f"{leg} far"] == ("body", BACK)
        near, far = (guard.polygon(meshes[names.index(f"{leg} {k}")].V[meshes[names.index(f"{leg} {k}")].boundary, :2], "leg")
                     for k in ("near", "far"))
        assert near.intersection(far).area > 0.2 * min(near.area, far.area)  # they do overlap in the drawing
    # the twin ears' bases touch on the head: the later one keeps clear of the other, and says so
    assert side["ear 0"][0] == side["ear 1"][0] == "head"
    assert any("ear 1" in n and "ear 0" in n for n in res.notes)


def _limb_ratios(meshes, res):
    """{part: (ratio in the assembled mesh, ratio of the part's own layer)}: the thickness
    just outside the host's outline over the thickness at mid-limb (mesh_checks), for the
    limbs that reach far enough past their host."""
    V, F = res.mesh.V, res.mesh.F
    out = {}
    for a in res.attachments:
        m = meshes[a.upper]
        h = mc.edge_length(m.V, m.F)
        part = guard.polygon(m.V[m.boundary, :2], "p")
        host = guard.polygon(meshes[a.lower].V[meshes[a.lower].boundary, :2], "h")
        r = mc.limb_depth_ratio(V, F, res.face_layer, res.face_kind, a.upper, part, host, h)
        if np.isfinite(r):
            own = mc.own_layer_depth_ratio(m.V, m.F, part, host, h)
            out[a.upper] = (r, own)
    return out


@pytest.mark.parametrize("seed", [0, 2])
def test_limbs_leave_their_hosts_without_a_thin_neck(seed):
    # issue 34, point 5, measured as the issue says: the thickness of a limb just outside its
    # host's outline against its thickness at mid-limb (the full corpus in the benchmark)
    layers, meshes, closed, names, res = _assembled(seed)
    ratios = [r for r, _ in _limb_ratios(meshes, res).values()]
    assert len(ratios) >= 4 and np.median(ratios) >= 0.9 and min(ratios) >= 0.8, ratios


def test_a_tail_leaving_the_body_near_its_outline_keeps_its_own_thickness():
    # seed 16: the tail's junction lies close to the body's outline, so the junction's fairing
    # reached past the outline and pinched the tail into a neck (0.62 of its own thickness just
    # outside the body; ratio 0.49). Held there (fair.limb_hold), it kept 0.76, under the
    # issue's 0.8 although drawn at 0.80 (its own layer's ratio): the hold still rose over the
    # first edge lengths past the outline, where the fairing thinned it. Faired once more with
    # the hold starting inside the outline (the neck try), it keeps what it was drawn with.
    layers, meshes, closed, names, res = _assembled(16)
    r, own = _limb_ratios(meshes, res)[names.index("tail")]
    assert own < 0.85 and r >= 0.8, (r, own)
    ang = mc.junction_angles(res.mesh.V, res.mesh.F, res.face_layer, 8 * mc.layers_edge_length(meshes))
    assert ang.max() <= 90.0 and np.mean(ang <= 45) >= 0.999


def test_the_independent_checks_see_a_crossing_an_open_edge_and_a_fold():
    # the checks themselves, on hand-made triangles
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, -1], [0.3, 0.2, 1], [0.2, 0.3, 1]], float)
    F = np.array([[0, 1, 2], [3, 4, 5]])
    assert mc.self_intersections(V, F) == 1 and mc.boundary_edges(F) == 6
    V[3:, 2] += 2.0
    assert mc.self_intersections(V, F) == 0
    # a fold: two triangles on one edge, folded back onto each other
    V2 = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 1, 0.01]], float)
    key, ang = mc.dihedral(V2, np.array([[0, 1, 2], [1, 0, 3]]))
    assert len(ang) == 1 and ang[0] > 170
    layer = np.array([0, 1])
    assert mc.seam_zone(V2, np.array([[0, 1, 2], [1, 0, 3]]), layer, 0.1).tolist() == [True, True, False, False]


@pytest.mark.parametrize("seed", [23, 41, 15])
def test_a_fold_the_wide_fairing_leaves_is_relieved(seed):
    # Seeds 23 and 41 kept one junction edge over 90 degrees (98 and 104) after the wide zone and
    # its unheld rings around the fold; the fold freed in wider rings (with the limbs still
    # held) leaves none, and the limbs keep their thickness. Seed 15's fold (106 degrees) lay in
    # rings kept back from a crossing, where the fairing did not look for folds: now it does.
    _joins_fold_free(seed, min_ratio=0.85)


@pytest.mark.parametrize("seed", [27, 30])
def test_an_eye_beside_a_snouts_junction_moves_with_the_faired_head(seed):
    # Seeds 27 and 30: the faces under the eye were held out of the fairing, and the snout's
    # junction ends beside it: a 163 / 133 degree fold. Faired like the rest (the eye left out of
    # the fairing's crossing check, since it moves afterwards), with the eye moved up as far as
    # its support rose (fair.reseat), and rings that would cross faired part of the way
    # (fair._part_way): no fold left, the eye neither sinks in nor floats off.
    layers, meshes, closed, names, res = _assembled(seed)
    V, F = res.mesh.V, res.mesh.F
    h = mc.layers_edge_length(meshes)
    assert mc.junction_angles(V, F, res.face_layer, 8 * h).max() <= 90.0
    assert mc.self_intersections(V, F) == 0 and mc.boundary_edges(F) == 0
    eyes = [k for k, layer in enumerate(layers) if layer.name in ("eye", "eye far")]
    assert len(eyes) == 2 and all(layers[k].closed for k in eyes)
    for k in eyes:
        eye = np.unique(F[res.face_layer == k])
        others = np.unique(F[res.face_layer != k])
        # the nearest surface below the eye's lowest vertex: within a few edge lengths
        low = eye[np.argmin(V[eye, 2])]
        d = np.linalg.norm(V[others] - V[low], axis=1).min()
        assert d < 3 * h, (layers[k].name, d / h)


@pytest.mark.parametrize("seed", [3, 44])
def test_a_group_left_creased_is_faired_again_with_wider_ends(seed):
    # Seed 3 kept a 112-degree fold where a thin snout's front, faired next to its junction's end,
    # would cross its own back (the rings there kept back); seed 44 had 99.89% of its junction
    # edges under 45 degrees. Faired again with 16 rings around the junctions' ends instead of 12,
    # and 21 where 16 still left too many (only the groups left creased): no fold, 99.9% under 45,
    # nothing crossing, limbs as thick.
    res = _joins_fold_free(seed, min_ratio=0.8)
    assert res.solver["fair_rings"] in (16, 21)


@pytest.mark.parametrize("seed", [19, 46])
def test_a_birds_eye_and_beak_come_out_round_and_unfolded(seed):
    # The eye and the beak are 2-3 edge lengths in size at the default resolution; inflated at
    # that resolution the eye was a faceted lump (its faces bent by 40 and 39 degrees against
    # each other) and the beak's tip folded the model by 125 and 106 degrees. The inflater
    # meshes such narrow parts finer: no edge of the whole model bends over 90 degrees, the
    # eye's by at most 25, the beak's tip by at most 80 (measured by mesh_checks alone).
    layers, meshes, closed, names, res = _assembled(seed)
    V, F = res.mesh.V, res.mesh.F
    key, bend = mc.dihedral(V, F)
    assert bend.max() <= 90.0, bend.max()
    eye, beak = names.index("eye"), names.index("beak")
    # the eye's own front and back: edges between vertices no other face (nor its rim) touches
    mine = (res.face_layer == eye) & (res.face_kind != 2)
    inner = np.zeros(len(V), bool)
    inner[F[mine]] = True
    inner[F[~mine]] = False
    on_eye = inner[key[:, 0]] & inner[key[:, 1]]
    assert on_eye.sum() > 200 and bend[on_eye].max() <= 25.0, bend[on_eye].max()
    h = mc.layers_edge_length(meshes)
    tip = mc.at_drawn_tips(V, F, res.face_layer, [mc.drawn_tips(m) if k == beak else np.zeros((0, 2))
                                                  for k, m in enumerate(meshes)], 3 * h)
    assert tip.any() and bend[tip].max() <= 80.0


@pytest.mark.parametrize("seed", [19, 34, 58])
def test_a_beak_meshed_finer_than_its_head_joins_it_without_a_crease(seed):
    # The beak is meshed at a third of the head's edge length. Faired with every edge weighted
    # alike, its first rings next to the junction creased (seeds 19, 58: 99.87% and 99.89% of
    # the junction edges under 45 degrees) and seed 34's beak folded by 109 degrees; with the
    # weights following the edges' lengths (fair.vertex_scale): no fold, 99.9% under 45,
    # nothing crossing, the limbs at full thickness (seed 34's near leg is drawn narrower where
    # it leaves the body: 0.74 in its own layer, 0.74 assembled).
    _joins_fold_free(seed, min_ratio=0.8)


def _host_kept_around(meshes, res, raw, host, part, reach):
    """The median thickness of layer ``host`` in the assembled mesh over its thickness unfaired
    (``raw``: the same assembly with ``fair`` 0), on a grid of points of the host within
    ``reach`` of its edge lengths of the part ``part``'s outline (off the part's footprint and
    the host's rim), by mesh_checks alone."""
    import shapely

    mh, mp = meshes[host], meshes[part]
    h = mc.edge_length(mh.V, mh.F)
    region_h = guard.polygon(mh.V[mh.boundary, :2], "h")
    region_p = guard.polygon(mp.V[mp.boundary, :2], "p")
    x0, y0, x1, y1 = region_h.bounds
    gx, gy = np.meshgrid(np.linspace(x0, x1, 80), np.linspace(y0, y1, 80))
    P = np.c_[gx.ravel(), gy.ravel()]
    near = region_h.buffer(-h).difference(region_p.buffer(2 * h)).intersection(region_p.buffer(reach * h))
    P = P[shapely.contains_xy(near, P[:, 0], P[:, 1])]
    a = mc.thickness(res.mesh.V, res.mesh.F, res.face_layer, res.face_kind, host, P)
    b = mc.thickness(raw.mesh.V, raw.mesh.F, raw.face_layer, raw.face_kind, host, P)
    ok = np.isfinite(a) & np.isfinite(b) & (b > 0)
    assert ok.sum() >= 100, ok.sum()
    return float(np.median(a[ok] / b[ok]))


@pytest.mark.parametrize(("seed", "wing", "kept"), [(1, "wing far", 0.6), (40, "wing near", 0.85)])
def test_a_tail_glued_near_a_wings_tip_leaves_the_wing_its_thickness(seed, wing, kept):
    # The tail is glued on a wing near its tip, where the wing is about as thick as the rings
    # the fairing spreads over around the junction's ends. Counted over the whole surface, those
    # rings wrapped over the wing's rim onto its other face and squashed it: around the tail the
    # wing kept a median 0.42 (seed 1) and 0.59 (seed 40) of its unfaired thickness, creased by
    # up to 85 degrees (99.68% and 99.77% of the junction edges under 45). Counted over the face
    # the tail is glued on (fair.far_weights): 0.70 and 0.96, no fold, nothing crossing. Seed 40
    # then kept 9 creased edges on the tail's base under the limb's hold (99.896% of the
    # junction edges under 45, one edge short); the hold let go at creases
    # (fair.crease_release): 99.91%, seed 1 99.908%.
    layers, meshes, closed, names, res = _assembled(seed)
    raw = assemble_detailed(meshes, closed, names=names, params={"fair": 0})
    assert _host_kept_around(meshes, res, raw, names.index(wing), names.index("tail"), 12) >= kept
    if seed == 1:
        _joins_fold_free(seed, min_ratio=0.8)
    V, F = res.mesh.V, res.mesh.F
    ang = mc.junction_angles(V, F, res.face_layer, 8 * mc.layers_edge_length(meshes))
    assert ang.max() <= 90.0 and np.mean(ang <= 45) >= 0.999, (ang.max(), np.mean(ang <= 45))
    assert mc.self_intersections(V, F) == 0 and mc.boundary_edges(F) == 0
    thin = {names[k]: (r, own) for k, (r, own) in _limb_ratios(meshes, res).items() if r < min(0.8, 0.9 * own)}
    assert not thin, thin


def _rim_steps(mesh, rims, size=400):
    """Seen from the side (the drawing turned by 90° about its vertical), the angles in degrees
    between the normals of neighbouring pixels on one continuous surface (heights within 3
    pixels) next to where the rim pairs ``rims`` (r, 2) of ``mesh`` (an AssembledMesh) project:
    what shades as a line along a part's outline seen edge-on."""
    import dataclasses

    from scipy.ndimage import binary_erosion

    from sketchforge.geometry.gbuffer import View, front_surface

    t = np.radians(90.0)
    R = np.array([[np.cos(t), 0.0, np.sin(t)], [0.0, 1.0, 0.0], [-np.sin(t), 0.0, np.cos(t)]])
    V = (mesh.V - mesh.V.mean(axis=0)) @ R.T
    side = dataclasses.replace(mesh, V=V)
    s = front_surface([side], View.framing([side], size, size, 0.05))
    H, W = s.mask.shape
    pix = np.floor(s.view.to_pixels(0.5 * (V[rims[:, 0]] + V[rims[:, 1]]))).astype(int)
    near = np.zeros((H, W), bool)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            near[np.clip(pix[:, 1] + dy, 0, H - 1), np.clip(pix[:, 0] + dx, 0, W - 1)] = True
    inside = binary_erosion(s.mask, iterations=2)
    N = s.normal.astype(np.float64)
    steps = []
    for axis in (0, 1):
        other = np.roll(N, -1, axis=axis)
        same = np.abs(s.height - np.roll(s.height, -1, axis=axis)) < 3.0 / s.view.scale
        ok = inside & np.roll(inside, -1, axis=axis) & same & near
        steps.append(np.degrees(np.arccos(np.clip(np.einsum("ijk,ijk->ij", N, other), -1.0, 1.0)))[ok])
    return np.concatenate(steps)


def _rim_corners(V, F, pairs):
    """(r,) float64: for each rim pair (front, back vertex), the sharpest corner of the part's
    profile across its rim, in degrees: the profile runs from the mean of the front vertex's
    neighbours off the rim, through the two rim vertices, to the back's; its turns at the two
    rim vertices count as one corner where they lie under 0.3 of the first step apart."""
    rim = np.zeros(len(V), bool)
    rim[pairs.ravel()] = True
    E = np.unique(np.sort(np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    E = np.vstack([E, E[:, ::-1]])
    E = E[~rim[E[:, 1]]]
    total = np.zeros((len(V), 3))
    np.add.at(total, E[:, 0], V[E[:, 1]])
    count = np.bincount(E[:, 0], minlength=len(V))

    def turn(a, c, e):
        u, v = c - a, e - c
        return np.degrees(np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1.0, 1.0)))

    out = []
    for f, b in pairs:
        if not count[f] or not count[b]:
            continue
        q1, q4 = total[f] / count[f], total[b] / count[b]
        mid = 0.5 * (V[f] + V[b])
        o = mid[:2] - 0.5 * (q1[:2] + q4[:2])
        o /= np.linalg.norm(o)
        P = [np.array([(p[:2] - mid[:2]) @ o, p[2]]) for p in (q1, V[f], V[b], q4)]
        t2, t3 = turn(*P[:3]), turn(*P[1:])
        out.append(t2 + t3 if np.linalg.norm(P[2] - P[1]) < 0.3 * np.linalg.norm(P[1] - P[0]) else max(t2, t3))
    return np.array(out)


def test_a_parts_outline_seen_edge_on_is_round_and_shades_without_a_line(monkeypatch):
    """Issue 34, point 5: seen from the side, the README's bird showed a line through its body
    and along its legs (the front's and the back's rim normals, tilted by ±15° towards their
    own side, met within a pixel), and its outline a point there (the inflated profile's whole
    turn near the rim fell on one vertex: a corner of 26-33° on every limb). Now the rim is
    lifted (sheet.rim_lift) and the display shares the rim pairs' normals."""
    import sketchforge_assemble.sheet as sheet
    from sketchforge.geometry.mesh import AssembledMesh
    from sketchforge_assemble.plugin import assemble_layers

    layers, meshes, closed = meshes_from_journal(drawn_creature(1))
    model = assemble_layers(layers, {})
    assert len(model.rim_pairs) > 500 and np.mean(model.rim_weights == 1.0) > 0.3
    kept = model.rim_pairs[model.rim_weights == 1.0]  # the rims the fairing left as stitched
    monkeypatch.setattr(sheet, "RIM_LIFT", 0.0)  # the rim as it was: the margin only, unshared
    before = assemble_detailed(meshes, closed, names=[l.name for l in layers])
    old = AssembledMesh(before.mesh.V, before.mesh.F)
    old_kept = before.rim_pairs[np.isin(before.rim_pairs[:, 0], kept[:, 0])]
    shared, apart = _rim_steps(model, kept), _rim_steps(old, old_kept)
    assert len(shared) > 1000 and len(apart) > 1000
    assert np.percentile(apart, 90) > 15.0 and np.mean(apart > 10.0) > 0.1  # the line, measured
    assert np.percentile(shared, 90) < 8.0 and np.mean(shared > 10.0) < 0.03, (
        np.percentile(shared, 90), np.mean(shared > 10.0))
    # the outline's corner across the rim: 26-33° on the limbs before, a third less now
    now, then = _rim_corners(model.V, model.F, kept), _rim_corners(old.V, old.F, old_kept)
    assert np.median(then) > 20.0 and np.median(now) < 0.75 * np.median(then), (np.median(now), np.median(then))
