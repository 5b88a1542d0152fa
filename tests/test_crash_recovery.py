"""A native crash loses nothing: before a solve starts, the autosave holds the document as it was
before the user's action and a pending record names that action; at the next start the work
is recovered without it.

The crash itself is real: a subprocess runs the app's own machinery (MainWindow, CommandRunner,
the OBSERVATION view's assembly job) on a plugin whose solver calls ``os.abort()``.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from crash_plugin import live_session

from sketchforge.document import Document, autosave
from sketchforge.document import fileformat as ff
from sketchforge.document.autosave import Autosaver, describe_stop, find_recoverable, forget, recover, writer_alive
from sketchforge.plugins.testing import FanInflater, make_test_host

ROOT = Path(__file__).resolve().parent.parent
TESTS = Path(__file__).resolve().parent
EXAMPLE = ROOT / "examples" / "creature.json"

# The app in a subprocess: a document with two real (inflated) layers and unsaved changes,
# then a solve that aborts the process. ``expected.json`` is the state before the crashing
# step, written for the test to compare with.
SCRIPT = r"""
import os, resource, sys, time
from pathlib import Path

resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # no core file for a deliberate abort
mode, out = sys.argv[1], Path(sys.argv[2])

from PySide6.QtCore import QSettings
from sketchforge.document import commands as C
from sketchforge.document import fileformat as ff
from sketchforge.document.document import Document
from sketchforge.plugins.testing import make_test_host
from sketchforge.qt.app import ensure_qapp
from sketchforge.qt.main_window import MainWindow
import sketchforge_inflate.plugin as inflate
from crash_plugin import AbortPlugin, AbortSolve, AbortingAssembler

app = ensure_qapp()
plugins = [inflate, AbortPlugin()] + ([AbortingAssembler()] if mode == "assemble" else [])
host = make_test_host(*plugins)
settings = QSettings(str(out / "settings.ini"), QSettings.Format.IniFormat)
w = MainWindow(Document(host=host), host=host, settings=settings)
doc = w.doc

import numpy as np
t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
body = np.c_[np.cos(t), 0.6 * np.sin(t)].round(4).tolist()
arm = np.c_[0.9 + 0.35 * np.cos(t), 0.4 + 0.15 * np.sin(t)].round(4).tolist()
for entry in [
    {"command": "add_layer", "id": "body", "name": "Body"},
    {"command": "set_inflate_params", "layer": "body", "params": {"resolution": 0.08}},
    {"command": "set_contour", "layer": "body", "points": body, "closed": True},
    {"command": "add_layer", "id": "arm", "name": "Arm"},
    {"command": "set_inflate_params", "layer": "arm", "params": {"resolution": 0.05, "inflation": 0.8}},
    {"command": "set_contour", "layer": "arm", "points": arm},
    {"command": "set_light", "direction": [0.6, 0.8]},
]:
    doc.execute(entry)
assert all(l.mesh is not None for l in doc.layers) and not doc.undo_stack.is_clean()
ff.save(doc, out / "expected.json", mark_clean=False)

if mode == "plain":
    w.runner.run(AbortSolve(layer="arm"), label="Crashing")
elif mode == "macro":
    # Unchanged since the last autosave: only the pending record is written before the solve.
    w.autosaver.save_now()
    (out / "autosave_before.bin").write_bytes(w.autosaver.path.read_bytes())
    w.runner.run(
        AbortSolve(layer="new"), label="Crashing", macro="Draw layer",
        before=[C.AddLayer(id="new", layer_name="New part")],
    )
else:  # the OBSERVATION view assembles on a worker (OSQP in the real plugin)
    w.view3d.gl = object()  # no OpenGL needed: nothing is drawn
    w.view3d._show = lambda meshes, note: None
    w.set_mode("observation")

deadline = time.monotonic() + 60
while time.monotonic() < deadline:
    app.processEvents()
    time.sleep(0.005)
