"""The inflation's child process, headless (issue 39, point 1: no test ever crashed the child, so
its restart path never ran).

The crash is real: a parameter value whose unpickling calls ``os.abort()`` (SIGABRT, what a
segfaulting native library does: no ``finally`` runs) is sent to the child with a job, so the
child dies in the middle of that job. The window's thread must get one SolverError line, and
the next inflation must run in a new child and give, bit for bit, the mesh this process makes.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time

import numpy as np
import pytest

from sketchforge.errors import SolverError
from sketchforge.offload import OffloadedInflation
from sketchforge.plugins.manager import PluginHost
from sketchforge.plugins.solvers import Inflater
from sketchforge.plugins.testing import FanInflater, make_test_host

T = np.linspace(0.0, 2.0 * np.pi, 90, endpoint=False)
ELLIPSE = np.c_[np.cos(T), 0.6 * np.sin(T)]
HOLE = np.c_[0.2 * np.cos(T[::6]), 0.15 * np.sin(T[::6])]


class AbortInTheChild:
    """Unpickles as ``os.abort()``: sent to the child, it ends the child mid-job."""

    def __reduce__(self):
        return (os.abort, ())


@pytest.fixture(scope="module")
def host():
    return PluginHost.create(allowlist=["inflate"], skip_broken=True)


@pytest.fixture(scope="module")
def offloaded(host):
    off = OffloadedInflation(host)
    yield off
    off.shutdown()


def _children() -> set[int]:
    return {p.pid for p in multiprocessing.active_children()}


def test_the_child_answers_for_the_hosts_own_inflater_and_matches_it_bit_for_bit(host, offloaded):
    assert offloaded.offloading() and offloaded.offloading("poisson")
    assert not offloaded.offloading("no_such_inflater")
    here = host.inflate(ELLIPSE, True, {"resolution": 0.08}, holes=[HOLE])
    there = offloaded.inflate(ELLIPSE, True, {"resolution": 0.08}, holes=[HOLE])
    assert there.identical(here) and len(there.holes) == 1
    assert not there.V.flags.writeable and not there.F.flags.writeable  # a Mesh of this process
    open_here = host.inflate(ELLIPSE[:60], False, {"resolution": 0.1})
    open_there = offloaded.inflate(ELLIPSE[:60], False, {"resolution": 0.1}, holes=None)
    assert open_there.identical(open_here) and len(open_there.junction) > 0
    # everything else is the host's own
    assert offloaded.wrapped is host and offloaded.commands is host.commands
    assert offloaded.solvers("inflate") is host.solvers("inflate")
    with pytest.raises(AttributeError) as info:
        offloaded.__no_such_dunder__  # noqa: B018 - the lookup is the test
    assert str(info.value) == "__no_such_dunder__"
    # special names are never the host's (pickling and copying ask the wrapper itself)
    host.__dict__["__sketchforge_probe__"] = 1
    try:
        with pytest.raises(AttributeError):
            offloaded.__sketchforge_probe__  # noqa: B018 - the lookup is the test
    finally:
        del host.__dict__["__sketchforge_probe__"]


def test_a_child_that_crashes_mid_job_is_one_line_and_the_next_job_runs_in_a_new_child(host, offloaded):
    assert offloaded.offloading()
    before = _children()
    assert before, "the child process is running"
    with pytest.raises(SolverError) as info:
        offloaded.inflate(ELLIPSE, True, {"resolution": AbortInTheChild()})
    msg = str(info.value)
    assert msg == "the inflation stopped in native code (the solver process crashed); nothing was changed"
    # The next job runs, in another process, and gives what this process gives.
    again = offloaded.inflate(ELLIPSE, True, {"resolution": 0.09})
    assert again.identical(host.inflate(ELLIPSE, True, {"resolution": 0.09}))
    assert offloaded.offloading()
    after = _children()  # (other tests' processes may be children too: they stay in both)
    assert (before - after) and (after - before), (before, after)  # the crashed child is gone, a new one answers
    # and it keeps answering after a second crash
    with pytest.raises(SolverError):
        offloaded.inflate(ELLIPSE, True, {"resolution": AbortInTheChild()})
    assert offloaded.inflate(ELLIPSE, True, {"resolution": 0.09}).identical(again)


def test_an_inflaters_own_refusal_comes_back_as_it_is(offloaded):
    from sketchforge.errors import ContourError, ParameterError

    with pytest.raises(ParameterError, match="resolution"):
        offloaded.inflate(ELLIPSE, True, {"resolution": -1.0})
    with pytest.raises(ContourError):
        offloaded.inflate(np.array([[0.0, 0.0], [1.0, 0.0]]), True, {})
    assert offloaded.inflate(ELLIPSE, True, {"resolution": 0.1}) is not None  # the child is still the same good one


def test_a_host_whose_inflater_the_child_does_not_have_inflates_here():
    fan = make_test_host(FanInflater())
    off = OffloadedInflation(fan)
    try:
        assert not off.offloading() and not off.offloading("fan")
        square = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
        assert off.inflate(square, True, {}).identical(fan.inflate(square, True, {}))
    finally:
        off.shutdown()


def test_an_inflater_of_the_same_name_but_another_implementation_inflates_here():
    """The child answers only for the very function (plugin, module, name, version) the
    window's host has under that name: a look-alike stays in this process."""

    class LookAlike:
        from sketchforge.plugins.hookspecs import hookimpl

        @hookimpl
        def sketchforge_inflaters(self):
            return [Inflater("poisson", FanInflater().inflate, version="1")]

    host = make_test_host(LookAlike())
    off = OffloadedInflation(host)
    try:
        assert not off.offloading()
        square = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
        assert off.inflate(square, True, {}).n_vertices == 5  # the fan, made here
    finally:
        off.shutdown()


