"""Assembly closes the rim of every hole (issue 12, point 2): a free part with k holes is a
closed, oriented 2-manifold of genus k (Euler characteristic 2 - 2k), also when another part
is attached to it (its junction is cut into the holed sheet) and when a part shows through
the hole."""

import numpy as np
import pytest

from sketchforge_assemble import assemble_detailed
from sketchforge_assemble import diagnostics as dg
from sketchforge_inflate import inflate_stroke

PARAMS = {"resolution": 0.06, "inflation": 1.0, "smoothing": 0.5}


def ring(r, n=60, cx=0.0, cy=0.0):
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)])


def slab_with_holes(k):
    outline = np.array([[-0.6 * k - 0.7, -0.8], [0.6 * k + 0.7, -0.8], [0.6 * k + 0.7, 0.8], [-0.6 * k - 0.7, 0.8]])
    holes = [ring(0.35, 48, cx=1.2 * (i - (k - 1) / 2.0)) for i in range(k)]
    return inflate_stroke(outline, True, PARAMS, holes=holes)


def check_closed(res):
    V, F = res.mesh.V, res.mesh.F
    _, count = dg.edge_counts(F)
    assert np.all(count == 2), "every edge is shared by exactly two triangles"
    assert dg.is_consistently_oriented(F)
    assert dg.signed_volume(V, F) > 0
    assert len(dg.intersecting_pairs(V, F, res.face_layer)) == 0
    return dg.euler_characteristics(F)


@pytest.mark.parametrize("k", [0, 1, 2, 3])
def test_free_part_with_k_holes_has_euler_characteristic_2_minus_2k(k):
    mesh = slab_with_holes(k)
    assert len(mesh.holes) == k
    res = assemble_detailed([mesh], [True], names=["slab"])
    assert check_closed(res) == [2 - 2 * k]


def test_part_attached_to_a_holed_body_and_a_part_seen_through_the_hole():
    body = slab_with_holes(2)
    t = np.radians(np.linspace(-60.0, 60.0, 40))
    arm = np.column_stack([1.2 + 0.9 * np.cos(t), 0.45 * np.sin(t)])  # junction x = 1.65 inside the body
    arm = inflate_stroke(arm, False, PARAMS)
    assert arm.junction.size
    behind = inflate_stroke(ring(0.5, 60, cx=-0.6), True, PARAMS)  # seen through the left hole
    res = assemble_detailed([behind, body, arm], [True, True, False], names=["behind", "body", "arm"])
    assert [(a.upper, a.lower) for a in res.attachments] == [(2, 1)]
    euler = sorted(check_closed(res))
    assert euler == [-2, 2], euler  # body + arm: genus 2; the free part behind: a sphere


def test_holes_example_a_b_with_two_legs_one_mirrored_from_the_other(real_host):
    """examples/holes.json: a B (two holes), a left leg, a copy of it duplicated in place and
    mirrored about the host's axis (past the sibling it was copied from): a right leg; the
    assembly is one closed genus-2 surface."""
    from pathlib import Path

    from sketchforge.document import fileformat as ff

    doc = ff.load(Path(__file__).resolve().parents[1] / "examples" / "holes.json", host=real_host)
    body, left, right = (np.asarray(doc.layer(i).points) for i in ("b", "leg", "leg2"))
    cx = 0.5 * (body[:, 0].min() + body[:, 0].max())
    assert np.abs(right[:, 0] - (2 * cx - left[:, 0])).max() < 1e-12 and right[:, 0].mean() > 0.2
    res = assemble_detailed([l.mesh for l in doc.layers], [l.closed for l in doc.layers], names=doc.layer_ids())
    assert sorted((doc.layers[a.upper].id, doc.layers[a.lower].id) for a in res.attachments) == [("leg", "b"), ("leg2", "b")]
    assert check_closed(res) == [-2]


@pytest.mark.parametrize("gap", [0.03, 0.01])
def test_a_junction_passing_within_half_an_edge_of_a_hole_keeps_the_hole_s_rim(gap):
    # the re-triangulation drops interior vertices near a junction; the hole's rim vertices are
    # constrained edges and must stay, however close the junction passes (here half an edge
    # and a sixth of one, h = 0.06)
    body = slab_with_holes(1)
    t = np.radians(np.linspace(-90.0, 90.0, 40))
    arm = inflate_stroke(np.column_stack([0.35 + gap + 0.3 * np.cos(t), 0.25 * np.sin(t)]), False, PARAMS)
    res = assemble_detailed([body, arm], [True, False], names=["body", "arm"])
    assert [(a.upper, a.lower) for a in res.attachments] == [(1, 0)]
    assert check_closed(res) == [0]  # body with its hole, arm glued on: one genus-1 surface
    # the plain sleeve (no fairing, which moves the vertices near the junction) keeps every
    # rim vertex of the hole where it was drawn
    plain = assemble_detailed([body, arm], [True, False], params={"fillet": 0.0}, names=["body", "arm"])
    assert check_closed(plain) == [0]
    hole = body.V[np.asarray(body.holes[0]), :2]
    V = plain.mesh.V
    for p in hole:
        assert np.min(np.linalg.norm(V[:, :2] - p, axis=1)) <= 1e-9


def test_a_part_inside_a_hole_does_not_overlap_the_holed_layer():
    # a disk drawn in front, wholly inside the hole: it overlaps nothing (the hole is not part of
    # the layer's region), so it gets no depth row and rests at the drawing plane
    body = slab_with_holes(1)
    disk = inflate_stroke(ring(0.2, 40), True, PARAMS)
    res = assemble_detailed([body, disk], [True, True], names=["body", "disk"])
    assert res.solver["overlapping_pairs"] == 0 and res.n_inequalities == 0
    assert res.solver["free_shift"] == {}
    assert sorted(check_closed(res)) == [0, 2]
    # a larger disk reaching over the rim does overlap it
    big = inflate_stroke(ring(0.5, 40), True, PARAMS)
    res = assemble_detailed([body, big], [True, True], names=["body", "disk"])
    assert res.solver["overlapping_pairs"] == 1 and res.n_inequalities > 0
