"""Run slow pure work (a command's ``prepare``, an assembly, a solver warm-up) off the GUI thread.

A :class:`Job` wraps a callable in a ``QRunnable`` on a ``QThreadPool``; its result or error
comes back through Qt signals, queued onto the GUI thread, where the caller pushes the prepared
command on the document. Cancelling a job cannot interrupt numpy, so it marks the job cancelled:
the result is dropped when it arrives and the GUI is free at once. A callable that accepts a
``cancelled`` keyword gets a function it may poll to stop early.

:class:`JobRunner` owns the pool, keeps the jobs alive until they finish, and tells the progress
indicator (the status bar) when something is running.
"""

from __future__ import annotations

import inspect
import traceback
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QObject, QRunnable, QThreadPool, Signal


class _JobSignals(QObject):
    finished = Signal(object)  # result
    failed = Signal(object, str)  # exception, formatted traceback


class Job(QRunnable):
    """One call of ``fn()`` on a pool thread."""

    def __init__(self, fn: Callable[..., Any], label: str) -> None:
        super().__init__()
        self.setAutoDelete(False)  # the runner keeps a reference until the signal arrives
        self.fn = fn
        self.label = label
        self.background = False  # a job no progress is shown for (JobRunner.start)
        self.cancelled = False
        self.done = False
        self.signals = _JobSignals()
        try:
            self._pass_cancel = "cancelled" in inspect.signature(fn).parameters
        except (TypeError, ValueError):
            self._pass_cancel = False

    def cancel(self) -> None:
        self.cancelled = True

    def run(self) -> None:  # pool thread
        try:
            if self._pass_cancel:
                result = self.fn(cancelled=lambda: self.cancelled)
            else:
                result = self.fn()
        except BaseException as exc:  # noqa: BLE001 - reported to the GUI thread
            self._report(self.signals.failed, exc, traceback.format_exc())
        else:
            self._report(self.signals.finished, result)

    @staticmethod
    def _report(signal, *args) -> None:
        # A background job (a solver's warm-up) may outlive its window: its signals are then
        # gone with it, and there is nobody left to tell.
        try:
            signal.emit(*args)
        except RuntimeError:
            pass


class JobRunner(QObject):
    """Starts jobs and reports how many are running (``busy_changed(label or "")``)."""

    busy_changed = Signal(str)

    def __init__(self, parent: QObject | None = None, pool: QThreadPool | None = None) -> None:
        super().__init__(parent)
        self.pool = pool or QThreadPool.globalInstance()
        self._jobs: list[Job] = []
        self._pools = {id(self.pool): self.pool}  # every pool a job was started on

    def start(
        self,
        fn: Callable[..., Any],
        on_done: Callable[[Any], None],
        on_error: Callable[[BaseException, str], None],
        label: str = "Working",
        background: bool = False,
        pool: QThreadPool | None = None,
    ) -> Job:
        """Run ``fn`` on the pool (or on ``pool``: the command runner's own); ``on_done(result)``
        or ``on_error(exc, tb)`` on the GUI thread, unless the job was cancelled.
        ``background`` jobs (the warm-up) show no progress."""
        job = Job(fn, label)
        job.background = background

        def finish(callback, *args):
            job.done = True
            if job in self._jobs:
                self._jobs.remove(job)
            self._report()
            if not job.cancelled:
                callback(*args)

        job.signals.finished.connect(lambda result: finish(on_done, result))
        job.signals.failed.connect(lambda exc, tb: finish(on_error, exc, tb))
        self._jobs.append(job)
        self._report()
        pool = pool or self.pool
        self._pools[id(pool)] = pool
        pool.start(job)
        return job

    def running(self, include_background: bool = False) -> list[Job]:
        return [j for j in self._jobs if not j.cancelled and (include_background or not j.background)]

    def cancel_all(self) -> None:
        """Cancel the foreground jobs (the Cancel button)."""
        for job in self.running():
            job.cancel()
        self._report()

    def _report(self) -> None:
        jobs = self.running()
        self.busy_changed.emit(jobs[-1].label if jobs else "")

    def wait(self, msecs: int = 60_000) -> bool:
        """Block until the pools of the jobs started here are idle (tests and screenshots); the
        queued results are then delivered by the next event processing."""
        return all(p.waitForDone(msecs) for p in list(self._pools.values()))
