"""The app's side of crash recovery: the CommandRunner's guard (state flushed before the macro
opens, record cleared when the solver has returned, a cancelled one included), the assembly
job's guard, and the recovery question (declining keeps the autosave). The real crash runs in
a subprocess in tests/test_crash_recovery.py."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import ClassVar

import pytest
from crash_plugin import live_session
from PySide6.QtWidgets import QApplication, QMessageBox
from qt_helpers import wait_idle

from sketchforge.document import commands as C
from sketchforge.document import fileformat as ff
from sketchforge.document.autosave import Autosaver, find_recoverable
from sketchforge.document.document import Document
from sketchforge.plugins.hookspecs import hookimpl
from sketchforge.plugins.testing import FanInflater, make_test_host
from sketchforge.qt.command_runner import CommandRunner, GuardedJobs
from sketchforge.qt.workers import JobRunner

TRIANGLE = [[0, 0], [2, 0], [1, 1]]


@dataclass
class Blocking(C.ReplaceLayerCommand):
    """A solve that waits until the test lets it return (and records what it saw)."""

    name: ClassVar[str] = "blocking"
    gate: threading.Event = None
    seen: list = None

    def text(self) -> str:
        return "Blocking solve"

    def compute(self, doc, old):
        if self.seen is not None:
            self.seen.append("started")
        assert self.gate.wait(30)
        return old.evolve(name=old.name + "!")

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer}


class Recorder:
    def __init__(self, doc):
        self.doc = doc
        self.events = []

    def before(self, cmd=None, **kwargs):
        self.events.append(("before", cmd.text() if cmd else kwargs.get("text"), self.doc.layer_ids(), self.doc.undo_stack.in_macro()))
        return len(self.events)

    def after(self, token):
        self.events.append(("after", token))


@pytest.fixture
def fan_doc():
    doc = Document(host=make_test_host(FanInflater()))
    doc.execute({"command": "add_layer", "id": "a", "name": "Alpha"})
    doc.execute({"command": "set_contour", "layer": "a", "points": TRIANGLE})
    return doc


def settle(qtbot, jobs):
    qtbot.waitUntil(lambda: not jobs.running(), timeout=30_000)
    jobs.wait(30_000)
    qtbot.wait(20)  # queued results


def test_runner_guard_sees_the_state_before_the_macro_and_ends_after_every_outcome(qtbot, fan_doc):
    jobs = JobRunner()
    guard = Recorder(fan_doc)
    runner = CommandRunner(fan_doc, jobs, guard=guard)
    # success, in a macro: the guard runs before the macro opens and before its new layer
    runner.run(C.SetContour(layer="b", points=TRIANGLE), macro="Draw layer", before=[C.AddLayer(id="b")])
    settle(qtbot, jobs)
    assert guard.events == [("before", "Draw contour", ["a"], False), ("after", 1)]
    assert fan_doc.layer_ids() == ["a", "b"] and fan_doc.undo_stack.undo_text() == "Draw layer"
    # an error in the solver
    runner.run(C.SetContour(layer="a", points=[[0, 0], [1, 1]]))
    settle(qtbot, jobs)
    assert guard.events[-2:] == [("before", "Draw contour", ["a", "b"], False), ("after", 3)]
    # an error in a ``before`` command: no solve starts, the record is cleared at once
    runner.run(C.SetContour(layer="a", points=TRIANGLE), macro="Draw layer", before=[C.AddLayer(id="a")])
    assert guard.events[-1] == ("after", 5) and not runner.busy


def test_a_cancelled_solve_keeps_its_record_until_its_native_code_returns(qtbot, fan_doc):
    jobs = JobRunner()
    guard = Recorder(fan_doc)
    runner = CommandRunner(fan_doc, jobs, guard=guard)
    gate, seen = threading.Event(), []
    runner.run(Blocking(layer="a", gate=gate, seen=seen))
    qtbot.waitUntil(lambda: seen == ["started"])
    runner.cancel()
    assert not runner.busy
    # Whatever the cancel queued is delivered now; the solve itself cannot return before the
    # gate opens, so its record must still be there.
    QApplication.processEvents()
    assert [e[0] for e in guard.events] == ["before"] and not gate.is_set()
    gate.set()
    jobs.wait(30_000)
    qtbot.waitUntil(lambda: len(guard.events) == 2)
    assert guard.events[-1] == ("after", 1)
    assert fan_doc.layer("a").name == "Alpha"  # the cancelled result was dropped


def test_runner_without_guard_still_works(qtbot, fan_doc):
    jobs = JobRunner()
    runner = CommandRunner(fan_doc, jobs)
    runner.run(C.SetContour(layer="a", points=[[0, 0], [3, 0], [1, 2]]))
    settle(qtbot, jobs)
    assert fan_doc.layer("a").points.tolist() == [[0, 0], [3, 0], [1, 2]]


def test_guarded_jobs_wrap_the_assembly_and_pass_cancelled_through(qtbot, fan_doc):
    jobs = JobRunner()
    guard = Recorder(fan_doc)
    guarded = GuardedJobs(jobs, guard, "Assemble model")
    results = []
    guarded.start(lambda cancelled: cancelled(), results.append, lambda e, tb: results.append(e), label="Assembling")
    settle(qtbot, guarded)  # running() and wait() are the wrapped runner's
    assert results == [False]
    assert guard.events == [("before", "Assemble model", ["a"], False), ("after", 1)]


def _window_mid_solve(make_window, qtbot):
    """A window (its Autosaver in the test's data folder) with one dirty layer and a Blocking
    solve started; returns (window, the gate that lets the solve return)."""
    host = make_test_host(FanInflater())
    w = make_window(Document(host=host))
    w.autosaver = Autosaver(w.doc, interval_s=3600)  # in the patched data folder
    w.doc.execute({"command": "add_layer", "id": "a", "name": "Alpha"})
    w.doc.execute({"command": "set_contour", "layer": "a", "points": TRIANGLE})
    gate, seen = threading.Event(), []
    w.runner.run(Blocking(layer="a", gate=gate, seen=seen))
    qtbot.waitUntil(lambda: seen == ["started"])
    return w, gate


def test_the_window_flushes_before_a_solve_and_clears_the_record_after(make_window, qtbot, monkeypatch, tmp_path):
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(tmp_path / "data"))
    w, gate = _window_mid_solve(make_window, qtbot)
    [item] = find_recoverable()
    assert item.path == w.autosaver.path and item.running[-1]["text"] == "Blocking solve"
    assert item.running[-1]["layer_name"] == "Alpha"
    gate.set()
    wait_idle(qtbot, w)
    qtbot.waitUntil(lambda: not w.autosaver.pending_path.exists())
    assert w.doc.layer("a").name == "Alpha!" and w.autosaver.path.exists()


def test_the_assembly_in_observation_is_guarded(make_window, qtbot, monkeypatch, tmp_path):
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(tmp_path / "data"))
    seen = []

    from sketchforge.plugin_api import Assembler

    def peeking(layers, params):
        seen.extend(r.running[-1]["text"] for r in find_recoverable())
        return layers[0].mesh

    class PeekingAssembler:
        @hookimpl
        def sketchforge_assemblers(self):
            return [Assembler("peeking", peeking)]

    host = make_test_host(FanInflater(), PeekingAssembler())
    w = make_window(Document(host=host))
    w.autosaver = Autosaver(w.doc, interval_s=3600)
    w.doc.execute({"command": "add_layer", "id": "a"})
    w.doc.execute({"command": "set_contour", "layer": "a", "points": TRIANGLE})
    w.view3d.gl = object()  # no OpenGL: nothing is drawn
    w.view3d._show = lambda meshes, note: None
    w.set_mode("observation")
    qtbot.waitUntil(lambda: seen == ["Assemble model"], timeout=30_000)
    w.jobs.wait(30_000)
    qtbot.waitUntil(lambda: not w.autosaver.pending_path.exists())


def test_declining_recovery_keeps_the_autosave(make_window, dialogs, monkeypatch, tmp_path):
    """Declined, the autosave (and its record) survives this whole session, even one on the
    same file: its clean ticks, its edits, its save and its close."""
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(tmp_path / "data"))
    host = make_test_host(FanInflater())
    mine = tmp_path / "mine.json"
    crashed = Document(host=host)
    crashed.execute({"command": "add_layer", "id": "a", "name": "Alpha"})
    crashed.execute({"command": "set_contour", "layer": "a", "points": TRIANGLE})
    ff.save(crashed, mine)
    crashed.execute({"command": "rename_layer", "layer": "a", "name": "Unsaved"})
    saver = Autosaver(crashed, original_path=mine)
    saver.begin_solve(C.SetContour(layer="a", points=TRIANGLE))  # ... and the process died
    kept = {p: p.read_bytes() for p in (saver.path, saver.pending_path)}

    w = make_window(Document(host=host))
    assert w.open_path(mine)  # the same file the autosave is for
    dialogs.answers = [QMessageBox.StandardButton.No]
    assert w.offer_recovery() is False
    [(_, _, text)] = dialogs.of("question")
    assert "sketchforge stopped while computing 'Draw contour' on layer 'Unsaved'." in text
    assert "No keeps the autosave" in text
    w.autosaver.interval_s = 0
    w._autosave()  # clean: removes only its own autosave
    w.push(C.RenameLayer(layer="a", new_name="edited"))
    w._autosave()
    assert w.save_to(mine)
    w.close_now()
    assert {p: p.read_bytes() for p in kept} == kept
    [item] = find_recoverable()
    assert item.path == saver.path and item.running[-1]["layer"] == "a"


def test_a_crash_without_unsaved_work_is_reported_once(make_window, dialogs, monkeypatch, tmp_path):
    """A solve that crashed on a document with no unsaved changes: nothing to recover, but
    the next start says which step it was (once)."""
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(tmp_path / "data"))
    host = make_test_host(FanInflater())
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a", "name": "Alpha"})
    ff.save(doc, tmp_path / "mine.json")
    saver = Autosaver(doc, original_path=tmp_path / "mine.json")
    saver.begin_solve(C.SetContour(layer="a", points=TRIANGLE))  # ... and the process died
    assert not saver.path.exists()
    w = make_window(Document(host=host))
    assert w.offer_recovery() is False
    [(_, _, text)] = dialogs.of("information")
    assert "sketchforge stopped while computing 'Draw contour' on layer 'Alpha'." in text
    assert "no unsaved changes" in text and dialogs.of("question") == []
    assert find_recoverable() == [] and not saver.pending_path.exists()
    assert w.offer_recovery() is False and len(dialogs.of("information")) == 1


def test_a_cancelled_solve_keeps_its_record_across_a_save_and_an_open(make_window, qtbot, monkeypatch, tmp_path):
    """Saving or opening while a cancelled solve is still in native code: the window gets a
    new Autosaver, and the record stays until that solve really returns."""
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(tmp_path / "data"))
    folder, mine = tmp_path / "data" / "autosave", tmp_path / "mine.json"
    w, gate = _window_mid_solve(make_window, qtbot)
    w.runner.cancel()  # its native code runs on
    first = w.autosaver
    assert w.save_to(mine)
    assert w.autosaver is not first and not first.path.exists()
    [item] = find_recoverable()  # a crash now: the step is still reported
    assert not item.has_document and item.running[-1]["text"] == "Blocking solve"
    assert w.open_path(mine, ask=False)
    [item] = find_recoverable()
    assert not item.has_document and item.running[-1]["layer_name"] == "Alpha"
    gate.set()  # the solve returns: its record goes, whichever autosaver the window has now
    w.jobs.wait(30_000)
    qtbot.waitUntil(lambda: not w.autosaver.pending_path.exists())
    assert find_recoverable() == [] and list(folder.iterdir()) == []
    assert w.doc.layer("a").name == "Alpha"  # the cancelled result was dropped


def test_a_second_window_leaves_a_running_session_alone(make_window, dialogs, monkeypatch, tmp_path):
    """Another sketchforge still running (in the middle of a solve): nothing is reported,
    offered or deleted; once it has crashed, both its step and its work are."""
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(tmp_path / "data"))
    folder = tmp_path / "data" / "autosave"
    w = make_window(Document(host=make_test_host(FanInflater())))
    with live_session(folder) as proc:
        files = {p: p.read_bytes() for p in folder.iterdir()}
        dialogs.answers = [QMessageBox.StandardButton.Yes]
        assert w.offer_recovery() is False
        assert dialogs.calls == []
        assert {p: p.read_bytes() for p in folder.iterdir()} == files
        proc.kill()  # now it crashes
        proc.wait()
        assert w.offer_recovery() is True
    [(_, _, report)] = dialogs.of("information")
    assert "sketchforge stopped while computing 'Draw contour' on layer 'Beta'." in report
    [(_, _, question)] = dialogs.of("question")
    assert "sketchforge stopped while computing 'Draw contour' on layer 'Alpha'." in question
    assert w.doc.layer("a").name == "Alpha" and w.is_modified()
    assert [p for p in folder.iterdir() if p in files] == []  # the crashed session's files are gone
