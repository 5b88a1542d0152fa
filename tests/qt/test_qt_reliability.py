"""Issue 38 in the app: no silent overwrite (a file changed on disk since it was opened or saved
is never written over without a question), autosave hygiene (stale temps removed, malformed
autosaves set aside with one message, recovery's default Yes), a drawing slip in the status
bar, and the watchdog on the inflation's child process (a hang or a crash never stops the
app's computations)."""

from __future__ import annotations

import json
import os
import signal
import time

import numpy as np
import pytest
from PySide6.QtCore import QSettings, QThreadPool
from PySide6.QtWidgets import QMessageBox
from qt_helpers import wait_idle

from sketchforge.document import commands as C
from sketchforge.document import fileformat as ff
from sketchforge.document.autosave import Autosaver, find_recoverable
from sketchforge.document.document import Document

YES, NO = QMessageBox.StandardButton.Yes, QMessageBox.StandardButton.No


def _ellipse(cx=0.0, n=60):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([cx + 0.5 * np.cos(t), 0.3 * np.sin(t)])


def _saved(path, host, name="A"):
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a", "name": name})
    ff.save(doc, path)
    return path


def _names(path, host):
    return [l.name for l in ff.load(path, host=host).layers]


# --- no silent overwrite --------------------------------------------------------------------


def test_two_windows_on_one_file_never_lose_either_ones_work_without_a_question(make_window, host, tmp_path, dialogs,
                                                                                monkeypatch):
    """B saves, then A saves: B's work was gone without a question. Now A is asked; Enter
    (Save As) loses nobody's work, Overwrite does what it says."""
    path = _saved(tmp_path / "shared.json", host)
    a, b = make_window(), make_window()
    assert a.open_path(path) and b.open_path(path)
    a.push(C.RenameLayer(layer="a", new_name="by A"))
    b.push(C.RenameLayer(layer="a", new_name="by B"))
    assert b.save()
    assert _names(path, host) == ["by B"]
    other = tmp_path / "a-copy.json"
    import sketchforge.qt.window_files as mw  # the window's file actions

    saved_as = []
    monkeypatch.setattr(mw.QFileDialog, "getSaveFileName", staticmethod(lambda *a_, **k: saved_as.append(1) or (str(other), "")))
    assert a.save()  # Enter: Save As
    asked = dialogs.of("choice")
    assert len(asked) == 1 and asked[0][1] == "The file changed on disk" and str(path) in asked[0][2]
    assert dialogs.defaults[-1] == "Save As…" and saved_as == [1]
    assert _names(path, host) == ["by B"] and _names(other, host) == ["by A"]  # both kept
    assert a.path == other and not a.is_modified()
    # B goes on and saves again: its own file, unchanged by anyone since its save: no question.
    b.push(C.RenameLayer(layer="a", new_name="by B again"))
    assert b.save() and len(dialogs.of("choice")) == 1 and _names(path, host) == ["by B again"]


def test_a_file_replaced_on_disk_is_not_overwritten_without_a_question(make_window, host, tmp_path, dialogs):
    path = _saved(tmp_path / "doc.json", host)
    w = make_window()
    assert w.open_path(path)
    w.push(C.RenameLayer(layer="a", new_name="mine"))
    # Another program replaces the file (a new inode, other contents).
    replaced = tmp_path / "other.json"
    _saved(replaced, host, name="theirs")
    os.replace(replaced, path)
    dialogs.choices = ["Cancel"]
    assert not w.save()
    assert _names(path, host) == ["theirs"] and w.is_modified() and "changed on disk" in w.statusBar().currentMessage()
    dialogs.choices = ["Reload"]
    assert not w.save()
    assert [l.name for l in w.doc.layers] == ["theirs"] and not w.is_modified()  # reloaded, as chosen
    w.push(C.RenameLayer(layer="a", new_name="mine again"))
    assert w.save() and _names(path, host) == ["mine again"]  # reloaded: it is the file's version now
    # A change on disk with the same contents (a touch, a copy of the same bytes) is no change.
    os.utime(path, (time.time() + 5, time.time() + 5))
    w.push(C.RenameLayer(layer="a", new_name="touched"))
    n = len(dialogs.of("choice"))
    assert w.save() and len(dialogs.of("choice")) == n
    # Overwrite, when chosen, overwrites.
    os.replace(_saved(tmp_path / "x.json", host, name="theirs 2"), path)
    w.push(C.RenameLayer(layer="a", new_name="mine 3"))
    dialogs.choices = ["Overwrite"]
    assert w.save() and _names(path, host) == ["mine 3"]


