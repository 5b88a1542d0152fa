"""Holes: inner rings cut out of a part (issue 12, point 2).

Inflation keeps height 0 on every ring and matches the exact annulus solution; invalid holes
are refused with a message naming them before Triangle sees anything; the old trick of
concatenating an outer and an inner ring into one stroke is refused; set_contour's ``holes``
journal, save, reopen and replay bit for bit.
"""

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.document.commands import SetContour
from sketchforge.errors import ContourError
from sketchforge.geometry.contour import prepare_outline
from sketchforge_inflate import inflate_stroke


def ring(r, n=160, cx=0.0, cy=0.0, clockwise=False):
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    if clockwise:
        t = -t
    return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)])


def boundary_edge_count(F):
    E = np.sort(np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, c = np.unique(E, axis=0, return_counts=True)
    return int((c == 1).sum())


@pytest.mark.parametrize("clockwise", [False, True])
def test_annulus_matches_the_exact_inflation_and_is_zero_on_both_rings(clockwise):
    a, b = 0.4, 1.0
    m = inflate_stroke(ring(b, 240), True, {"resolution": 0.04, "smoothing": 0.0}, holes=[ring(a, 120, clockwise=clockwise)])
    assert len(m.holes) == 1
    r = np.hypot(m.V[:, 0], m.V[:, 1])
    assert np.all(m.V[m.rims, 2] == 0.0)
    assert np.abs(r[m.holes[0]] - a).max() < 0.01
    # Every boundary edge is on the outline or the hole: the mesh is an annulus.
    assert boundary_edge_count(m.F) == len(m.boundary) + len(m.holes[0])
    # no vertex inside the hole: every vertex off the rings lies farther out than the hole ring
    off_rings = np.setdiff1d(np.arange(len(r)), m.rims)
    assert r[off_rings].min() > r[m.holes[0]].max()
    # -Δu = 4, u(a) = u(b) = 0  =>  u = b² - r² - (b² - a²) ln(b/r) / ln(b/a), z = sqrt(u).
    u = b * b - r * r - (b * b - a * a) * np.log(b / r) / np.log(b / a)
    exact = np.sqrt(np.maximum(u, 0.0))
    err = np.abs(m.V[:, 2] - exact)
    assert err.max() < 0.03 * exact.max(), err.max()
    # The hole's loop has the surface on its left (clockwise), whatever orientation was drawn.
    P = m.V[m.holes[0], :2]
    area = 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    assert area < 0


def test_smoothing_keeps_every_ring_at_zero_and_two_holes_make_a_b():
    outline = np.array([[-1.0, -1.5], [1.0, -1.5], [1.0, 1.5], [-1.0, 1.5]])
    holes = [ring(0.45, 80, cy=-0.7), ring(0.45, 80, cy=0.7)]
    m = inflate_stroke(outline, True, {"resolution": 0.05, "smoothing": 0.5}, holes=holes)
    assert len(m.holes) == 2
    assert np.all(m.V[m.rims, 2] == 0.0) and np.all(m.V[:, 2] >= 0.0)
    assert boundary_edge_count(m.F) == len(m.rims)
    # Inside each hole there is no triangle.
    centroids = m.V[m.F].mean(axis=1)[:, :2]
    for c in ((0.0, -0.7), (0.0, 0.7)):
        assert np.min(np.hypot(*(centroids - c).T)) > 0.4


def test_open_stroke_with_a_hole_keeps_its_junction():
    t = np.linspace(0.0, np.pi, 80)
    arch = np.column_stack([np.cos(t), np.sin(t)])  # ends on y = 0: the junction
    m = inflate_stroke(arch, False, {"resolution": 0.05}, holes=[ring(0.25, 60, cy=0.45)])
    assert len(m.junction) > 2 and len(m.holes) == 1
    assert np.all(m.V[m.holes[0], 2] == 0.0)


@pytest.mark.parametrize(
    "hole, message",
    [
        (ring(0.5, 60, cx=0.8), "hole 2 crosses the outline"),
        (ring(0.3, 60, cx=3.0), "hole 2 near .* lies outside the outline"),
        (ring(0.01, 12, cx=0.5), "hole 2 is too small"),
        (ring(0.2, 60, cx=-0.1), "hole 2 crosses hole 1"),
        (ring(0.1, 60, cx=-0.3), "hole 2 lies inside hole 1"),
        (ring(0.3, 60, cx=0.69), "hole 2 comes within"),
        ([[0.5, 0.5], [0.7, 0.7], [0.7, 0.5], [0.5, 0.7]], "hole 2 crosses itself"),
        ([[0.5, 0.5], [0.6, 0.6], [0.7, 0.7]], "hole 2 is too small"),
        ([[0.5, 0.5], [np.nan, 0.6], [0.7, 0.7]], "hole 2 has a point that is not a finite number"),
    ],
)
def test_invalid_holes_get_a_one_line_error_naming_them(hole, message):
    with pytest.raises(ContourError, match=message) as info:
        inflate_stroke(ring(1.0, 160), True, {"resolution": 0.05}, holes=[ring(0.3, 60, cx=-0.3), hole])
    assert "\n" not in str(info.value)


def test_concatenated_outer_and_inner_ring_is_refused_as_a_slit_ring():
    outer = ring(1.0, 64)
    for inner in (ring(0.5, 64, clockwise=True), ring(0.5, 64)):
        for res in (0.03, 0.1):
            with pytest.raises(ContourError, match="draw the hole as a hole"):
                prepare_outline(np.vstack([outer, inner]), res, closed=True)
    # A C whose opening is wide is a C, not a slit ring.
    a = np.linspace(0.6, 2.0 * np.pi - 0.6, 60)
    c_shape = np.vstack([np.column_stack([np.cos(a), np.sin(a)]), 0.5 * np.column_stack([np.cos(a[::-1]), np.sin(a[::-1])])])
    assert prepare_outline(c_shape, 0.03, closed=True).area > 1.0


def test_holes_journal_save_reopen_and_replay_bit_identical(tmp_path, real_host):
    doc = Document(host=real_host)
    doc.execute({"command": "add_layer", "id": "o", "name": "O"})
    entry = {"command": "set_contour", "layer": "o", "points": ring(1.0, 100).tolist(), "closed": True,
             "holes": [ring(0.45, 60, clockwise=True).tolist()]}
    doc.execute(entry)
    assert doc.journal()[-1]["holes"] == entry["holes"]
    layer = doc.layer("o")
    assert len(layer.holes) == 1 and len(layer.mesh.holes) == 1
    path = tmp_path / "o.sketchforge.json"
    ff.save(doc, path)
    reopened = ff.load(path, host=real_host)
    replayed = ff.load(path, host=real_host, use_snapshot=False)
    assert ff.compare(doc, reopened) == [] and ff.compare(doc, replayed) == []
    assert replayed.layer("o").mesh.identical(layer.mesh) and len(replayed.layer("o").holes) == 1
    # A refused hole changes nothing and undo removes an accepted one in one step.
    before = doc.layer("o")
    with pytest.raises(ContourError, match="hole 1 crosses the outline"):
        doc.push(SetContour(layer="o", points=layer.points, closed=True, holes=[ring(0.5, 40, cx=0.9)]))
    assert doc.layer("o") is before
    doc.undo_stack.undo()
    assert doc.layer("o").mesh is None


def test_hole_gesture_plan_cuts_one_hole_in_one_undo_step_and_redraw_keeps_holes(real_host):
    from sketchforge.tools.draw import DrawContourTool, plan_stroke

    doc = Document(host=real_host)
    doc.execute({"command": "add_layer", "id": "o", "name": "O"})
    doc.execute({"command": "set_contour", "layer": "o", "points": ring(1.0, 100).tolist(), "closed": True})
    n = doc.undo_stack.count()
    # Refused: nothing selected, or a loop that leaves the part.
    assert "select a part" in plan_stroke(doc, ring(0.3, 40), "hole", None).refusal
    assert "inside “O”" in plan_stroke(doc, ring(0.3, 40, cx=0.9), "hole", "o").refusal
    plan = plan_stroke(doc, ring(0.3, 40, cx=-0.3), "hole", "o")
    assert plan.refusal is None and plan.redraw == "hole" and plan.target == "o" and len(plan.holes) == 1
    tool = DrawContourTool(doc, target_layer=plan.target, closed=plan.closed, keep_edits=True, holes=plan.holes)
    doc.push(tool.commands_for(plan.points)[1])
    assert doc.undo_stack.count() == n + 1 and len(doc.layer("o").mesh.holes) == 1
    # A second hole adds to the first.
    plan = plan_stroke(doc, ring(0.25, 40, cx=0.45), "hole", "o")
    doc.push(DrawContourTool(doc, target_layer="o", closed=True, holes=plan.holes).commands_for(plan.points)[1])
    assert len(doc.layer("o").mesh.holes) == 2
    doc.undo_stack.undo()
    assert len(doc.layer("o").mesh.holes) == 1
    # Redrawing the whole outline smaller keeps the hole that still fits and says so for the rest.
    plan = plan_stroke(doc, ring(0.8, 100, cx=-0.2), "redraw", "o")
    assert len(plan.holes) == 1
    plan = plan_stroke(doc, ring(0.5, 100, cx=0.5), "redraw", "o")
    assert plan.holes == () and "1 hole outside the new outline was dropped" in plan.notes[0]


def test_an_inflater_without_holes_still_works_and_refuses_a_layer_with_holes(fan_host):
    doc = Document(host=fan_host)
    doc.execute({"command": "add_layer", "id": "o", "name": "O"})
    doc.execute({"command": "set_contour", "layer": "o", "points": ring(1.0, 40).tolist(), "closed": True})
    assert doc.layer("o").mesh is not None
    with pytest.raises(ContourError, match="cannot cut holes"):
        doc.execute({"command": "set_contour", "layer": "o", "points": ring(1.0, 40).tolist(), "closed": True,
                     "holes": [ring(0.3, 20).tolist()]})
    assert doc.layer("o").holes == ()


def test_duplicate_offsets_the_copy_with_its_holes(real_host):
    doc = Document(host=real_host)
    doc.execute({"command": "add_layer", "id": "o", "name": "O"})
    doc.execute({"command": "set_contour", "layer": "o", "points": ring(1.0, 100).tolist(), "closed": True,
                 "holes": [ring(0.4, 50).tolist()]})
    doc.execute({"command": "duplicate_layer", "layer": "o", "id": "o2", "offset": [2.5, 0.0]})
    a, b = doc.layer("o"), doc.layer("o2")
    assert np.array_equal(b.holes[0], a.holes[0] + [2.5, 0.0])
    assert np.array_equal(b.mesh.V[b.mesh.holes[0], 0], a.mesh.V[a.mesh.holes[0], 0] + 2.5)