def test_a_child_that_has_not_started_in_time_leaves_the_inflation_here(host, monkeypatch):
    import sketchforge.offload as offload

    monkeypatch.setattr(offload, "START_TIMEOUT_S", 1e-6)  # no child starts that fast
    off = OffloadedInflation(host)
    try:
        assert not off.offloading()
        assert off.inflate(ELLIPSE, True, {"resolution": 0.1}).identical(host.inflate(ELLIPSE, True, {"resolution": 0.1}))
    finally:
        off.shutdown()


def test_after_shutdown_the_next_inflation_starts_a_child_again(host):
    off = OffloadedInflation(host)
    try:
        first = off.inflate(ELLIPSE, True, {"resolution": 0.1})
        off.shutdown()
        assert off.offloading()  # a new child, started on demand
        assert off.inflate(ELLIPSE, True, {"resolution": 0.1}).identical(first)
    finally:
        off.shutdown()


def test_the_child_starts_when_the_wrapper_is_made_not_at_the_first_stroke(host):
    import time

    before = _children()
    off = OffloadedInflation(host)
    try:
        deadline = time.monotonic() + 30.0
        while not (_children() - before) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _children() - before  # already starting, before anything asked for it
    finally:
        off.shutdown()


# --- the watchdog and the child's life (issue 39: bugs planted here changed only which processes
# run, so every test below also says which child processes exist, by pid) ------------------------


def _in_thread(fn):
    box: dict = {}

    def run():
        try:
            box["value"] = fn()
        except BaseException as exc:  # noqa: BLE001 - handed to the test
            box["error"] = exc

    th = threading.Thread(target=run, daemon=True)
    th.start()
    return th, box


def _cancel_when_running(off, th) -> None:
    """Press Cancel as soon as the job is in flight (cancel() says True from then on)."""
    deadline = time.monotonic() + 30.0
    while not off.cancel():
        assert th.is_alive() and time.monotonic() < deadline, "the job never started"
        time.sleep(0.01)


