"""Issue 35 in the app: the light disc (azimuth and elevation, one undo step per drag or typed
value; the in-plane drag in the drawing keeps working) and several isophotes redrawn in one
edit (Shift+click, a stroke for each, applied as one command: on the last stroke or with
Enter)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from PySide6.QtCore import QEvent, QPointF, Qt
from PySide6.QtGui import QMouseEvent
from PySide6.QtWidgets import QApplication
from qt_helpers import wait_idle

from sketchforge.document import fileformat as ff
from sketchforge.document.layer import Light

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from sculpt_helpers import isophote_stroke  # noqa: E402


def _disc_event(widget, kind, pos: QPointF, buttons):
    button = Qt.MouseButton.LeftButton if kind != QEvent.Type.MouseMove else Qt.MouseButton.NoButton
    ev = QMouseEvent(kind, pos, widget.mapToGlobal(pos), button, buttons, Qt.KeyboardModifier.NoModifier)
    QApplication.sendEvent(widget, ev)


def _drag_disc(disc, points):
    """Press, move, release on the light disc at disc points (unit disc, y up)."""
    c, r = disc._disc()
    px = [QPointF(c.x() + r * u, c.y() - r * v) for u, v in points]
    L = Qt.MouseButton.LeftButton
    _disc_event(disc, QEvent.Type.MouseButtonPress, px[0], L)
    for p in px[1:]:
        _disc_event(disc, QEvent.Type.MouseMove, p, L)
    _disc_event(disc, QEvent.Type.MouseButtonRelease, px[-1], Qt.MouseButton.NoButton)
    QApplication.processEvents()


def test_the_light_disc_sets_azimuth_and_elevation_one_undo_step_per_drag(make_window):
    w = make_window()
    doc, panel = w.doc, w.light_panel
    before = doc.light
    # A drag ending half way between rim and centre, up and to the left: elevation 45°, azimuth 135°.
    r = 0.5 / math.sqrt(2.0)
    _drag_disc(panel.disc, [(0.9, 0.0), (0.3, 0.3), (-r, r)])
    assert doc.undo_stack.count() == 1
    assert abs(doc.light.elevation - 45.0) < 2.0 and abs(doc.light.angle - 135.0) < 2.0
    assert abs(panel.elevation.value() - doc.light.elevation) < 0.051
    doc.undo_stack.undo()
    assert doc.light == before
    # Dragged past the rim: exactly in the drawing plane (the thesis' light).
    _drag_disc(panel.disc, [(0.2, 0.0), (0.0, 1.4)])
    assert doc.light.z == 0.0 and abs(doc.light.angle - 90.0) < 1.0
    # Typed: each value one command; the azimuth keeps the elevation and vice versa.
    n = doc.undo_stack.count()
    panel.elevation.setValue(60.0)
    assert doc.undo_stack.count() == n + 1 and abs(doc.light.elevation - 60.0) < 1e-9
    panel.angle.setValue(-30.0)
    assert doc.undo_stack.count() == n + 2
    assert abs(doc.light.elevation - 60.0) < 1e-9 and abs(doc.light.angle + 30.0) < 1e-9
    panel.elevation.setValue(90.0)
    assert doc.light == Light(0.0, 0.0, 1.0) and not panel.angle.isEnabled()
    panel.elevation.setValue(20.0)  # back down: the azimuth it had
    assert abs(doc.light.angle + 30.0) < 1e-9 and abs(doc.light.elevation - 20.0) < 1e-9


def test_the_in_plane_drag_in_the_drawing_still_sets_the_light(make_window, mouse):
    w = make_window()
    w.canvas.fit()
    w.modes.light.setChecked(True)
    m = mouse(w.canvas)
    c = w.canvas.view_center()
    m.drag([tuple(c + [0.05, 0.0]), tuple(c + [0.0, 0.3]), tuple(c + [-0.3, 0.0])])
    assert w.doc.light.in_plane and abs(abs(w.doc.light.angle) - 180.0) < 2.0
    assert w.doc.undo_stack.count() == 1
    # Raised in the panel, the drag turns it and keeps its elevation.
    w.light_panel.elevation.setValue(50.0)
    m.drag([tuple(c + [0.05, 0.0]), tuple(c + [0.0, -0.3])])
    assert abs(w.doc.light.elevation - 50.0) < 1e-9 and abs(w.doc.light.angle + 90.0) < 2.0
    assert w.doc.undo_stack.count() == 3


def _ellipse(host):
    t = np.linspace(0.0, 2 * np.pi, 96, endpoint=False)
    journal = [
        {"command": "add_layer", "id": "blob", "name": "Blob"},
        {"command": "set_contour", "layer": "blob", "points": np.c_[0.8 * np.cos(t), 0.55 * np.sin(t)].tolist(), "closed": True},
        {"command": "set_inflate_params", "layer": "blob", "params": {"resolution": 0.05}},
    ]
    return ff.document_from_dict({"format": "sketchforge", "version": 2, "light": [0.5, 0.5, 0.7071], "journal": journal},
                                 host=host)


def _shift_click(m, pixel):
    S = Qt.KeyboardModifier.ShiftModifier
    m._send(QEvent.Type.MouseMove, pixel, Qt.MouseButton.NoButton, Qt.MouseButton.NoButton, S)
    m._send(QEvent.Type.MouseButtonPress, pixel, Qt.MouseButton.LeftButton, Qt.MouseButton.LeftButton, S)
    m._send(QEvent.Type.MouseButtonRelease, pixel, Qt.MouseButton.LeftButton, Qt.MouseButton.NoButton, S)
    QApplication.processEvents()


def _two_picked(make_window, mouse, host):
    if "sculpt_isophotes" not in host.commands.names():
        pytest.skip("the isophote tool plugin is not installed")
    doc = _ellipse(host)
    w = make_window(doc)
    w.canvas.fit()
    w.modes.sculpture.setChecked(True)
    w.plugin_panels["isophote_sculpt"].spin.setValue(0.12)
    w.sculpt.set_preview(False)
    m = mouse(w.canvas)
    px1, pick1 = m.aim((0.35, 0.15))
    px2, pick2 = m.aim((-0.2, -0.2))
    m.click_pixel(px1)
    _shift_click(m, px2)
    assert w.sculpt.pick_count == 2, w.sculpt.status
    panel = w.plugin_panels["isophote_sculpt"]
    assert panel.apply.isVisibleTo(panel) and not panel.apply.isEnabled()
    mesh = doc.layer("blob").mesh
    strokes = [isophote_stroke(mesh, p, offset=0.08, half=0.18, light=doc.light.direction)[0] for p in (pick1, pick2)]
    return w, m, doc, (pick1, pick2), strokes


def _draw(m, stroke):
    pixels = []
    for p in stroke[:: max(1, len(stroke) // 12)]:
        px, _ = m.aim(tuple(p))
        if not pixels or (px - pixels[-1]).manhattanLength() > 3:
            pixels.append(px)
    m.drag_pixels(pixels)
    return np.array([m.aim(tuple(p))[1] for p in stroke[:: max(1, len(stroke) // 12)]])


def test_two_isophotes_redrawn_are_one_command_and_one_undo_step(make_window, mouse, qtbot, host):
    w, m, doc, picks, strokes = _two_picked(make_window, mouse, host)
    before = doc.layer("blob").mesh
    _draw(m, strokes[1])  # the second one's stroke first: kept, nothing applied yet
    assert doc.undo_stack.count() == 0 and "stroke kept for isophote 2" in w.sculpt.status
    assert w.plugin_panels["isophote_sculpt"].apply.isEnabled()
    assert len(w.canvas.overlays["isophote"]._path.toSubpathPolygons()) == 2  # both picked isophotes
    _draw(m, strokes[0])  # the last one: the joint edit runs
    wait_idle(qtbot, w, timeout=120_000)
    assert doc.undo_stack.count() == 1, w.sculpt.status
    entry = doc.journal()[-1]
    assert entry["command"] == "sculpt_isophotes" and len(entry["edits"]) == 2
    assert w.act_undo.text() == "Undo Sculpt 2 isophotes"
    assert "2 isophotes" in w.sculpt.status
    # Redrawing one of them replaces the attempt: still one step.
    _draw(m, strokes[0] + [0.01, 0.0])
    wait_idle(qtbot, w, timeout=120_000)
    assert doc.undo_stack.count() == 1 and doc.journal()[-1]["command"] == "sculpt_isophotes"
    doc.undo_stack.undo()
    assert doc.layer("blob").mesh is before


def test_enter_applies_the_strokes_drawn_so_far(make_window, mouse, qtbot, host):
    w, m, doc, picks, strokes = _two_picked(make_window, mouse, host)
    _draw(m, strokes[0])
    assert doc.undo_stack.count() == 0
    w.canvas.setFocus()
    qtbot.keyClick(w.canvas, Qt.Key.Key_Return)
    wait_idle(qtbot, w, timeout=120_000)
    assert doc.undo_stack.count() == 1 and doc.journal()[-1]["command"] == "sculpt_isophote"
    assert doc.journal()[-1]["pick"] == [float(v) for v in picks[0]]


def test_a_second_pick_off_the_part_or_with_a_one_isophote_solver_is_refused(make_window, mouse, host):
    w, m, doc, picks, strokes = _two_picked(make_window, mouse, host)
    _shift_click(m, m.aim((0.75, 0.5))[0])  # beside the ellipse
    assert w.sculpt.pick_count == 2 and "lie on one part" in w.sculpt.status
    if "strips" in host.solvers("sculpt"):
        panel = w.plugin_panels["isophote_sculpt"]
        panel.solver.setCurrentIndex(panel.solver.findData("strips"))
        m.click_pixel(m.aim(tuple(picks[0]))[0])
        _shift_click(m, m.aim(tuple(picks[1]))[0])
        assert w.sculpt.pick_count == 1 and "redraws one isophote per edit" in w.sculpt.status
