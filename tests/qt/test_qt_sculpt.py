"""SCULPTURE driven with the mouse: pick, band, stroke; the edit must equal the headless
``sculpt_isophote`` command given the same document-space inputs (this catches axis flips
between the view and the document)."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QApplication
from qt_helpers import wait_idle

from sketchforge.document import fileformat as ff
from sketchforge.document.document import Document

COMMAND = "sculpt_isophote"


def ellipse_doc(host) -> Document:
    t = np.linspace(0.0, 2 * np.pi, 96, endpoint=False)
    journal = [
        {"command": "add_layer", "id": "blob", "name": "Blob"},
        {"command": "set_contour", "layer": "blob", "points": np.c_[0.8 * np.cos(t), 0.55 * np.sin(t)].tolist(), "closed": True},
        {"command": "set_inflate_params", "layer": "blob", "params": {"resolution": 0.05}},
        {"command": "set_light", "direction": [1.0, 0.0, 0.0]},
    ]
    return ff.document_from_dict({"format": "sketchforge", "version": 1, "light": [1.0, 0.0, 0.0], "journal": journal}, host=host)


def test_pick_shows_the_isophote_and_band_and_the_wheel_changes_the_radius(make_window, mouse, host):
    if host.inflate(np.c_[np.cos(np.arange(8)), np.sin(np.arange(8))], True, {}) is None:
        pytest.skip("no inflate plugin is installed")
    w = make_window(ellipse_doc(host))
    w.canvas.fit()
    w.modes.sculpture.setChecked(True)
    m = mouse(w.canvas)
    pixel, pick = m.aim((0.35, 0.1))
    m.click_pixel(pixel)
    assert w.sculpt.layer_id == "blob"
    assert np.array_equal(w.sculpt.pick_point, pick)
    assert not w.canvas.overlays["isophote"].is_empty()
    assert not w.canvas.overlays["band"].is_empty()
    # with the light along +x the isophote through x = 0.35 stays on the right half
    iso = np.asarray(w.sculpt._isophote)
    assert iso[:, 0].min() > 0.0
    r = w.sculpt.radius
    m.wheel((0.35, 0.1), 2)
    assert w.sculpt.radius > r
    assert abs(w.plugin_panels["isophote_sculpt"].spin.value() - w.sculpt.radius) < 1e-3
    assert w.doc.undo_stack.count() == 0  # picking edits nothing


def test_pick_and_stroke_equal_the_headless_command(make_window, mouse, qtbot, host):
    if COMMAND not in host.commands.names():
        pytest.skip("the isophote tool plugin (command 'sculpt_isophote') is not installed yet")
    doc = ellipse_doc(host)
    before = ff.document_from_dict(ff.document_to_dict(doc), host=host)  # the state the edit starts from
    w = make_window(doc)
    w.canvas.fit()
    w.modes.sculpture.setChecked(True)
    w.plugin_panels["isophote_sculpt"].spin.setValue(0.15)
    m = mouse(w.canvas)
    pick_px, pick = m.aim((0.3, 0.05))
    m.click_pixel(pick_px)
    assert w.sculpt.layer_id == "blob"
    # redraw the isophote a little to the right, bottom to top (points > 10 px apart so the
    # first move starts the drag)
    aimed = [m.aim((0.36, y)) for y in np.linspace(-0.3, 0.3, 9)]
    m.drag_pixels([p for p, _ in aimed])
    wait_idle(qtbot, w, timeout=120_000)
    assert w.doc.undo_stack.count() == 1, w.sculpt.status
    assert w.act_undo.text().startswith("Undo ")
    stroke = np.array([d for _, d in aimed])

    cls = host.command_class(COMMAND)
    before.push(cls.from_dict({"command": COMMAND, "layer": "blob", "pick": pick.tolist(), "band": 0.15, "stroke": stroke.tolist()}))
    got, want = w.doc.layer("blob").mesh, before.layer("blob").mesh
    assert got.F.shape == want.F.shape
    assert np.allclose(got.V, want.V, rtol=0, atol=1e-9)
    assert not np.allclose(got.V, ff.document_from_dict(ff.document_to_dict(ellipse_doc(host)), host=host).layer("blob").mesh.V)

    # Ctrl+Z restores the inflated mesh
    w.activateWindow()
    qtbot.waitActive(w)
    qtbot.keyClick(w, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert np.array_equal(w.doc.layer("blob").mesh.V, ellipse_doc(host).layer("blob").mesh.V)


def _picked(make_window, mouse, host):
    """A window on the ellipse in SCULPTURE, band 0.15, the isophote through (0.3, 0.05) picked."""
    if COMMAND not in host.commands.names():
        pytest.skip("the isophote tool plugin is not installed")
    w = make_window(ellipse_doc(host))
    w.canvas.fit()
    w.modes.sculpture.setChecked(True)
    w.plugin_panels["isophote_sculpt"].spin.setValue(0.15)
    m = mouse(w.canvas)
    m.click_pixel(m.aim((0.3, 0.05))[0])
    return w, m


def _press_and_move(m, pixels):
    """A stroke drawn through ``pixels`` and not released yet."""
    from PySide6.QtCore import QEvent

    L, N = Qt.MouseButton.LeftButton, Qt.MouseButton.NoButton
    m._send(QEvent.Type.MouseMove, pixels[0], N, N)
    m._send(QEvent.Type.MouseButtonPress, pixels[0], L, L)
    for p in pixels[1:]:
        m._send(QEvent.Type.MouseMove, p, N, L)


def test_live_preview_while_drawing_then_cancel_or_apply(make_window, mouse, qtbot, host):
    """While the stroke is drawn the picked layer shows the previewed surface (computed off the
    GUI thread, the document untouched); cancelling drops it, releasing applies the edit."""
    from PySide6.QtCore import QEvent

    w, m = _picked(make_window, mouse, host)
    original = w.doc.layer("blob").mesh
    item = w.canvas._layer_items["blob"]
    pixels = [m.aim((0.36, y))[0] for y in np.linspace(-0.3, 0.3, 9)]
    _press_and_move(m, pixels)
    L, N = Qt.MouseButton.LeftButton, Qt.MouseButton.NoButton
    qtbot.waitUntil(lambda: w.sculpt.preview_result is not None and w.sculpt._preview_job is None, timeout=60_000)
    assert "preview" in w.sculpt.status
    assert item._mesh is not original and not np.array_equal(item._mesh.V, original.V)
    assert w.doc.undo_stack.count() == 0 and w.doc.layer("blob").mesh is original
    w.act_cancel.trigger()  # Esc
    assert w.sculpt.preview_result is None and item._mesh is original
    m._send(QEvent.Type.MouseButtonRelease, pixels[-1], L, N)  # the cancelled drag's release: nothing
    wait_idle(qtbot, w, timeout=120_000)
    # draw again and release: applied, and the view shows the document's new surface
    m.drag_pixels(pixels)
    wait_idle(qtbot, w, timeout=120_000)
    assert w.doc.undo_stack.count() == 1, w.sculpt.status
    assert "applied" in w.sculpt.status and "edge lengths" in w.sculpt.status
    assert item._mesh is w.doc.layer("blob").mesh


def test_a_second_stroke_previews_what_its_release_applies(make_window, mouse, qtbot, host):
    """Drawing again replaces the last attempt, so its preview must start from the surface
    before that attempt, not from the attempt itself; and a gesture's previews leave no crash
    record behind once they are over."""
    from PySide6.QtCore import QEvent

    w, m = _picked(make_window, mouse, host)
    m.drag_pixels([m.aim((0.36, y))[0] for y in np.linspace(-0.3, 0.3, 9)])
    wait_idle(qtbot, w, timeout=120_000)
    assert w.doc.undo_stack.count() == 1, w.sculpt.status
    pixels = [m.aim((0.33, y))[0] for y in np.linspace(-0.3, 0.3, 9)]
    _press_and_move(m, pixels)
    L, N = Qt.MouseButton.LeftButton, Qt.MouseButton.NoButton
    qtbot.waitUntil(lambda: w.sculpt._preview_job is None and w.sculpt.preview_result is not None, timeout=60_000)
    # the queued latest stroke may still be computing: wait until the preview is for all of it
    qtbot.waitUntil(lambda: w.sculpt._preview_job is None and w.sculpt._preview_pending is None, timeout=60_000)
    previewed = w.sculpt.preview_result.mesh
    m._send(QEvent.Type.MouseButtonRelease, pixels[-1], L, N)
    QApplication.processEvents()
    wait_idle(qtbot, w, timeout=120_000)
    assert w.doc.undo_stack.count() == 1  # replaced, not stacked
    assert np.allclose(w.doc.layer("blob").mesh.V, previewed.V, atol=1e-12)
    qtbot.waitUntil(lambda: w.sculpt._preview_job is None, timeout=60_000)
    QApplication.processEvents()
    assert not w.autosaver.pending_path.exists()