print("the solver did not crash", file=sys.stderr)
sys.exit(3)
"""

EXPECTED_TEXT = {
    "plain": "sketchforge stopped while computing 'Abort solve' on layer 'Arm'.",
    "macro": "sketchforge stopped while computing 'Draw layer' on layer 'New part'.",
    "assemble": "sketchforge stopped while computing 'Assemble model'.",
}


def crash_app(tmp_path: Path, mode: str) -> tuple[Path, Path]:
    """Run the app until its solver aborts; returns (the autosave folder, the output folder)."""
    out = tmp_path / "out"
    out.mkdir()
    data = tmp_path / "data"
    env = dict(
        os.environ,
        QT_QPA_PLATFORM="offscreen",
        SKETCHFORGE_DATA_DIR=str(data),
        SKETCHFORGE_AUTOSAVE_INTERVAL="3600",  # only the pre-solve flush writes
        PYTHONPATH=os.pathsep.join([str(TESTS), os.environ.get("PYTHONPATH", "")]),
    )
    proc = subprocess.run(
        [sys.executable, "-c", SCRIPT, mode, str(out)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == -signal.SIGABRT, f"exit status {proc.returncode}\n{proc.stderr[-3000:]}"
    return data / "autosave", out


def inflate_host():
    import sketchforge_inflate.plugin as inflate

    return make_test_host(inflate)  # recovering needs no crashing plugin: its step is not in the file


@pytest.mark.parametrize("mode", ["plain", "macro", "assemble"])
def test_a_native_crash_in_a_solve_is_recovered_without_the_crashing_step(tmp_path, monkeypatch, qtbot, mode):
    folder, out = crash_app(tmp_path, mode)

    # The autosave is there, with the record of the step that was running.
    items = find_recoverable(folder)
    assert len(items) == 1
    item = items[0]
    assert item.has_document and item.original is None and len(item.running) == 1
    rec = item.running[-1]
    if mode == "plain":
        assert rec["command"] == {"command": "abort_solve", "layer": "arm"}
        assert rec["text"] == "Abort solve" and rec["layer"] == "arm" and rec["layer_name"] == "Arm"
    elif mode == "macro":
        assert rec["command"] == {"command": "abort_solve", "layer": "new"} and rec["macro"] == "Draw layer"
        assert rec["before"] == [{"command": "add_layer", "id": "new", "name": "New part"}]
        assert rec["new_layer"] is True
        # The document had not changed since the last autosave: it was not written again.
        assert item.path.read_bytes() == (out / "autosave_before.bin").read_bytes()
    else:
        assert rec["command"] is None and rec["text"] == "Assemble model"
    assert describe_stop(item) == EXPECTED_TEXT[mode]

    # Recovered: bit-identical to the state before the step, which is not in the journal.
    host = inflate_host()
    back = recover(item, host=host)
    expected = ff.load(out / "expected.json", host=host)
    assert back.layer_ids() == expected.layer_ids() == ["body", "arm"]
    for a, b in zip(back.layers, expected.layers):
        assert a.mesh is not None and a.mesh.identical(b.mesh) and a.same_state(b)
    assert ff.compare(back, expected) == [] and back.light == expected.light
    assert back.journal() == expected.journal()
    assert all(e["command"] != "abort_solve" and e.get("id") != "new" for e in back.journal())
    assert not back.undo_stack.is_clean()
    # The journal and the snapshot agree (no half-done macro in the file): replaying gives the same.
    assert ff.compare(ff.load(item.path, host=host, use_snapshot=False), back) == []

    # The app's question names the step; answering Yes recovers the work without it.
    pytest.importorskip("PySide6")
    from PySide6.QtCore import QSettings
    from PySide6.QtWidgets import QMessageBox

    from sketchforge.qt.main_window import MainWindow

    asked = []

    def question(parent, title, text, *args, **kwargs):
        asked.append(text)
        return QMessageBox.StandardButton.Yes

    monkeypatch.setattr(QMessageBox, "question", staticmethod(question))
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(folder.parent))
    settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
    w = MainWindow(Document(host=host), host=host, settings=settings)
    qtbot.addWidget(w)
    assert w.offer_recovery() is True
    assert len(asked) == 1 and EXPECTED_TEXT[mode] in asked[0]
    if mode == "assemble":
        assert "not part of it" in asked[0]
    else:
        assert "up to that step can be recovered; that step was left out" in asked[0]
    assert w.doc.same_state(expected) and w.is_modified()
    assert all(e["command"] != "abort_solve" for e in w.doc.journal())
    # The window's own autosave took over; the crashed one and its record are gone.
    assert not item.path.exists() and not item.pending_path.exists()
    assert [i.path for i in find_recoverable(folder)] == [w.autosaver.path]
    w.close_now()
    assert find_recoverable(folder) == []


# --- the Autosaver's pre-solve flush, without a crash ------------------------------------------


def dirty_doc():
    doc = Document(host=make_test_host(FanInflater()))
    doc.execute({"command": "add_layer", "id": "a", "name": "Alpha"})
    doc.execute({"command": "set_contour", "layer": "a", "points": [[0, 0], [2, 0], [1, 1]]})
    return doc


def contour(layer, points=((0, 0), (1, 0), (0, 1))):
    from sketchforge.document import commands as C

    return C.SetContour(layer=layer, points=list(points))


def test_begin_solve_flushes_the_state_and_names_the_step_then_end_solve_clears_it(tmp_path):
    doc = dirty_doc()
    saver = Autosaver(doc, original_path=tmp_path / "mine.json", interval_s=3600, folder=tmp_path / "auto")
    token = saver.begin_solve(contour("a"))
    # The state before the step is on disk (the 3600 s interval did not matter) ...
    assert saver.path.exists() and saver.pending_path.exists()
    [item] = find_recoverable(tmp_path / "auto")
    assert item.original == str((tmp_path / "mine.json").resolve())
    assert item.running[-1]["text"] == "Draw contour" and item.running[-1]["layer_name"] == "Alpha"
    assert item.running[-1]["command"]["command"] == "set_contour"
    assert ff.compare(recover(item, host=doc.host), doc) == []
    # ... and once the solver returned, only the record goes: the work is still unsaved.
    saver.end_solve(token)
    assert saver.path.exists() and not saver.pending_path.exists()
    assert find_recoverable(tmp_path / "auto")[0].running == ()
    autosaved = saver.path.read_bytes()
    saver.end_solve(token)  # twice is harmless: nothing changes
    assert sorted((tmp_path / "auto").iterdir()) == [saver.path] and saver.path.read_bytes() == autosaved
    [item] = find_recoverable(tmp_path / "auto")
    assert item.running == () and item.pending_path is None


def test_an_unchanged_document_is_not_written_again_before_a_solve(tmp_path):
    doc = dirty_doc()
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    assert saver.save_now() is True
    stat = saver.path.stat()
    token = saver.begin_solve(contour("a"))
    assert saver.path.stat().st_mtime_ns == stat.st_mtime_ns and saver.path.stat().st_ino == stat.st_ino
    assert saver.pending_path.stat().st_size < 1000
    saver.end_solve(token)


def test_a_clean_document_gets_only_the_record_and_recovery_reports_it(tmp_path):
    doc = dirty_doc()
    doc.undo_stack.set_clean()  # as if just saved to mine.json
    saver = Autosaver(doc, original_path=tmp_path / "mine.json", folder=tmp_path / "auto")
    token = saver.begin_solve(contour("a"))
    assert not saver.path.exists() and saver.pending_path.exists()
    [item] = find_recoverable(tmp_path / "auto")
    assert not item.has_document and item.running[-1]["layer"] == "a"
    assert describe_stop(item) == "sketchforge stopped while computing 'Draw contour' on layer 'Alpha'."
    saver.end_solve(token)
    assert find_recoverable(tmp_path / "auto") == []
    # A crash reported once is forgotten once shown.
    saver.begin_solve(contour("a"))
    forget(find_recoverable(tmp_path / "auto")[0])
    assert find_recoverable(tmp_path / "auto") == []


def test_no_autosave_is_written_in_the_middle_of_a_macro(tmp_path):
    from sketchforge.document import commands as C

    doc = dirty_doc()
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    add = C.AddLayer(id="b", layer_name="Beta")
    token = saver.begin_solve(contour("b"), macro="Draw layer", before=[add])
    before = saver.path.read_bytes()
    doc.undo_stack.begin_macro("Draw layer")
    doc.push(add)
    assert saver.tick() is False and saver.save_now() is False  # half a macro is no state
    assert saver.path.read_bytes() == before
    [item] = find_recoverable(tmp_path)
    assert item.running[-1]["layer_name"] == "Beta" and item.running[-1]["new_layer"] is True
    assert recover(item, host=doc.host).layer_ids() == ["a"]
    doc.undo_stack.abort_macro()
    saver.end_solve(token)


def test_a_cancelled_solve_still_running_keeps_its_record_and_the_autosave_keeps_up(tmp_path):
    """A cancelled solve's native code runs on until it returns: its record stays, and the
    autosave follows the person's later edits at every tick instead of once a minute."""
    doc = dirty_doc()
    saver = Autosaver(doc, interval_s=3600, folder=tmp_path)
    first = saver.begin_solve(contour("a"))  # cancelled in the GUI, still running
    doc.execute({"command": "rename_layer", "layer": "a", "name": "Renamed"})
    assert saver.tick() is True  # written at once although the interval is an hour
    second = saver.begin_solve(contour("a", ((0, 0), (3, 0), (0, 3))))
    [item] = find_recoverable(tmp_path)
    assert len(item.running) == 2 and "cancelled but still running" in describe_stop(item)
    assert recover(item, host=doc.host).layer("a").name == "Renamed"
    saver.end_solve(second)
    assert len(find_recoverable(tmp_path)[0].running) == 1
    saver.end_solve(first)
    assert not saver.pending_path.exists()


