"""Inflation in a child process, so that a long solve never stalls the window (issue 30, point 4),
watched so that a hung or dead child never stalls the app (issue 38, point 2).

The app prepares every inflation on a worker thread (``Command.prepare``), but the fairing's
sparse factorisation and the inflation's solve hold Python's GIL in native code: drawing a
part of 24k vertices stopped the event loop for 0.5 s, one of 46k for 1.5 s, progress
indicator included. A child process has its own interpreter. The child builds the same plugin
host from the same entry points and answers only for an inflater whose implementation (plugin,
function, version) is the one the window's host has under that name; otherwise (a test host,
a plugin object passed in by hand) the inflation stays in this process.

The watchdog: the caller waits for the child's answer in short slices, never longer than
:data:`INFLATE_TIMEOUT_S` in all, and :meth:`OffloadedInflation.cancel` (the app's Cancel)
ends the wait at once. A child that hangs (even stopped with SIGSTOP), crashes, passes the
timeout or is cancelled mid-job is killed and a new one started; the job ends in one
SolverError line (nothing was changed) and the next job runs in the new child. A child that
died while idle is found dead before the next job is sent and replaced first; the job then
runs normally. Every restart is reported through ``notify`` (one line; the app's status bar).

No Qt here: the window wraps its document's host with :class:`OffloadedInflation`.
"""

from __future__ import annotations

import multiprocessing
import threading
import time
from collections.abc import Callable

import numpy as np

from sketchforge.errors import SolverError

#: Seconds to wait for the child to start (imports and plugin host) before inflating here.
START_TIMEOUT_S = 60.0
#: Seconds one inflation may take in the child before it is stopped (the largest layer the
#: limits allow, 200 000 vertices, inflates in well under a minute).
INFLATE_TIMEOUT_S = 180.0
#: How often a waiting caller looks at Cancel, the deadline and the child's pulse.
POLL_S = 0.05
#: Children in a row that may fail to start before inflations stay in this process for good
#: (a child that cannot import the plugins would fail every time, and each try costs a start).
MAX_START_FAILURES = 3

_CHILD_HOST = None


def _inflaters_key(host) -> dict:
    """{inflater name: (plugin, module, qualified name, version)}: which function answers for
    each named inflater on ``host``."""
    out = {}
    for name, inflater in host.solvers("inflate").items():
        fn = inflater.inflate
        out[name] = (host.provider_of(inflater), getattr(fn, "__module__", None), getattr(fn, "__qualname__", None),
                     inflater.version)
    return out


def _child_inflate(points, closed, params, holes, solver):
    mesh = _CHILD_HOST.inflate(points, closed, params, holes, solver=solver)
    if mesh is None:
        return None
    # Plain arrays: the parent builds its own Mesh, whose arrays are read-only again.
    return (np.asarray(mesh.V), np.asarray(mesh.F), np.asarray(mesh.boundary), np.asarray(mesh.junction),
            tuple(np.asarray(h) for h in mesh.holes))


def _child_main(conn) -> None:  # the child process
    """Build the host, say which inflaters answer here, then serve one request at a time:
    ``(args)`` in, ``("ok", result)`` or ``("error", exception)`` out."""
    global _CHILD_HOST
    try:
        from sketchforge.plugins.manager import PluginHost

        _CHILD_HOST = PluginHost.create(skip_broken=True)
        conn.send(("ready", _inflaters_key(_CHILD_HOST)))
    except BaseException as exc:  # noqa: BLE001 - the parent inflates itself then
        conn.send(("error", SolverError(f"the solver process could not start: {type(exc).__name__}: {exc}")))
        return
    while True:
        try:
            args = conn.recv()
        except (EOFError, OSError):
            return  # the parent is gone or closed the pipe
        try:
            out = ("ok", _child_inflate(*args))
        except BaseException as exc:  # noqa: BLE001 - reported to the parent
            out = ("error", exc)
        try:
            conn.send(out)
        except Exception as exc:  # noqa: BLE001 - an exception that does not pickle
            conn.send(("error", SolverError(f"{type(out[1]).__name__}: {out[1]}" if out[0] == "error" else str(exc))))


