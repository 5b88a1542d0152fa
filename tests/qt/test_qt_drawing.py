"""Drawing like Monster Mash, driven through the real window with mouse and key events: one
stroke per part, drawing behind, depth and copies by keys, feedback for every refused gesture,
and every gesture one undo step that a journal replays to the same meshes."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QApplication
from qt_helpers import circle, wait_idle

from sketchforge.document.document import Document

K = Qt.Key
M = Qt.KeyboardModifier


@pytest.fixture
def w(drawing_window):
    return drawing_window


def draw(w, mouse, qtbot, pts, button=Qt.MouseButton.LeftButton, modifiers=M.NoModifier):
    mouse(w.canvas).drag(list(pts), button, modifiers)
    wait_idle(qtbot, w)


def loop(r, center, n=40):
    pts = circle(r, n, center)
    return list(pts) + [pts[0]]


def u_shape(center, width, depth, n=30):
    """An open U hanging down from y = center[1] (its open side, the junction, at the top)."""
    t = np.linspace(np.pi, 2 * np.pi, n)
    return np.c_[center[0] + 0.5 * width * np.cos(t), center[1] + depth * np.sin(t)]


def key(w, qtbot, k, mod=M.NoModifier):
    qtbot.keyClick(QApplication.focusWidget() or w, k, mod)
    QApplication.processEvents()


def status(w) -> str:
    return w.statusBar().currentMessage()


def test_each_stroke_makes_a_new_part_in_front_one_undo_step_each(w, mouse, qtbot):
    draw(w, mouse, qtbot, loop(0.5, (0, 0)))
    body = w.doc.layers[0].id
    assert w.current_layer == body  # the new part is selected...
    draw(w, mouse, qtbot, loop(0.25, (0.1, 0.55)))
    # ...yet the next stroke is a new part, in front, not a redraw of the selection
    assert [l.id for l in w.doc.layers][0] == body and len(w.doc.layers) == 2
    assert w.doc.undo_stack.count() == 2 and w.act_undo.text() == "Undo Draw layer"
    assert all(l.closed for l in w.doc.layers)  # ends met: closed, as the panel shows
    assert w.creation_panel.closed.isChecked()
    key(w, qtbot, K.Key_Z, M.ControlModifier)
    assert len(w.doc.layers) == 1 and w.doc.layers[0].id == body


def test_right_drag_and_shift_drag_draw_behind_the_backmost_overlapped_part(w, mouse, qtbot):
    draw(w, mouse, qtbot, loop(0.4, (0, 0)))  # body
    draw(w, mouse, qtbot, loop(0.2, (0.75, 0.75)))  # away from it, in front of the body
    draw(w, mouse, qtbot, loop(0.2, (0.35, -0.3)), button=Qt.MouseButton.RightButton)
    names = [l.id for l in w.doc.layers]
    assert len(names) == 3 and names[0] == w.current_layer  # under the body, the backmost it overlaps
    assert "behind" in status(w)
    assert w.doc.undo_stack.count() == 3
    # Shift + left drag does the same: overlapping only the far part -> just behind it
    draw(w, mouse, qtbot, loop(0.15, (0.85, 0.75)), modifiers=M.ShiftModifier)
    ids = [l.id for l in w.doc.layers]
    assert ids.index(w.current_layer) == 2 and ids[3] == names[2]
    # the journal puts them at the same depths again
    replayed = Document(host=w.host)
    for entry in w.doc.journal():
        replayed.execute(entry)
    assert [l.id for l in replayed.layers] == ids


def test_a_stroke_fills_an_empty_layer_made_with_plus(w, mouse, qtbot):
    draw(w, mouse, qtbot, loop(0.4, (0, 0)))
    w.layers_panel.select(w.doc.layers[0].id)
    w.layers_panel.add_requested.emit()  # the "+" button: an empty layer, selected
    empty = w.current_layer
    assert w.doc.layer(empty).points is None
    draw(w, mouse, qtbot, loop(0.2, (0.5, 0.5)))
    assert len(w.doc.layers) == 2 and w.doc.layer(empty).mesh is not None
    assert w.act_undo.text() == "Undo Draw contour"


def test_open_stroke_on_a_part_attaches_open_over_nothing_becomes_a_free_part(w, mouse, qtbot, host):
    draw(w, mouse, qtbot, loop(0.5, (0, 0)))
    # an open U whose ends lie inside the body: stays open (its junction attaches)
    draw(w, mouse, qtbot, u_shape((0.0, -0.3), 0.3, 0.6))
    leg = w.doc.layers[-1]
    assert not leg.closed and len(leg.mesh.junction) > 0
    assert not w.creation_panel.closed.isChecked()
    # the same U far from every part: closed, and the status bar says why
    draw(w, mouse, qtbot, u_shape((0.8, 0.9), 0.3, 0.6))
    free = w.doc.layers[-1]
    assert free.closed and len(free.mesh.junction) == 0
    assert "touch no part" in status(w)
    # assembled as the panel says: the assembler gets closed=True for it
    assert w.creation_panel.closed.isChecked()


def test_closed_box_flips_the_selected_part_and_never_carries_over(w, mouse, qtbot):
    draw(w, mouse, qtbot, loop(0.5, (0, 0)))
    draw(w, mouse, qtbot, u_shape((0.0, -0.3), 0.3, 0.6))
    leg = w.doc.layers[-1].id
    n = w.doc.undo_stack.count()
    w.creation_panel.closed.click()  # the person ticks it for the selected leg
    wait_idle(qtbot, w)
    assert w.doc.layer(leg).closed and len(w.doc.layer(leg).mesh.junction) == 0
    assert w.doc.undo_stack.count() == n + 1
    # a new open U on the body after selecting the (closed) eye-like part is still open
    draw(w, mouse, qtbot, u_shape((0.2, -0.2), 0.2, 0.5))
    assert not w.doc.layers[-1].closed


def test_partial_redraw_replaces_a_stretch_and_keeps_the_part(w, mouse, qtbot):
    draw(w, mouse, qtbot, loop(0.5, (0, 0), n=80))
    layer = w.doc.layers[0]
    area_before = float(np.ptp(layer.points[:, 0]))
    # from the outline at 0° out to x = 0.9 and back to the outline at 60°: a bump
    a, b = np.array([0.5, 0.0]), np.array([0.25, 0.433])
    bump = [a, (0.9, 0.1), (0.8, 0.4), (0.5, 0.6), b]
    draw(w, mouse, qtbot, bump)
    assert len(w.doc.layers) == 1
    new = w.doc.layers[0]
    assert new.points.shape != layer.points.shape
    assert float(new.points[:, 0].max()) > 0.85 and float(np.ptp(new.points[:, 0])) > area_before
    assert new.points[:, 0].min() < -0.45  # the far side of the outline is kept
    assert w.act_undo.text() == "Undo Draw contour" and "part of the outline" in status(w)


def test_depth_keys_delete_and_duplicates(w, mouse, qtbot):
    draw(w, mouse, qtbot, loop(0.4, (0, 0)))
    draw(w, mouse, qtbot, loop(0.2, (0.8, 0)))
    draw(w, mouse, qtbot, loop(0.2, (-0.8, 0)))
    a, b, c = [l.id for l in w.doc.layers]
    w.canvas.setFocus()
    mouse(w.canvas).click((0.0, 0.0))  # select the body by clicking it
    assert w.current_layer == a
    key(w, qtbot, K.Key_PageUp)
    assert [l.id for l in w.doc.layers] == [b, a, c]
    key(w, qtbot, K.Key_Home)
    assert [l.id for l in w.doc.layers] == [b, c, a]
    key(w, qtbot, K.Key_Home)
    assert "already at the front" in status(w)
    key(w, qtbot, K.Key_End)
    assert [l.id for l in w.doc.layers] == [a, b, c]
    key(w, qtbot, K.Key_PageDown)
    assert "already at the back" in status(w)
    # double-click: left duplicates behind, right in front
    mouse(w.canvas).double_click((0.8, 0.0))
    ids = [l.id for l in w.doc.layers]
    assert len(ids) == 4 and ids.index(w.current_layer) == ids.index(b) - 1
    mouse(w.canvas).double_click((-0.8, 0.0), Qt.MouseButton.RightButton)
    ids = [l.id for l in w.doc.layers]
    assert len(ids) == 5 and ids.index(w.current_layer) == ids.index(c) + 1
    # Ctrl+D: a copy moved aside (1.25 of its width to the right)
    mouse(w.canvas).click((0.0, 0.0))
    key(w, qtbot, K.Key_D, M.ControlModifier)
    copy = w.doc.layer(w.current_layer)
    src = w.doc.layer(a)
    shift = copy.mesh.V[:, :2].mean(axis=0) - src.mesh.V[:, :2].mean(axis=0)
    assert np.allclose(shift, [1.0, 0.0], atol=0.02)
    assert np.array_equal(copy.mesh.F, src.mesh.F)
    # Del removes the selected part; every key was one undo step
    n = len(w.doc.layers)
    key(w, qtbot, K.Key_Delete)
    assert len(w.doc.layers) == n - 1
    assert w.doc.undo_stack.count() == 3 + 3 + 2 + 1 + 1  # draws, moves, double-clicks, Ctrl+D, Del
    # and the journal replays these gestures to the same meshes, bit for bit
    replayed = Document(host=w.host)
    for entry in w.doc.journal():
        replayed.execute(entry)
    assert [l.id for l in replayed.layers] == [l.id for l in w.doc.layers]
    for x, y in zip(replayed.layers, w.doc.layers):
        assert np.array_equal(x.mesh.V, y.mesh.V) and np.array_equal(x.mesh.F, y.mesh.F)


def test_refused_gestures_say_why(w, mouse, qtbot):
    mouse(w.canvas).click((0.3, 0.3))
    assert "no part here" in status(w)
    key(w, qtbot, K.Key_PageUp)
    assert "select a part first" in status(w)
    p = mouse(w.canvas).px((0.0, 0.0))
    from PySide6.QtCore import QPointF

    # a slip of 6 pixels: a drag, but no part
    mouse(w.canvas).drag_pixels([p, QPointF(p.x() + 3, p.y()), QPointF(p.x() + 6, p.y() + 1)])
    assert len(w.doc.layers) == 0 and "shorter than" in status(w)
    # a 2-pixel wobble is a click: it says how to draw
    mouse(w.canvas).drag_pixels([p, QPointF(p.x() + 2, p.y())])
    assert len(w.doc.layers) == 0 and "drag to draw" in status(w)
    mouse(w.canvas).double_click((0.3, 0.3))
    assert "double-click a part" in status(w)
    mouse(w.canvas).drag(loop(0.3, (0, 0)), modifiers=M.ControlModifier)
    assert "select a part first" in status(w)


def test_parameter_edits_during_a_solve_are_coalesced_and_ctrl_z_cancels(w, mouse, qtbot):
    draw(w, mouse, qtbot, loop(0.5, (0, 0)))
    spin = w.creation_panel.spins["inflation"]
    start = spin.value()
    for _ in range(5):  # five clicks on the arrow, faster than the solves
        spin.stepUp()
    assert w.runner.busy or w.jobs.running()
    wait_idle(qtbot, w)
    qtbot.waitUntil(lambda: not w._pending_params and not w.runner.busy, timeout=60_000)
    wait_idle(qtbot, w)
    assert w.doc.layers[0].params["inflation"] == pytest.approx(start + 5 * spin.singleStep())
    assert spin.value() == pytest.approx(start + 5 * spin.singleStep())
    assert w.doc.undo_stack.count() == 3  # the draw, the first click, the four coalesced ones
    # Ctrl+Z while a solve runs cancels it: the document stays as it was
    before = w.doc.layers[0]
    n = w.doc.undo_stack.count()
    spin.stepUp()
    assert w.runner.busy
    key(w, qtbot, K.Key_Z, M.ControlModifier)
    assert not w.runner.busy and "cancelled" in status(w)
    wait_idle(qtbot, w)
    assert w.doc.layers[0] is before and w.doc.undo_stack.count() == n


def test_shortcuts_work_after_every_mode_switch_and_help_lists_them(w, mouse, qtbot):
    from sketchforge.qt.shortcuts import SHORTCUTS

    draw(w, mouse, qtbot, loop(0.4, (0, 0)))
    draw(w, mouse, qtbot, loop(0.2, (0.5, 0)))
    for k in (K.Key_F3, K.Key_F2):
        key(w, qtbot, k)
        assert QApplication.focusWidget() is w.canvas
    w.set_mode("observation")
    assert QApplication.focusWidget() is not None and w.isAncestorOf(QApplication.focusWidget())
    w.set_mode("creation")
    assert QApplication.focusWidget() is w.canvas
    key(w, qtbot, K.Key_End)
    assert w.doc.layers[0].id == w.current_layer
    key(w, qtbot, K.Key_F1)
    assert w.help_overlay.isVisible()
    text = w.help_overlay.text()
    assert all(k in text for k, _ in SHORTCUTS)
    key(w, qtbot, K.Key_Escape)
    assert not w.help_overlay.isVisible()


def test_the_readme_lists_every_gesture_and_key_the_help_overlay_shows():
    from pathlib import Path

    from sketchforge.qt.shortcuts import shortcut_markdown

    assert shortcut_markdown() in (Path(__file__).resolve().parents[2] / "README.md").read_text()


def test_strokes_drawn_while_a_part_inflates_wait_and_are_all_drawn(w, mouse, qtbot, monkeypatch):
    import threading

    from sketchforge.document import commands as C

    # The first inflation waits until the test lets it go, as a slow one would.
    gate = threading.Event()
    compute = C.SetContour.compute

    def slow(self, doc, old):
        gate.wait(30)
        return compute(self, doc, old)

    monkeypatch.setattr(C.SetContour, "compute", slow)
    m = mouse(w.canvas)
    m.drag(loop(0.4, (0, 0)))
    assert w.runner.busy  # the body inflates...
    m.drag(loop(0.2, (0.5, 0.4)))  # ...while the head and a leg behind are drawn
    m.drag(loop(0.15, (-0.3, -0.4)), Qt.MouseButton.RightButton)
    assert "2 strokes waiting" in status(w) and len(w.doc.layers) == 1
    gate.set()
    qtbot.waitUntil(lambda: len(w.doc.layers) == 3 and not w.runner.busy and not w._pending_strokes, timeout=60_000)
    wait_idle(qtbot, w)
    body, head = w.doc.layers[1], w.doc.layers[2]
    assert w.doc.layers[0].id == w.current_layer  # the leg went behind the body
    assert np.allclose(body.points.mean(axis=0), 0, atol=0.02) and head.points[:, 0].mean() > 0.4
    assert w.doc.undo_stack.count() == 3
    # Esc drops waiting strokes along with the running solve
    gate.clear()
    m.drag(loop(0.1, (0.6, -0.6)))
    m.drag(loop(0.1, (-0.6, 0.6)))
    assert w.runner.busy and len(w._pending_strokes) == 1
    key(w, qtbot, K.Key_Escape)
    gate.set()
    wait_idle(qtbot, w)
    assert len(w.doc.layers) == 3 and not w._pending_strokes and "dropped 1 waiting stroke" in status(w)


def test_right_click_selects_and_question_mark_opens_the_help(w, mouse, qtbot):
    draw(w, mouse, qtbot, loop(0.4, (0, 0)))
    draw(w, mouse, qtbot, loop(0.2, (0.7, 0.5)))
    mouse(w.canvas).click((0.0, 0.0), Qt.MouseButton.RightButton)
    assert w.current_layer == w.doc.layers[0].id and len(w.doc.layers) == 2
    key(w, qtbot, K.Key_Question)
    assert w.help_overlay.isVisible()
    mouse(w.canvas).click((0.5, -0.5))
    QApplication.processEvents()


def test_a_double_click_copy_is_moved_with_the_arrow_keys(w, mouse, qtbot):
    draw(w, mouse, qtbot, loop(0.5, (0, 0)))
    draw(w, mouse, qtbot, u_shape((-0.2, -0.3), 0.16, 0.6))  # a leg, open, on the body
    leg = w.doc.layers[-1].id
    mouse(w.canvas).double_click((-0.2, -0.7), Qt.MouseButton.RightButton)  # a copy in front, in place
    copy = w.current_layer
    assert copy != leg and "arrow keys" in status(w)
    w.canvas.setFocus()
    before = w.doc.layer(copy).mesh.V.copy()
    n = w.doc.undo_stack.count()
    for _ in range(4):
        key(w, qtbot, K.Key_Right)
    step = 10 * w.canvas.pixel_size()
    moved = w.doc.layer(copy).mesh.V
    assert np.allclose(moved[:, 0] - before[:, 0], 4 * step) and np.array_equal(moved[:, 1:], before[:, 1:])
    assert w.doc.undo_stack.count() == n + 4 and w.act_undo.text() == "Undo Move layer"
    # arrows in the Layers list still move the list's selection, not the part
    w.layers_panel.list.setFocus()
    key(w, qtbot, K.Key_Right)
    assert w.doc.undo_stack.count() == n + 4
    # the journal replays the copy and its moves bit for bit
    replayed = Document(host=w.host)
    for entry in w.doc.journal():
        replayed.execute(entry)
    for a, b in zip(replayed.layers, w.doc.layers):
        assert np.array_equal(a.mesh.V, b.mesh.V)


def test_a_junction_partly_off_its_part_is_said_when_the_stroke_is_released(w, mouse, qtbot):
    # issue 34, point 3: an open stroke whose junction runs off the part it lies on (or spans
    # two parts) attaches by the stretch on it, and says so at once, not first in OBSERVATION
    draw(w, mouse, qtbot, loop(0.5, (0, 0)))  # body
    body = w.doc.layers[0]
    draw(w, mouse, qtbot, u_shape((0.0, -0.3), 0.3, 0.6))  # a leg, its junction well inside
    assert "glued to “" in status(w) and body.name in status(w)
    # a head whose junction pokes out of the body's outline on one side
    t = np.linspace(np.radians(200), np.radians(-20), 40)
    head = np.c_[0.35 + 0.32 * np.cos(t), 0.45 + 0.32 * np.sin(t)]
    draw(w, mouse, qtbot, head)
    part = w.doc.layers[-1]
    assert not part.closed and len(part.mesh.junction) > 0
    assert "runs off" in status(w) and "is glued" in status(w) and part.name in status(w)