def test_two_sessions_on_one_file_never_touch_each_others_autosave(tmp_path):
    """The crashed session's autosave survives a new session on the same file: its clean ticks,
    its own autosaves and its discard (a save or a close) remove only its own files."""
    crashed_doc = dirty_doc()
    crashed = Autosaver(crashed_doc, original_path=tmp_path / "mine.json", interval_s=0, folder=tmp_path)
    crashed.begin_solve(contour("a"))  # ... and the process died here
    files = sorted(p.name for p in tmp_path.iterdir())
    doc = dirty_doc()
    doc.undo_stack.set_clean()
    now = Autosaver(doc, original_path=tmp_path / "mine.json", interval_s=0, folder=tmp_path)
    assert now.path != crashed.path
    now.tick()  # clean: removes its own autosave (none), not the crashed one
    doc.execute({"command": "rename_layer", "layer": "a", "name": "x"})
    now.tick()
    now.begin_solve(contour("a"))
    now.discard()
    assert sorted(p.name for p in tmp_path.iterdir()) == files
    assert find_recoverable(tmp_path)[0].running[-1]["layer"] == "a"


@pytest.mark.skipif(not EXAMPLE.exists(), reason="examples/creature.json is not there")
def test_before_a_solve_an_unchanged_example_gets_only_its_small_record(tmp_path):
    """Why the pre-solve flush is cheap (timings: benchmarks/bench_autosave.py): a document
    unchanged since its last autosave is not written again, only the record is."""
    doc = ff.load(EXAMPLE, host=inflate_host())
    doc.execute({"command": "rename_layer", "layer": doc.layer_ids()[0], "name": "changed"})
    saver = Autosaver(doc, interval_s=3600, folder=tmp_path)
    cmd = contour(doc.layer_ids()[0])
    saver.end_solve(saver.begin_solve(cmd))  # changed: the whole document is written
    written, stat = saver.path.read_bytes(), saver.path.stat()
    token = saver.begin_solve(cmd)  # unchanged: the pending record only
    now = saver.path.stat()
    assert (now.st_ino, now.st_mtime_ns, now.st_size) == (stat.st_ino, stat.st_mtime_ns, stat.st_size)
    assert saver.path.read_bytes() == written
    assert len(written) > 100_000 and saver.pending_path.stat().st_size < 2_000
    saver.end_solve(token)