def test_a_hung_child_is_stopped_at_the_timeout_in_one_line_and_the_next_job_runs_in_a_new_one(host):
    said = []
    off = OffloadedInflation(host, notify=said.append, timeout_s=1.5)
    try:
        assert off.offloading()
        pid = off.child_pid
        os.kill(pid, signal.SIGSTOP)  # a hang in native code: the child never answers
        t0 = time.monotonic()
        with pytest.raises(SolverError) as info:
            off.inflate(ELLIPSE, True, {"resolution": 0.1})
        assert time.monotonic() - t0 >= 1.5  # never stopped before its time
        assert str(info.value) == ("the inflation took longer than 1.5 s and was stopped (the solver process was "
                                   "restarted); nothing was changed")
        assert said == ["the inflation took longer than 1.5 s: the solver process was stopped and a new one started"]
        assert pid not in _children() and off.child_pid not in (None, pid)  # the hung one is gone
        assert off.inflate(ELLIPSE, True, {"resolution": 0.1}).identical(host.inflate(ELLIPSE, True, {"resolution": 0.1}))
        assert len(said) == 1 and off.cancel() is False  # the job is over: nothing to cancel
    finally:
        off.shutdown()


def test_cancel_ends_a_hung_job_at_once_whether_the_child_is_working_or_still_starting(host):
    said = []
    off = OffloadedInflation(host, notify=said.append)
    try:
        assert off.cancel() is False  # nothing running: nothing to cancel
        for starting in (True, False):
            if not starting:
                assert off.offloading()
            pid = off.child_pid
            os.kill(pid, signal.SIGSTOP)  # stopped while importing, or while idle (then mid-job)
            th, box = _in_thread(lambda: off.inflate(ELLIPSE, True, {"resolution": 0.1}))
            _cancel_when_running(off, th)
            th.join(30.0)
            assert not th.is_alive(), "cancel did not end the wait"
            assert str(box.get("error")) == "the inflation was cancelled; nothing was changed", (starting, box)
            assert said == ["cancelled: the solver process was stopped and a new one started"], starting
            assert pid not in _children() and off.child_pid not in (None, pid)
            assert off.cancel() is False  # the cancelled job is over
            said.clear()
        assert off.inflate(ELLIPSE, True, {"resolution": 0.1}).identical(host.inflate(ELLIPSE, True, {"resolution": 0.1}))
    finally:
        off.shutdown()


def test_a_child_killed_while_idle_is_replaced_before_the_next_job_and_said_once(host):
    said = []

    def notify(text):  # a message that fails never fails the job
        said.append(text)
        raise RuntimeError("the status bar is gone")

    off = OffloadedInflation(host, notify=notify)
    try:
        assert off.offloading()
        pid = off.child_pid
        os.kill(pid, signal.SIGKILL)
        deadline = time.monotonic() + 10.0
        while pid in _children() and time.monotonic() < deadline:
            time.sleep(0.02)
        assert off.inflate(ELLIPSE, True, {"resolution": 0.1}).identical(host.inflate(ELLIPSE, True, {"resolution": 0.1}))
        assert said == ["the solver process had stopped; a new one was started"]
        assert off.child_pid not in (None, pid) and off.offloading()
    finally:
        off.shutdown()


def test_a_child_that_dies_while_starting_leaves_the_job_here_at_once(host, monkeypatch):
    import sketchforge.offload as offload

    monkeypatch.setattr(offload, "START_TIMEOUT_S", 600.0)  # only a dead pipe ends the wait early
    off = OffloadedInflation(host)
    try:
        os.kill(off.child_pid, signal.SIGKILL)  # long before it has imported anything
        th, box = _in_thread(lambda: off.inflate(ELLIPSE, True, {"resolution": 0.1}))
        th.join(60.0)
        assert not th.is_alive(), "the job waited for a child that is dead"
        assert box["value"].identical(host.inflate(ELLIPSE, True, {"resolution": 0.1}))
    finally:
        off.shutdown()


