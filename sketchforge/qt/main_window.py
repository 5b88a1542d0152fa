"""The main window (thesis figure 4.1): left menu, central drawing region, controls top right,
layers and history bottom right; menus, shortcuts, files, the status bar's progress indicator.

The window owns one Document for its whole life: opening a file loads it into a new Document
first (so a bad file loses nothing) and then adopts its state (``Document.restore_state``).
Every edit is a command pushed on ``doc.undo_stack``; slow ones go through the CommandRunner.

Native solvers can crash the process. Before any of them runs (a command's ``prepare``, the
OBSERVATION view's assembly) the window's Autosaver flushes the document as it was before the
user's action and names the step (``AutosaveGuard``); at the next start ``offer_recovery``
says which step was running and recovers the work without it.

The window builds the widgets and keeps the state (the document, its path and autosaver, the
mode, the selected layer, the edits waiting for a solve); what it does is split by job into
small controllers that hold a reference to it: its files, autosave and recovery
(:mod:`.window_files`), its menus and tool palette (:mod:`.window_menus`), its modes
(:mod:`.window_modes`), the light (:mod:`.window_light`), the layer actions
(:mod:`.window_layers`) and the drawing of parts (:mod:`.window_drawing`). Their methods keep
the window's names (``window.draw_stroke`` is ``window.drawing.draw_stroke``).
"""

from __future__ import annotations

import logging
from pathlib import Path

from PySide6.QtCore import QSettings, Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QLabel,
    QMainWindow,
    QProgressBar,
    QPushButton,
    QSplitter,
    QStackedWidget,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from sketchforge.document import commands as C
from sketchforge.document.autosave import Autosaver, autosave_interval, poll_interval_ms
from sketchforge.errors import SketchforgeError
from sketchforge.qt.canvas import Canvas
from sketchforge.qt.command_runner import CommandRunner, GuardedJobs
from sketchforge.qt.errors_ui import show_error
from sketchforge.qt.panel_api import AppContext
from sketchforge.qt.panels.assembly_panel import AssemblyPanel
from sketchforge.qt.panels.creation_panel import CreationPanel
from sketchforge.qt.panels.history_panel import HistoryPanel
from sketchforge.qt.panels.layers_panel import LayersPanel
from sketchforge.qt.panels.light_panel import LightPanel
from sketchforge.qt.panels.mode_panel import ModePanel
from sketchforge.qt.panels.sculpt_panel import SculptPanel
from sketchforge.qt.plugins_dialog import PluginsDialog, ProblemsButton
from sketchforge.qt.sculpt import SculptController
from sketchforge.qt.shortcuts import HelpOverlay
from sketchforge.qt.view3d import View3D
from sketchforge.qt.window_drawing import SPLICE_PIXELS, DrawingController
from sketchforge.qt.window_files import FILE_FILTER, MAX_RECENT, AutosaveGuard, FileActions
from sketchforge.qt.window_layers import DUPLICATE_OFFSET, NUDGE_PIXELS, LayerActions
from sketchforge.qt.window_light import LightControl
from sketchforge.qt.window_menus import WindowMenus
from sketchforge.qt.window_modes import ModeController
from sketchforge.qt.workers import JobRunner

log = logging.getLogger("sketchforge.qt")

__all__ = ["MainWindow", "FILE_FILTER", "MAX_RECENT", "SPLICE_PIXELS", "DUPLICATE_OFFSET", "NUDGE_PIXELS"]


class _Delegated:
    """A window method that one of the window's controllers implements: ``window.name`` is the
    bound method of that controller (``window.<controller>.name``). Assigning the attribute on
    a window shadows it, as for any method."""

    def __init__(self, controller: str) -> None:
        self.controller = controller

    def __set_name__(self, owner, name: str) -> None:
        self.name = name

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        return getattr(getattr(obj, self.controller), self.name)