# --- another sketchforge still running ----------------------------------------------------------


def test_a_running_session_s_files_are_neither_listed_nor_touched_until_it_stops(tmp_path):
    """A second sketchforge started while the first one is in the middle of a solve does not
    take the first one's autosave and records for a crash; once that process is gone, they
    are."""
    folder = tmp_path / "auto"
    with live_session(folder) as proc:
        files = {p: p.read_bytes() for p in folder.iterdir()}
        assert sorted(p.suffix for p in files) == [".json", ".pending", ".pending"]
        assert find_recoverable(folder) == []
        assert {p: p.read_bytes() for p in folder.iterdir()} == files
        for path, raw in files.items():  # each file names its writer
            writer = json.loads(raw)["autosave"] if path.suffix == ".json" else json.loads(raw)
            assert writer["pid"] == proc.pid and writer["host"] == socket.gethostname()
        proc.kill()  # now it crashes
        proc.wait()
        items = find_recoverable(folder)
    [report] = [i for i in items if not i.has_document]
    [work] = [i for i in items if i.has_document]
    assert describe_stop(report) == "sketchforge stopped while computing 'Draw contour' on layer 'Beta'."
    assert describe_stop(work) == "sketchforge stopped while computing 'Draw contour' on layer 'Alpha'."
    assert work.original == str((tmp_path / "mine.json").resolve())
    assert recover(work, host=make_test_host(FanInflater())).layer("a").name == "Alpha"
    assert {p: p.read_bytes() for p in folder.iterdir()} == files