def test_a_child_that_could_not_start_is_replaced_before_the_next_job_a_few_times_in_a_row(host, monkeypatch):
    """The job that finds the child dead while starting runs here; the next one gets a new child
    (else every later inflation would run in the app's process, the freeze the child is for).
    Children that keep failing to start are replaced at most MAX_START_FAILURES - 1 times in a row,
    then the inflations stay here and that is said once."""
    import sketchforge.offload as offload

    said = []
    monkeypatch.setattr(offload, "START_TIMEOUT_S", 600.0)
    off = OffloadedInflation(host, notify=said.append)
    try:
        want = host.inflate(ELLIPSE, True, {"resolution": 0.1})
        dead = off.child_pid
        os.kill(dead, signal.SIGKILL)
        assert off.inflate(ELLIPSE, True, {"resolution": 0.1}).identical(want)  # here, at once
        assert off.inflate(ELLIPSE, True, {"resolution": 0.1}).identical(want)  # in a new child
        assert said == ["the solver process could not start; a new one was started"]
        assert off.child_pid not in (None, dead) and off.offloading()
        assert off._start_failures == 0  # it started: the count begins again
        # children that never start (they exit at once): the job that finds each one runs here,
        # the next replaces it, twice in a row; then the inflations stay here, said once
        said.clear()

        class NeverStarts(offload._Child):
            def __init__(self) -> None:
                ctx = multiprocessing.get_context("spawn")
                self.conn, theirs = ctx.Pipe()
                self.process = ctx.Process(target=os._exit, args=(3,), daemon=True)
                self.process.start()
                theirs.close()
                self.key, self.failed = None, False

        monkeypatch.setattr(offload, "_Child", NeverStarts)
        off.restart()
        pids = set()
        for _ in range(offload.MAX_START_FAILURES + 2):
            pids.add(off.child_pid)
            assert off.inflate(ELLIPSE, True, {"resolution": 0.1}).identical(want)
        again = "the solver process could not start; a new one was started"
        assert said[:-1] == [again] * (offload.MAX_START_FAILURES - 1)
        assert len(said) == offload.MAX_START_FAILURES and "in the app's process from now on" in said[-1]
        assert len(pids) == offload.MAX_START_FAILURES  # the first one and its replacements, no more
    finally:
        off.shutdown()


def test_one_child_per_wrapper_restart_replaces_it_and_shutdown_ends_it(host):
    before = _children()
    off = OffloadedInflation(host)
    try:
        for _ in range(2):
            off.inflate(ELLIPSE, True, {"resolution": 0.1})
        assert _children() - before == {off.child_pid}  # one process does every job
        old = off.child_pid
        off.restart()
        assert old not in _children() and off.child_pid in _children() - before
        assert off.offloading() and _children() - before == {off.child_pid}
        pid = off.child_pid
    finally:
        off.shutdown()
    assert off.child_pid is None and pid not in _children() and not (_children() - before)


class _BrokenPipe:
    """A child's pipe that breaks when a job is sent (the child died between the check and
    the send); everything else is the real pipe's."""

    def __init__(self, conn):
        self._conn = conn

    def send(self, obj):
        raise BrokenPipeError(32, "Broken pipe")

    def __getattr__(self, name):
        return getattr(self._conn, name)


def test_a_job_that_cannot_be_sent_is_one_line_and_the_child_is_replaced(host):
    off = OffloadedInflation(host)
    try:
        assert off.offloading()
        pid = off.child_pid
        off._child.conn = _BrokenPipe(off._child.conn)
        with pytest.raises(SolverError) as info:
            off.inflate(ELLIPSE, True, {"resolution": 0.1})
        assert str(info.value) == "the solver process had stopped; a new one was started: try again"
        assert pid not in _children() and off.child_pid not in (None, pid)  # as it says
        assert off.inflate(ELLIPSE, True, {"resolution": 0.1}).identical(host.inflate(ELLIPSE, True, {"resolution": 0.1}))
    finally:
        off.shutdown()
