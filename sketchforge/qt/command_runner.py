"""Push commands whose ``prepare`` is slow without freezing the window.

``run(cmd)``: ``cmd.prepare(doc)`` runs on a pool thread, then ``doc.push(cmd)`` on the GUI
thread swaps the result in. While a command is being prepared, the runner is ``busy`` and the
window refuses other edits, so the document the worker reads does not change under it. An
error (a SketchforgeError from the solver, or from ``push``) leaves the document as it was and
is reported; a cancelled job's result is dropped.

A macro can wrap the push: ``run(cmd, macro="Draw layer", before=[AddLayer(...)])`` opens the
macro, pushes the cheap ``before`` commands at once (prepare needs the new layer), prepares
``cmd`` off-thread and closes the macro; on error or cancel the macro is aborted (undone).

A native crash in a solver ends the process, so the runner takes an optional ``guard`` (the
app's autosaver): ``token = guard.before(cmd, macro=..., before=[...])`` is called on the GUI
thread before anything happens (before the macro opens, so the state it records is the one
before the user's action) and ``guard.after(token)`` once ``prepare`` has returned on the
worker, whatever the outcome, a cancelled job included (its native code runs on until it
returns). :class:`GuardedJobs` does the same for other native work started through a
JobRunner (the OBSERVATION view's assembly).
"""

from __future__ import annotations

import functools
from collections.abc import Callable

from PySide6.QtCore import QObject, QThreadPool, Signal

from sketchforge.qt.workers import Job, JobRunner

#: ``run``'s default ``guard_token``: the runner starts its own crash record.
_NO_TOKEN = object()


def end_guard(guard, token) -> None:
    """End a crash record started with ``guard.before`` (nothing if there was none)."""
    if guard is not None and token is not None:
        guard.after(token)


class CommandRunner(QObject):
    busy_changed = Signal(bool)
    #: (exception, traceback text, the command) — the window shows it
    failed = Signal(object, str, object)
    #: the command, after it was pushed
    pushed = Signal(object)
    #: (guard token) emitted on the worker when ``prepare`` returns; queued to the GUI thread
    _prepare_returned = Signal(object)
    #: the running preparation was cancelled (the window stops the solver process's job)
    cancelled = Signal()

    def __init__(self, doc, jobs: JobRunner, parent: QObject | None = None, guard=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.jobs = jobs
        self.guard = guard
        # Commands prepare on threads of their own, not on the shared pool (the warm-up, the
        # assembly, thumbnails): a preparation that waits on the solver process, or a cancelled
        # one whose native code runs on, never takes a thread the rest of the app needs
        # (issue 38: two hung inflations stopped every computation). Idle threads expire.
        self.pool = QThreadPool(self)
        self.pool.setMaxThreadCount(max(4, QThreadPool.globalInstance().maxThreadCount()))
        self._job: Job | None = None
        self._macro_open = False
        self._on_cancel: Callable | None = None
        self._prepare_returned.connect(self._guard_after)

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
        guard_token=_NO_TOKEN,
    ) -> bool:
        """Start; returns False (and does nothing) if another command is being prepared.

        ``guard_token``: the caller already called ``guard.before`` (because it changed the
        document first, e.g. undid an attempt it replaces) and passes what it returned (None
        when that flush failed: it is not retried on the changed document); the runner ends
        that record instead of starting its own. If ``run`` returns False the caller ends it."""
        if self.busy:
            return False
        before = list(before)
        # The state before the user's action, with the action named, is on disk before any
        # native code runs: a crash in the solver loses nothing and is not replayed.
        token = guard_token
        if token is _NO_TOKEN:
            token = self.guard.before(cmd, macro=macro, before=before) if self.guard is not None else None
        stack = self.doc.undo_stack
        if macro is not None:
            stack.begin_macro(macro)
            self._macro_open = True
        try:
            for c in before:
                self.doc.push(c)
        except Exception as exc:  # noqa: BLE001
            self._close_macro(abort=True)
            self._guard_after(token)
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
            self._report(self._named(exc, cmd), tb, cmd, on_error)

        def work():
            try:
                return cmd.prepare(self.doc)
            finally:
                self._prepare_returned.emit(token)  # before the result: the record goes first

        self._job = self.jobs.start(work, done, error, label=label, pool=self.pool)
        self.busy_changed.emit(True)
        return True

    def _guard_after(self, token) -> None:
        end_guard(self.guard, token)

    def cancel(self) -> None:
        """Drop the running preparation; the document stays as it was before ``run``."""
        if self._job is None:
            return
        self._job.cancel()
        self.jobs.cancel_all()
        self._job = None
        self._close_macro(abort=True)
        self.cancelled.emit()
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

    def _named(self, exc, cmd):
        """A bug in a command's ``prepare`` (not a SketchforgeError) as a PluginError naming the
        plugin that provides the command (the traceback still goes to the dialog's details)."""
        from sketchforge.errors import PluginError, SketchforgeError

        if isinstance(exc, SketchforgeError) or not isinstance(exc, Exception):
            return exc
        host = getattr(self.doc, "host", None)
        who = host.provider_of(type(cmd)) if hasattr(host, "provider_of") else None
        by = f" (from plugin {who!r})" if who else ""
        err = PluginError(f"command {getattr(cmd, 'name', '?')!r}{by} failed: {type(exc).__name__}: {exc}; the document is unchanged")
        err.__cause__ = exc
        return err

    def _report(self, exc, tb, cmd, on_error) -> None:
        if on_error is not None and on_error(exc):
            return
        self.failed.emit(exc, tb, cmd)


class GuardedJobs(QObject):
    """A JobRunner for work that runs native code (the assembly's OSQP): ``start`` calls
    ``guard.before(None, text=text)`` first and ``guard.after(token)`` once the callable has
    returned on the worker (cancelled or not). Everything else is the wrapped JobRunner's."""

    _returned = Signal(object)

    def __init__(self, jobs: JobRunner, guard, text: str, parent: QObject | None = None) -> None:
        super().__init__(parent if parent is not None else jobs)
        self._jobs = jobs
        self.guard = guard
        self.text = text
        self._returned.connect(self._after)

    def start(self, fn, on_done, on_error, label: str = "Working", background: bool = False):
        token = self.guard.before(None, text=self.text) if self.guard is not None else None

        @functools.wraps(fn)  # keeps fn's signature: JobRunner passes ``cancelled`` if it takes it
        def work(*args, **kwargs):
            try:
                return fn(*args, **kwargs)
            finally:
                self._returned.emit(token)

        return self._jobs.start(work, on_done, on_error, label=label, background=background)

    def _after(self, token) -> None:
        end_guard(self.guard, token)

    def __getattr__(self, name):  # running(), wait(), cancel_all(), busy_changed, ...
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self._jobs, name)