def test_a_recovered_autosave_asks_before_it_replaces_a_file_changed_since(make_window, host, tmp_path, dialogs,
                                                                           monkeypatch):
    path = _saved(tmp_path / "doc.json", host)
    folder = tmp_path / "data" / "autosave"
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(folder.parent))
    doc = ff.load(path, host=host)
    digest = ff.stamp_of(os.stat(path), __import__("hashlib").sha256(path.read_bytes()).hexdigest())[4]
    saver = Autosaver(doc, path, folder=folder, original_sha256=digest)
    doc.push(C.RenameLayer(layer="a", new_name="crashed work"))
    saver.save_now()
    data = json.loads(saver.path.read_text())
    data["autosave"]["pid"] = 2**22 + 12345  # a session that is gone
    saver.path.write_text(json.dumps(data))
    os.replace(_saved(tmp_path / "x.json", host, name="saved elsewhere"), path)
    w = make_window()
    dialogs.answers = [YES]
    assert w.offer_recovery() and w.path == path
    dialogs.choices = ["Cancel"]
    assert not w.save() and _names(path, host) == ["saved elsewhere"]


# --- autosave hygiene -----------------------------------------------------------------------


@pytest.mark.parametrize("meta, why", [
    ({"original": 5}, "'original' is not a file path"),
    ({"original": "/tmp/a\x00b"}, "'original' is not a file path"),
    ({"original": "/tmp/x.json", "saved_at": "yesterday"}, "'saved_at' is not a time"),
    ({"original": "/tmp/x.json", "pid": "12"}, "'pid' is malformed"),
    ([], "'autosave' record is not an object"),
])
def test_a_malformed_autosave_is_set_aside_with_one_message_never_a_crash(make_window, host, tmp_path, dialogs,
                                                                         monkeypatch, meta, why):
    """An ``original`` of 5 made the app exit with a TypeError when the user answered Yes, and
    the autosave was kept, so every start ended the same way."""
    folder = tmp_path / "data" / "autosave"
    folder.mkdir(parents=True)
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(folder.parent))
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    bad = folder / "0123abcd.json"
    data = ff.document_to_dict(doc)
    data["autosave"] = meta
    bad.write_text(json.dumps(data))
    w = make_window()
    dialogs.answers = [YES, YES]
    assert w.offer_recovery() is False
    info = dialogs.of("information")
    assert len(info) == 1 and why in info[0][2] and "set-aside" in info[0][2] and "\n" not in info[0][2]
    assert info[0][2].startswith("The autosave 0123abcd.json cannot be used")
    assert dialogs.of("question") == []  # nothing offered
    assert not bad.exists() and (folder / "set-aside" / bad.name).exists()  # kept for the user
    dialogs.calls.clear()
    assert w.offer_recovery() is False and dialogs.calls == []  # the next start: nothing more


def test_an_autosave_that_fails_to_load_is_set_aside_not_offered_forever(make_window, host, tmp_path, dialogs,
                                                                        monkeypatch):
    folder = tmp_path / "data" / "autosave"
    folder.mkdir(parents=True)
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(folder.parent))
    bad = folder / "feedbeef.json"
    bad.write_text(json.dumps({"format": "sketchforge", "version": 1, "journal": [{"command": "nope"}],
                               "autosave": {"original": None, "saved_at": 1.0}}))
    w = make_window()
    dialogs.answers = [YES]
    assert w.offer_recovery() is False
    [crit] = dialogs.of("critical")
    assert "unknown command 'nope'" in crit[2] and "moved to" in crit[2]
    assert not bad.exists() and find_recoverable(folder) == []


def test_recovery_answers_yes_on_enter_and_every_question_has_a_reviewed_default(make_window, host, tmp_path, dialogs,
                                                                                  monkeypatch):
    """Enter answered No to "Recover unsaved work?": every yes/no question defaulted to No."""
    folder = tmp_path / "data" / "autosave"
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(folder.parent))
    doc = Document(host=host)
    saver = Autosaver(doc, folder=folder)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    doc.push(C.RenameLayer(layer="a", new_name="unsaved"))
    saver.save_now()
    data = json.loads(saver.path.read_text())
    data["autosave"]["pid"] = 2**22 + 12346
    saver.path.write_text(json.dumps(data))
    w = make_window()
    dialogs.answers = [YES]
    assert w.offer_recovery()
    assert dialogs.defaults == [YES]


def test_parts_left_their_host_keeps_the_change_on_enter(make_window, host, qtbot, dialogs):
    """The other yes/no questions, reviewed: "Parts left their host: undo the change?" keeps
    what the person just did on Enter (Ctrl+Z still undoes it); "Redraw the contour without
    its sculpt edits?" redraws on Enter (Undo brings the edits back; No would drop the stroke)."""
    root = __import__("pathlib").Path(__file__).resolve().parents[2]
    w = make_window(ff.load(root / "examples" / "creature.json", host=host))
    body = w.doc.layer("body")
    P = np.asarray(body.points)
    c = P.mean(axis=0)
    dialogs.answers = [NO]
    w._redraw(body, c + 0.8 * (P - c), body.closed, "redrew the outline")
    wait_idle(qtbot, w)
    assert [t for _, t, _ in dialogs.of("question")] == ["Parts left their host"] and dialogs.defaults == [NO]


