"""The main window (thesis figure 4.1): left menu, central drawing region, controls top right,
layers and history bottom right; menus, shortcuts, files, the status bar's progress indicator.

The window owns one Document for its whole life: opening a file loads it into a new Document
first (so a bad file loses nothing) and then adopts its state (``Document.restore_state``).
Every edit is a command pushed on ``doc.undo_stack``; slow ones go through the CommandRunner.

Native solvers can crash the process. Before any of them runs (a command's ``prepare``, the
OBSERVATION view's assembly) the window's Autosaver flushes the document as it was before the
user's action and names the step (``_AutosaveGuard``); at the next start ``offer_recovery``
says which step was running and recovers the work without it.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
from PySide6.QtCore import QSettings, Qt, QTimer, Signal
from PySide6.QtGui import QAction, QActionGroup, QIcon, QKeySequence
from PySide6.QtWidgets import (
    QFileDialog,
    QLabel,
    QMainWindow,
    QMenu,
    QMessageBox,
    QProgressBar,
    QPushButton,
    QSplitter,
    QStackedWidget,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from sketchforge.atomic import refuse_input_as_output, same_file
from sketchforge.document import commands as C
from sketchforge.document import fileformat as ff
from sketchforge.document.autosave import Autosaver, autosave_interval, describe_stop, find_recoverable, forget, recover
from sketchforge.document.autosave import set_aside
from sketchforge.document.autosave import poll_interval_ms
from sketchforge.document.layer import Light
from sketchforge.errors import ContourError, EditsDoNotApplyError, SketchforgeError
from sketchforge.geometry.parts import part_at
from sketchforge.qt.canvas import Canvas
from sketchforge.qt.command_runner import CommandRunner, GuardedJobs
from sketchforge.qt import errors_ui
from sketchforge.qt.errors_ui import ask_yes_no, error_text, show_error
from sketchforge.qt.panels.assembly_panel import AssemblyPanel
from sketchforge.qt.panels.creation_panel import CreationPanel
from sketchforge.qt.panels.history_panel import HistoryPanel
from sketchforge.qt.panels.layers_panel import LayersPanel
from sketchforge.qt.panels.light_panel import LightPanel
from sketchforge.qt.panels.mode_panel import ModePanel
from sketchforge.qt.panels.sculpt_panel import SculptPanel
from sketchforge.qt.panel_api import AppContext
from sketchforge.qt.plugins_dialog import PluginsDialog, ProblemsButton
from sketchforge.qt.sculpt import SculptController
from sketchforge.qt.shortcuts import HelpOverlay
from sketchforge.qt.view3d import View3D
from sketchforge.qt.workers import JobRunner
from sketchforge.tools import DrawContourTool
from sketchforge.tools.draw import closes, layer_outlines, plan_stroke

log = logging.getLogger("sketchforge.qt")

FILE_FILTER = "sketchforge documents (*.json *.sketchforge);;All files (*)"
MAX_RECENT = 8
#: A redraw stroke's ends must lie this close (screen pixels) to the selected outline.
SPLICE_PIXELS = 10
#: Ctrl+D moves the copy this many part widths to the right: beside it with a gap (a second
#: eye, leg...), so the copy's junction does not lie across the original.
DUPLICATE_OFFSET = 1.25
#: An arrow key moves the selected part this many screen pixels.
NUDGE_PIXELS = 10


class _AutosaveGuard:
    """The CommandRunner's (and the assembly's) guard: the window's current Autosaver writes
    the state before the solve and names it (``Autosaver.begin_solve``), and forgets the record
    when the solver has returned, even after a save or an open in between (the record was
    handed over to the new Autosaver, ``Autosaver.hand_over``). A failing disk is reported but
    never blocks the solve."""

    def __init__(self, window) -> None:
        self.window = window

    def before(self, cmd=None, **kwargs):
        saver = getattr(self.window, "autosaver", None)
        if saver is None:
            return None
        try:
            return saver, saver.begin_solve(cmd, **kwargs)
        except (SketchforgeError, OSError) as exc:
            self.window.show_message(f"autosave before the solve failed: {error_text(exc)}")
            return None

    def after(self, token) -> None:
        saver, inner = token
        try:
            saver.end_solve(inner)  # the autosaver that started it passes it on if it was handed over
        except (SketchforgeError, OSError) as exc:
            self.window.show_message(f"autosave failed: {error_text(exc)}")


class MainWindow(QMainWindow):
    #: one line from the solver process's watchdog (any thread): shown in the status bar
    solver_process_note = Signal(str)

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
        self.solve_guard = _AutosaveGuard(self)
        self.runner = CommandRunner(doc, self.jobs, self, guard=self.solve_guard)
        #: {layer id: {param: value}} edited while a solve ran: applied when it ends (last wins)
        self._pending_params: dict[str, dict] = {}
        #: [(points, kind)] strokes drawn while a solve ran: drawn in order when it ends
        self._pending_strokes: list[tuple] = []

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

    def _autosave(self) -> None:
        """Timer tick. A failure (full disk, a file where the data folder should be) is shown
        once in the status bar, where it stays, and the autosave is retried at every interval;
        the first success after it says so."""
        try:
            wrote = self.autosaver.tick()
        except (SketchforgeError, OSError) as exc:
            text = f"autosave failed: {error_text(exc)} (retrying every {self.autosaver.interval_s:g} s)"
            if text != self.autosave_error:
                self.autosave_error = text
                self.statusBar().showMessage(text)  # no timeout: it stays until the next message
            return
        if self.autosave_error is not None and (wrote or self.doc.undo_stack.is_clean()):
            self.autosave_error = None
            self.show_message("autosave works again")

    def offer_recovery(self) -> bool:
        """At start: offer the newest autosave left by a session that did not end normally,
        naming the step that was running if a solver crashed (that step is not in the
        autosave, so it is not replayed). Returns True when one was recovered (it opens as
        unsaved changes). Declining keeps the autosave: it is offered again next time. The files
        of another sketchforge still running are never offered, reported or removed."""
        set_aside_notes: list[str] = []
        items = find_recoverable(set_aside_notes=set_aside_notes)  # also removes killed autosaves' temps
        if set_aside_notes:
            QMessageBox.information(self, "An autosave was set aside", "\n\n".join(n[:1].upper() + n[1:] for n in set_aside_notes))
        reports = [i for i in items if not i.has_document]
        if reports:
            # A crash during a solve on a document without unsaved changes: nothing to
            # recover, but the person should know which step brought sketchforge down.
            lines = []
            for r in reports:
                name = r.original or "the untitled document"
                if any(rec.get("unsaved") for rec in r.running):  # the autosave could not be written
                    lines.append(f"{describe_stop(r)} The unsaved changes to {name} could not be autosaved before that step; the step was not applied.")
                else:
                    lines.append(f"{describe_stop(r)} There were no unsaved changes to {name}, so nothing was lost; that step was not applied.")
            QMessageBox.information(self, "sketchforge stopped during a computation", "\n\n".join(lines))
            for r in reports:
                forget(r)
        items = [i for i in items if i.has_document]
        if not items:
            return False
        item = items[0]
        where = item.original or "an untitled document"
        stopped = describe_stop(item)
        if stopped and any(r.get("command") is not None for r in item.running):
            question = f"{stopped} Your work on {where} up to that step can be recovered; that step was left out. Recover it?"
        elif stopped:
            question = f"{stopped} Your work on {where} can be recovered (that computation is not part of it). Recover it?"
        else:
            question = f"sketchforge found unsaved work on {where} from a session that did not close normally. Recover it?"
        question += f"\n\nNo keeps the autosave ({item.path}); it is offered again at the next start."
        if not ask_yes_no(self, "Recover unsaved work?", question, default_yes=True):
            return False  # the autosave stays where it is: this session never writes or removes it
        try:
            loaded = recover(item, host=self.host)
        except Exception as exc:  # noqa: BLE001 - a bad autosave must never end the app
            # Kept for the user, but out of the way: it would fail the same way at every start.
            note = set_aside(item.path, error_text(exc))
            QMessageBox.critical(self, "Cannot recover the autosave", note)
            return False
        # The file's digest when the crashed session last read or saved it: a save over it
        # asks first if it changed since.
        stamp = (None, None, None, None, item.original_sha256) if item.original and item.original_sha256 else None
        self.adopt(loaded, Path(item.original) if item.original else None, stamp)
        self.doc.undo_stack.reset_clean()  # recovered work is not saved anywhere yet
        self._sync_title()
        try:
            self.autosaver.save_now()  # the new autosaver takes over from here...
        except (SketchforgeError, OSError) as exc:
            self.show_message(f"autosave failed: {error_text(exc)}; the recovered autosave {item.path} is kept")
            return True
        forget(item)  # ...and only then is the old one removed
        if stopped:
            self.show_message("recovered; the step that was running when sketchforge stopped was left out")
        return True

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
        self.observe_note = QLabel("OBSERVATION: drag to orbit, wheel to zoom.\nThe left menu switches between the assembled model and each layer's mesh.")
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

    def _action(self, menu, text, slot, shortcut=None, checkable=False) -> QAction:
        act = QAction(text, self)
        if shortcut is not None:
            if isinstance(shortcut, (list, tuple)):
                act.setShortcuts([QKeySequence(s) for s in shortcut])
            else:
                act.setShortcut(QKeySequence(shortcut))
        act.setCheckable(checkable)
        act.triggered.connect(slot)
        menu.addAction(act)
        return act

    def _build_menus(self) -> None:
        mb = self.menuBar()
        f = mb.addMenu("&File")
        self.act_new = self._action(f, "&New", self.new_document, QKeySequence.StandardKey.New)
        self.act_open = self._action(f, "&Open…", self.open_dialog, QKeySequence.StandardKey.Open)
        self.recent_menu = f.addMenu("Open &Recent")
        f.addSeparator()
        self.act_save = self._action(f, "&Save", self.save, QKeySequence.StandardKey.Save)
        self.act_save_as = self._action(f, "Save &As…", self.save_as, QKeySequence.StandardKey.SaveAs)
        self.act_export = self._action(f, "&Export…", self.export_dialog, "Ctrl+E")
        f.addSeparator()
        self._action(f, "&Quit", self.close, QKeySequence.StandardKey.Quit)

        e = mb.addMenu("&Edit")
        self.act_undo = self._action(e, "Undo", self.undo, QKeySequence.StandardKey.Undo)
        self.act_redo = self._action(e, "Redo", self.redo, ["Ctrl+Shift+Z", "Ctrl+Y"])
        e.addSeparator()
        self.act_cancel = self._action(e, "Cancel", self.cancel_current, "Esc")
        # Enter applies the strokes drawn for several picked isophotes; only while the drawing
        # has the focus (elsewhere Enter belongs to the fields).
        self.act_apply_strokes = self._action(e, "Apply sculpt strokes", self.apply_sculpt_strokes, ["Return", "Enter"])
        self.act_apply_strokes.setShortcutContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
        self.canvas.addAction(self.act_apply_strokes)

        lm = mb.addMenu("&Layer")
        self._action(lm, "&Add layer", self.add_layer, "Ctrl+Shift+N")
        self._action(lm, "&Remove layer", lambda: self._on_current(self.remove_layer), "Del")
        self._action(lm, "&Duplicate layer", lambda: self._on_current(self.duplicate_aside), "Ctrl+D")
        self._action(lm, "&Mirror layer", lambda: self._on_current(self.mirror_layer), "Ctrl+M")
        self._action(lm, "Mirror layer about its &own axis",
                     lambda: self._on_current(lambda i: self.mirror_layer(i, axis="own")), "Ctrl+Shift+M")
        lm.addSeparator()
        self._action(lm, "Bring &forward", lambda: self._on_current(lambda lid: self.move_depth(lid, +1)), "PgUp")
        self._action(lm, "Send &backward", lambda: self._on_current(lambda lid: self.move_depth(lid, -1)), "PgDown")
        self._action(lm, "Bring to fron&t", lambda: self._on_current(lambda lid: self.move_depth(lid, "front")), "Home")
        self._action(lm, "Send to bac&k", lambda: self._on_current(lambda lid: self.move_depth(lid, "back")), "End")
        lm.addSeparator()
        # Arrows move the selected part only while the drawing has the focus: elsewhere they
        # belong to the lists and fields.
        for text, key, step in (("left", "Left", (-1, 0)), ("right", "Right", (1, 0)), ("up", "Up", (0, 1)), ("down", "Down", (0, -1))):
            act = self._action(lm, f"Move {text}", lambda _=False, s=step: self._on_current(lambda lid: self.nudge(lid, s)), key)
            act.setShortcutContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
            self.canvas.addAction(act)

        v = mb.addMenu("&View")
        self._action(v, "&Fit drawing", self.canvas.fit, "Ctrl+0")
        self._action(v, "Reference &image…", self.reference_dialog)
        self._action(v, "&Clear reference image", lambda: self.canvas.set_reference_image(None))
        v.addSeparator()
        self.act_light = self._action(v, "&Light tool", lambda on: self.modes.light.setChecked(on), "L", checkable=True)
        v.addSeparator()
        group = QActionGroup(self)
        for name, key in (("editing", "F2"), ("sculpture", "F3"), ("observation", "F4")):
            act = self._action(v, f"{name.upper()}", lambda _=False, n=name: self.set_mode(n), key)
            group.addAction(act)
        h = mb.addMenu("&Help")
        self._action(h, "&Gestures and keys", self.toggle_help, ["F1", "?"])
        self.act_plugins = self._action(h, "&Plugins…", self.show_plugins)
        self.update_recent_menu()

    def _build_tool_palette(self) -> None:
        """Every registered tool, in the SCULPTURE panel's palette and a Tools menu with its
        shortcut (a tool's ``shortcut`` that the window already uses is dropped, with a
        message naming the plugin)."""
        entries = self.sculpt.tool_entries()
        taken = {a.shortcut().toString() for a in self.findChildren(QAction) if not a.shortcut().isEmpty()}
        menu = QMenu("&Tools", self)
        help_menu = next((a for a in self.menuBar().actions() if a.text() == "&Help"), None)
        self.menuBar().insertMenu(help_menu, menu) if help_menu is not None else self.menuBar().addMenu(menu)
        self.tool_actions: dict[str, QAction] = {}
        usable = []
        icons = {}
        for name, label, shortcut in entries:
            cls = self.host.tools[name]
            icon_path = getattr(cls, "icon", "") or ""
            if icon_path and Path(icon_path).is_file():
                icons[name] = QIcon(str(icon_path))
            key = QKeySequence(shortcut).toString() if shortcut else ""
            if key and key in taken:
                who = self.host.provider_of(cls) if hasattr(self.host, "provider_of") else None
                self.show_message(f"tool {name!r} (plugin {who!r}): shortcut {shortcut} is already used; choose it from the Tools menu")
                key = ""
            taken.add(key)
            act = self._action(menu, label, lambda _=False, n=name: self.select_tool(n), key or None)
            if name in icons:
                act.setIcon(icons[name])
            self.tool_actions[name] = act
            usable.append((name, label, key))
        if not entries:
            menu.addAction("(no tool plugin installed)").setEnabled(False)
        self.sculpt_panel.set_tools(usable, self.sculpt.tool_name, icons)

    def select_tool(self, name: str) -> None:
        """Switch to SCULPTURE with the tool ``name`` (palette, Tools menu, shortcut)."""
        if self.mode != "editing" or self.state != "sculpture":
            self.set_mode("sculpture")
        if self.sculpt.select_tool(name):
            self.sculpt_panel.show_state(self.sculpt)

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
            lambda k: self.view3d.set_style(self.view3d.style, k) if k > 0 else None
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

    def _on_light(self, light) -> None:
        self.light_panel.show_light(light)
        self._thumbnail_timer.start()

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

    # --- modes ----------------------------------------------------------------------------------
    def set_mode(self, mode: str) -> None:
        """"editing" (keeps the state), "creation", "sculpture" or "observation"."""
        if mode in ("creation", "sculpture"):
            self.set_state(mode)
            mode = "editing"
        self.mode = mode
        for b, on in ((self.modes.editing, mode == "editing"), (self.modes.observation, mode == "observation")):
            b.blockSignals(True)
            b.setChecked(on)
            b.blockSignals(False)
        self.modes._enable(mode)
        self.light_panel.setVisible(mode == "editing")
        if mode == "observation":
            self.center.setCurrentWidget(self.view3d)
            self.controls.setCurrentWidget(self.observe_page)
            self.view3d.activate()
        else:
            self.view3d.deactivate()
            self.center.setCurrentWidget(self.canvas)
            self.set_state(self.state)
        self.app_context._set_mode(self.mode, self.state)
        self._focus_center()

    def _focus_center(self) -> None:
        """Keys go to the view after every mode switch: the widget that had focus (a mode
        button, or the canvas just hidden) would otherwise keep it or leave none."""
        widget = self.center.currentWidget()
        gl = getattr(widget, "gl", None)
        target = gl if isinstance(gl, QWidget) else widget
        target.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        target.setFocus(Qt.FocusReason.OtherFocusReason)
        self.activateWindow()

    def toggle_help(self) -> None:
        self.help_overlay.toggle()

    def set_state(self, state: str) -> None:
        self.state = state
        self.app_context._set_mode(self.mode, self.state)
        for b, on in ((self.modes.creation, state == "creation"), (self.modes.sculpture, state == "sculpture")):
            b.blockSignals(True)
            b.setChecked(on)
            b.blockSignals(False)
        if self.mode != "editing":
            return
        self.controls.setCurrentWidget(self.creation_page if state == "creation" else self.sculpt_panel)
        self._apply_interaction()
        if state == "sculpture":
            self.sculpt.reset()
            self.sculpt_panel.show_state(self.sculpt)
        self._focus_center()

    def _light_toggled(self, on: bool) -> None:
        self.act_light.setChecked(on)
        self._apply_interaction()
        self._focus_center()

    def _apply_interaction(self) -> None:
        if self.modes.light.isChecked():
            self.canvas.set_interaction("light")
        else:
            self.canvas.set_interaction("draw" if self.state == "creation" else "sculpt")

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

    def _on_current(self, fn) -> None:
        if self.current_layer is not None and self.current_layer in self.doc.layer_ids():
            fn(self.current_layer)
        else:
            self.show_message("select a part first (click it in the drawing or in the Layers list)")

    def add_layer(self) -> None:
        cmd = C.AddLayer()
        if self.push(cmd):
            self.layers_panel.select(cmd.id)

    def remove_layer(self, layer_id: str) -> None:
        self.push(C.RemoveLayer(layer=layer_id))

    def duplicate_layer(self, layer_id: str) -> None:
        cmd = C.DuplicateLayer(layer=layer_id)
        if self.push(cmd):
            self.layers_panel.select(cmd.new_id)

    def mirror_layer(self, layer_id: str, axis: str = "host") -> None:
        """Mirror about the host's vertical axis (a left leg becomes a right leg; a free part
        about its own), or with ``axis="own"`` about the part's own axis."""
        if self._refuse_if_busy():
            return
        cmd = C.MirrorLayer(layer=layer_id, axis=axis)
        name = self.doc.layer(layer_id).name

        def done(c):
            where = "its host's axis" if c.used_axis == "host" else "its own axis"
            self.show_message(f"mirrored “{name}” about {where}")

        self.runner.run(cmd, label="Inflating", on_done=done)

    def set_params(self, params: dict) -> None:
        if self.current_layer is None:
            self.show_message("select a part first (click it) to change its parameters")
            return
        if self.runner.busy:
            # Coalesced: the edits made during a solve run together when it ends, the last
            # value of each parameter wins, none is dropped.
            self._pending_params.setdefault(self.current_layer, {}).update(params)
            self.show_message("a solve is running: this change is applied when it ends")
            return
        self._run_params(self.current_layer, params)

    def set_inflater(self, name: str) -> None:
        """The Creation panel's inflater: the selected part is inflated by it (from its
        defaults; one undo step, its sculpt edits re-applied or the switch refused), and new
        parts are too."""
        layer = self.doc.layer(self.current_layer) if self.current_layer in self.doc.layer_ids() else None
        if layer is None or layer.solver == name or (layer.solver is None and name == self.host.default_solver_name("inflate")):
            self.show_message(f"new parts are inflated by “{name}”")
            return
        if self._refuse_if_busy():
            self._sync_current_layer()
            return
        self.runner.run(
            C.SetInflateParams(layer=layer.id, solver=name),
            label=f"Inflating with {name}",
            on_done=lambda *_: self.show_message(f"“{layer.name}” is inflated by “{name}”; new parts are too"),
            on_error=lambda exc: self._sync_current_layer() or False,
        )

    def set_assembly(self, solver, params: dict) -> None:
        """The Assembly panel: choose the assembler (``solver``, from its defaults) or change
        its parameters; one ``set_assembly`` (one undo step). A value the assembler refuses is
        one status line, and the panel shows the document's values again."""
        if self._refuse_if_busy():
            self.assembly_panel.show_assembly(self.doc.assembly)
            return
        try:
            self.doc.push(C.SetAssembly(solver=solver, params=dict(params)))
        except SketchforgeError as exc:
            self.show_message(error_text(exc))
            self.assembly_panel.show_assembly(self.doc.assembly)

    def _run_params(self, layer_id: str, params: dict) -> None:
        edits = len(self.doc.layer(layer_id).edits)
        # With sculpt edits the layer is re-inflated and its edits re-applied in order (or the
        # change is refused with the reason); say so, since it takes longer and may fail.
        label = f"Inflating and re-applying {edits} sculpt edit{'s' * (edits != 1)}" if edits else "Inflating"
        self.runner.run(
            C.SetInflateParams(layer=layer_id, params=params),
            label=label,
            on_done=(lambda *_: self.show_message(f"re-applied {edits} sculpt edit{'s' * (edits != 1)} to the rebuilt surface")) if edits else None,
            on_error=lambda exc: self._sync_current_layer() or False,
        )

    def _run_pending(self) -> None:
        """After a solve: the strokes drawn meanwhile (in order), then the parameter edits."""
        if self.runner.busy:
            return
        if self._pending_strokes:
            pts, kind = self._pending_strokes.pop(0)
            self.draw_stroke(pts, kind)
            return
        self._run_pending_params()

    def _run_pending_params(self) -> None:
        if self.runner.busy or not self._pending_params:
            return
        layer_id = next(iter(self._pending_params))
        params = self._pending_params.pop(layer_id)
        if layer_id not in self.doc.layer_ids():
            self._sync_current_layer()
            return
        old = self.doc.layer(layer_id).params
        if all(old.get(k) == v for k, v in params.items()):
            self._sync_current_layer()
            self._run_pending_params()
            return
        self._run_params(layer_id, params)

    def _azimuth(self) -> float:
        """The light's azimuth; straight overhead (which has none), the one the panel shows."""
        light = self.doc.light
        return self.light_panel.angle.value() if light.elevation >= 90.0 else light.angle

    def set_light_angle(self, degrees: float) -> None:
        """A typed azimuth: the light turns about the view axis, keeping its elevation."""
        light = Light.from_angle(degrees, 0.0 if self.doc.light.in_plane else self.doc.light.elevation)
        if light != self.doc.light:
            self.push(C.SetLight(direction=light.to_list()))

    def set_light_elevation(self, degrees: float) -> None:
        """A typed elevation (0: in the drawing plane, 90: overhead), keeping the azimuth."""
        light = Light.from_angle(self._azimuth(), degrees)
        if light != self.doc.light:
            self.push(C.SetLight(direction=light.to_list()))

    def _light_drag_started(self) -> None:
        self._light_gesture = C.new_gesture_id()

    def _light_dragged(self, light) -> None:
        """A step of a drag on the light disc: commands of one drag share a gesture id, so the
        drag is one undo step."""
        gesture = getattr(self, "_light_gesture", None)
        if gesture is not None and light != self.doc.light:
            if not self.push(C.SetLight(direction=light.to_list(), gesture=gesture)):
                self._light_gesture = None  # refused (a solve runs): the rest of the drag too
                self.light_panel.show_light(self.doc.light)

    def _light_drag_ended(self) -> None:
        self._light_gesture = None

    # --- parts drawn and arranged with the mouse and keys (Monster Mash) ------------------------
    def _outlines(self) -> list:
        return layer_outlines(self.doc)

    def draw_stroke(self, points, kind: str = "front") -> None:
        """A finished stroke of ``kind`` "front", "behind" or "redraw" (see
        :func:`~sketchforge.tools.draw.plan_stroke` for where it goes)."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if self.runner.busy:
            # Drawn while the last part inflates: drawn as soon as it is done, so quick
            # strokes are never lost; where it goes is decided then, on the new document.
            self._pending_strokes.append((pts, kind))
            n = len(self._pending_strokes)
            self.show_message(f"{n} stroke{'s' * (n != 1)} waiting: drawn when the current inflation ends (Esc drops them)")
            return
        if len(pts) < 2:
            self.show_message("the stroke is too short: press, drag around the shape and release")
            return
        plan = plan_stroke(self.doc, pts, kind, self.current_layer, SPLICE_PIXELS * self.canvas.pixel_size())
        if plan.refusal is not None:
            self.show_message(plan.refusal)
        elif plan.redraw is not None:
            what = {"whole": "redrew the outline", "stretch": "redrew part of the outline", "hole": "cut a hole"}[plan.redraw]
            self._redraw(self.doc.layer(plan.target), plan.points, plan.closed, what, holes=plan.holes,
                         notes=plan.notes)
        else:
            self._new_part(plan)

    def _new_part(self, plan) -> None:
        """A new part (or the contour of the empty layer ``plan.target``)."""
        inflater = self.creation_panel.new_part_inflater
        if plan.target is not None and self.doc.layer(plan.target).solver is not None:
            inflater = None  # an empty layer keeps the inflater it was given
        tool = DrawContourTool(self.doc, target_layer=plan.target, closed=plan.closed, index=plan.index, inflater=inflater)
        before, cmd = tool.commands_for(plan.points)
        kind = "closed" if plan.closed else "open"

        def done(c):
            self.layers_panel.select(c.layer)
            notes = list(plan.notes) + self._attachment_notes(self.doc.layer(c.layer))
            self.show_message(f"new {kind} part “{self.doc.layer(c.layer).name}”" + "".join("; " + n for n in notes))

        self.runner.run(cmd, label="Inflating", macro="Draw layer" if before else None, before=before, on_done=done,
                        on_error=self._drawing_slip)

    def _drawing_slip(self, exc) -> bool:
        """A stroke that cannot become an outline (it crosses itself, encloses no area): a slip
        of the hand, said in the status bar; nothing changed and nothing to dismiss (a
        blocking dialog for each slip was too much, issue 38). Other errors: a dialog."""
        if not isinstance(exc, ContourError):
            return False
        self.show_message(f"the stroke was not drawn: {error_text(exc)}")
        return True

    def _redraw(self, layer, pts, closed: bool, what: str, keep_edits: bool = True, holes=(), notes=()) -> None:
        """Replace ``layer``'s outline and holes (one undo step); its sculpt edits are kept when
        they still apply, else the person is asked whether to redraw without them."""
        keep = keep_edits and bool(layer.edits)
        tool = DrawContourTool(self.doc, target_layer=layer.id, closed=bool(closed), keep_edits=keep, holes=holes)
        _, cmd = tool.commands_for(pts)

        def error(exc) -> bool:
            if self._drawing_slip(exc):
                return True
            if not isinstance(exc, EditsDoNotApplyError):
                return False
            if ask_yes_no(
                self,
                "Redraw the contour?",
                f"Layer “{layer.name}” has {len(layer.edits)} sculpt edit(s) that do not apply to the new "
                f"outline ({exc}). Redraw it without them? (Undo brings them back.)",
                default_yes=True,  # Yes loses nothing (Undo brings the edits back); No drops the stroke
            ):
                QTimer.singleShot(0, lambda: self._redraw(self.doc.layer(layer.id), pts, closed, what, keep_edits=False,
                                                          holes=holes, notes=notes))
            else:
                self.show_message("the outline was not redrawn: its sculpt edits would be lost")
            return True

        kept = f"; kept its {len(layer.edits)} sculpt edit(s)" if keep else ""
        kept += "".join("; " + n for n in notes)
        glued = self._parts_glued_to(layer)

        def done(c) -> None:
            self.show_message(f"{what} {'in' if what == 'cut a hole' else 'of'} “{layer.name}”{kept}")
            self._check_parts_still_glued(layer.id, glued, what, c)

        self.runner.run(cmd, label="Inflating", on_done=done, on_error=error)

    def _attachment_notes(self, layer) -> list[str]:
        """What the person should hear when a part is drawn (issue 34): its junction runs off
        the part it lies on, spans two parts (glued to the one holding most of it) or cannot
        be glued at all (it will be assembled free, and why) — said now, not first in
        OBSERVATION."""
        if layer.closed or layer.mesh is None or len(layer.mesh.junction) < 2:
            return []
        host, problem = C.attachment(self.doc, layer)
        if problem:
            return [problem]
        note = C.attachment_note(self.doc, layer)
        if note:
            return [note]
        return [f"glued to “{host.name}”"] if host is not None else []

    def _parts_glued_to(self, host) -> list[str]:
        """Ids of the parts the assembly glues to ``host`` now (their junction lies on it)."""
        return [pid for pid, (now, _) in C.attachments(self.doc).items() if pid != host.id and now is host]

    def _check_parts_still_glued(self, host_id: str, glued: list[str], what: str, cmd) -> None:
        """After ``host_id``'s outline changed: each part that was glued to it and whose
        junction no longer lies on it is named in the status bar, and the person is offered
        to undo the change (issue 30: a tail left hanging by a redrawn body was only found in
        OBSERVATION, as an assembly error)."""
        if host_id not in self.doc.layer_ids():
            return
        host = self.doc.layer(host_id)
        left = []
        present = [pid for pid in glued if pid in self.doc.layer_ids()]
        for pid, (now, problem) in C.attachments(self.doc, set(present)).items():
            part = self.doc.layer(pid)
            if now is None or now.id != host_id:
                where = (f"it is now glued to “{now.name}”" if now is not None else
                         problem if problem else "it is now a free part")
                left.append((part, where))
        if not left:
            return
        names = ", ".join(f"“{p.name}”" for p, _ in left)
        self.show_message(f"the junction of {names} no longer lies on “{host.name}”: Ctrl+Z undoes the change")
        details = "; ".join(f"“{p.name}”: {w}" for p, w in left)
        if ask_yes_no(
            self,
            "Parts left their host",
            f"After this change ({what}), the junction of {names} no longer lies on “{host.name}” ({details}). "
            "Undo the change? (No keeps it: redraw or move those parts to attach them again.)",
            default_yes=False,  # keep what the person just did; Ctrl+Z still undoes it
        ):
            # Only if the change is still the last thing done (a queued stroke may have run
            # while the question was open).
            if self.runner.busy or host_id not in self.doc.layer_ids() or self.doc.layer(host_id) is not cmd._new:
                self.show_message("not undone: something changed meanwhile; Ctrl+Z undoes step by step")
                return
            self.doc.undo_stack.undo()
            self.show_message(f"undid the change of “{host.name}”: {names} glued to it again")

    def set_closed(self, closed: bool) -> None:
        """The panel's box: make the selected part closed (free) or open (attached by its
        closing segment), re-inflated from the same stroke."""
        layer = self.doc.layer(self.current_layer) if self.current_layer in self.doc.layer_ids() else None
        if layer is None or layer.points is None:
            self.show_message("select a part first (click it) to make it open or closed")
            self._sync_current_layer()
            return
        if self._refuse_if_busy():
            self._sync_current_layer()
            return
        if not closed and closes(layer.points, layer.params):
            self._sync_current_layer()
            self.show_message(f"“{layer.name}” stays closed: the ends of its stroke meet, so it has no open side to attach by")
            return
        self._redraw(layer, layer.points, closed, "made closed" if closed else "made open")

    def _selected_or_say(self, what: str):
        if self.current_layer not in self.doc.layer_ids():
            self.show_message(f"select a part first (click it) to {what}")
            return None
        return self.doc.layer(self.current_layer)

    def select_at(self, point) -> None:
        k = part_at(point, self._outlines())
        if k < 0:
            self.show_message("no part here: drag to draw one, click a part to select it")
            return
        self.layers_panel.select(self.doc.layers[k].id)
        self.show_message(f"selected “{self.doc.layers[k].name}”")

    def duplicate_at(self, point, button: str) -> None:
        """Double click: duplicate the part under the pointer, behind it (left) or in front
        (right), as Monster Mash does."""
        k = part_at(point, self._outlines())
        if k < 0:
            self.show_message("double-click a part to duplicate it (left: behind it, right: in front)")
            return
        layer = self.doc.layers[k]
        cmd = C.DuplicateLayer(layer=layer.id, index=k if button == "left" else k + 1)
        if self.push(cmd):
            self.layers_panel.select(cmd.new_id)
            self.show_message(
                f"duplicated “{layer.name}” {'behind' if button == 'left' else 'in front of'} itself, in place: "
                "the arrow keys move the copy"
            )

    def duplicate_aside(self, layer_id: str) -> None:
        """Ctrl+D: a copy in front, moved right by 1.25 part widths (beside it)."""
        layer = self.doc.layer(layer_id)
        pts = layer.points if layer.points is not None else None
        width = float(np.ptp(pts[:, 0])) if pts is not None and len(pts) else 0.0
        step = DUPLICATE_OFFSET * (width if width > 0 else 0.4)
        cmd = C.DuplicateLayer(layer=layer_id, offset=[step, 0.0])
        if self.push(cmd):
            self.layers_panel.select(cmd.new_id)
            self.show_message(f"duplicated “{layer.name}”, moved aside")

    def nudge(self, layer_id: str, step) -> None:
        """Arrow keys: move the selected part NUDGE_PIXELS screen pixels (one undo step)."""
        d = NUDGE_PIXELS * self.canvas.pixel_size()
        if self.push(C.TransformLayer(layer=layer_id, matrix=[[1.0, 0.0, step[0] * d], [0.0, 1.0, step[1] * d]])):
            self.show_message(f"moved “{self.doc.layer(layer_id).name}” (arrow keys)")

    def transform_layer(self, layer_id: str, matrix) -> None:
        """The end of a handle drag: one transform_layer with the whole drag's matrix."""
        if layer_id not in self.doc.layer_ids() or self._refuse_if_busy():
            return
        cmd = C.TransformLayer(layer=layer_id, matrix=matrix)
        if self.push(cmd):
            self.show_message(f"{cmd.text().split()[0].lower()}d “{self.doc.layer(layer_id).name}” (Ctrl+Z undoes it)")

    def move_depth(self, layer_id: str, where) -> None:
        """PgUp / PgDn: one step to the front / back; Home / End: to the very front / back."""
        n = len(self.doc.layers)
        i = self.doc.index_of(layer_id)
        name = self.doc.layer(layer_id).name
        target = {"front": n - 1, "back": 0}.get(where, i + (where if isinstance(where, int) else 0))
        target = max(0, min(n - 1, target))
        if target == i:
            self.show_message(f"“{name}” is already at the {'front' if i == n - 1 else 'back'}")
            return
        if self.push(C.MoveLayer(layer=layer_id, index=target)):
            self.layers_panel.select(layer_id)
            self.show_message(f"“{name}” is now {'the frontmost' if target == n - 1 else 'the backmost' if target == 0 else f'at depth {target + 1} of {n}'} part")

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

    # --- files ----------------------------------------------------------------------------------
    def maybe_save(self) -> bool:
        """True when it is fine to drop the document (saved, or the person chose to)."""
        if not self.is_modified():
            return True
        answer = QMessageBox.question(
            self,
            "Unsaved changes",
            "The document has unsaved changes. Save them first?",
            QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Discard | QMessageBox.StandardButton.Cancel,
            QMessageBox.StandardButton.Save,
        )
        if answer == QMessageBox.StandardButton.Save:
            return self.save()
        return answer == QMessageBox.StandardButton.Discard

    def adopt(self, loaded, path: Path | None, stamp: tuple | None = None) -> None:
        """Take over the state of a freshly loaded document (history starts here). ``stamp``:
        what ``path`` held when ``loaded`` was read from it (:func:`ff.stamp_of`), so that a
        save can tell whether someone else changed the file since."""
        self._pending_strokes.clear()
        self._pending_params.clear()
        self.runner.cancel()
        self.doc.adopt(loaded)
        self.path = path
        self.disk_stamp = stamp if path is not None else None
        # A new autosave file; the records of solves still running (a cancelled one, the
        # assembly) go on until those solves end.
        self.autosaver = self.autosaver.hand_over(path, original_sha256=self.disk_stamp[4] if self.disk_stamp else None)
        self.current_layer = None
        self.canvas.rebuild()
        self._sync_all()
        self.history_panel.rebuild()
        self.canvas.fit()
        self.view3d.reframe()  # a new model: frame it when it is next shown

    def new_document(self) -> None:
        if self._refuse_if_busy() or not self.maybe_save():
            return
        from sketchforge.document.document import Document

        self.adopt(Document(host=self.host), None)

    def open_dialog(self) -> None:
        if self._refuse_if_busy() or not self.maybe_save():
            return
        path, _ = QFileDialog.getOpenFileName(self, "Open document", str(self._dir()), FILE_FILTER)
        if path:
            self.open_path(Path(path), ask=False)

    def open_path(self, path: Path, ask: bool = True) -> bool:
        """Open a file; on error show it and keep the open document untouched."""
        if ask and (self._refuse_if_busy() or not self.maybe_save()):
            return False
        info: dict = {}
        try:
            loaded = ff.load(path, host=self.host, info=info)
        except SketchforgeError as exc:
            show_error(self, "Cannot open the document", exc)
            return False
        except Exception as exc:  # noqa: BLE001 - a bug, but the open document must survive
            show_error(self, "Cannot open the document", exc)
            return False
        self.adopt(loaded, Path(path), ff.stamp_of(info["stat"], info["sha256"]))
        self._add_recent(path)
        self.show_message(f"opened {path}")
        return True

    def save(self) -> bool:
        if self.path is None:
            return self.save_as()
        return self.save_to(self.path)

    def save_as(self) -> bool:
        path, _ = QFileDialog.getSaveFileName(self, "Save document", str(self._dir() / "untitled.json"), FILE_FILTER)
        if not path:
            return False
        return self.save_to(Path(path))

    def save_to(self, path: Path) -> bool:
        if self._refuse_if_busy():
            return False
        if self.path is not None and same_file(path, self.path):
            changed, self.disk_stamp = ff.changed_on_disk(path, self.disk_stamp)
            if changed:
                return self._save_over_a_changed_file(Path(path))
        try:
            stamp = ff.save(self.doc, path)
        except SketchforgeError as exc:
            show_error(self, "Cannot save the document", exc)
            return False
        self.path = Path(path)
        self.disk_stamp = stamp
        # running solves keep their record
        self.autosaver = self.autosaver.hand_over(self.path, original_sha256=stamp[4])
        self._add_recent(path)
        self._sync_title()
        self.history_panel.rebuild()
        self.show_message(f"saved {path}")
        return True

    def _save_over_a_changed_file(self, path: Path) -> bool:
        """The window's file was changed on disk since it was opened or saved here (another
        window or program saved over it): saving now would destroy that work without a word
        (issue 38). Ask; Enter chooses Save As, which loses nobody's work."""
        choice = errors_ui.ask_choice(
            self,
            "The file changed on disk",
            f"{path} was changed on disk since this window opened or saved it (by another window or program).\n\n"
            "Overwrite: replace it with this window's document (the other changes are lost).\n"
            "Save As: save this window's document as another file (nothing is lost).\n"
            "Reload: open the file as it is on disk (this window's unsaved changes are lost).",
            ["Overwrite", "Save As…", "Reload", "Cancel"],
            default=1,
            cancel=3,
        )
        if choice == 0:
            self.disk_stamp = None  # the person chose: write over it
            return self.save_to(path)
        if choice == 1:
            return self.save_as()
        if choice == 2:
            self.open_path(path, ask=False)
            return False
        self.show_message(f"not saved: {path} changed on disk")
        return False

    def export_dialog(self) -> None:
        filters = ";;".join(
            f"{e.description} ({' '.join('*' + s for s in e.suffixes)})" for e in self.host.exporters.values()
        )
        path, _ = QFileDialog.getSaveFileName(self, "Export mesh", str(self._dir() / "model.obj"), filters)
        if path:
            self.export_to(Path(path))

    def export_to(self, path: Path) -> bool:
        """Export the assembled model (the visible layers merged without an assembler)."""
        try:
            refuse_input_as_output(path, [self.path], "export")  # never over the open document
            exporter = self.host.exporter_for(path, self.doc)
            if exporter.write_document is not None:  # a whole document (an animation): seconds of solving
                from sketchforge.qt.document_export import export_document_in_background

                return export_document_in_background(self, exporter, path)
            summary = self.host.export(path, mesh=self.doc.export_mesh())  # atomic, errors name the plugin
        except SketchforgeError as exc:
            show_error(self, "Cannot export", exc)
            return False
        self.show_message(f"exported {path} ({summary})")
        return True

    def reference_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Reference image", str(self._dir()), "Images (*.png *.jpg *.jpeg *.bmp)")
        if path:
            try:
                self.canvas.set_reference_image(path)
            except SketchforgeError as exc:
                show_error(self, "Cannot show the image", exc)

    def _dir(self) -> Path:
        return self.path.parent if self.path is not None else Path.cwd()

    # --- recent files ---------------------------------------------------------------------------
    def recent_files(self) -> list[str]:
        value = self.settings.value("recent_files", [])
        if isinstance(value, str):
            value = [value]
        return [str(v) for v in (value or [])]

    def _add_recent(self, path) -> None:
        p = str(Path(path).resolve())
        files = [p] + [f for f in self.recent_files() if f != p]
        self.settings.setValue("recent_files", files[:MAX_RECENT])
        self.update_recent_menu()

    def update_recent_menu(self) -> None:
        self.recent_menu.clear()
        files = self.recent_files()
        for f in files:
            act = self.recent_menu.addAction(f)
            act.triggered.connect(lambda _=False, f=f: self.open_path(Path(f)))
        self.recent_menu.setEnabled(bool(files))

    def apply_sculpt_strokes(self) -> None:
        """Enter in SCULPTURE: apply the strokes drawn for the picked isophotes as one edit."""
        if self.canvas.interaction != "sculpt":
            return
        if self._refuse_if_busy():
            return
        self.sculpt.apply_drawn()

    def cancel_current(self) -> None:
        """Esc: close the help, stop the running solve, and drop a sculpt stroke being drawn
        with its preview."""
        if self.help_overlay.isVisible():
            self.help_overlay.hide()
            self._focus_center()
            return
        if self._pending_strokes:
            self.show_message(f"dropped {len(self._pending_strokes)} waiting stroke(s)")
        self._pending_strokes.clear()
        self.runner.cancel()
        if self.canvas.interaction == "sculpt":
            self.sculpt.cancel()

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
