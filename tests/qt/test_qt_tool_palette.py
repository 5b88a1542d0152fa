"""Plugin tools in the app: the palette lists every registered tool, and a plugin brush (the
example bump brush, installed by `make`) is driven like the isophote tool: overlay while
dragging, its command prepared on the worker with the progress indicator, one undo step,
bit-identical to the headless command."""

from __future__ import annotations

import numpy as np
from PySide6.QtWidgets import QApplication
from qt_helpers import wait_idle
from test_qt_sculpt import ellipse_doc

from sketchforge.document import fileformat as ff


def test_palette_lists_every_registered_tool(make_window, host):
    w = make_window(ellipse_doc(host))
    combo = w.sculpt_panel.tool
    names = [combo.itemData(i) for i in range(combo.count())]
    assert names == list(host.tools) and {"sculpt_isophote", "bump_brush"} <= set(names)
    texts = [combo.itemText(i) for i in range(combo.count())]
    assert "Bump brush (Shift+B)" in texts and "Redraw isophote" in texts
    assert all(not combo.itemIcon(i).isNull() for i in range(combo.count()))  # icon or letter
    assert set(w.tool_actions) == set(names)
    assert w.tool_actions["bump_brush"].shortcut().toString() == "Shift+B"
    assert w.sculpt.tool_name == "sculpt_isophote"  # the default stays the isophote tool


def test_plugin_brush_runs_through_the_sculpt_plumbing(make_window, mouse, qtbot, host):
    doc = ellipse_doc(host)
    before = doc.layer("blob")
    w = make_window(doc)
    w.canvas.fit()
    w.tool_actions["bump_brush"].trigger()  # the Tools menu / Shift+B
    assert w.state == "sculpture" and w.sculpt.tool_name == "bump_brush" and not w.sculpt.picking
    assert w.sculpt_panel.tool.currentData() == "bump_brush" and not w.plugin_panels["isophote_sculpt"].spin.isEnabled()

    busy = []
    w.runner.busy_changed.connect(busy.append)
    m = mouse(w.canvas)
    start, mid, end = (0.1, 0.0), (0.1, 0.08), (0.1, 0.15)
    # The overlay while dragging: the press shows the brush disc.
    w.sculpt.stroke_press(np.array(start))
    rect = w.canvas.overlays["stroke"].boundingRect()  # the disc: 2 x the brush radius (0.3)
    assert abs(rect.width() - 0.6) < 1e-3 and abs(rect.height() - 0.6) < 1e-3
    w.sculpt.cancel()
    assert w.canvas.overlays["stroke"].is_empty() and doc.undo_stack.count() == 0

    m.drag([start, mid, end])
    wait_idle(qtbot, w)
    assert busy[:1] == [True] and busy[-1] is False  # the command ran through the runner
    assert doc.undo_stack.count() == 1 and doc.undo_stack.undo_text() == "Bump brush"
    cmd = doc.undo_stack.command(0)
    assert cmd.name == "bump_brush" and cmd.height > 0.1  # dragged up ~0.15 drawing units
    layer = doc.layer("blob")
    assert [e["command"] for e in layer.edits] == ["bump_brush"]
    dz = layer.mesh.V[:, 2] - before.mesh.V[:, 2]
    assert dz.max() > 0.1 and np.all(dz[before.mesh.boundary] == 0.0)
    # Headless replay of the journal gives the same surface, bit for bit.
    replayed = ff.replay_journal(doc.initial_light, doc.journal(), "journal", host=host)
    assert not ff.compare(doc, replayed)
    w.undo()
    QApplication.processEvents()
    assert doc.layer("blob").same_state(before)


def test_a_plugin_tool_error_goes_to_the_status_bar(make_window, mouse, qtbot, host):
    w = make_window(ellipse_doc(host))
    w.canvas.fit()
    w.select_tool("bump_brush")
    mouse(w.canvas).drag([(0.75, 0.5), (0.75, 0.55)])  # in view, outside the ellipse
    wait_idle(qtbot, w)
    assert "press on a shape to brush it" in w.sculpt.status
    assert w.doc.undo_stack.count() == 0


