"""The selected part's handles (issue 12, point 3): a drag on the centre marker moves it, on a
corner scales it about the opposite corner, on the knob rotates it; each drag is one
transform_layer (one undo step); Alt + drag cuts a hole; Ctrl+M mirrors about the host's axis."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from qt_helpers import circle, wait_idle

from sketchforge.document.document import Document
from sketchforge.tools import transform as tr

M = Qt.KeyboardModifier


@pytest.fixture
def w(drawing_window):
    return drawing_window


def loop(r, center, n=40):
    pts = circle(r, n, center)
    return list(pts) + [pts[0]]


def drag(w, mouse, qtbot, pts, modifiers=M.NoModifier):
    mouse(w.canvas).drag(list(pts), Qt.MouseButton.LeftButton, modifiers)
    wait_idle(qtbot, w)


def path(a, b, n=12):
    return [np.asarray(a) + t * (np.asarray(b) - np.asarray(a)) for t in np.linspace(0.0, 1.0, n)]


def test_handle_drags_move_scale_rotate_one_undo_step_each(w, mouse, qtbot):
    drag(w, mouse, qtbot, loop(0.5, (0.0, 0.0)))
    body = w.current_layer
    h = w.canvas.current_handles()
    assert h is not None and tr.hit(h, h.center) == "move" and tr.hit(h, h.knob) == "rotate"
    n = w.doc.undo_stack.count()
    V0 = np.array(w.doc.layer(body).mesh.V)

    drag(w, mouse, qtbot, path(h.center, h.center + [0.3, 0.1]))  # move
    V1 = np.array(w.doc.layer(body).mesh.V)
    d = V1[:, :2] - V0[:, :2]
    assert w.doc.undo_stack.count() == n + 1 and len(w.doc.layers) == 1  # moved, not drawn
    assert np.allclose(d, d[0], atol=1e-12) and np.allclose(d[0], [0.3, 0.1], atol=3 * w.canvas.pixel_size())
    assert w.act_undo.text() == "Undo Move layer"

    h = w.canvas.current_handles()
    opp = h.corners[0]
    drag(w, mouse, qtbot, path(h.corners[2], opp + 1.5 * (h.corners[2] - opp)))  # scale x1.5 about the lower left
    V2 = np.array(w.doc.layer(body).mesh.V)
    s = np.ptp(V2[:, 0]) / np.ptp(V1[:, 0])
    assert abs(s - 1.5) < 0.02 and w.doc.undo_stack.count() == n + 2
    assert np.allclose(V2[:, :2].min(axis=0), V1[:, :2].min(axis=0), atol=1e-9)  # the opposite corner stays
    assert abs(V2[:, 2].max() / V1[:, 2].max() - s) < 1e-9  # heights scale with the part

    h = w.canvas.current_handles()
    c = h.center
    r = np.linalg.norm(h.knob - c)
    arc = [c + r * np.array([np.cos(a), np.sin(a)]) for a in np.radians(np.linspace(90.0, 180.0, 20))]
    drag(w, mouse, qtbot, arc)  # a quarter turn, counter-clockwise
    V3 = np.array(w.doc.layer(body).mesh.V)
    assert w.doc.undo_stack.count() == n + 3
    assert abs(np.ptp(V3[:, 0]) - np.ptp(V2[:, 1])) < 0.03 and abs(np.ptp(V3[:, 1]) - np.ptp(V2[:, 0])) < 0.03
    assert [e["command"] for e in w.doc.journal()[-3:]] == ["transform_layer"] * 3
    # Undo walks the three drags back; the journal replays them bit for bit.
    replayed = Document(host=w.host)
    for entry in w.doc.journal():
        replayed.execute(entry)
    assert replayed.layers[0].mesh.identical(w.doc.layer(body).mesh)
    for _ in range(3):
        w.doc.undo_stack.undo()
    assert np.array_equal(w.doc.layer(body).mesh.V, V0)


def test_alt_drag_cuts_a_hole_and_ctrl_m_mirrors_about_the_host(w, mouse, qtbot):
    drag(w, mouse, qtbot, loop(0.6, (0.0, 0.0), 60))
    body = w.current_layer
    n = w.doc.undo_stack.count()
    drag(w, mouse, qtbot, loop(0.15, (0.25, 0.2)), modifiers=M.AltModifier)
    assert w.doc.undo_stack.count() == n + 1 and len(w.doc.layers) == 1
    assert len(w.doc.layer(body).mesh.holes) == 1 and "cut a hole" in w.statusBar().currentMessage()
    # a leg on the left of the body, then Ctrl+M: the right leg
    t = np.linspace(np.pi, 2 * np.pi, 30)
    leg = np.c_[-0.3 + 0.08 * np.cos(t), -0.3 + 0.6 * np.sin(t)]
    drag(w, mouse, qtbot, leg)
    leg_id = w.current_layer
    x0 = float(np.mean(w.doc.layer(leg_id).points[:, 0]))
    w.mirror_layer(leg_id)
    wait_idle(qtbot, w)
    x1 = float(np.mean(w.doc.layer(leg_id).points[:, 0]))
    assert x0 < -0.2 and abs(x1 + x0) < 0.02, (x0, x1)
    assert "host's axis" in w.statusBar().currentMessage()
