"""Fixtures for the desktop app's tests: an offscreen Qt, a window built from a given Document
and plugin host, mouse gestures in document coordinates, and patched dialogs.

QT_QPA_PLATFORM is set to ``offscreen`` before anything imports Qt, so these tests need no
display. The OpenGL test (``@pytest.mark.gl``) runs the app in a subprocess on the xcb platform
under the X server that pytest-xvfb starts; it is skipped without one.
"""

from __future__ import annotations

import os

os.environ["QT_QPA_PLATFORM"] = "offscreen"  # before any Qt import (pytest-qt imports lazily)
os.environ.setdefault("QT_LOGGING_RULES", "qt.qpa.*=false")

import pytest

pytest.importorskip("PySide6")
pytest.importorskip("pyqtgraph")

from PySide6.QtCore import QSettings  # noqa: E402
from PySide6.QtWidgets import QMessageBox  # noqa: E402

from sketchforge.document.document import Document  # noqa: E402


@pytest.fixture(scope="session")
def host():
    """Every installed plugin that loads (a plugin still being written is left out)."""
    from sketchforge.qt.app import plugin_host

    return plugin_host()


@pytest.fixture
def dialogs(monkeypatch):
    """Record QMessageBox calls instead of blocking; ``dialogs.answers`` feeds ``question``."""

    class Recorder:
        def __init__(self):
            self.calls: list[tuple[str, str, str]] = []
            self.answers: list = []
            #: the default button of each question (what Enter answers), in order
            self.defaults: list = []
            #: labels answering ``errors_ui.ask_choice`` (none left: its default, as Enter)
            self.choices: list[str] = []

        def _record(self, kind):
            def fn(parent, title, text, *args, **kwargs):
                self.calls.append((kind, title, text))
                if kind == "question":
                    self.defaults.append(args[1] if len(args) > 1 else kwargs.get("defaultButton"))
                    return self.answers.pop(0) if self.answers else QMessageBox.StandardButton.Discard
                return QMessageBox.StandardButton.Ok

            return fn

        def _choice(self, parent, title, text, choices, default, cancel):
            self.calls.append(("choice", title, text))
            self.defaults.append(choices[default])
            return choices.index(self.choices.pop(0)) if self.choices else default

        def of(self, kind):
            return [c for c in self.calls if c[0] == kind]

    rec = Recorder()
    for kind in ("critical", "warning", "information", "question"):
        monkeypatch.setattr(QMessageBox, kind, staticmethod(rec._record(kind)))
    from sketchforge.qt import errors_ui

    monkeypatch.setattr(errors_ui, "ask_choice", rec._choice)
    return rec


@pytest.fixture
def make_window(qtbot, host, tmp_path, dialogs):
    """``make_window(doc=None)`` -> a shown MainWindow on ``doc`` (a new Document by default)."""
    from sketchforge.qt.main_window import MainWindow

    windows = []

    def make(doc=None, size=(1100, 750)):
        settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
        # A window on a given document uses that document's plugins (files it opens need them).
        w = MainWindow(doc if doc is not None else Document(host=host), host=host if doc is None else doc.host,
                       settings=settings)
        qtbot.addWidget(w)
        w.resize(*size)
        w.show()
        qtbot.waitExposed(w)
        windows.append(w)
        return w

    yield make
    for w in windows:
        w.close_now()
        w.jobs.wait(30_000)


@pytest.fixture
def mouse():
    from qt_helpers import Mouse

    return Mouse


@pytest.fixture
def drawing_window(make_window, host):
    """A shown, active window whose host really inflates (skips where no inflate plugin is
    installed): for tests that draw parts with the mouse."""
    from qt_helpers import circle

    if host.inflate(circle(0.5, 24), True, {"resolution": 0.1, "inflation": 1.0, "smoothing": 0.0}) is None:
        pytest.skip("no inflate plugin is installed")
    win = make_window()
    win.activateWindow()
    return win
