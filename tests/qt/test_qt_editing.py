"""The editing view, driven as a person would: mouse gestures on the drawing region, buttons,
menus and shortcuts. Offscreen; no OpenGL."""

from __future__ import annotations

import math

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtGui import QColor
from qt_helpers import circle, wait_idle

from sketchforge.document import commands as C


def draw_circle(window, mouse, qtbot, radius=0.5, center=(0.0, 0.0), n=48, modifiers=Qt.KeyboardModifier.NoModifier):
    pts = circle(radius, n, center)
    mouse(window.canvas).drag(list(pts) + [pts[0]], modifiers=modifiers)
    wait_idle(qtbot, window)
    return pts


def needs_inflate(host):
    if host.inflate(circle(0.5, 24), True, {"resolution": 0.1, "inflation": 1.0, "smoothing": 0.0}) is None:
        pytest.skip("no inflate plugin is installed")


def test_view_y_axis_points_up(make_window):
    w = make_window()
    top, bottom = w.canvas.doc_to_widget((0.0, 1.0)), w.canvas.doc_to_widget((0.0, -1.0))
    assert top.y() < bottom.y()  # document y up = screen up
    left, right = w.canvas.doc_to_widget((-1.0, 0.0)), w.canvas.doc_to_widget((1.0, 0.0))
    assert left.x() < right.x()
    # and back: a pixel maps to the point it was aimed at
    p = w.canvas.widget_to_doc(w.canvas.doc_to_widget((0.3, 0.7)))
    assert np.allclose(p, (0.3, 0.7), atol=2 * pixel_size(w))


def pixel_size(w) -> float:
    return 1.0 / (w.canvas.doc_to_widget((1, 0)).x() - w.canvas.doc_to_widget((0, 0)).x())


def test_draw_contour_makes_a_layer_with_a_mesh_and_one_undo_step(make_window, mouse, qtbot, host):
    needs_inflate(host)
    w = make_window()
    pts = draw_circle(w, mouse, qtbot, 0.4, center=(0.3, 0.45))
    doc = w.doc
    assert len(doc.layers) == 1
    layer = doc.layers[0]
    assert layer.mesh is not None and layer.mesh.n_faces > 50
    # the stroke arrived where it was drawn (to a pixel), not mirrored
    tol = 1.5 * pixel_size(w)
    assert np.max(np.abs(layer.points[: len(pts)] - pts)) < tol
    assert layer.mesh.V[:, 1].mean() > 0.3  # upper half of the drawing
    # and it is drawn in the upper right of the view: shaded pixels there, none lower left
    img = w.canvas.grab().toImage()
    c = w.canvas.doc_to_widget((0.3, 0.45))
    assert QColor(img.pixel(int(c.x()), int(c.y()))) != w.canvas.backgroundBrush().color()
    m = w.canvas.doc_to_widget((-0.3, -0.45))
    assert QColor(img.pixel(int(m.x()), int(m.y()))).name() == QColor(242, 240, 236).name()
    # one undo step names the command
    assert doc.undo_stack.count() == 1
    assert w.act_undo.text() == "Undo Draw layer"
    assert w.layers_panel.current_id() == layer.id


def test_ctrl_drag_redraws_the_whole_contour_of_the_selected_layer(make_window, mouse, qtbot, host):
    needs_inflate(host)
    w = make_window()
    draw_circle(w, mouse, qtbot, 0.4)
    first = w.doc.layers[0].mesh
    draw_circle(w, mouse, qtbot, 0.3, center=(0.2, 0.0), modifiers=Qt.KeyboardModifier.ControlModifier)
    assert len(w.doc.layers) == 1
    assert w.doc.layers[0].mesh is not first
    assert w.act_undo.text() == "Undo Draw contour"


def test_redraw_warns_when_the_layer_has_sculpt_edits(make_window, mouse, qtbot, host, dialogs):
    needs_inflate(host)
    w = make_window()
    draw_circle(w, mouse, qtbot, 0.4)
    layer = w.doc.layers[0]
    # pretend the layer was sculpted (the warning only looks at the edits list)
    w.doc._replace_layer(layer.evolve(edits=({"command": "sculpt_isophote"},)))
    dialogs.answers = [pytest.importorskip("PySide6.QtWidgets").QMessageBox.StandardButton.No]
    before = w.doc.layers[0]
    draw_circle(w, mouse, qtbot, 0.3, modifiers=Qt.KeyboardModifier.ControlModifier)
    assert len(dialogs.of("question")) == 1
    assert w.doc.layers[0] is before  # declined: nothing changed