def test_a_plugin_whose_hook_raises_is_named_in_the_status_bar_and_the_app_starts(qtbot, tmp_path, dialogs):
    from PySide6.QtCore import QSettings

    from sketchforge.document.document import Document
    from sketchforge.plugins.hookspecs import hookimpl
    from sketchforge.plugins.testing import FanInflater, make_test_host
    from sketchforge.qt.main_window import MainWindow

    class BrokenTools:
        @hookimpl
        def sketchforge_tools(self):
            raise KeyError("brushes.json")

    host = make_test_host(FanInflater(), BrokenTools())
    host.validate()  # what the app's plugin_host() does at start-up
    settings = QSettings(str(tmp_path / "s.ini"), QSettings.Format.IniFormat)
    w = MainWindow(Document(host=host), host=host, settings=settings)
    qtbot.addWidget(w)
    text = w.statusBar().currentMessage()
    assert "plugin-1-BrokenTools" in text and "brushes.json" in text
    assert w.sculpt_panel.tool.count() == 0 and not dialogs.calls


def test_a_plugin_command_that_fails_on_the_worker_names_its_plugin(qtbot, tmp_path, dialogs):
    from dataclasses import dataclass
    from typing import ClassVar

    from PySide6.QtCore import QSettings

    from sketchforge.document.document import Document
    from sketchforge.plugin_api import ReplaceLayerCommand, Tool, hookimpl
    from sketchforge.plugins.testing import FanInflater, make_test_host
    from sketchforge.qt.main_window import MainWindow

    @dataclass
    class Crash(ReplaceLayerCommand):
        name: ClassVar[str] = "crash_brush"

        def compute(self, doc, old):
            return 1 / 0  # a bug, on the worker thread

        def to_dict(self):
            return {"command": self.name, "layer": self.layer}

        @classmethod
        def from_dict(cls, d):
            return cls(layer=d["layer"])

    class CrashTool(Tool):
        name, label = "crash_brush", "Crash brush"

        def release(self, pos):
            return self.doc.push(Crash(layer="a"))

    class CrashPlugin:
        @hookimpl
        def sketchforge_commands(self):
            return [Crash]

        @hookimpl
        def sketchforge_tools(self):
            return [CrashTool]

    host = make_test_host(FanInflater(), CrashPlugin())
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": [[0, 0], [1, 0], [0, 1]]})
    before = doc.layer("a")
    w = MainWindow(doc, host=host, settings=QSettings(str(tmp_path / "s.ini"), QSettings.Format.IniFormat))
    qtbot.addWidget(w)
    w.select_tool("crash_brush")
    w.sculpt.stroke_press(np.array([0.2, 0.2]))
    w.sculpt.stroke_release(np.array([0.2, 0.2]))
    wait_idle(qtbot, w)
    assert "command 'crash_brush' (from plugin 'plugin-1-CrashPlugin') failed: ZeroDivisionError" in w.sculpt.status
    assert doc.layer("a") is before and doc.undo_stack.count() == 2


def test_each_tool_with_a_warm_up_is_warmed_up_in_the_background(qtbot, tmp_path, dialogs):
    """What the isophote tool's JAX compilation uses: the window runs a tool's ``warm_up`` on a
    worker at start (the app calls start_warm_up) and says when it is done."""
    import threading

    from PySide6.QtCore import QSettings

    from sketchforge.document.document import Document
    from sketchforge.plugin_api import Tool, hookimpl
    from sketchforge.plugins.testing import FanInflater, make_test_host
    from sketchforge.qt.main_window import MainWindow

    threads = []

    class SlowTool(Tool):
        name, label = "slow_brush", "Slow brush"

        @staticmethod
        def warm_up():
            threads.append(threading.current_thread() is threading.main_thread())

    class ColdTool(Tool):
        name, label = "cold_brush", "Cold brush"  # no warm_up: nothing to run

    class Tools:
        @hookimpl
        def sketchforge_tools(self):
            return [SlowTool, ColdTool]

    host = make_test_host(FanInflater(), Tools())
    w = MainWindow(Document(host=host), host=host, settings=QSettings(str(tmp_path / "s.ini"), QSettings.Format.IniFormat))
    qtbot.addWidget(w)
    said = []
    shown = w.show_message
    w.show_message = lambda text, *a, **k: (said.append(text), shown(text, *a, **k))
    w.start_warm_up()
    wait_idle(qtbot, w)
    # The "ready" line arrives as a queued signal and the status bar fades it after a few
    # seconds: on a loaded machine either can fall outside one look at the bar.
    qtbot.waitUntil(lambda: "“Slow brush” is ready" in said, timeout=20_000)
    assert threads == [False]  # once, off the GUI thread
    w.close_now()