def test_temps_of_killed_autosaves_are_removed_at_start(make_window, host, tmp_path, dialogs, monkeypatch):
    """A kill during an autosave left a document-sized temp that was never removed (its
    autosave's name is new at each session): 21 MB after 20 kills."""
    import subprocess
    import sys

    folder = tmp_path / "data" / "autosave"
    folder.mkdir(parents=True)
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(folder.parent))
    script = ("import sys, os\nfrom sketchforge.atomic import write_bytes_atomic\n"
              "import sketchforge.atomic as a\nreal = a._write_all\n"
              "def die(fh, data):\n    real(fh, data[: len(data) // 2]); fh.flush(); os._exit(9)\n"
              "a._write_all = die\nwrite_bytes_atomic(sys.argv[1], b'x' * (1 << 20))\n")
    for k in range(3):
        res = subprocess.run([sys.executable, "-c", script, str(folder / f"{k:032x}.json")], timeout=60)
        assert res.returncode == 9
    stale = sorted(folder.glob(".*.tmp"))
    assert len(stale) == 3 and all(p.stat().st_size == 1 << 19 for p in stale)
    live = folder / f".{'f' * 32}.json.0123456789.{os.getpid()}.0badc0de.tmp"  # this process writes it
    live.write_bytes(b"x")
    w = make_window()
    w.offer_recovery()
    assert sorted(p.name for p in folder.glob(".*.tmp")) == [live.name]


# --- a drawing slip -------------------------------------------------------------------------


def test_a_self_crossing_stroke_is_a_status_line_not_a_dialog(drawing_window, qtbot, dialogs):
    w = drawing_window
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    eight = np.column_stack([0.5 * np.sin(t), 0.3 * np.sin(2 * t)])
    w.draw_stroke(np.vstack([eight, eight[:1]]), "front")
    wait_idle(qtbot, w)
    assert dialogs.of("critical") == []
    assert "the stroke was not drawn: the outline crosses itself" in w.statusBar().currentMessage()
    assert len(w.doc.layers) == 0 and w.doc.undo_stack.count() == 0  # nothing changed


# --- the watchdog on the inflation's child process ----------------------------------------------


@pytest.fixture
def offloaded(qtbot, host, tmp_path, dialogs):
    from sketchforge.qt.main_window import MainWindow

    settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
    w = MainWindow(Document(host=host), host=host, settings=settings, offload_inflation=True)
    qtbot.addWidget(w)
    assert w.offload.offloading()
    yield w
    w.close_now()
    w.jobs.wait(30_000)


def _draw(w, qtbot, cx):
    n = len(w.doc.layers)
    w.draw_stroke(_ellipse(cx), "front")
    wait_idle(qtbot, w, timeout=120_000)
    return len(w.doc.layers) == n + 1


def test_a_hung_solver_process_never_stops_the_app(offloaded, qtbot, dialogs):
    """SIGSTOP the child: Esc freed the window, but each cancelled job kept one of the two
    shared worker threads waiting forever; after two tries nothing computed again. Now Cancel
    stops the child and starts another, the wait is off the shared pool, and the next
    inflation works; each time the status bar says so in one line."""
    w = offloaded
    assert _draw(w, qtbot, 0.0)
    for attempt in range(3):
        os.kill(w.offload.child_pid, signal.SIGSTOP)
        w.draw_stroke(_ellipse(1.5 + attempt), "front")
        qtbot.waitUntil(lambda: w.runner.busy, timeout=5_000)
        time.sleep(0.3)  # the job now waits on the stopped child
        assert QThreadPool.globalInstance().activeThreadCount() == 0  # not on the shared pool
        w.cancel_current()
        qtbot.waitUntil(lambda: "solver process was stopped" in w.statusBar().currentMessage(), timeout=10_000)
        qtbot.waitUntil(lambda: w.runner.pool.activeThreadCount() == 0, timeout=10_000)
    assert len(w.doc.layers) == 1 and dialogs.of("critical") == []
    w.push(C.RenameLayer(layer=w.doc.layers[0].id, new_name="renamed"))  # a rename works
    assert w.doc.layers[0].name == "renamed"
    assert _draw(w, qtbot, 5.0)  # and so does the next inflation, in the new child


def test_a_solver_process_that_hangs_past_the_timeout_is_one_line_and_the_next_job_works(offloaded, qtbot, dialogs):
    w = offloaded
    w.offload.timeout_s = 2.0
    os.kill(w.offload.child_pid, signal.SIGSTOP)
    w.draw_stroke(_ellipse(), "front")
    qtbot.waitUntil(lambda: bool(dialogs.of("critical")), timeout=30_000)
    [(kind, title, text)] = dialogs.of("critical")
    assert "took longer than 2 s and was stopped" in text and "\n" not in text
    wait_idle(qtbot, w)
    assert len(w.doc.layers) == 0
    w.offload.timeout_s = 180.0
    assert _draw(w, qtbot, 0.0)


def test_a_solver_process_killed_while_idle_is_restarted_before_the_next_job(offloaded, qtbot, dialogs):
    """It made the next inflation fail with "the solver process crashed"."""
    w = offloaded
    pid = w.offload.child_pid
    child = w.offload._child
    os.kill(pid, signal.SIGKILL)
    qtbot.waitUntil(lambda: not child.alive(), timeout=10_000)
    assert _draw(w, qtbot, 0.0)
    assert dialogs.of("critical") == []
    assert w.offload.child_pid != pid