def test_light_drag_sets_the_direction_in_one_undo_step(make_window, mouse, qtbot, host):
    needs_inflate(host)
    w = make_window()
    draw_circle(w, mouse, qtbot, 0.5)
    w.canvas.render_now()
    shown_before = w.canvas.scene_item.pixels().copy()
    gbuf = w.canvas._gbuf
    count = w.doc.undo_stack.count()

    qtbot.mouseClick(w.modes.light, Qt.MouseButton.LeftButton)
    assert w.canvas.interaction == "light"
    center = w.canvas.view_center()
    # drag around to the lower left: angle atan2(-0.6, -0.3) from the centre of the view
    path = [center + d for d in ([0.2, 0.1], [0.4, -0.3], [-0.1, -0.5], [-0.3, -0.6])]
    mouse(w.canvas).drag(path)
    expected = math.degrees(math.atan2(path[-1][1] - center[1], path[-1][0] - center[0]))
    got = w.doc.light.angle
    assert abs((got - expected + 180) % 360 - 180) < 1.0
    assert w.doc.undo_stack.count() == count + 1  # the whole drag is one step
    assert w.act_undo.text() == "Undo Set light"
    assert len(w.doc.layers) == 1  # a light drag never draws
    # shading followed, from the same per-pixel buffer (a light drag never rasterises again)
    assert w.canvas._gbuf is gbuf
    changed = np.any(w.canvas.scene_item.pixels() != shown_before, axis=2)
    assert changed.mean() > 0.05
    # the layer's thumbnail follows once the light rests (not on every step of the drag)
    thumb = w.layers_panel.list.item(0).icon().pixmap(48, 48).toImage()
    qtbot.waitUntil(lambda: w.layers_panel.list.item(0).icon().pixmap(48, 48).toImage() != thumb, timeout=2000)
    assert abs(w.light_panel.angle.value() - round(got, 1)) < 0.051
    w.undo()
    assert w.doc.undo_stack.count() == count + 1 and w.doc.undo_stack.index == count
    w.canvas.render_now()
    np.testing.assert_array_equal(w.canvas.scene_item.pixels(), shown_before)


