"""What a plugin's panel gets from the desktop app: :class:`AppContext`.

A plugin contributes panels through the ``sketchforge_qt_panels`` hook
(:class:`sketchforge.plugin_api.Panel`); the window calls each ``panel.create(app)`` once,
after its canvas, 3D view and sculpt controller exist, with ``app`` an :class:`AppContext`,
and shows the widget it returns in the controls of the panel's ``place``:

- ``"creation"``: below the inflation and display controls (EDITING → CREATION);
- ``"sculpture"``: inside the Sculpture box, between the tool palette and the tool's status;
- ``"observation"``: below the OBSERVATION note, above the free space.

Panels of one place are sorted by ``order`` (then name); ``available(host)`` false leaves one
out; a ``create`` that raises, or returns something that is not a QWidget, is named in the
status bar and the log (with its plugin) and left out, and the app starts without it.

This module is the stable API for panels: everything else in ``sketchforge.qt`` may change.
Rules the rest of the app keeps too: a panel changes the document only through commands
(:meth:`AppContext.run`, or ``app.doc.push`` for a quick one), and does no math itself.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QObject, Signal

# An exception as one status-bar line: a SketchforgeError's message, anything else with its type.
from sketchforge.qt.errors_ui import error_text

# The parameter form of a solver, generated from what it declares: a panel that lets the person
# choose a solver shows its parameters with it (the isophote tool's sculpt solver choice).
from sketchforge.qt.param_form import SolverForm

# The band radius range of the sculpt controller (drawing units): a panel with a band radius
# control offers exactly this range.
from sketchforge.qt.sculpt import MAX_RADIUS, MIN_RADIUS

__all__ = ["AppContext", "MAX_RADIUS", "MIN_RADIUS", "SolverForm", "error_text"]

BUSY = "a solve is running: wait for it or cancel it (Esc)"


class AppContext(QObject):
    """The app as a plugin panel sees it. Built by the window; read-only for panels.

    Attributes (read-only properties)
    ---------------------------------
    doc : Document
        The window's document, the same object for the window's whole life (opening a file
        replaces its state, not the object): connect to its signals (``layer_changed``,
        ``plugin_data_changed``, ``history_changed``...) once.
    host : PluginHost
        The plugins (``host.solvers("sculpt")``, ``host.commands``, ``host.provider_of``...).
    canvas : Canvas
        The 2D drawing view (``canvas.set_overlay(name, polylines)`` draws (k, 2) document
        polylines over the shapes).
    view3d : View3D
        The OBSERVATION view: ``gl`` (pyqtgraph's 3D view with GLViewWidget's API, rendered
        offscreen: :class:`sketchforge.qt.glview.GLView`; None without OpenGL),
        ``model_item`` (the shown mesh item) and the signal ``assembled_shown(mesh or None)``
        each time an assembled model is put on screen.
    sculpt : SculptController
        SCULPTURE's controller, which drives whichever tool is chosen in the palette:
        ``tool_name``, ``tool`` (the tool object, None without one), ``picking``,
        ``radius`` / ``set_radius(r)``, ``live_preview`` / ``set_preview(on)``,
        ``show_strips``, ``show_regions`` / ``set_show(strips, regions)``,
        ``set_options(dict)`` (extra command fields for a tool with ``set_options``),
        ``pick_count`` / ``strokes_drawn`` / ``strokes_to_apply`` and ``apply_drawn()`` (several
        isophotes picked with Shift+click: what Enter applies), and the signal ``changed``
        whenever any of these or the status text changes.
    mode, state : str
        ``mode`` "editing" or "observation"; ``state`` "creation" or "sculpture" (kept while
        in OBSERVATION).

    Signals
    -------
    mode_changed(mode: str, state: str)
        After every change of mode or state.
    closing()
        The window is closing: stop timers and threads the panel started.
    """

    mode_changed = Signal(str, str)
    closing = Signal()

    def __init__(self, *, doc, host, canvas, view3d, sculpt, runner, show_message: Callable[[str], None],
                 parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._doc, self._host, self._canvas, self._view3d, self._sculpt = doc, host, canvas, view3d, sculpt
        self._runner = runner
        self._show_message = show_message
        self._mode, self._state = "editing", "creation"

    @property
    def doc(self):
        return self._doc

    @property
    def host(self):
        return self._host

    @property
    def canvas(self):
        return self._canvas

    @property
    def view3d(self):
        return self._view3d

    @property
    def sculpt(self):
        return self._sculpt

    @property
    def mode(self) -> str:
        return self._mode

    @property
    def state(self) -> str:
        return self._state

    @property
    def busy(self) -> bool:
        """A command is being prepared (:meth:`run` would refuse another)."""
        return self._runner.busy

    def run(self, command, label: str = "Computing", on_done: Callable | None = None,
            on_error: Callable | None = None) -> bool:
        """Prepare ``command`` on a worker thread (``command.prepare(doc)``: the solve), with the
        status bar's progress indicator and Cancel, then push it on the undo stack on the GUI
        thread. Crash-safe: the autosave is brought up to date first. Returns False (and says
        so in the status bar) while another command is being prepared.

        ``on_done(command)`` runs after the push. ``on_error(exc) -> bool`` runs when the
        command failed (the document is unchanged); returning True means it was handled,
        otherwise the app shows the error naming the command."""
        if self._runner.busy:
            self.show_message(BUSY)
            return False
        return self._runner.run(command, label=label, on_done=on_done, on_error=on_error)

    def background(self, fn: Callable[[], Any], label: str, on_done: Callable | None = None) -> None:
        """Run ``fn()`` on a worker thread without progress indicator (a warm-up, such as a
        solver compiling ahead of its first use); ``on_done(result)`` on the GUI thread. A
        failure is only logged: nothing waits for it."""
        import logging

        def failed(exc, tb):
            logging.getLogger("sketchforge.qt").warning("%s failed: %s", label, exc)

        self._runner.jobs.start(fn, on_done or (lambda _r: None), failed, label=label, background=True)

    def show_message(self, text: str) -> None:
        """One line in the status bar (it fades after a few seconds)."""
        self._show_message(str(text))

    # --- the window's side -------------------------------------------------------------------------
    def _set_mode(self, mode: str, state: str) -> None:
        if (mode, state) != (self._mode, self._state):
            self._mode, self._state = mode, state
            self.mode_changed.emit(mode, state)
