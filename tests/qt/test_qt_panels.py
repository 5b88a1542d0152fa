"""Plugin panels (``sketchforge_qt_panels``): the window builds each in its place with an
AppContext, sorted by order; a failing one is named and left out; the built-in plugins' panels
(animation, the isophote tool's controls) come the same way, and the sculpt panel's solver
choice reaches the journal."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QSettings
from PySide6.QtWidgets import QLabel
from qt_helpers import wait_idle

from sketchforge.document import commands as C
from sketchforge.document.document import Document
from sketchforge.plugin_api import Panel, SculptSolver, hookimpl
from sketchforge.plugins.testing import FanInflater, make_test_host
from sketchforge.qt.panel_api import BUSY, AppContext


def window_on(host, qtbot, tmp_path, doc=None):
    from sketchforge.qt.main_window import MainWindow

    settings = QSettings(str(tmp_path / "s.ini"), QSettings.Format.IniFormat)
    w = MainWindow(doc if doc is not None else Document(host=host), host=host, settings=settings)
    qtbot.addWidget(w)
    w.resize(1100, 750)
    w.show()
    return w


class ProbePanels:
    """A third-party plugin with a panel in every place (two in SCULPTURE, around the isophote
    tool's order 10), one that is not available, one that raises and one that returns no
    widget."""

    def __init__(self):
        self.contexts: dict[str, AppContext] = {}
        self.events: list = []

    def _make(self, name):
        def create(app):
            self.contexts[name] = app
            return QLabel(f"probe {name}")

        return create

    @hookimpl
    def sketchforge_qt_panels(self):
        def broken(app):
            raise RuntimeError("no gizmo attached")

        def never(app):
            raise AssertionError("an unavailable panel must not be built")

        return [
            Panel("probe_creation", "creation", self._make("probe_creation")),
            Panel("probe_late", "sculpture", self._make("probe_late"), order=20),
            Panel("probe_early", "sculpture", self._make("probe_early"), order=5),
            Panel("probe_observation", "observation", self._make("probe_observation")),
            Panel("probe_off", "observation", never, available=lambda host: False),
            Panel("broken", "sculpture", broken),
            Panel("nothing", "creation", lambda app: None),
        ]


def test_a_plugin_panel_shows_in_its_place_with_an_app_context(qtbot, tmp_path, dialogs):
    probe = ProbePanels()
    host = make_test_host(FanInflater(), probe, entry_points=True, allowlist=["isophote_tool"])
    w = window_on(host, qtbot, tmp_path)
    built = w.plugin_panels
    assert set(built) == {"probe_creation", "probe_late", "probe_early", "probe_observation", "isophote_sculpt"}
    # each in its place
    assert built["probe_creation"].parentWidget() is w.creation_page
    assert built["probe_observation"].parentWidget() is w.observe_page
    obs = w.observe_page.layout()
    assert 0 < obs.indexOf(built["probe_observation"]) < obs.count() - 1  # below the note, above the stretch
    rows = {name: w.sculpt_panel._form.getWidgetPosition(built[name])[0]
            for name in ("probe_early", "isophote_sculpt", "probe_late")}
    status_row = w.sculpt_panel._form.getWidgetPosition(w.sculpt_panel.status)[0]
    assert 0 < rows["probe_early"] < rows["isophote_sculpt"] < rows["probe_late"] < status_row  # by order
    # one context, the window's own pieces
    ctx = probe.contexts["probe_creation"]
    assert all(c is ctx for c in probe.contexts.values()) and isinstance(ctx, AppContext)
    assert ctx.doc is w.doc and ctx.host is host and ctx.canvas is w.canvas and ctx.view3d is w.view3d
    assert ctx.sculpt is w.sculpt
    # the mode and its signal
    seen = []
    ctx.mode_changed.connect(lambda m, s: seen.append((m, s)))
    assert (ctx.mode, ctx.state) == ("editing", "creation")
    w.set_mode("sculpture")
    w.set_mode("observation")
    assert seen == [("editing", "sculpture"), ("observation", "sculpture")] and ctx.mode == "observation"
    w.set_mode("creation")
    assert seen[-1] == ("editing", "creation")
    # commands through the window's runner; a second one while the first runs is refused
    assert ctx.run(C.AddLayer(id="from_panel"), label="Adding")
    assert not ctx.run(C.AddLayer(id="second"), label="Adding")
    assert w.statusBar().currentMessage() == BUSY
    wait_idle(qtbot, w)
    assert w.doc.layer_ids() == ["from_panel"] and w.doc.undo_stack.count() == 1
    ctx.show_message("hello from a panel")
    assert w.statusBar().currentMessage() == "hello from a panel"
    closed = []
    ctx.closing.connect(lambda: closed.append(True))
    w.close_now()
    assert closed == [True]


def test_a_panel_whose_create_fails_is_named_and_the_window_starts(qtbot, tmp_path, dialogs):
    host = make_test_host(FanInflater(), ProbePanels())
    w = window_on(host, qtbot, tmp_path)
    text = w.statusBar().currentMessage()
    broken = "panel 'broken' (plugin 'plugin-1-ProbePanels') left out: RuntimeError: no gizmo attached"
    nothing = "panel 'nothing' (plugin 'plugin-1-ProbePanels') left out: TypeError: create must return a QWidget, got NoneType"
    assert text == f"plugin problems (none disabled): {broken} (and 1 more: Help > Plugins)"
    assert w.panel_problems == [broken, nothing]
    # Each is listed once, under its plugin, in Help > Plugins and the status-bar button stays.
    assert w.problems_button.isVisible() and w.problems_button.text() == "⚠ 2 plugin problems"
    assert w.show_plugins().problem_lines() == [broken, nothing]
    assert w.plugins_dialog.problem_refs("plugin-1-ProbePanels") == "problems 1, 2 (below)"
    assert host.problems_of("plugin-1-ProbePanels") == [broken, nothing]
    assert "broken" not in w.plugin_panels and "nothing" not in w.plugin_panels and "probe_late" in w.plugin_panels
    assert not dialogs.calls
    w.set_mode("sculpture")  # the window works
    assert w.controls.currentWidget() is w.sculpt_panel
    w.close_now()


def _descendants_named(widget, cls_name):
    return [c for c in widget.findChildren(object) if type(c).__name__ == cls_name]


def test_without_the_animate_plugin_there_is_no_animation_panel(qtbot, tmp_path, dialogs):
    pytest.importorskip("sketchforge_animate")
    without = make_test_host(FanInflater(), entry_points=True, allowlist=["isophote_tool"])
    w = window_on(without, qtbot, tmp_path)
    assert "animation" not in w.plugin_panels and _descendants_named(w, "AnimationPanel") == []
    assert "isophote_sculpt" in w.plugin_panels
    w.close_now()
    with_it = make_test_host(FanInflater(), entry_points=True, allowlist=["isophote_tool", "animate"])
    w = window_on(with_it, qtbot, tmp_path)
    panel = w.plugin_panels["animation"]
    assert _descendants_named(w, "AnimationPanel") == [panel] and panel.parentWidget() is w.observe_page
    w.close_now()


# --- the isophote tool's panel: the solver choice --------------------------------------------
#: Threads a solver's warm-up ran on (the panel starts it when the solver is chosen).
WARMED: list = []


class FakeSolver:
    """A second sculpt solver: Gauss-Newton's work under another name, with a warm-up."""

    @hookimpl
    def sketchforge_sculpt_solvers(self):
        import threading

        from sketchforge_isophote_tool import GAUSS_NEWTON

        return [SculptSolver("fake", GAUSS_NEWTON.solve, GAUSS_NEWTON.check_params, label="Fake (test)",
                             warm_up=lambda: WARMED.append(threading.current_thread()))]


def test_the_solver_chosen_in_the_sculpt_panel_is_in_the_next_sculpt_command(qtbot, tmp_path, dialogs):
    pytest.importorskip("sketchforge_isophote_tool")
    from test_qt_sculpt import ellipse_doc

    host = make_test_host(FakeSolver(), entry_points=True, allowlist=["inflate", "isophote_tool", "soft_brdf"])
    if "soft_lambert" not in host.reflectance_models:
        pytest.skip("the example soft_brdf plugin is not installed")
    w = window_on(host, qtbot, tmp_path, ellipse_doc(host))
    w.set_mode("sculpture")
    panel = w.plugin_panels["isophote_sculpt"]
    combo = panel.solver
    assert [combo.itemData(i) for i in range(combo.count())] == ["gauss_newton", "fake"]
    assert [combo.itemText(i) for i in range(combo.count())] == ["Gauss–Newton (local)", "Fake (test)"]
    assert combo.currentData() == host.default_solver_name("sculpt") == "gauss_newton" and combo.isEnabled()
    tool = w.sculpt.tool
    # model and solver are set together: choosing one keeps the other
    panel.model.setCurrentText("soft_lambert")
    combo.setCurrentIndex(combo.findData("fake"))
    assert tool.options == {"model": "soft_lambert", "solver": "fake"}
    # choosing it warmed it up, once, off the GUI thread
    import threading

    qtbot.waitUntil(lambda: len(WARMED) == 1, timeout=10_000)
    assert WARMED[0] is not threading.main_thread()
    combo.setCurrentIndex(combo.findData("gauss_newton"))
    assert tool.options == {"model": "soft_lambert"}
    combo.setCurrentIndex(combo.findData("fake"))
    panel.model.setCurrentText("lambertian")
    assert tool.options == {"solver": "fake"}

    # an edit with the chosen solver: the journal and the layer's edit name it
    sc = w.sculpt
    sc.set_radius(0.15)
    assert sc.pick(np.array([0.3, 0.05]))
    stroke = np.c_[np.full(9, 0.36), np.linspace(-0.3, 0.3, 9)]
    sc.stroke_press(stroke[0])
    for p in stroke[1:]:
        sc.stroke_move(p)
    sc.stroke_release(stroke[-1])
    wait_idle(qtbot, w, timeout=120_000)
    entry = w.doc.journal()[-1]
    assert entry["command"] == "sculpt_isophote" and entry["solver"] == "fake" and "model" not in entry, sc.status
    assert w.doc.layer("blob").edits[-1]["solver"] == "fake"
    # back to the default: the next command names no solver (as before this panel existed)
    combo.setCurrentIndex(combo.findData("gauss_newton"))
    assert sc.pick(np.array([0.3, 0.05]))
    assert "solver" not in sc.tool.command_dict(stroke) and sc.tool.options == {}
    w.close_now()


def test_the_sculpt_panel_follows_the_controller_and_is_off_for_another_tool(make_window, host):
    from test_qt_sculpt import ellipse_doc

    if "bump_brush" not in host.tools or "isophote_sculpt" not in host.qt_panels:
        pytest.skip("the isophote tool and the example bump brush are needed")
    w = make_window(ellipse_doc(host))
    panel = w.plugin_panels["isophote_sculpt"]
    w.sculpt.set_show(strips=True, regions=False)
    w.sculpt.set_preview(False)
    w.sculpt.set_radius(0.25)
    assert panel.strips.isChecked() and not panel.regions.isChecked() and not panel.preview.isChecked()
    assert abs(panel.spin.value() - 0.25) < 1e-9
    panel.regions.setChecked(True)
    panel.preview.setChecked(True)
    assert w.sculpt.show_regions and w.sculpt.show_strips and w.sculpt.live_preview
    panel.spin.setValue(0.125)
    assert w.sculpt.radius == 0.125
    w.select_tool("bump_brush")
    assert not any(c.isEnabled() for c in (panel.model, panel.solver, panel.slider, panel.spin))
    w.select_tool("sculpt_isophote")
    assert all(c.isEnabled() for c in (panel.model, panel.solver, panel.slider, panel.spin))