def test_ctrl_z_and_ctrl_shift_z(make_window, mouse, qtbot, host):
    needs_inflate(host)
    w = make_window()
    draw_circle(w, mouse, qtbot, 0.4)
    w.activateWindow()
    qtbot.waitActive(w)
    qtbot.keyClick(w, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert len(w.doc.layers) == 0
    assert w.act_redo.text() == "Redo Draw layer"
    qtbot.keyClick(w, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert len(w.doc.layers) == 1
    qtbot.keyClick(w, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    qtbot.keyClick(w, Qt.Key.Key_Y, Qt.KeyboardModifier.ControlModifier)
    assert len(w.doc.layers) == 1 and w.doc.layers[0].mesh is not None


def test_history_panel_mirrors_the_undo_stack(make_window, qtbot):
    w = make_window()
    w.add_layer()
    w.add_layer()
    w.push(C.RenameLayer(layer="layer1", new_name="Body"))
    h = w.history_panel
    assert h.count() == w.doc.undo_stack.count() + 1
    assert [h.item(i).text() for i in range(1, h.count())] == ["Add layer", "Add layer", "Rename layer"]
    assert h.currentRow() == 3
    h.setCurrentRow(1)  # click: back to after the first command
    assert w.doc.undo_stack.index == 1 and w.doc.layer_ids() == ["layer1"]
    w.undo()
    assert h.currentRow() == 0


def test_title_marks_unsaved_changes(make_window, tmp_path):
    w = make_window()
    assert not w.isWindowModified()
    w.add_layer()
    assert w.isWindowModified() and "[*]" in w.windowTitle()
    assert w.save_to(tmp_path / "a.json")
    assert not w.isWindowModified()
    assert w.windowTitle().startswith("a.json")
    w.undo()
    assert w.isWindowModified()


def test_save_reopen_same_document(make_window, mouse, qtbot, host, tmp_path):
    needs_inflate(host)
    w = make_window()
    draw_circle(w, mouse, qtbot, 0.45)
    w.push(C.SetLight(direction=[0.0, 1.0, 0.0]))
    w.push(C.RenameLayer(layer=w.doc.layers[0].id, new_name="Blob"))
    path = tmp_path / "blob.json"
    assert w.save_to(path)
    w2 = make_window()
    assert w2.open_path(path)
    assert w2.doc.same_state(w.doc)
    assert w2.doc.journal() == w.doc.journal()
    assert not w2.isWindowModified()
    assert str(path.resolve()) in w2.recent_files()
    assert w2.layers_panel.list.item(0).text() == "Blob"


def test_corrupt_file_shows_an_error_and_keeps_the_open_document(make_window, tmp_path, dialogs):
    w = make_window()
    w.add_layer()
    w.push(C.RenameLayer(layer="layer1", new_name="Keep me"))
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "sketchforge", "version": 1, "journal": [{"command": "add_layer", "id": 5}]')
    assert not w.open_path(bad, ask=False)
    (kind, title, text) = dialogs.of("critical")[-1]
    assert "bad.json" in text
    assert w.doc.layer_ids() == ["layer1"] and w.doc.layers[0].name == "Keep me"
    assert w.doc.undo_stack.count() == 2  # the history survives too
    assert w.path is None


def test_command_errors_show_a_dialog_and_change_nothing(make_window, dialogs, mouse, qtbot):
    w = make_window()
    w.add_layer()
    before = w.doc.layers[0]
    assert not w.push(C.RenameLayer(layer="layer1", new_name="   "))
    assert dialogs.of("critical") and "empty" in dialogs.of("critical")[-1][2]
    assert w.doc.layers[0] is before
    # a stroke that cannot become a contour: a slip of the hand, named in the status bar (no
    # dialog to dismiss, issue 38); nothing is added
    n = w.doc.undo_stack.count()
    mouse(w.canvas).drag([(0.0, 0.0), (0.3, 0.0), (0.0, 0.0), (0.3, 0.0)])
    wait_idle(qtbot, w)
    assert w.doc.undo_stack.count() == n
    assert w.doc.layers[0] is before
    assert len(dialogs.of("critical")) == 1
    assert w.statusBar().currentMessage().startswith("the stroke was not drawn: ")


def test_layers_panel_buttons_visibility_rename_and_reorder(make_window, qtbot, mouse, host):
    needs_inflate(host)
    w = make_window()
    draw_circle(w, mouse, qtbot, 0.4)
    lp = w.layers_panel
    qtbot.mouseClick(lp.add, Qt.MouseButton.LeftButton)
    assert len(w.doc.layers) == 2 and lp.current_id() == w.doc.layers[1].id
    qtbot.mouseClick(lp.remove, Qt.MouseButton.LeftButton)
    assert len(w.doc.layers) == 1
    lid = w.doc.layers[0].id
    lp.select(lid)
    qtbot.mouseClick(lp.duplicate, Qt.MouseButton.LeftButton)
    assert len(w.doc.layers) == 2 and w.doc.layers[1].mesh is w.doc.layers[0].mesh
    qtbot.mouseClick(lp.mirror, Qt.MouseButton.LeftButton)
    wait_idle(qtbot, w)
    assert w.act_undo.text() == "Undo Mirror layer"
    # visibility: uncheck the bottom row (the back layer)
    item = lp.list.item(1)
    item.setCheckState(Qt.CheckState.Unchecked)
    qtbot.waitUntil(lambda: not w.doc.layers[0].visible)
    assert not w.canvas._layer_items[w.doc.layers[0].id].isVisible()
    # rename by editing the row
    lp.list.item(0).setText("Front")
    qtbot.waitUntil(lambda: w.doc.layers[1].name == "Front")
    # reorder: the top row (front layer) goes to the back
    front = w.doc.layers[1].id
    lp.move_requested.emit(front, 0)
    assert w.doc.layers[0].id == front
    assert lp.list.item(lp.list.count() - 1).data(Qt.ItemDataRole.UserRole) == front
    assert not lp.list.item(0).icon().isNull()


def test_inflation_parameters_apply_to_the_current_layer(make_window, mouse, qtbot, host):
    needs_inflate(host)
    w = make_window()
    draw_circle(w, mouse, qtbot, 0.4)
    zmax = w.doc.layers[0].mesh.V[:, 2].max()
    w.creation_panel.spins["inflation"].setValue(2.0)
    wait_idle(qtbot, w)
    assert w.doc.layers[0].params["inflation"] == 2.0
    assert w.doc.layers[0].mesh.V[:, 2].max() > 1.2 * zmax
    assert w.act_undo.text() == "Undo Set inflation parameters"


def test_unsaved_changes_are_asked_about_on_close(make_window, dialogs):
    from PySide6.QtWidgets import QMessageBox

    w = make_window()
    w.add_layer()
    dialogs.answers = [QMessageBox.StandardButton.Cancel]
    assert not w.close()
    assert w.isVisible()
    dialogs.answers = [QMessageBox.StandardButton.Discard]
    assert w.close()


def test_new_document_after_discarding(make_window, dialogs):
    from PySide6.QtWidgets import QMessageBox

    w = make_window()
    w.add_layer()
    dialogs.answers = [QMessageBox.StandardButton.Discard]
    w.new_document()
    assert w.doc.layers == () and w.doc.undo_stack.count() == 0
    assert w.layers_panel.list.count() == 0 and w.history_panel.count() == 1


def test_sculpture_state_without_the_plugin_says_so(qtbot, tmp_path, mouse, dialogs):
    from PySide6.QtCore import QSettings

    from sketchforge.document.document import Document
    from sketchforge.plugins.testing import make_test_host
    from sketchforge.qt.main_window import MainWindow
    from sketchforge.qt.sculpt import PLUGIN_MISSING

    bare = make_test_host()  # the core plugin only: no isophote tool
    w = MainWindow(Document(host=bare), host=bare, settings=QSettings(str(tmp_path / "s.ini"), QSettings.Format.IniFormat))
    qtbot.addWidget(w)
    w.resize(900, 600)
    w.show()
    qtbot.mouseClick(w.modes.sculpture, Qt.MouseButton.LeftButton)
    assert w.canvas.interaction == "sculpt"
    assert w.controls.currentWidget() is w.sculpt_panel
    assert not w.sculpt.available()
    assert w.sculpt_panel.status.text() == PLUGIN_MISSING
    mouse(w.canvas).click((0.0, 0.0))  # a pick says so too, and edits nothing
    assert w.statusBar().currentMessage() == PLUGIN_MISSING
    assert w.doc.undo_stack.count() == 0
    w.close_now()


def test_observation_without_opengl_explains(make_window):
    w = make_window()
    w.set_mode("observation")
    assert w.center.currentWidget() is w.view3d
    assert w.view3d.gl is None  # offscreen: no GL widget is ever created
    assert "OpenGL" in w.view3d.info.text()
    w.set_mode("editing")
    assert w.center.currentWidget() is w.canvas


def test_reference_image_shows_under_the_drawing_upright(make_window, tmp_path):
    """A reference image lies under the drawing (behind layers), fitted to the view, top row
    up; an unreadable file is a clear error and removes nothing."""
    import numpy as np

    from sketchforge.errors import SketchforgeError
    from sketchforge.geometry.raster import write_png

    rgb = np.zeros((40, 60, 3), np.uint8)
    rgb[:20] = (255, 0, 0)  # top half red, bottom half black
    path = tmp_path / "ref.png"
    write_png(path, rgb)
    w = make_window()
    w.canvas.set_reference_image(str(path))
    item = w.canvas._reference
    assert item is not None and item.zValue() < 0
    rect = item.mapRectToParent(item.boundingRect())
    view = w.canvas.vb.viewRect()
    assert view.contains(rect.center()) and rect.width() <= view.width() + 1e-9
    data = item.image  # [x, y] with y up: the top (largest y) columns hold the red half
    assert data[:, -1, 0].min() == 255 and data[:, 0, 0].max() == 0
    bad = tmp_path / "not_an_image.png"
    bad.write_bytes(b"nope")
    try:
        w.canvas.set_reference_image(str(bad))
    except SketchforgeError as exc:
        assert "cannot read the image" in str(exc)
        assert w.canvas._reference is item  # the previous image stays
    else:
        raise AssertionError("an unreadable image must be an error")


def test_closed_checkbox_shows_the_selected_layers_kind(make_window, host):
    """Selecting a closed (free) layer shows 'closed outline' checked, an open one unchecked,
    so redrawing keeps the layer's kind by default."""
    import json
    from pathlib import Path

    from sketchforge.document import fileformat as ff

    data = json.loads((Path(__file__).resolve().parents[2] / "examples" / "toucan.json").read_text())
    doc = ff.document_from_dict(data, "toucan", host=host)
    w = make_window(doc)
    for lid, closed in (("eye", True), ("beak", False), ("body", True)):
        w.layers_panel.select(lid)
        assert w.current_layer == lid
        assert w.creation_panel.closed.isChecked() is closed
