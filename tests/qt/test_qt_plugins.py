"""Everything a plugin adds is usable in the app (issue 37): the Creation panel chooses the
inflater, every solver's parameters are a form generated from what it declares (inflater,
sculpt solver, assembler; no plugin writes Qt for them), Help > Plugins lists every plugin with
its problems once each, and a reflectance model shades the canvas with its own R(n, l)."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtWidgets import QApplication, QComboBox, QDoubleSpinBox, QLineEdit, QSpinBox
from qt_helpers import circle, wait_idle
from third_party_solvers import ThirdPartySolvers

from sketchforge.document.document import Document
from sketchforge.plugin_api import Exporter, hookimpl
from sketchforge.plugins.testing import make_host


@pytest.fixture(scope="module")
def solvers_host():
    pytest.importorskip("sketchforge_inflate")
    return make_host(ThirdPartySolvers(), installed=("inflate", "isophote_tool", "assemble", "soft_brdf"))


@pytest.fixture
def w(make_window, solvers_host):
    win = make_window(Document(solvers_host))
    win.activateWindow()
    return win


def loop(r, center, n=40):
    pts = circle(r, n, center)
    return list(pts) + [pts[0]]


def draw(w, mouse, qtbot, pts):
    mouse(w.canvas).drag(list(pts))
    wait_idle(qtbot, w)


def choose(combo: QComboBox, data) -> None:
    combo.setCurrentIndex(combo.findData(data))
    QApplication.processEvents()


def test_the_creation_panel_chooses_the_inflater_and_shows_its_own_parameters(w, mouse, qtbot):
    panel = w.creation_panel
    assert [panel.inflater.itemData(i) for i in range(panel.inflater.count())] == ["poisson", "rings"]
    draw(w, mouse, qtbot, loop(0.5, (0.0, 0.0)))
    first = w.doc.layers[0]
    assert first.solver == "poisson" and set(panel.spins) == {"resolution", "inflation", "smoothing"}
    # Choosing "rings" switches the selected part (one undo step, from rings' defaults)...
    choose(panel.inflater, "rings")
    qtbot.waitUntil(lambda: w.doc.layer(first.id).solver == "rings", timeout=60_000)
    wait_idle(qtbot, w)
    assert w.doc.layer(first.id).solver == "rings" and dict(w.doc.layer(first.id).params) == {"height": 1.0, "rings": 12}
    assert w.doc.undo_stack.count() == 2 and w.act_undo.text() == "Undo Set inflater"
    # ...and the form is rings' own, generated from its declared checks: ranges and defaults.
    height, rings = panel.spins["height"], panel.spins["rings"]
    assert isinstance(height, QDoubleSpinBox) and (height.minimum(), height.maximum(), height.value()) == (0.0, 100.0, 1.0)
    assert isinstance(rings, QSpinBox) and (rings.minimum(), rings.maximum(), rings.value()) == (2, 200, 12)
    assert "range: 2 <= rings <= 200" in rings.toolTip()
    rings.setValue(5)  # an edit is a set_inflate_params of that inflater's parameter
    qtbot.waitUntil(lambda: w.doc.layer(first.id).params["rings"] == 5, timeout=60_000)
    wait_idle(qtbot, w)
    mesh = w.doc.layer(first.id).mesh
    assert w.doc.layer(first.id).params["rings"] == 5 and len(mesh.V) == 5 * len(mesh.boundary) + 1
    # A new part is inflated by the inflater chosen.
    draw(w, mouse, qtbot, loop(0.15, (0.8, 0.5)))
    assert len(w.doc.layers) == 2
    new = w.doc.layers[-1]
    assert new.solver == "rings" and w.current_layer == new.id and panel.inflater.currentData() == "rings"
    assert w.act_undo.text() == "Undo Draw layer"
    # Undo brings the first part back to poisson, and the panel shows poisson's form again.
    for _ in range(3):
        w.undo()
        wait_idle(qtbot, w)
    w.layers_panel.select(first.id)
    QApplication.processEvents()
    assert w.doc.layer(first.id).solver == "poisson" and panel.inflater.currentData() == "poisson"
    assert set(panel.spins) == {"resolution", "inflation", "smoothing"}


def test_the_sculpt_solver_s_parameters_are_a_form_and_go_into_the_next_edit(w, qtbot):
    from sketchforge_isophote_tool.qt.panel import IsophoteSculptPanel

    w.set_mode("sculpture")
    panel = w.plugin_panels["isophote_sculpt"]
    assert isinstance(panel, IsophoteSculptPanel)
    form = panel.params
    assert form.solver_name == "gauss_newton" and not form.form.isVisible()  # folded: the box is small
    form.toggle.click()
    assert form.form.isVisible() and form.toggle.text() == "Parameters (7)"
    ring = form.form.widgets["ring"]
    assert form.form.auto["ring"].isChecked() and not ring.isEnabled()  # None: automatic
    steps = form.form.widgets["steps"]
    assert (steps.minimum(), steps.maximum(), steps.value()) == (1, 50, 4)
    steps.setValue(9)
    assert panel.options() == {"params": {"steps": 9}} and w.sculpt.tool.options == {"params": {"steps": 9}}
    assert form.toggle.text() == "Parameters (7, 1 changed)"
    # Another solver shows its own parameters, from its defaults.
    choose(panel.solver, "probe")
    assert form.solver_name == "probe" and set(form.widgets) == {"radius", "amplitudes"}
    assert panel.options() == {"solver": "probe"}
    form.widgets["amplitudes"].setValue(3)
    assert w.sculpt.tool.options == {"solver": "probe", "params": {"amplitudes": 3}}


def test_a_tolerance_is_typed_in_scientific_notation(make_window):
    pytest.importorskip("sketchforge_strips")
    host = make_host(installed=("inflate", "isophote_tool", "strips"))
    win = make_window(Document(host))
    panel = win.plugin_panels["isophote_sculpt"]
    choose(panel.solver, "strips")
    rtol = panel.params.widgets["rtol"]
    assert isinstance(rtol, QLineEdit) and float(rtol.text()) == 1e-6
    rtol.setText("1e-7")
    rtol.editingFinished.emit()
    assert win.sculpt.tool.options == {"solver": "strips", "params": {"rtol": 1e-7}}
    assert isinstance(panel.params.widgets["integrator"], QComboBox)


def test_the_assembly_panel_is_the_assembler_s_form_and_each_edit_one_undo_step(w, qtbot):
    w.set_mode("observation")
    panel = w.assembly_panel
    assert panel.isVisibleTo(w.observe_page) and panel.assembler.currentData() == "depth_qp"
    fillet = panel.params.widgets["fillet"]
    solver = panel.params.widgets["qp_solver"]
    assert isinstance(solver, QComboBox) and [solver.itemText(i) for i in range(solver.count())] == ["osqp", "active_set"]
    fillet.setValue(2.0)
    assert dict(w.doc.assembly.params) == {"fillet": 2.0} and w.act_undo.text() == "Undo Set assembly"
    solver.setCurrentIndex(1)
    assert dict(w.doc.assembly.params) == {"fillet": 2.0, "qp_solver": "active_set"}
    w.undo()
    QApplication.processEvents()
    assert dict(w.doc.assembly.params) == {"fillet": 2.0} and solver.currentText() == "osqp"
    assert fillet.value() == 2.0


class ClashingFormats:
    """Two plugins claiming the suffix .xyz: the host names both, the app lists it under each."""

    def __init__(self, tag):
        self.__name__ = f"formats_{tag}"

    @hookimpl
    def sketchforge_exporters(self):
        return [Exporter(f"xyz_{self.__name__}", (".xyz",), lambda path, mesh: None)]


class RaisingTools:
    __name__ = "raising_tools"

    @hookimpl
    def sketchforge_tools(self):
        raise RuntimeError("the tool plugin is half installed")


def test_help_plugins_lists_every_plugin_and_each_problem_once_and_the_button_stays(make_window, qtbot, capsys):
    from sketchforge.plugins.inventory import format_inventory, plugin_inventory

    host = make_host(ClashingFormats("a"), ClashingFormats("b"), RaisingTools(), installed=("inflate",))
    win = make_window(Document(host))
    clash = ("plugins 'formats_a' and 'formats_b' both write '.xyz' (exporters 'xyz_formats_a' and 'xyz_formats_b'): "
             "error, neither is used for '.xyz' until one of them is uninstalled (or left out with SKETCHFORGE_PLUGINS)")
    disabled = "plugin 'raising_tools' disabled: its sketchforge_tools hook raised RuntimeError: the tool plugin is half installed"
    assert sorted(host.problems) == sorted([clash, disabled])
    assert win.problems_button.isVisible() and win.problems_button.text() == "⚠ 2 plugin problems"
    win.statusBar().showMessage("something else")  # a later message replaces the status line...
    assert win.problems_button.isVisible()  # ...not the button
    win.problems_button.click()
    dialog = win.plugins_dialog
    rows = {dialog.tree.topLevelItem(i).text(0): dialog.tree.topLevelItem(i) for i in range(dialog.tree.topLevelItemCount())}
    assert list(rows)[:2] == ["sketchforge-core", "formats_a"] and "raising_tools" in rows and "inflate" in rows
    assert rows["raising_tools"].text(2).startswith("disabled")
    # Each problem once, in full; every plugin it names refers to it.
    assert sorted(dialog.problem_lines()) == sorted([clash, disabled])
    n = dialog.problem_lines().index(clash) + 1
    assert dialog.problem_refs("formats_a") == dialog.problem_refs("formats_b") == f"problem {n} (below)"
    assert dialog.problem_refs("inflate") == ""
    inflate = rows["inflate"]
    assert [(inflate.child(i).text(0), inflate.child(i).text(2)) for i in range(inflate.childCount())] == [
        ("inflaters", "poisson")]
    assert rows["inflate"].text(1) and rows["sketchforge-core"].text(1)  # versions
    # The CLI's list is the same inventory.
    lines = format_inventory(plugin_inventory(host))
    assert sum(clash in line for line in lines) == 1 and lines[-3] == "2 problems:"
    dialog.close()


def test_a_reflectance_model_shades_the_canvas_with_its_own_definition(w, mouse, qtbot):
    from sketchforge.geometry.model_shading import model_shader

    draw(w, mouse, qtbot, loop(0.5, (0.0, 0.0)))
    panel = w.creation_panel
    keys = [panel.shader.itemData(i) for i in range(panel.shader.count())]
    assert keys == ["lambert", "cel", "model:lambertian", "model:soft_lambert"]
    assert panel.shader.itemText(3) == "soft_lambert (reflectance model)"
    w.canvas.render_now()
    lambert = w.canvas.scene_item.pixels().copy()
    panel.shader.setCurrentIndex(3)
    QApplication.processEvents()
    soft = w.canvas.scene_item.pixels().copy()
    assert w.canvas.shader_name == "model:soft_lambert" and not np.array_equal(lambert, soft)
    # Where one fragment fills a pixel (no outline, no other layer), its colour is the model's
    # own R(n, l) of that pixel's normal: clay * (0.3 + 0.7 clip(R, 0, 1)).
    g = w.canvas._gbuf
    model = w.doc.host.reflectance_models["soft_lambert"]
    l = np.asarray(w.doc.light.direction)
    plain = (g.alpha >= 0.999) & ~np.isin(g.pix, g.stack_pixels) & ~np.isin(g.pix, g.edge_pix)
    assert plain.sum() > 1000
    want = np.clip(model_shader(model).shade(g.normal[plain], l) * 255.0 + 0.5, 0, 255).astype(int)
    got = soft.reshape(-1, 4)[g.pix[plain]][:, [2, 1, 0]].astype(int)
    assert np.abs(got - want).max() <= 1
    c = g.normal[plain].astype(np.float64) @ l
    mid = (c > 0.2) & (c < 0.8)  # soft Lambert 0.6c + 0.4c³ is darker than Lambert there
    darker = soft.reshape(-1, 4)[g.pix[plain]][mid, 2].astype(int) < lambert.reshape(-1, 4)[g.pix[plain]][mid, 2]
    assert darker.mean() > 0.95