class _Child:
    """One child process and the parent's end of its pipe."""

    def __init__(self) -> None:
        ctx = multiprocessing.get_context("spawn")
        self.conn, theirs = ctx.Pipe()
        self.process = ctx.Process(target=_child_main, args=(theirs,), daemon=True, name="sketchforge-inflate")
        self.process.start()
        theirs.close()
        self.key: dict | None = None  # the inflaters it answers for, once it said so
        self.failed = False  # it could not start

    def wait_ready(self, timeout: float) -> dict | None:
        """The child's inflaters once it has started (None: not within ``timeout``, or it
        could not start)."""
        if self.key is None and not self.failed:
            try:
                if self.conn.poll(timeout):
                    kind, value = self.conn.recv()
                    if kind == "ready":
                        self.key = value
                    else:
                        self.failed = True
            except (EOFError, OSError):
                self.failed = True
        return self.key

    def alive(self) -> bool:
        return self.process.is_alive()

    def kill(self) -> None:
        try:
            self.process.kill()  # SIGKILL: ends a stopped (SIGSTOP) process too
            self.process.join(5.0)
        except (OSError, ValueError, AttributeError):
            pass
        try:
            self.conn.close()
        except OSError:
            pass


class OffloadedInflation:
    """The wrapped plugin host, with ``inflate`` run in one watched child process when the
    child's inflate implementation is the host's own. Every other attribute is the host's.

    ``notify(text)`` is called (from the thread that saw it) with one line whenever the child
    is replaced: after a crash, a timeout, a cancel, or when found dead while idle."""

    def __init__(self, host, notify: Callable[[str], None] | None = None, timeout_s: float | None = None) -> None:
        self._host = host
        self.notify = notify
        self.timeout_s = INFLATE_TIMEOUT_S if timeout_s is None else float(timeout_s)
        self._lock = threading.Lock()  # guards _child and _cancel
        self._busy = threading.Lock()  # one job in the child at a time
        self._child: _Child | None = None
        self._cancel: threading.Event | None = None  # the running job's
        self._start_failures = 0  # children in a row that could not start
        self.start()

    @property
    def wrapped(self):
        return self._host

    @property
    def child_pid(self) -> int | None:
        """The child's process id (tests stop or kill it)."""
        child = self._child
        return child.process.pid if child is not None else None

    def start(self) -> None:
        """Start the child (in the background: the first inflation waits for it)."""
        with self._lock:
            if self._child is None:
                self._child = _Child()

    def _current(self) -> _Child:
        # Made and read under one lock: a restart or close() on another thread may clear it
        # between the two (mypy found the gap: start() then self._child could be None).
        with self._lock:
            if self._child is None:
                self._child = _Child()
            return self._child

    def offloading(self, solver: str | None = None) -> bool:
        """True when inflations by the inflater ``solver`` (None: the default) go to the child
        (waits for it to start, at most START_TIMEOUT_S)."""
        return self._answers(self._current().wait_ready(START_TIMEOUT_S), solver)

    def _answers(self, key: dict | None, solver: str | None) -> bool:
        if key is None:
            return False
        name = solver if solver is not None else self._host.default_solver_name("inflate")
        return name is not None and name in key and key[name] == _inflaters_key(self._host).get(name)

    def inflate(self, points, closed: bool, params: dict, holes=(), solver: str | None = None):
        if not self._busy.acquire(timeout=self.timeout_s):
            raise SolverError("the solver process is still busy with an earlier inflation; nothing was changed")
        cancel = threading.Event()
        with self._lock:
            self._cancel = cancel
        try:
            self._revive_if_dead()
            child = self._current()
            key = self._wait_ready(child, cancel)
            if key is not None:
                self._start_failures = 0
            if not self._answers(key, solver):
                return self._host.inflate(points, closed, params, holes, solver=solver)
            holes = [] if holes is None else [np.asarray(h, dtype=np.float64) for h in holes]
            args = (np.asarray(points, dtype=np.float64), bool(closed), dict(params), holes, solver)
            out = self._run(child, args, cancel)
        finally:
            with self._lock:
                if self._cancel is cancel:
                    self._cancel = None
            self._busy.release()
        if out is None:
            return None
        from sketchforge.geometry.mesh import Mesh

        V, F, boundary, junction, rings = out
        return Mesh(V, F, boundary, junction, tuple(rings))

    def _wait_ready(self, child: _Child, cancel: threading.Event) -> dict | None:
        """The child's inflaters once it has started, waiting in slices so that Cancel ends the
        wait (a child stopped while starting hung the job for START_TIMEOUT_S)."""
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline:
            key = child.wait_ready(POLL_S)
            if key is not None or child.failed:
                return key
            if cancel.is_set():
                self._replace(child)
                self._say("cancelled: the solver process was stopped and a new one started")
                raise SolverError("the inflation was cancelled; nothing was changed")
        return None

    def _revive_if_dead(self) -> None:
        """A child that died while idle (killed, out of memory) is replaced before use: the next
        job must not be the one that finds out. A child that could not start (killed or crashed
        while importing) is replaced too, up to :data:`MAX_START_FAILURES` in a row: the job that
        found it ran here at once, and without a new child every later inflation would run here
        as well, in the app's process, which is what the child is for (the window pauses on a
        large part). Past that the inflations stay here and the user is told once."""
        child = self._child
        if child is None:
            return
        if child.key is not None and not child.alive():
            self._replace(child)
            self._say("the solver process had stopped; a new one was started")
        elif child.failed:
            self._start_failures += 1
            if self._start_failures < MAX_START_FAILURES:
                self._replace(child)
                self._say("the solver process could not start; a new one was started")
            elif self._start_failures == MAX_START_FAILURES:
                self._say(f"the solver process could not start {MAX_START_FAILURES} times in a row: inflations run "
                          "in the app's process from now on (the window may pause on large parts)")

    def _run(self, child: _Child, args, cancel: threading.Event):
        """Send ``args`` to the child and wait for its answer, watching Cancel, the deadline and
        the child's pulse. Raises SolverError (the child replaced) or the inflater's error."""
        try:
            child.conn.send(args)
        except (OSError, ValueError):
            self._replace(child)
            raise SolverError("the solver process had stopped; a new one was started: try again") from None
        deadline = time.monotonic() + self.timeout_s
        while True:
            try:
                ready = child.conn.poll(POLL_S)
            except (OSError, ValueError):
                ready = False
            kind = None
            if ready:
                try:
                    kind, value = child.conn.recv()
                except (EOFError, OSError):
                    kind, value = "crashed", None
                if kind == "ok":
                    return value
                if kind == "error":
                    raise value
            if kind == "crashed" or (not ready and not child.alive()):
                self._replace(child)
                self._say("the solver process crashed; a new one was started")
                raise SolverError("the inflation stopped in native code (the solver process crashed); nothing was changed")
            if cancel.is_set():
                self._replace(child)
                self._say("cancelled: the solver process was stopped and a new one started")
                raise SolverError("the inflation was cancelled; nothing was changed")
            if time.monotonic() > deadline:
                self._replace(child)
                self._say(f"the inflation took longer than {self.timeout_s:g} s: the solver process was stopped and a new one started")
                raise SolverError(
                    f"the inflation took longer than {self.timeout_s:g} s and was stopped (the solver process was "
                    "restarted); nothing was changed"
                )

    def cancel(self) -> bool:
        """Stop the inflation running in the child, if any (the app's Cancel): the child is
        killed and a new one started, and the waiting thread returns at once. True when one
        was running."""
        with self._lock:
            cancel = self._cancel
        if cancel is None:
            return False
        cancel.set()
        return True

    def _replace(self, child: _Child) -> None:
        with self._lock:
            if self._child is child:
                self._child = None
        child.kill()
        self.start()  # the next one starts now, in the background

    def _say(self, text: str) -> None:
        if self.notify is not None:
            try:
                self.notify(text)
            except Exception:  # noqa: BLE001 - a message must never fail the job
                pass

    def restart(self) -> None:
        with self._lock:
            child, self._child = self._child, None
        if child is not None:
            child.kill()
        self.start()

    def shutdown(self) -> None:
        with self._lock:
            child, self._child = self._child, None
            cancel = self._cancel
        if cancel is not None:
            cancel.set()
        if child is not None:
            child.kill()

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self._host, name)
