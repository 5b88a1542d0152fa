"""A creature drawn from scratch, one picture per gesture, for the docs:
``QT_QPA_PLATFORM=offscreen python -m sketchforge.qt.drawing_strip OUTDIR``.

The gestures are real mouse and key events sent to the real window (as the Qt tests send
them), so the pictures show what a person gets: body, head in front, a leg drawn behind with
the right button, its copy by Ctrl+D sent to the back by End and two more legs, an eye (a
closed loop on the head) and its twin by Ctrl+D, and the help overlay (F1). Writes
``drawing-1-body.png`` … ``drawing-6-help.png``; ``--save DOC`` also saves the document, which
``make screenshots`` then shows assembled in OBSERVATION (``drawing-7-observation.png``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

#: Size of the window the gestures are drawn in.
SIZE = (1100, 750)


def _ellipse(c, rx, ry, n=90):
    t = np.linspace(0.0, 2 * np.pi, n + 1)
    return np.c_[c[0] + rx * np.cos(t), c[1] + ry * np.sin(t)]


def _u(c, width, depth, n=40):
    t = np.linspace(np.pi, 2 * np.pi, n)
    return np.c_[c[0] + 0.5 * width * np.cos(t), c[1] + depth * np.sin(t)]


class _Mouse:
    """Mouse events on the canvas viewport aimed in document coordinates."""

    def __init__(self, canvas) -> None:
        self.canvas = canvas
        self.vp = canvas.viewport()

    def _send(self, kind, pos, button, buttons, modifiers) -> None:
        from PySide6.QtGui import QMouseEvent
        from PySide6.QtWidgets import QApplication

        QApplication.sendEvent(self.vp, QMouseEvent(kind, pos, self.vp.mapToGlobal(pos), button, buttons, modifiers))

    def drag(self, pts, right: bool = False) -> None:
        from PySide6.QtCore import QEvent, Qt
        from PySide6.QtWidgets import QApplication

        button = Qt.MouseButton.RightButton if right else Qt.MouseButton.LeftButton
        none, mods = Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier
        px = [self.canvas.doc_to_widget(p) for p in pts]
        self._send(QEvent.Type.MouseMove, px[0], none, none, mods)
        self._send(QEvent.Type.MouseButtonPress, px[0], button, button, mods)
        for p in px[1:]:
            self._send(QEvent.Type.MouseMove, p, none, button, mods)
        self._send(QEvent.Type.MouseButtonRelease, px[-1], button, none, mods)
        QApplication.processEvents()


def main(argv=None) -> int:
    import argparse

    parser = argparse.ArgumentParser(prog="python -m sketchforge.qt.drawing_strip")
    parser.add_argument("outdir", type=Path)
    parser.add_argument("--save", type=Path, help="also save the drawn document (for an OBSERVATION screenshot)")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    out = args.outdir
    out.mkdir(parents=True, exist_ok=True)
    from PySide6.QtCore import QSettings, Qt
    from PySide6.QtTest import QTest

    from sketchforge.document.document import Document
    from sketchforge.qt.app import ensure_qapp, plugin_host, settle
    from sketchforge.qt.main_window import MainWindow

    app = ensure_qapp()
    host = plugin_host()
    settings = QSettings(str(out / ".strip-settings.ini"), QSettings.Format.IniFormat)
    w = MainWindow(Document(host=host), host=host, settings=settings)
    w.resize(*SIZE)
    w.show()
    w.activateWindow()
    settle(w, app)
    mouse = _Mouse(w.canvas)
    drag = mouse.drag

    def gesture(*args, **kwargs) -> None:
        drag(*args, **kwargs)
        settle(w, app)  # a stroke drawn while the last one inflates is refused (and says so)

    mouse.drag = gesture
    shots = []

    def shot(name: str) -> None:
        settle(w, app)
        path = out / f"drawing-{len(shots) + 1}-{name}.png"
        if not w.grab().save(str(path), "PNG"):
            raise SystemExit(f"cannot write {path}")
        shots.append(path)
        print(f"wrote {path}: {w.statusBar().currentMessage()}", file=sys.stderr)

    mouse.drag(_ellipse((0.0, -0.1), 0.62, 0.42))  # 1: the body, a closed stroke
    shot("body")
    mouse.drag(_ellipse((0.55, 0.42), 0.3, 0.26))  # 2: the head, in front
    shot("head")
    mouse.drag(_u((-0.4, -0.3), 0.16, 0.62), right=True)  # 3: a leg behind the body (right drag)
    shot("leg-behind")
    QTest.keyClick(w.canvas, Qt.Key.Key_D, Qt.KeyboardModifier.ControlModifier)  # 4: its copy, moved aside...
    settle(w, app)
    QTest.keyClick(w.canvas, Qt.Key.Key_End)  # ...and sent to the back (End)
    mouse.drag(_u((0.2, -0.3), 0.16, 0.62), right=True)  # two more legs at the front end
    mouse.drag(_u((0.4, -0.3), 0.16, 0.62), right=True)
    shot("legs")
    mouse.drag(_ellipse((0.5, 0.5), 0.045, 0.055, n=40))  # 5: an eye on the head, and its twin (Ctrl+D)
    settle(w, app)
    QTest.keyClick(w.canvas, Qt.Key.Key_D, Qt.KeyboardModifier.ControlModifier)
    shot("eyes")
    QTest.keyClick(w.canvas, Qt.Key.Key_F1)  # 6: every gesture and key
    shot("help")
    if args.save is not None:
        from sketchforge.document import fileformat as ff

        ff.save(w.doc, args.save)
        print(f"wrote {args.save}", file=sys.stderr)
    w.close_now()
    w.jobs.wait(30_000)
    (out / ".strip-settings.ini").unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
