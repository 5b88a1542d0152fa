"""The animation front end: pin gestures become undoable commands, recording runs in sync with
the loop, posing runs on a worker thread; picking maths is checked without OpenGL."""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge.document.document import Document

pytest.importorskip("sketchforge_animate")

from qt_helpers import GL_WINDOW_PRELUDE  # noqa: E402

from sketchforge_animate import Animation  # noqa: E402
from sketchforge_animate.picking import pick_vertex, project, unproject_at_depth  # noqa: E402

BLOB = [[np.cos(t), 0.5 * np.sin(t)] for t in np.linspace(0, 2 * np.pi, 40, endpoint=False)]


def settle(ctl, qtbot):
    """Wait until the pose worker has nothing left to do and its last result arrived."""
    qtbot.waitUntil(lambda: ctl.worker._pending is None and not ctl.worker.busy, timeout=30000)
    qtbot.wait(50)
    return ctl._pose


@pytest.fixture
def ctl(qtbot, host):
    from sketchforge_animate.qt import AnimationController

    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": BLOB, "closed": True})
    doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"resolution": 0.08}})
    c = AnimationController(doc, doc.push)
    with qtbot.waitSignal(c.pose_ready, timeout=20000):
        c.set_mesh(doc.export_mesh())
    yield c
    c.shutdown()


def test_pins_drag_and_record_become_commands(ctl, qtbot):
    doc, V = ctl.doc, ctl.mesh.V
    left, right = V[np.argmin(V[:, 0])], V[np.argmax(V[:, 0])]
    with qtbot.waitSignal(ctl.pose_ready, timeout=20000):
        ctl.add_pin(left)
    ctl.add_pin(right)
    assert [p.id for p in Animation.of(doc).pins] == ["pin1", "pin2"] and ctl.selected == "pin2"
    # a pose drag: live solves on the worker, one command at the end
    n = len(doc.journal())
    ctl.begin_drag("pin2")
    for k in range(1, 6):
        ctl.drag_to(right + [0, 0.05 * k, 0])
    ctl.end_drag()
    assert len(doc.journal()) == n + 1 and doc.journal()[-1]["command"] == "move_pin"
    P = settle(ctl, qtbot)
    assert P.shape == V.shape and np.abs(P - V).max() > 0.1  # the model follows the pin
    # recording: one sample per tick, the first recording defines the loop and playback starts
    ctl.begin_drag("pin1", record=True)
    for k in range(30):
        ctl.drag_to(left + [0.1 * np.sin(k / 5), 0, 0])
        ctl._tick()
    ctl.end_drag()
    anim = Animation.of(doc)
    assert anim.loop == 30 and ctl.playing
    # a later recording starts at the current loop frame (in sync with the first)
    ctl.playing = False
    ctl._sync_timer()
    ctl.set_frame(10)
    ctl.begin_drag("pin2", record=True)
    for k in range(5):
        ctl.drag_to(right + [0, 0.1, 0.01 * k])
        ctl._tick()
    ctl.end_drag()
    assert doc.journal()[-1]["command"] == "record_motion" and doc.journal()[-1]["start"] == 10
    # pin in place, copy/paste, remove: each one undo step
    ctl.selected = "pin1"
    ctl.copy_motion()
    ctl.selected = "pin2"
    ctl.paste_motion()
    assert doc.journal()[-1]["command"] == "copy_motion"
    ctl.hold_selected()
    assert Animation.of(doc).pin("pin2").motion is None
    ctl.remove_selected()
    assert [p.id for p in Animation.of(doc).pins] == ["pin1"]
    doc.undo_stack.undo()
    assert [p.id for p in Animation.of(doc).pins] == ["pin1", "pin2"]


def test_window_exports_the_animation_off_the_gui_thread(make_window, host, qtbot, tmp_path):
    from sketchforge_animate.gltf import read_glb

    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": BLOB, "closed": True})
    doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"resolution": 0.08}})
    V = doc.export_mesh().V
    doc.execute({"command": "add_pin", "id": "a", "at": V[np.argmin(V[:, 0])].tolist()})
    right = V[np.argmax(V[:, 0])]
    doc.execute({"command": "add_pin", "id": "b", "at": right.tolist()})
    wave = [(right + [0.0, 0.2 * np.sin(2 * np.pi * k / 12), 0.0]).tolist() for k in range(12)]
    doc.execute({"command": "record_motion", "pin": "b", "start": 0, "samples": wave})
    w = make_window(doc)
    assert "animation" in w.plugin_panels  # the panel is there when the plugin is installed
    out = tmp_path / "a.glb"
    assert w.export_to(out)
    qtbot.waitUntil(lambda: not w.jobs.running(), timeout=60000)
    qtbot.waitUntil(out.exists, timeout=5000)
    gltf, _ = read_glb(out.read_bytes())
    assert len(gltf["meshes"][0]["primitives"][0]["targets"]) == 11  # a 12-frame loop


