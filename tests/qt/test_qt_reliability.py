"""Issue 38 in the app: the watchdog on the inflation's child process (a hang or a crash never
stops the app's computations)."""

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