def test_writer_alive(monkeypatch):
    here = socket.gethostname()
    assert writer_alive({"pid": 1, "host": here}) is True  # init: always running
    assert writer_alive({"pid": 1, "host": here + "-elsewhere"}) is False  # cannot be checked: offered
    assert writer_alive({"pid": os.getpid(), "host": here}) is False  # this process knows its own files
    for meta in [{}, {"pid": "1", "host": here}, {"pid": True, "host": here}, {"pid": 0, "host": here}, {"pid": -1, "host": here}, None]:
        assert writer_alive(meta) is False, meta
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True).stdout
    assert writer_alive({"pid": int(dead), "host": here}) is False  # ended (and reaped)

    def refused(pid, sig):
        raise PermissionError(1, "Operation not permitted")  # another user's live process

    monkeypatch.setattr(autosave.os, "kill", refused)
    assert writer_alive({"pid": 12345, "host": here}) is True


# --- a save or an open while a solve still runs ------------------------------------------------


def test_a_solve_s_record_outlives_a_save_and_an_open_until_the_solve_ends(tmp_path):
    """A cancelled solve (or a sculpt preview, an assembly) may still be in native code when
    the document is saved or another is opened: its record stays until it ends."""
    folder, mine = tmp_path / "auto", tmp_path / "mine.json"
    doc = dirty_doc()
    saver = Autosaver(doc, original_path=mine, interval_s=3600, folder=folder)
    token = saver.begin_solve(contour("a"))
    ff.save(doc, mine)  # what MainWindow.save_to does ...
    saved = saver.hand_over(mine)  # ... with the autosaver
    assert not saver.path.exists() and saved.path != saver.path
    [item] = find_recoverable(folder)  # a crash now: the step is reported, nothing was lost
    assert not item.has_document and item.original == str(mine.resolve())
    assert item.running[-1]["text"] == "Draw contour" and item.running[-1]["unsaved"] is False
    # Edits after the save are autosaved at every tick while the solve runs, beside the record.
    doc.execute({"command": "rename_layer", "layer": "a", "name": "after the save"})
    assert saved.tick() is True
    [item] = find_recoverable(folder)
    assert item.path == saved.path and item.has_document and item.running[-1]["layer"] == "a"
    assert recover(item, host=doc.host).layer("a").name == "after the save"
    # Another document opened (MainWindow.adopt): handed over again.
    doc.adopt(ff.load(mine, host=doc.host))
    opened = saved.hand_over(mine)
    assert not saved.path.exists()
    [item] = find_recoverable(folder)
    assert not item.has_document and item.running[-1]["text"] == "Draw contour"
    assert saved.tick() is False and saved.save_now() is False  # a handed-over autosaver writes nothing
    # The solve ends: its token, given to the first autosaver, reaches the one in charge now.
    saver.end_solve(token)
    assert find_recoverable(folder) == [] and list(folder.iterdir()) == []
    doc.execute({"command": "rename_layer", "layer": "a", "name": "x"})
    assert opened.save_now() is True
    opened.discard()
    assert list(folder.iterdir()) == []


