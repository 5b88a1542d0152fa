"""Push commands whose ``prepare`` is slow without freezing the window.

``run(cmd)``: ``cmd.prepare(doc)`` runs on a pool thread, then ``doc.push(cmd)`` on the GUI
thread swaps the result in. While a command is being prepared, the runner is ``busy`` and the
window refuses other edits, so the document the worker reads does not change under it. An
error (a SketchforgeError from the solver, or from ``push``) leaves the document as it was and
is reported; a cancelled job's result is dropped.

A macro can wrap the push: ``run(cmd, macro="Draw layer", before=[AddLayer(...)])`` opens the
macro, pushes the cheap ``before`` commands at once (prepare needs the new layer), prepares
``cmd`` off-thread and closes the macro; on error or cancel the macro is aborted (undone).
"""

from __future__ import annotations

from typing import Callable

from PySide6.QtCore import QObject, Signal

from sketchforge.qt.workers import JobRunner


class CommandRunner(QObject):
    busy_changed = Signal(bool)
    #: (exception, traceback text, the command) — the window shows it
    failed = Signal(object, str, object)
    #: the command, after it was pushed
    pushed = Signal(object)

    def __init__(self, doc, jobs: JobRunner, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.jobs = jobs
        self._job = None
        self._macro_open = False
        self._on_cancel: Callable | None = None

    @property
    def busy(self) -> bool:
        return self._job is not None

    def run(
        self,
        cmd,
        label: str = "Computing",
        macro: str | None = None,
        before=(),
        on_done: Callable | None = None,
        on_error: Callable | None = None,
        on_cancel: Callable | None = None,
    ) -> bool:
        """Start; returns False (and does nothing) if another command is being prepared."""
        if self.busy:
            return False
        stack = self.doc.undo_stack
        if macro is not None:
            stack.begin_macro(macro)
            self._macro_open = True
        try:
            for c in before:
                self.doc.push(c)
        except Exception as exc:  # noqa: BLE001
            self._close_macro(abort=True)
            self._report(exc, "", cmd, on_error)
            return True
        self._on_cancel = on_cancel

        def done(_result) -> None:
            self._job = None
            try:
                self.doc.push(cmd)  # ``do`` only swaps the prepared result in
            except Exception as exc:  # noqa: BLE001
                self._close_macro(abort=True)
                self.busy_changed.emit(False)
                self._report(exc, "", cmd, on_error)
                return
            self._close_macro(abort=False)
            self.busy_changed.emit(False)
            self.pushed.emit(cmd)
            if on_done is not None:
                on_done(cmd)

        def error(exc, tb) -> None:
            self._job = None
            self._close_macro(abort=True)
            self.busy_changed.emit(False)
            self._report(exc, tb, cmd, on_error)

        self._job = self.jobs.start(lambda: cmd.prepare(self.doc), done, error, label=label)
        self.busy_changed.emit(True)
        return True

    def cancel(self) -> None:
        """Drop the running preparation; the document stays as it was before ``run``."""
        if self._job is None:
            return
        self._job.cancel()
        self.jobs.cancel_all()
        self._job = None
        self._close_macro(abort=True)
        self.busy_changed.emit(False)
        if self._on_cancel is not None:
            self._on_cancel()

    def _close_macro(self, abort: bool) -> None:
        if not self._macro_open:
            return
        self._macro_open = False
        if abort:
            self.doc.undo_stack.abort_macro()
        else:
            self.doc.undo_stack.end_macro()

    def _report(self, exc, tb, cmd, on_error) -> None:
        if on_error is not None and on_error(exc):
            return
        self.failed.emit(exc, tb, cmd)
