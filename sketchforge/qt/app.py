"""Starting the desktop app: ``run_app`` (called by ``sketchforge [DOC]``), the plugin host it
uses, and the ``--screenshot`` path.

``--screenshot OUT.png`` opens the document, lets every pending solve finish and the window
paint, saves a grab of the whole window and exits. The editing view needs no OpenGL and works
with ``QT_QPA_PLATFORM=offscreen``; ``--mode observation`` needs OpenGL (an X server, e.g.
``xvfb-run -a`` with ``QT_QPA_PLATFORM=xcb``).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

#: Window size used for screenshots (and the initial size of the app).
WINDOW_SIZE = (1280, 800)


def plugin_host():
    """Every installed plugin that imports and whose hooks run; a broken one is left out
    (reported on stderr, and by the window in its status bar) so the app still starts.
    ``SKETCHFORGE_PLUGINS`` limits which entry points are tried."""
    from sketchforge.plugins.manager import PluginHost

    host = PluginHost.create(skip_broken=True)
    # Every registry now: a hook that raises disables its plugin. Each problem once (a plugin
    # that could not be loaded is one of them); the window lists them in Help > Plugins.
    for text in host.validate():
        print(f"sketchforge: warning: {text}", file=sys.stderr)
    return host


def ensure_qapp():
    from PySide6.QtWidgets import QApplication

    app = QApplication.instance()
    if app is None:
        app = QApplication(sys.argv[:1])
    app.setOrganizationName("sketchforge")
    app.setApplicationName("sketchforge")
    return app


def settle(window, app, timeout_s: float = 120.0) -> None:
    """Process events until no job runs and the window has painted."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        app.processEvents()
        if not window.jobs.running():
            # results are queued signals: deliver them, then check again
            app.processEvents()
            if not window.jobs.running():
                break
        window.jobs.wait(100)
    for _ in range(5):
        app.processEvents()
        time.sleep(0.02)


def grab_window(window, path) -> None:
    """Save the whole window as a PNG (the OpenGL view included, under a real display)."""
    from sketchforge.errors import ExportError

    window.canvas.render_now()  # a view change may still wait for its pause to rasterise
    pix = window.grab()
    if window.view3d.gl is not None and window.mode == "observation":
        # QWidget.grab renders QOpenGLWidgets through their framebuffer; make sure it is fresh.
        window.view3d.gl.update()
    path = Path(path)
    if path.parent and not path.parent.exists():
        raise ExportError(f"cannot write {path}: the folder {path.parent} does not exist")
    if not pix.save(str(path), "PNG"):
        raise ExportError(f"cannot write the screenshot {path}")


def run_app(doc_path=None, screenshot: str | None = None, mode: str = "editing") -> int:
    """Start the app on ``doc_path`` (or an empty document). With ``screenshot``, save a PNG of
    the window in ``mode`` ("editing", "sculpture" or "observation") and return.

    Where Qt could not open a window (no display, the xcb plugin's libraries missing), one line
    says what to do (:mod:`sketchforge.qt.platform_check`) and the exit status is 2: Qt's own
    abort text names no package."""
    if "PySide6.QtWidgets" not in sys.modules or sys.modules["PySide6.QtWidgets"].QApplication.instance() is None:
        from sketchforge.qt.platform_check import diagnose

        problem = diagnose()
        if problem is not None:
            print(problem, file=sys.stderr)
            return 2
    app = ensure_qapp()
    from sketchforge.document.document import Document
    from sketchforge.qt.main_window import MainWindow

    host = plugin_host()
    window = MainWindow(Document(host=host), host=host, offload_inflation=screenshot is None)
    window.resize(*WINDOW_SIZE)
    if doc_path is not None:
        # Errors opening a file are shown (a dialog when interactive, stderr for a screenshot).
        if screenshot is not None:
            from sketchforge.document import fileformat as ff

            window.adopt(ff.load(doc_path, host=host), Path(doc_path))
        else:
            window.open_path(Path(doc_path))
    window.show()
    window.canvas.fit()
    if screenshot is not None:
        window.set_mode(mode)
        settle(window, app)
        if mode == "observation":
            settle(window, app)
        grab_window(window, screenshot)
        print(f"wrote {screenshot}", file=sys.stderr)
        window.close_now()
        return 0
    window.start_warm_up()
    window.offer_recovery()
    return app.exec()