def test_the_pending_record_names_the_step_its_macro_and_what_came_before(tmp_path):
    """The record is what a person (or support) reads after a crash: the step, the macro it was
    part of, the macro's earlier commands, and whether the work was unsaved."""
    from sketchforge.document import commands as C

    doc = dirty_doc()
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    add = C.AddLayer(id="b", layer_name="Beta")
    other = C.AddLayer(id="c", layer_name="Gamma")
    token = saver.begin_solve(contour("b"), macro="Draw layer", before=[other, add])
    [record] = json.loads(saver.pending_path.read_text())["running"]
    assert record["text"] == "Draw layer" and record["macro"] == "Draw layer"
    assert record["before"] == [other.to_dict(), add.to_dict()]
    assert record["command"] == contour("b").to_dict()
    assert (record["layer"], record["layer_name"], record["new_layer"]) == ("b", "Beta", True)
    assert record["unsaved"] is True
    saver.end_solve(token)

    # a solve without a command (an assembly) and a plugin command that cannot be written
    class Odd(C.Command):
        name = "odd"

        def to_dict(self):
            return {"command": "odd", "data": object()}

        def text(self):
            return "Odd thing"

    doc.undo_stack.set_clean()
    t1 = saver.begin_solve()
    t2 = saver.begin_solve(Odd(), before=[Odd()])
    t3 = saver.begin_solve(text="Assemble")
    records = json.loads(saver.pending_path.read_text())["running"]
    assert [r["text"] for r in records] == ["a computation", "Odd thing", "Assemble"]
    assert [r["command"] for r in records] == [None, None, None]
    assert records[1]["before"] == [] and records[1]["macro"] is None
    assert all(r["unsaved"] is False and r["layer"] is None and r["new_layer"] is False for r in records)
    for t in (t1, t2, t3):
        saver.end_solve(t)
    assert not saver.pending_path.exists()


def test_a_new_layer_is_named_only_from_its_own_add_layer(tmp_path):
    from sketchforge.document import commands as C

    doc = dirty_doc()
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    unrelated = C.AddLayer(id="z", layer_name="Zed")
    renamed = C.RenameLayer(layer="b", new_name="Not an add")
    token = saver.begin_solve(contour("b"), macro="Draw layer", before=[unrelated, renamed])
    [record] = json.loads(saver.pending_path.read_text())["running"]
    assert record["layer_name"] is None and record["new_layer"] is True
    [item] = find_recoverable(tmp_path)
    assert describe_stop(item) == "sketchforge stopped while computing 'Draw layer' on a new layer."
    saver.end_solve(token)


def test_a_pending_file_that_is_not_our_record_is_left_alone(tmp_path):
    doc = dirty_doc()
    doc.undo_stack.set_clean()
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    token = saver.begin_solve(contour("a"))
    assert len(find_recoverable(tmp_path)) == 1
    data = json.loads(saver.pending_path.read_text())
    assert data["format"] == "sketchforge-pending" and data["saved_at"] <= saver.pending_path.stat().st_mtime + 1
    # the same record from another program (or an older, different format): not offered
    data["format"] = "SKETCHFORGE-PENDING"
    saver.pending_path.write_text(json.dumps(data))
    assert find_recoverable(tmp_path) == []
    assert saver.pending_path.exists()  # and not deleted: it is not ours to remove
    saver.end_solve(token)
