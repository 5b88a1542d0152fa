"""Placing a drawn part (sketchforge.geometry.parts): closed by its own ends, overlap for
drawing behind, the junction chord touching a part, the partial redraw of an outline, and the
commands that duplicate with an offset and redraw keeping sculpt edits."""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge.errors import ContourError, EditsDoNotApplyError
from sketchforge.geometry.parts import chord_touches, overlapped, part_at, splice_outline, stroke_closes


def ring(r=0.5, c=(0.0, 0.0), n=60, end=2 * np.pi):
    t = np.linspace(0.0, end, n, endpoint=False)
    return np.c_[c[0] + r * np.cos(t), c[1] + r * np.sin(t)]


def u(c=(0.0, 0.0), width=0.3, depth=0.6, n=30):
    t = np.linspace(np.pi, 2 * np.pi, n)
    return np.c_[c[0] + 0.5 * width * np.cos(t), c[1] + depth * np.sin(t)]


@pytest.mark.parametrize("seed", range(6))
def test_a_stroke_is_closed_exactly_when_its_ends_meet(seed):
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.2, 0.8)
    jitter = rng.normal(scale=0.002 * r, size=(200, 2))
    # ends one sample (< 2 edge lengths) apart: closed
    assert stroke_closes(ring(r, n=200) + jitter, 0.03)
    # leaving a gap of a third of the circle: open
    assert not stroke_closes(ring(r, n=200, end=4 / 3 * np.pi) + jitter, 0.03)
    # an overshoot past the start closes it too
    over = np.vstack([ring(r, n=200), ring(r, n=200)[:20]])
    assert stroke_closes(over, 0.03)


def test_a_line_is_not_an_outline():
    with pytest.raises(ContourError):
        stroke_closes([[0, 0], [1, 0], [2, 0]], 0.03)


def test_overlap_and_the_backmost_part_a_stroke_covers():
    outlines = [ring(0.5), ring(0.2, (2.0, 0.0)), None, ring(0.3, (0.6, 0.0))]
    got = overlapped(ring(0.2, (0.55, 0.0)), outlines)
    assert got.tolist() == [True, False, False, True]
    assert overlapped(ring(0.1, (5.0, 5.0)), outlines).tolist() == [False] * 4


def test_the_junction_chord_touches_a_part_only_when_it_lies_on_one():
    body = [ring(0.5)]
    assert chord_touches(u((0.0, -0.3)), body)  # ends inside the body
    assert not chord_touches(u((2.0, 0.0)), body)  # over empty space


def test_part_at_picks_the_frontmost():
    outlines = [ring(0.5), ring(0.2, (0.3, 0.0)), None]
    assert part_at((0.3, 0.0), outlines) == 1
    assert part_at((-0.3, 0.0), outlines) == 0
    assert part_at((3.0, 0.0), outlines) == -1


def test_splice_replaces_the_shorter_stretch_between_the_stroke_ends():
    P = ring(0.5, n=120)
    tol = 0.01
    # a bump from the outline at 0° to 60°, out to r = 0.8
    t = np.linspace(0.0, np.pi / 3, 20)
    bump = np.c_[0.8 * np.cos(t), 0.8 * np.sin(t)]
    bump[0], bump[-1] = P[0], P[20]
    out = splice_outline(P, True, bump, tol)
    r = np.linalg.norm(out, axis=1)
    assert out.shape == (len(P) - 21 + 20, 2)  # P[0..20] gave way to the 20 stroke points
    assert r.max() == pytest.approx(0.8) and np.sum(r > 0.6) == 18
    assert np.sum(np.isclose(r, 0.5)) == len(P) - 21 + 2  # the rest of the circle is untouched
    # drawn the other way round, the same stretch is replaced
    back = splice_outline(P, True, bump[::-1], tol)
    assert sorted(map(tuple, back.round(12))) == sorted(map(tuple, out.round(12)))
    # one end off the outline, or both ends at one point: not a redraw
    off = bump.copy()
    off[-1] = (0.9, 0.9)
    assert splice_outline(P, True, off, tol) is None
    assert splice_outline(P, True, np.array([P[3], [0.9, 0.0], P[3]]), tol) is None


def test_splice_of_an_open_outline_keeps_its_ends():
    P = u(n=60)
    S = np.array([P[10], [0.0, -1.0], P[40]])
    out = splice_outline(P, False, S, 1e-9)
    assert np.array_equal(out[0], P[0]) and np.array_equal(out[-1], P[-1])
    assert len(out) == 60 - 31 + 3
    assert np.array_equal(splice_outline(P, False, S[::-1], 1e-9), out)


# --- the commands the gestures push ---------------------------------------------------------


def body_doc(host):
    from sketchforge.document.document import Document

    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": ring(0.6, n=120).tolist(), "closed": True})
    return doc


