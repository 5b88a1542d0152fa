"""Issue 30 in the app: an assembly failure shown at once naming the part (point 2), a redraw
that leaves a glued part's junction off its host warned about with an offer to undo (point 3),
inflation off the window's interpreter (point 4), Ctrl+D then Ctrl+M giving the twin (point 8)."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QMessageBox
from qt_helpers import wait_idle

from sketchforge.document import commands as C
from sketchforge.document import fileformat as ff
from sketchforge.document.document import Document

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]


@pytest.fixture
def creature(make_window, host):
    doc = ff.load(ROOT / "examples" / "creature.json", host=host)
    return make_window(doc)


def _shrunk_body(w, f=0.8):
    body = w.doc.layer("body")
    P = np.asarray(body.points)
    c = P.mean(axis=0)
    return body, c + f * (P - c)


# --- point 3: a redraw that leaves a glued part ------------------------------------------------


def test_a_redraw_that_leaves_parts_off_their_host_warns_and_offers_undo(creature, qtbot, dialogs):
    w = creature
    body, pts = _shrunk_body(w)
    assert sorted(w._parts_glued_to(body)) == ["arm_back", "arm_front", "head", "leg_l", "leg_r", "tail"]
    n = w.doc.undo_stack.count()
    dialogs.answers = [QMessageBox.StandardButton.Yes]  # Undo
    w._redraw(body, pts, body.closed, "redrew the outline")
    wait_idle(qtbot, w)
    asked = dialogs.of("question")
    assert len(asked) == 1 and asked[0][1] == "Parts left their host"
    text = asked[0][2]
    # the head's junction now lies on no part; the tail's still lies partly on the body, and that
    # stretch is glued (issue 34), so only the head is named
    assert "“Head”" in text and "free part" in text
    assert "“Left leg”" not in text and "“Tail”" not in text  # still on the body
    # Undone: the body is as it was, the redraw is on the redo side.
    assert w.doc.layer("body") is body and w.doc.undo_stack.count() == n + 1 and w.doc.undo_stack.can_redo()
    assert "glued to it again" in w.statusBar().currentMessage()


def test_keeping_the_redraw_names_the_parts_in_the_status_bar(creature, qtbot, dialogs):
    w = creature
    body, pts = _shrunk_body(w)
    dialogs.answers = [QMessageBox.StandardButton.No]  # Keep
    w._redraw(body, pts, body.closed, "redrew the outline")
    wait_idle(qtbot, w)
    assert w.doc.layer("body") is not body  # kept, one undo step
    msg = w.statusBar().currentMessage()
    assert "“Head”" in msg and "no longer lies on “Body”" in msg and "Ctrl+Z" in msg
    w.undo()
    assert w.doc.layer("body") is body


def test_a_redraw_that_keeps_every_part_on_asks_nothing(creature, qtbot, dialogs):
    w = creature
    body, pts = _shrunk_body(w, 1.02)
    w._redraw(body, pts, body.closed, "redrew the outline")
    wait_idle(qtbot, w)
    assert dialogs.of("question") == [] and w.doc.layer("body") is not body


def test_attachment_follows_the_assembly_rule_both_sides(host):
    doc = ff.load(ROOT / "examples" / "creature.json", host=host)
    # The tail is behind the body, glued to its back face: both find the body.
    assert C.host_of(doc, doc.layer("tail")).id == "body"
    assert C.attachment(doc, doc.layer("tail"))[0].id == "body"
    assert C.attachment(doc, doc.layer("eye")) == (None, None)  # a free part


# --- point 2: the assembly failure shown at once --------------------------------------------------


def test_a_part_that_will_be_free_is_named_at_once_and_the_model_still_assembles(creature, qtbot, monkeypatch):
    # issue 34, point 4: one part that cannot be glued never refuses the model. A copy of the
    # tail left in place (its junction lies where the tail's is glued) is named at once, in a
    # notice, not a failure; the assembly runs, and its result is shown with the same notice.
    w = creature
    w.doc.execute({"command": "duplicate_layer", "layer": "tail", "id": "tail2"})
    v = w.view3d
    v._active = True  # offscreen there is no OpenGL: the view's logic runs all the same
    started = []
    monkeypatch.setattr(
        v.jobs,
        "start",
        lambda *a, **k: (
            started.append(a) or type("J", (), {"done": False, "cancelled": False, "cancel": lambda s: None})()
        ),
    )
    v.refresh()
    assert started, "the assembly is run"
    assert v.failure is None and v.notice and "free part" in v.notice[0] and "Tail copy" in v.notice[0]
    assert v.banner.isVisibleTo(v) and "Assembled, with parts left free" in v.banner.text()
    assert "The assembly failed" not in v.banner.text()
    # the assembler's answer: the model, with the copy free and why
    job, done = started[-1][0], started[-1][1]
    mesh = job()
    assert "tail2" in mesh.free and any("Tail copy" in t for t in mesh.warnings)
    messages = []
    v.message.connect(messages.append)
    done(mesh)
    assert v.failure is None and v.shown and v.shown[0][0] is mesh and v.notice == list(mesh.warnings)
    assert "Tail copy" in v.banner.text()
    # the per-layer view needs no assembly and shows no notice
    v.source = "layers"
    v.refresh()
    assert not v.banner.isVisibleTo(v)


def test_the_assemblers_own_failure_names_the_part_and_a_success_clears_it(creature, qtbot, dialogs):
    w = creature
    v = w.view3d
    v._active = True
    layers = [l for l in w.doc.layers if l.visible]
    from sketchforge_assemble.errors import AttachmentError

    v._fail(str(AttachmentError("The junction of layer 'Tail' runs outside layer 'Body'; redraw it.")), layers)
    assert [m for m, c in v.shown if c == __import__("sketchforge.qt.view3d", fromlist=["x"]).FAILED_COLOUR] == [w.doc.layer("tail").mesh]
    v._set_failure(None)
    assert not v.banner.isVisibleTo(v)


# --- point 4: inflation in a child process ----------------------------------------------------------


def test_the_app_inflates_in_a_child_process_with_the_same_result(make_window, host, qtbot, monkeypatch):
    from PySide6.QtCore import QSettings

    from sketchforge.offload import OffloadedInflation
    from sketchforge.qt.main_window import MainWindow

    doc = Document(host=host)
    w = MainWindow(doc, host=host, settings=QSettings(), offload_inflation=True)
    qtbot.addWidget(w)
    try:
        assert isinstance(doc.host, OffloadedInflation) and doc.host.offloading()
        # Inflating in this process would now fail: the part is still drawn, so it was not.
        monkeypatch.setattr(host, "inflate", lambda *a, **k: (_ for _ in ()).throw(AssertionError("inflated in the window's process")))
        t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
        pts = np.column_stack([np.cos(t), 0.6 * np.sin(t)])
        w.draw_stroke(pts, "front")
        wait_idle(qtbot, w)
        layer = w.doc.layers[-1]
        assert layer.mesh is not None and not layer.mesh.V.flags.writeable
        monkeypatch.undo()
        here = host.inflate(layer.points, layer.closed, dict(layer.params), holes=[])
        assert here.identical(layer.mesh)  # bit for bit the mesh this process would make
    finally:
        w.close_now()


def test_a_host_with_another_inflater_inflates_here(fan_host):
    from sketchforge.offload import OffloadedInflation

    off = OffloadedInflation(fan_host)
    try:
        assert not off.offloading()  # the child's inflate plugin is not this host's
        m = off.inflate(np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]), True, {"resolution": 0.2})
        assert m is not None and off.commands is fan_host.commands
    finally:
        off.shutdown()


def test_big_layers_are_rasterised_and_thumbnailed_off_the_gui_thread(make_window, host, qtbot, monkeypatch):
    import sketchforge.qt.panels.layers_panel as lp
    from sketchforge.qt import canvas as cv

    doc = Document(host=host)
    w = make_window(doc)
    threads = []
    real = lp.thumbnail_pixels
    monkeypatch.setattr(lp, "thumbnail_pixels", lambda *a, **k: threads.append(threading.current_thread().name) or real(*a, **k))
    rasters = []  # (thread, triangles) of every canvas rasterisation
    real_raster = cv.gb.rasterise
    monkeypatch.setattr(cv.gb, "rasterise", lambda meshes, view, *a, **k: rasters.append(
        (threading.current_thread().name, sum(m.n_faces for m in meshes if m is not None))) or real_raster(meshes, view, *a, **k))
    monkeypatch.setattr(cv, "EDIT_RASTER_NOW_FACES", 1000)
    monkeypatch.setattr(lp, "THUMBNAIL_NOW_FACES", 1000)
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    w.draw_stroke(np.column_stack([np.cos(t), 0.6 * np.sin(t)]), "front")
    wait_idle(qtbot, w)
    qtbot.waitUntil(lambda: threads and w.canvas._raster_thread is None, timeout=20_000)
    assert w.doc.layers[-1].mesh.n_faces > 1000
    assert "MainThread" not in threads
    big = [t for t, faces in rasters if faces > 1000]
    assert big and "MainThread" not in big, rasters


# --- point 8: Ctrl+D then Ctrl+M -------------------------------------------------------------------


def test_ctrl_d_then_ctrl_m_gives_the_twin_at_the_mirrored_place(creature, qtbot):
    w = creature
    leg = w.doc.layer("leg_l")
    w.layers_panel.select("leg_l")
    w.activateWindow()
    w.canvas.setFocus()
    qtbot.keyClick(w.canvas, Qt.Key.Key_D, Qt.KeyboardModifier.ControlModifier)
    wait_idle(qtbot, w)
    copy_id = w.current_layer
    assert copy_id != "leg_l"
    qtbot.keyClick(w.canvas, Qt.Key.Key_M, Qt.KeyboardModifier.ControlModifier)
    wait_idle(qtbot, w)
    host, _ = C.attachment(w.doc, leg)
    hp = np.asarray(host.points)
    cx = 0.5 * (hp[:, 0].min() + hp[:, 0].max())
    want = np.array(leg.points)
    want[:, 0] = 2 * cx - want[:, 0]
    assert np.abs(np.asarray(w.doc.layer(copy_id).points) - want).max() < 1e-12
    assert "host's axis" in w.statusBar().currentMessage()
