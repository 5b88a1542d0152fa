"""Inflation in a child process, so that a long solve never stalls the window (issue 30, point 4).

The app prepares every inflation on a worker thread (``Command.prepare``), but the fairing's
sparse factorisation and the inflation's solve hold Python's GIL in native code: drawing a
part of 24k vertices stopped the event loop for 0.5 s, one of 46k for 1.5 s, progress
indicator included. A child process has its own interpreter. The child builds the same plugin
host from the same entry points and answers only for an inflater whose implementation (plugin,
function, version) is the one the window's host has under that name; otherwise (a test host,
a plugin object passed in by hand) the inflation stays in this process. A native crash in the child no longer ends the app either: it
becomes a one-line SolverError and the child is started again.

No Qt here: the window wraps its document's host with :class:`OffloadedInflation`.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import threading

import numpy as np

from sketchforge.errors import SolverError

#: Seconds to wait for the child to start (imports and plugin host) before inflating here.
START_TIMEOUT_S = 60.0

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


def _child_start():
    global _CHILD_HOST
    from sketchforge.plugins.manager import PluginHost

    _CHILD_HOST = PluginHost.create(skip_broken=True)
    return _inflaters_key(_CHILD_HOST)


def _child_inflate(points, closed, params, holes, solver):
    mesh = _CHILD_HOST.inflate(points, closed, params, holes, solver=solver)
    if mesh is None:
        return None
    # Plain arrays: the parent builds its own Mesh, whose arrays are read-only again.
    return (np.asarray(mesh.V), np.asarray(mesh.F), np.asarray(mesh.boundary), np.asarray(mesh.junction),
            tuple(np.asarray(h) for h in mesh.holes))


class OffloadedInflation:
    """The wrapped plugin host, with ``inflate`` run in one child process when the child's
    inflate implementation is the host's own. Every other attribute is the host's."""

    def __init__(self, host) -> None:
        self._host = host
        self._lock = threading.Lock()
        self._pool: cf.ProcessPoolExecutor | None = None
        self._started: cf.Future | None = None
        self.start()

    @property
    def wrapped(self):
        return self._host

    def start(self) -> None:
        """Start the child (in the background: the first inflation waits for it)."""
        with self._lock:
            if self._pool is None:
                self._pool = cf.ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"))
                self._started = self._pool.submit(_child_start)

    def offloading(self, solver: str | None = None) -> bool:
        """True when inflations by the inflater ``solver`` (None: the default) go to the child
        (waits for it to start, at most START_TIMEOUT_S)."""
        self.start()
        try:
            child = self._started.result(timeout=START_TIMEOUT_S)
        except Exception:  # noqa: BLE001 - no child (no fork, no memory): inflate here
            return False
        name = solver if solver is not None else self._host.default_solver_name("inflate")
        return name is not None and name in child and child[name] == _inflaters_key(self._host).get(name)

    def inflate(self, points, closed: bool, params: dict, holes=(), solver: str | None = None):
        if not self.offloading(solver):
            return self._host.inflate(points, closed, params, holes, solver=solver)
        from sketchforge.geometry.mesh import Mesh

        holes = [] if holes is None else [np.asarray(h, dtype=np.float64) for h in holes]
        try:
            out = self._pool.submit(_child_inflate, np.asarray(points, dtype=np.float64), bool(closed), dict(params), holes,
                                    solver).result()
        except cf.process.BrokenProcessPool:
            self.restart()
            raise SolverError("the inflation stopped in native code (the solver process crashed); nothing was changed") from None
        if out is None:
            return None
        V, F, boundary, junction, rings = out
        return Mesh(V, F, boundary, junction, tuple(rings))

    def restart(self) -> None:
        with self._lock:
            pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
        self.start()

    def shutdown(self) -> None:
        with self._lock:
            pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self._host, name)