class MainWindow(QMainWindow):
    #: one line from the solver process's watchdog (any thread): shown in the status bar
    solver_process_note = Signal(str)

    # The controllers' methods under the names the window has always had (menus, signal
    # connections, plugins and tests use them).
    # files (window_files)
    maybe_save = _Delegated("file_actions")
    adopt = _Delegated("file_actions")
    new_document = _Delegated("file_actions")
    open_dialog = _Delegated("file_actions")
    open_path = _Delegated("file_actions")
    save = _Delegated("file_actions")
    save_as = _Delegated("file_actions")
    save_to = _Delegated("file_actions")
    _save_over_a_changed_file = _Delegated("file_actions")
    export_dialog = _Delegated("file_actions")
    export_to = _Delegated("file_actions")
    reference_dialog = _Delegated("file_actions")
    _dir = _Delegated("file_actions")
    recent_files = _Delegated("file_actions")
    _add_recent = _Delegated("file_actions")
    update_recent_menu = _Delegated("file_actions")
    # autosave and recovery (window_files)
    _autosave = _Delegated("file_actions")
    offer_recovery = _Delegated("file_actions")
    # menus (window_menus)
    _action = _Delegated("menus")
    _build_menus = _Delegated("menus")
    _build_tool_palette = _Delegated("menus")
    # modes (window_modes)
    select_tool = _Delegated("mode_control")
    set_mode = _Delegated("mode_control")
    _focus_center = _Delegated("mode_control")
    toggle_help = _Delegated("mode_control")
    set_state = _Delegated("mode_control")
    _light_toggled = _Delegated("mode_control")
    _apply_interaction = _Delegated("mode_control")
    apply_sculpt_strokes = _Delegated("mode_control")
    cancel_current = _Delegated("mode_control")
    # light (window_light)
    _on_light = _Delegated("light_control")
    _azimuth = _Delegated("light_control")
    set_light_angle = _Delegated("light_control")
    set_light_elevation = _Delegated("light_control")
    _light_drag_started = _Delegated("light_control")
    _light_dragged = _Delegated("light_control")
    _light_drag_ended = _Delegated("light_control")
    # layer actions (window_layers)
    _on_current = _Delegated("layer_actions")
    add_layer = _Delegated("layer_actions")
    remove_layer = _Delegated("layer_actions")
    duplicate_layer = _Delegated("layer_actions")
    mirror_layer = _Delegated("layer_actions")
    set_params = _Delegated("layer_actions")
    set_inflater = _Delegated("layer_actions")
    set_assembly = _Delegated("layer_actions")
    _run_params = _Delegated("layer_actions")
    _run_pending_params = _Delegated("layer_actions")
    _selected_or_say = _Delegated("layer_actions")
    select_at = _Delegated("layer_actions")
    duplicate_at = _Delegated("layer_actions")
    duplicate_aside = _Delegated("layer_actions")
    nudge = _Delegated("layer_actions")
    transform_layer = _Delegated("layer_actions")
    move_depth = _Delegated("layer_actions")
    # drawing (window_drawing)
    _run_pending = _Delegated("drawing")
    _outlines = _Delegated("drawing")
    draw_stroke = _Delegated("drawing")
    _new_part = _Delegated("drawing")
    _drawing_slip = _Delegated("drawing")
    _redraw = _Delegated("drawing")
    _attachment_notes = _Delegated("drawing")
    _parts_glued_to = _Delegated("drawing")
    _check_parts_still_glued = _Delegated("drawing")
    set_closed = _Delegated("drawing")

    def __init__(self, doc, host=None, settings: QSettings | None = None, parent=None,
                 offload_inflation: bool = False) -> None:
        super().__init__(parent)
        self.doc = doc
        self.host = host or doc.host
        #: With ``offload_inflation`` (the app), inflations run in a child process: their
        #: native factorisation holds the GIL, which froze this window for up to 1.5 s even
        #: though the solve runs on a worker thread (see sketchforge.offload). Its watchdog's
        #: notes (a restart after a crash, a timeout, a cancel) come through a queued signal.
        self.offload = None
        if offload_inflation:
            from sketchforge.offload import OffloadedInflation

            self.offload = OffloadedInflation(doc.host, notify=self.solver_process_note.emit)
            doc.host = self.offload
        self.settings = settings or QSettings()
        self.path: Path | None = None
        #: what ``path`` held when this window last opened or saved it (ff.stamp_of)
        self.disk_stamp: tuple | None = None
        self.mode = "editing"
        self.state = "creation"
        self.current_layer: str | None = None
        self.jobs = JobRunner(self)
        self.solve_guard = AutosaveGuard(self)
        self.runner = CommandRunner(doc, self.jobs, self, guard=self.solve_guard)
        #: {layer id: {param: value}} edited while a solve ran: applied when it ends (last wins)
        self._pending_params: dict[str, dict] = {}
        #: [(points, kind)] strokes drawn while a solve ran: drawn in order when it ends
        self._pending_strokes: list[tuple] = []
        # What the window does, by job; the window's methods of the same names call them.
        self.file_actions = FileActions(self)
        self.menus = WindowMenus(self)
        self.mode_control = ModeController(self)
        self.light_control = LightControl(self)
        self.layer_actions = LayerActions(self)
        self.drawing = DrawingController(self)

        if hasattr(self.host, "validate"):
            self.host.validate()  # every registry now: each plugin problem is known from the start
        self._build_widgets()
        self._build_plugin_panels()
        self._build_menus()
        self._build_tool_palette()
        self._build_status_bar()
        self._connect()
        self._sync_all()
        self.set_state("creation")
        self._report_plugin_problems()

        # Autosave of unsaved work (the Autosaver decides when; the timer only polls).
        self.autosaver = Autosaver(doc, interval_s=autosave_interval(self.settings.value("autosave/interval_s")))
        self._autosave_timer = QTimer(self)
        self._autosave_timer.setInterval(poll_interval_ms(self.autosaver.interval_s))
        self._autosave_timer.timeout.connect(self._autosave)
        self._autosave_timer.start()
        #: The autosave failure being shown (shown once, not at every retry), or None.
        self.autosave_error: str | None = None

    def _report_plugin_problems(self) -> None:
        """Plugins left out at start-up (import failed, a hook raised, a contract broken), and
        panels that failed: one status-bar line naming them, and a status-bar button that stays
        while there are any and opens Help > Plugins, where each problem is listed once under
        its plugin."""
        skipped = dict(getattr(self.host, "skipped", {}) or {})
        problems = list(getattr(self.host, "problems", []) or [])
        for text in self.panel_problems:  # the window's own findings join the host's list
            if text not in problems and hasattr(self.host, "report_problem"):
                self.host.report_problem(text, *self._panel_owner.get(text, ()))
                problems.append(text)
        self.problems_button.show_count(problems)
        if problems:
            names = ", ".join(sorted(skipped)) or "none disabled"
            n = len(problems)
            self.show_message(f"plugin problems ({names}): {problems[0]}"
                              + (f" (and {n - 1} more: Help > Plugins)" if n > 1 else ""))

    def show_plugins(self) -> PluginsDialog:
        """Help > Plugins: every plugin, its version, what it registers and its problems."""
        dialog = PluginsDialog(self.host, self)
        dialog.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
        self.plugins_dialog = dialog
        dialog.show()
        return dialog

    # --- construction ---------------------------------------------------------------------------
    def _build_widgets(self) -> None:
        doc = self.doc
        self.canvas = Canvas(doc, self.host)
        # The assembly runs OSQP (native): guarded like a command's solve.
        self.view3d = View3D(doc, GuardedJobs(self.jobs, self.solve_guard, "Assemble model", self))
        self.center = QStackedWidget()
        self.center.addWidget(self.canvas)
        self.center.addWidget(self.view3d)

        self.modes = ModePanel()
        self.creation_panel = CreationPanel(self.host)
        shadings = self.host.display_shadings()
        self.creation_panel.set_shaders(shadings.keys(), self.canvas.shader_name,
                                        {k: f"{s.name} (reflectance model)" for k, s in shadings.items() if k.startswith("model:")})
        self.sculpt_panel = SculptPanel()
        self.light_panel = LightPanel()
        self.creation_page = QWidget()
        creation_lay = QVBoxLayout(self.creation_page)
        creation_lay.setContentsMargins(0, 0, 0, 0)
        creation_lay.addWidget(self.creation_panel)
        self.controls = QStackedWidget()
        self.controls.addWidget(self.creation_page)
        self.controls.addWidget(self.sculpt_panel)
        self.observe_note = QLabel(
            "OBSERVATION: drag to orbit, wheel to zoom.\nThe left menu switches between the assembled model and each layer's mesh."
        )
        self.observe_note.setWordWrap(True)
        self.observe_note.setAlignment(Qt.AlignmentFlag.AlignTop)
        self.observe_page = QWidget()
        observe_lay = QVBoxLayout(self.observe_page)
        observe_lay.setContentsMargins(0, 0, 0, 0)
        observe_lay.addWidget(self.observe_note)
        self.assembly_panel = AssemblyPanel(self.host)
        observe_lay.addWidget(self.assembly_panel)
        observe_lay.addStretch(1)  # plugin panels go above it (_build_plugin_panels)
        self.controls.addWidget(self.observe_page)
        top = QWidget()
        top_lay = QVBoxLayout(top)
        top_lay.setContentsMargins(0, 0, 0, 0)
        top_lay.addWidget(self.controls)
        top_lay.addWidget(self.light_panel)
        top_lay.addStretch(1)

        self.layers_panel = LayersPanel(doc, lambda: (self.doc.light, self.canvas._shader()))
        # Thumbnails follow the light once it rests: re-rendering every layer's thumbnail on each
        # step of a light drag would cost more than shading the canvas itself.
        self._thumbnail_timer = QTimer(self)
        self._thumbnail_timer.setSingleShot(True)
        self._thumbnail_timer.setInterval(150)
        self._thumbnail_timer.timeout.connect(self.layers_panel.refresh_thumbnails)
        self.history_panel = HistoryPanel(doc)
        self.history_panel.enabled_edits = lambda: not self.runner.busy
        tabs = QTabWidget()
        tabs.addTab(self.layers_panel, "Layers")
        tabs.addTab(self.history_panel, "History")
        self.bottom_tabs = tabs

        right = QSplitter(Qt.Orientation.Vertical)
        right.addWidget(top)
        right.addWidget(tabs)
        right.setStretchFactor(0, 0)
        right.setStretchFactor(1, 1)
        right.setMinimumWidth(290)
        right.setMaximumWidth(380)

        main = QSplitter(Qt.Orientation.Horizontal)
        main.addWidget(self.modes)
        main.addWidget(self.center)
        main.addWidget(right)
        main.setStretchFactor(1, 1)
        main.setChildrenCollapsible(False)
        self.setCentralWidget(main)

        self.sculpt = SculptController(doc, self.host, self.canvas, self.runner)
        self.canvas.sculpt = self.sculpt
        self.help_overlay = HelpOverlay(self.center)

    def _build_plugin_panels(self) -> None:
        """The plugins' panels (``host.qt_panels``), each built once with the window's
        :class:`AppContext` and shown in the controls of its place, sorted by ``order``. One
        whose ``available(host)`` is false is left out; one whose ``available`` or ``create``
        raises (or whose ``create`` returns no widget) is named with its plugin in the status
        bar and the log and left out: the window starts without it."""
        self.app_context = AppContext(doc=self.doc, host=self.host, canvas=self.canvas, view3d=self.view3d,
                                      sculpt=self.sculpt, runner=self.runner, show_message=self.show_message,
                                      parent=self)
        #: {panel name: its widget}
        self.plugin_panels: dict[str, QWidget] = {}
        #: one line per panel left out because it failed
        self.panel_problems: list[str] = []
        self._panel_owner: dict[str, tuple] = {}
        observe = self.observe_page.layout()
        places = {
            "creation": self.creation_page.layout().addWidget,
            "sculpture": self.sculpt_panel.add_panel,
            "observation": lambda w: observe.insertWidget(observe.count() - 1, w),  # above the stretch
        }
        for panel in sorted(self.host.qt_panels.values(), key=lambda p: (p.order, p.name)):
            who = self.host.provider_of(panel)
            try:
                if panel.available is not None and not panel.available(self.host):
                    continue
                widget = panel.create(self.app_context)
                if not isinstance(widget, QWidget):
                    raise TypeError(f"create must return a QWidget, got {type(widget).__name__}")
            except Exception as exc:  # noqa: BLE001 - a plugin's code must not stop the app
                text = f"panel {panel.name!r} (plugin {who!r}) left out: {type(exc).__name__}: {exc}"
                log.warning("%s", text, exc_info=True)
                self.panel_problems.append(text)
                self._panel_owner[text] = (who,) if who else ()
                continue
            places[panel.place](widget)
            self.plugin_panels[panel.name] = widget
        # The pages are hidden: without this the splitter would size the controls column
        # from their size before the panels were added.
        for page in (self.creation_page, self.sculpt_panel, self.observe_page):
            page.layout().activate()
        self.controls.updateGeometry()

    def _build_status_bar(self) -> None:
        sb = self.statusBar()
        self.progress = QProgressBar()
        self.progress.setRange(0, 0)  # busy indicator
        self.progress.setMaximumWidth(160)
        self.progress_label = QLabel()
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.clicked.connect(self.runner.cancel)
        for w in (self.progress_label, self.progress, self.cancel_button):
            sb.addPermanentWidget(w)
            w.setVisible(False)
        self.problems_button = ProblemsButton(self.show_plugins)
        sb.addPermanentWidget(self.problems_button)

    def _connect(self) -> None:
        doc = self.doc
        stack = doc.undo_stack
        for sig in (stack.can_undo_changed, stack.can_redo_changed, stack.undo_text_changed, stack.redo_text_changed):
            sig.connect(lambda *_: self._sync_undo())
        stack.clean_changed.connect(lambda *_: self._sync_title())
        # Once, the first time the undo history's memory budget drops its oldest steps: it
        # stays in the status bar until the next message.
        stack.history_trimmed.connect(lambda text: self.statusBar().showMessage(text[:1].upper() + text[1:]))
        doc.history_changed.connect(self._sync_undo)
        doc.history_changed.connect(self._sync_title)
        doc.light_changed.connect(self._on_light)
        doc.layer_changed.connect(lambda *a: self._sync_current_layer())
        doc.layer_removed.connect(lambda *a: self._sync_current_layer())

        self.canvas.stroke_finished.connect(self.draw_stroke)
        self.canvas.part_clicked.connect(self.select_at)
        self.canvas.part_double_clicked.connect(self.duplicate_at)
        self.canvas.transform_requested.connect(self.transform_layer)
        self.creation_panel.closed_toggled.connect(self.set_closed)
        self.canvas.message.connect(self.show_message)
        self.view3d.message.connect(self.show_message)
        self.sculpt.message.connect(self.show_message)
        self.sculpt.changed.connect(lambda: self.sculpt_panel.show_state(self.sculpt))
        self.sculpt.layer_picked.connect(self.layers_panel.select)

        self.modes.mode_changed.connect(lambda m: self.set_mode(m if m == "observation" else self.state))
        self.modes.state_changed.connect(self.set_state)
        self.modes.light_toggled.connect(self._light_toggled)
        self.modes.observe_changed.connect(self.view3d.set_source)
        self.modes.fit_requested.connect(self.canvas.fit)
        self.modes.fit_requested.connect(self.view3d.fit)
        self.modes.display3d_changed.connect(lambda style: self.view3d.set_style(style, self.canvas.isoline_count or 8))
        self.creation_panel.tint_changed.connect(self.canvas.set_layer_tint)
        self.creation_panel.outlines_changed.connect(self.canvas.set_layer_outlines)

        self.creation_panel.params_edited.connect(self.set_params)
        self.creation_panel.inflater_changed.connect(self.set_inflater)
        self.assembly_panel.assembly_edited.connect(self.set_assembly)
        doc.assembly_changed.connect(lambda: self.assembly_panel.show_assembly(self.doc.assembly))
        self.creation_panel.shader_changed.connect(self._shader_changed)
        self.creation_panel.isolines_changed.connect(self.canvas.set_isoline_count)
        # the 3D view's isophote style follows the same count, live (0 lines: keep its last count)
        self.creation_panel.isolines_changed.connect(
            lambda k: self.view3d.set_style(self.view3d.shading_style, k) if k > 0 else None
        )
        self.sculpt_panel.tool_selected.connect(self.select_tool)
        self.light_panel.angle_edited.connect(self.set_light_angle)
        self.light_panel.elevation_edited.connect(self.set_light_elevation)
        self.light_panel.disc.pressed.connect(self._light_drag_started)
        self.light_panel.disc.dragged.connect(self._light_dragged)
        self.light_panel.disc.released.connect(self._light_drag_ended)

        lp = self.layers_panel
        lp.add_requested.connect(self.add_layer)
        lp.remove_requested.connect(self.remove_layer)
        lp.duplicate_requested.connect(self.duplicate_layer)
        lp.mirror_requested.connect(self.mirror_layer)
        lp.visibility_requested.connect(lambda lid, v: self.push(C.SetLayerVisible(layer=lid, visible=v)))
        lp.rename_requested.connect(lambda lid, name: self.push(C.RenameLayer(layer=lid, new_name=name)))
        lp.move_requested.connect(lambda lid, i: self.push(C.MoveLayer(layer=lid, index=i)))
        lp.current_changed.connect(self._current_layer_changed)

        self.runner.busy_changed.connect(self._busy)
        self.solver_process_note.connect(self.show_message)
        if self.offload is not None:
            self.runner.cancelled.connect(self.offload.cancel)  # Cancel stops the child's job too
        self.runner.failed.connect(lambda exc, tb, cmd: show_error(self, f"{cmd.text()} failed", exc, tb))
        self.jobs.busy_changed.connect(self._progress)

    # --- synchronising widgets with the document ------------------------------------------------
    def _sync_all(self) -> None:
        self.assembly_panel.show_assembly(self.doc.assembly)
        self._sync_undo()
        self._sync_title()
        self.light_panel.show_light(self.doc.light)
        self.layers_panel.rebuild()  # thumbnails included
        self._sync_current_layer()
        self.sculpt.reset()

    def _sync_undo(self) -> None:
        stack = self.doc.undo_stack
        self.act_undo.setEnabled(stack.can_undo())
        self.act_redo.setEnabled(stack.can_redo())
        self.act_undo.setText(f"Undo {stack.undo_text()}" if stack.can_undo() else "Undo")
        self.act_redo.setText(f"Redo {stack.redo_text()}" if stack.can_redo() else "Redo")

    def is_modified(self) -> bool:
        return not self.doc.undo_stack.is_clean()

    def _sync_title(self) -> None:
        name = self.path.name if self.path is not None else "Untitled"
        self.setWindowTitle(f"{name}[*] — sketchforge")
        self.setWindowModified(self.is_modified())

    def _current_layer_changed(self, layer_id) -> None:
        self.current_layer = layer_id
        self.canvas.set_current_layer(layer_id)
        self._sync_current_layer()

    def _sync_current_layer(self) -> None:
        ids = self.doc.layer_ids()
        if self.current_layer not in ids:
            self.current_layer = self.layers_panel.current_id()
        layer = self.doc.layer(self.current_layer) if self.current_layer in ids else None
        self.creation_panel.show_layer(layer, self._pending_params.get(self.current_layer))

    def _shader_changed(self, name: str) -> None:
        if name:
            self.canvas.set_shader(name)
            self._thumbnail_timer.start()

    def show_message(self, text: str) -> None:
        self.statusBar().showMessage(text, 8000)

    def _busy(self, busy: bool) -> None:
        self.canvas.busy = busy
        # Undo stays enabled: during a solve it cancels the solve (see ``undo``).
        for act in (self.act_redo, self.act_new, self.act_open, self.act_save, self.act_save_as):
            act.setEnabled(not busy)
        if busy:
            self.act_undo.setEnabled(True)
        else:
            self._sync_undo()
            if self._pending_params or self._pending_strokes:
                # Queued so that the finished solve's own callbacks run first.
                QTimer.singleShot(0, self._run_pending)

    def _progress(self, label: str) -> None:
        for w in (self.progress_label, self.progress, self.cancel_button):
            w.setVisible(bool(label))
        self.progress_label.setText(label + "…" if label else "")

    # --- edits ----------------------------------------------------------------------------------
    def _refuse_if_busy(self) -> bool:
        if self.runner.busy:
            self.show_message("a solve is running: wait for it or cancel it (Esc)")
            return True
        return False

    def push(self, cmd) -> bool:
        """Push a quick command; an error shows a dialog and leaves the document unchanged."""
        if self._refuse_if_busy():
            self.layers_panel.rebuild()
            return False
        try:
            self.doc.push(cmd)
            return True
        except SketchforgeError as exc:
            show_error(self, f"{cmd.text()} failed", exc)
            self.layers_panel.rebuild()
            return False

    def undo(self) -> None:
        """Ctrl+Z. During a solve it cancels the solve: the action being computed is not on the
        stack yet, so dropping it is what undoing it means; the next Ctrl+Z undoes the step
        before."""
        if self.runner.busy:
            self._pending_params.clear()
            self._pending_strokes.clear()
            self.runner.cancel()
            self._sync_current_layer()
            self.show_message("cancelled the running computation; its action was not applied")
            return
        if self.doc.undo_stack.can_undo():
            self.doc.undo_stack.undo()
        else:
            self.show_message("nothing to undo")

    def redo(self) -> None:
        if not self._refuse_if_busy():
            self.doc.undo_stack.redo()

    # --- background warm-up and closing ---------------------------------------------------------
    def start_warm_up(self) -> None:
        """Run each tool's ``warm_up`` (compiling its solver) in the background."""
        for cls in self.host.tools.values():
            warm = getattr(cls, "warm_up", None)
            if callable(warm):
                label = getattr(cls, "label", "") or cls.name
                self.jobs.start(warm, lambda _r, label=label: self.show_message(f"“{label}” is ready"),
                                lambda e, tb: None, label="Warming up", background=True)

    def closeEvent(self, event) -> None:
        if getattr(self, "_closing_now", False) or self.maybe_save():
            self.runner.cancel()
            self.app_context.closing.emit()
            self._autosave_timer.stop()
            self.autosaver.discard()  # a normal close: nothing to recover next time
            if self.offload is not None:
                self.offload.shutdown()
            event.accept()
        else:
            event.ignore()

    def close_now(self) -> None:
        """Close without asking (screenshots, tests)."""
        self._closing_now = True
        self.runner.cancel()
        self.close()
        if self.offload is not None:
            self.offload.shutdown()
