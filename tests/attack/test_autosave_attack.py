"""Autosave never loses work: declining recovery keeps the file (offered again), any interval
of 1 s or more is honoured (once polled every 5 s), and a failing autosave (a data folder that
is a file) is shown once in the status bar and retried; the app's Save into a folder that
refuses new files shows a dialog and the title keeps its unsaved mark."""

from __future__ import annotations

import pytest

pytest.importorskip("PySide6")

from PySide6.QtCore import QSettings  # noqa: E402
from PySide6.QtWidgets import QMessageBox  # noqa: E402

from sketchforge.document import commands as C  # noqa: E402
from sketchforge.document import fileformat as ff  # noqa: E402
from sketchforge.document.autosave import (  # noqa: E402
    MIN_INTERVAL_S,
    Autosaver,
    autosave_interval,
    find_recoverable,
    poll_interval_ms,
)
from sketchforge.document.document import Document  # noqa: E402
from sketchforge.errors import ExportError  # noqa: E402
from sketchforge.plugins.testing import FanInflater, make_test_host  # noqa: E402

TRIANGLE = [[0, 0], [2, 0], [1, 1]]


@pytest.fixture
def host():
    return make_test_host(FanInflater())


@pytest.fixture
def dialogs(monkeypatch):
    calls, answers = [], []

    def record(kind):
        def fn(parent, title, text, *a, **k):
            calls.append((kind, title, text))
            if kind == "question":
                return answers.pop(0) if answers else QMessageBox.StandardButton.No
            return QMessageBox.StandardButton.Ok

        return fn

    for kind in ("critical", "warning", "information", "question"):
        monkeypatch.setattr(QMessageBox, kind, staticmethod(record(kind)))
    return calls, answers


@pytest.fixture
def window(qtbot, host, tmp_path, dialogs, monkeypatch):
    from sketchforge.qt.main_window import MainWindow

    made = []

    def make(doc=None, interval=None):
        settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
        if interval is not None:
            settings.setValue("autosave/interval_s", interval)
        w = MainWindow(doc or Document(host=host), host=host, settings=settings)
        qtbot.addWidget(w)
        made.append(w)
        return w

    yield make
    for w in made:
        w.close_now()


@pytest.mark.parametrize(
    "setting, seconds, poll_ms",
    [
        (1, 1.0, 1000),
        (2.5, 2.5, 2500),
        (0.2, 0.2, MIN_INTERVAL_S * 1000),
        (60, 60.0, 5000),
        ("junk", 60.0, 5000),
        (float("nan"), 60.0, 5000),
    ],
)
def test_interval_is_honoured_down_to_one_second(monkeypatch, setting, seconds, poll_ms):
    monkeypatch.delenv("SKETCHFORGE_AUTOSAVE_INTERVAL", raising=False)
    assert autosave_interval(setting) == seconds
    assert poll_interval_ms(seconds) == poll_ms


def test_window_polls_at_the_configured_interval(window, monkeypatch):
    monkeypatch.delenv("SKETCHFORGE_AUTOSAVE_INTERVAL", raising=False)
    w = window(interval=2)
    assert w.autosaver.interval_s == 2.0 and w._autosave_timer.interval() == 2000


def test_one_second_autosave_really_writes_within_two_seconds(window, qtbot, tmp_path, monkeypatch, host):
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("SKETCHFORGE_AUTOSAVE_INTERVAL", "1")
    w = window()
    w.push(C.AddLayer(id="a", layer_name="A"))
    qtbot.waitUntil(lambda: w.autosaver.path.exists(), timeout=2500)


def test_data_folder_that_is_a_file(tmp_path, host):
    blocker = tmp_path / "data"
    blocker.write_text("not a folder")
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a"})
    saver = Autosaver(doc, folder=blocker / "autosave", interval_s=1)
    with pytest.raises(ExportError, match="is a file, not a folder"):
        saver.save_now()
    blocker.unlink()
    assert saver.save_now() and saver.path.exists()  # retried: works once the folder can exist


def test_failing_autosave_is_shown_once_and_retried(window, tmp_path, monkeypatch):
    blocker = tmp_path / "data"
    blocker.write_text("not a folder")
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(blocker))
    w = window(interval=1)
    shown = []
    real = w.statusBar().showMessage
    monkeypatch.setattr(w.statusBar(), "showMessage", lambda text, *a: (shown.append(text), real(text, *a)))
    w.push(C.AddLayer(id="a", layer_name="A"))
    for _ in range(4):
        w.autosaver._last_time -= 2  # an interval has passed
        w._autosave()
    failures = [t for t in shown if t.startswith("autosave failed")]
    assert len(failures) == 1 and "is a file, not a folder" in failures[0]
    assert w.statusBar().currentMessage() == failures[0]  # it stays
    blocker.unlink()
    w.autosaver._last_time -= 2
    w._autosave()
    assert w.autosaver.path.exists() and shown[-1] == "autosave works again"


def test_declined_recovery_keeps_the_autosave_across_ticks_and_offers_it_again(window, dialogs, tmp_path, monkeypatch, host):
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(tmp_path / "data"))
    calls, answers = dialogs
    mine = tmp_path / "mine.json"
    crashed = Document(host=host)
    crashed.execute({"command": "add_layer", "id": "a", "name": "Alpha"})
    ff.save(crashed, mine)
    crashed.execute({"command": "rename_layer", "layer": "a", "name": "Unsaved"})
    left = Autosaver(crashed, original_path=mine)
    assert left.save_now()  # ...and that session ended abnormally
    content = left.path.read_bytes()
    for _attempt in range(2):  # two starts, both answered No
        w = window(interval=1)
        assert w.open_path(mine, ask=False)
        answers.append(QMessageBox.StandardButton.No)
        assert w.offer_recovery() is False
        for _ in range(3):
            w.autosaver._last_time -= 2
            w._autosave()
        w.close_now()
        assert left.path.read_bytes() == content
        assert [i.path for i in find_recoverable()] == [left.path]
    assert sum(1 for c in calls if c[0] == "question") == 2


def test_app_save_into_a_folder_that_refuses_new_files(window, dialogs, tmp_path, monkeypatch):
    from attack_helpers import refuse_new_files

    calls, _ = dialogs
    w = window()
    w.push(C.AddLayer(id="a", layer_name="A"))
    assert w.isWindowModified()
    refuse_new_files(monkeypatch)
    assert w.save_to(tmp_path / "doc.json") is False
    [(kind, title, text)] = [c for c in calls if c[0] == "critical"]
    assert title == "Cannot save the document" and "does not allow new files" in text and "\n" not in text
    assert w.isWindowModified() and "[*]" in w.windowTitle()
    assert w.path is None


def test_app_export_never_replaces_the_open_document(window, dialogs, tmp_path, host):
    calls, _ = dialogs
    w = window()
    w.push(C.AddLayer(id="a", layer_name="A"))
    w.push(C.SetContour(layer="a", points=TRIANGLE))
    path = tmp_path / "doc.obj"  # a document saved under a mesh suffix
    assert w.save_to(path)
    before = path.read_bytes()
    assert w.export_to(path) is False
    assert path.read_bytes() == before
    assert any("it is the input document" in c[2] for c in calls if c[0] == "critical")