def test_duplicate_with_offset_and_index_replays_bit_identically(real_host):
    doc = body_doc(real_host)
    doc.execute({"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3,
                 "stroke": [[0.1, -0.3], [0.15, -0.1], [0.22, 0.1], [0.3, 0.3]]})
    doc.execute({"command": "duplicate_layer", "layer": "body", "id": "b2", "index": 0, "offset": [0.5, -0.25]})
    assert [l.id for l in doc.layers] == ["b2", "body"]
    src, copy = doc.layer("body"), doc.layer("b2")
    assert np.array_equal(copy.mesh.V[:, :2], src.mesh.V[:, :2] + [0.5, -0.25])
    assert np.array_equal(copy.mesh.V[:, 2], src.mesh.V[:, 2]) and np.array_equal(copy.mesh.F, src.mesh.F)
    assert copy.edits[0]["pick"] == [0.7, -0.15]
    # the copy's edits apply where the copy is: a parameter change re-applies them
    doc.execute({"command": "set_inflate_params", "layer": "b2", "params": {"inflation": 1.2}})
    assert len(doc.layer("b2").edits) == 1
    from sketchforge.document.document import Document

    again = Document(host=real_host)
    for entry in doc.journal():
        again.execute(entry)
    for a, b in zip(again.layers, doc.layers):
        assert np.array_equal(a.mesh.V, b.mesh.V) and np.array_equal(a.mesh.F, b.mesh.F)
    doc.undo_stack.undo()
    doc.undo_stack.undo()
    assert [l.id for l in doc.layers] == ["body"]


def test_redraw_keeps_sculpt_edits_that_apply_and_refuses_those_that_do_not(real_host):
    doc = body_doc(real_host)
    doc.execute({"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3,
                 "stroke": [[0.1, -0.3], [0.15, -0.1], [0.22, 0.1], [0.3, 0.3]]})
    sculpted = doc.layer("body")
    # a bump on the far side: the edit still applies and is kept
    P = np.asarray(sculpted.points)
    t = np.linspace(np.pi * 0.9, np.pi * 1.1, 12)
    bump = np.c_[0.8 * np.cos(t), 0.8 * np.sin(t)]
    i, j = np.argmin(np.linalg.norm(P - [0.6 * np.cos(np.pi * 0.9), 0.6 * np.sin(np.pi * 0.9)], axis=1)), \
        np.argmin(np.linalg.norm(P - [0.6 * np.cos(np.pi * 1.1), 0.6 * np.sin(np.pi * 1.1)], axis=1))
    bump[0], bump[-1] = P[i], P[j]
    new = splice_outline(P, True, bump, 1e-9)
    doc.execute({"command": "set_contour", "layer": "body", "points": new.tolist(), "closed": True, "keep_edits": True})
    kept = doc.layer("body")
    assert len(kept.edits) == 1 and kept.mesh.V[:, 0].min() < -0.75
    # the sculpted side no longer exists (a small blob far away): nothing changes, the error says so
    with pytest.raises(EditsDoNotApplyError, match="do not apply"):
        doc.execute({"command": "set_contour", "layer": "body", "points": ring(0.1, (-3.0, 0.0)).tolist(),
                     "closed": True, "keep_edits": True})
    assert doc.layer("body") is kept


# --- plan_stroke: the same decisions the window makes, headless -------------------------------


def test_plan_stroke_decides_new_behind_stretch_whole_and_free(real_host):
    from sketchforge.tools.draw import plan_stroke

    doc = body_doc(real_host)  # one closed body, r = 0.6
    doc.execute({"command": "add_layer", "id": "far", "name": "Far"})
    doc.execute({"command": "set_contour", "layer": "far", "points": ring(0.2, (2.0, 0.0), n=80).tolist(), "closed": True})
    head = ring(0.2, (0.5, 0.5), n=120)
    plan = plan_stroke(doc, head, "front", "body", 0.01)
    assert plan.target is None and plan.index is None and plan.closed and plan.redraw is None
    # behind: under the backmost part it overlaps (the body, index 0), or at the back
    assert plan_stroke(doc, ring(0.2, (2.1, 0.0), n=80), "behind", "body").index == 1
    plan = plan_stroke(doc, ring(0.1, (0.0, 2.0), n=80), "behind", "body")
    assert plan.index == 0 and "overlaps none" in plan.notes[0]
    # an open U on the body stays open; the same U in empty space is made free, and says so
    leg = u((0.0, -0.3), 0.3, 0.7, n=60)
    assert plan_stroke(doc, leg, "front", "far").closed is False
    plan = plan_stroke(doc, leg + [0.0, 3.0], "front", "far")
    assert plan.closed and "touch no part" in plan.notes[0]
    # from the body's outline back to it: that stretch; Ctrl: the whole outline; no selection: refused
    P = doc.layer("body").points
    bump = np.array([P[0], [0.9, 0.1], [0.8, 0.3], P[10]])
    plan = plan_stroke(doc, bump, "front", "body", 1e-9)
    assert plan.redraw == "stretch" and plan.target == "body" and len(plan.points) == len(P) - 11 + 4
    assert plan_stroke(doc, head, "redraw", "body").redraw == "whole"
    assert plan_stroke(doc, head, "redraw", None).refusal