def test_picking_projects_and_unprojects():
    # a simple perspective camera looking down -z from z = 5
    f = 2.0
    proj = np.array([[f, 0, 0, 0], [0, f, 0, 0], [0, 0, -1.02, -0.202], [0, 0, -1, 0]])
    view = np.eye(4)
    view[2, 3] = -5.0
    mvp = proj @ view
    P = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.5, 0.0]])
    px, depth = project(mvp, P, (400, 400))
    assert np.allclose(px[0], [200, 200]) and depth[1] < depth[0]
    assert pick_vertex(mvp, P, (400, 400), (201, 199)) == 1  # the nearer of two on one ray
    assert pick_vertex(mvp, P, (400, 400), (10, 10)) is None
    q = unproject_at_depth(mvp, P[2], (400, 400), px[2])
    assert np.allclose(q, P[2])
    moved = unproject_at_depth(mvp, P[2], (400, 400), px[2] + [40, 0])
    assert abs(moved[2] - P[2][2]) < 1e-9 and moved[0] > P[2][0]  # same depth, moved right


GL_SCRIPT = GL_WINDOW_PRELUDE.format(size=(1100, 760)) + r"""
import time
import numpy as np
from PySide6.QtCore import QPoint, Qt
from PySide6.QtTest import QTest
from sketchforge_animate import Animation
from sketchforge_animate.picking import project
w.set_mode("observation")
settle(w, app)
panel = w.plugin_panels["animation"]
ctl = panel.c

def wait_pose(timeout=90):
    t = time.monotonic()
    while time.monotonic() - t < timeout:
        app.processEvents()
        if ctl.worker._pending is None and not ctl.worker.busy and ctl._pose is not None:
            for _ in range(5):
                app.processEvents()
                time.sleep(0.02)
            if ctl.worker._pending is None and not ctl.worker.busy:
                return
        time.sleep(0.02)
    raise SystemExit("no pose arrived")

wait_pose()
assert w.view3d.model_item is not None
inter = [c for c in w.view3d.children() if type(c).__name__ == "PinInteraction"][0]
panel.pins.setChecked(True)
gl = w.view3d.gl
size = (gl.width(), gl.height())
mvp = inter._mvp()
P = ctl._pose
px, _ = project(mvp, P, size)
k = int(np.argmin(np.hypot(P[:, 0], P[:, 1]) - 0.01 * P[:, 2]))  # the belly, facing us
n0 = len(Animation.of(w.doc).pins)
QTest.mouseClick(gl, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, QPoint(int(px[k, 0]), int(px[k, 1])))
settle(w, app)
wait_pose()
assert len(Animation.of(w.doc).pins) == n0 + 1, "a click on the model adds a pin"
ids, T = ctl.pin_positions()
tp, _ = project(mvp, T, size)
i = ids.index("pin1")
a = QPoint(int(tp[i, 0]), int(tp[i, 1]))
n = len(w.doc.journal())
QTest.mousePress(gl, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, a)
assert ctl._drag is not None and ctl._drag["pin"] == "pin1", "a press on a pin starts a drag"
for d in range(5, 45, 5):
    QTest.mouseMove(gl, QPoint(a.x() + d, a.y() - d))
    app.processEvents()
QTest.mouseRelease(gl, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, QPoint(a.x() + 40, a.y() - 40))
settle(w, app)
wait_pose()
assert len(w.doc.journal()) == n + 1 and w.doc.journal()[-1]["command"] == "move_pin", w.doc.journal()[-1]
moved = np.array(Animation.of(w.doc).pin("pin1").target) - np.array(Animation.of(w.doc).pin("pin1").rest)
assert np.linalg.norm(moved) > 0.05, moved
grab_window(w, sys.argv[2])
print("ok", n0, np.linalg.norm(moved))
w.close_now()
"""


@pytest.mark.gl
def test_pins_are_added_and_dragged_with_the_mouse_in_the_3d_view(tmp_path):
    import os
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    from PySide6.QtGui import QImage

    if not os.environ.get("DISPLAY") or shutil.which("Xvfb") is None:
        pytest.skip("no X server: install Xvfb (pytest-xvfb then provides a display) for OpenGL tests")
    root = Path(__file__).resolve().parents[2]
    out = tmp_path / "anim.png"
    proc = subprocess.run(
        [sys.executable, "-c", GL_SCRIPT, str(root / "examples" / "animated.json"), str(out)],
        cwd=root, env=dict(os.environ, QT_QPA_PLATFORM="xcb"), capture_output=True, text=True, timeout=240,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "ok" in proc.stdout
    assert not QImage(str(out)).isNull()
