"""Helpers for the app tests: mouse gestures aimed in document coordinates, waiting for solves."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QEvent, QPoint, QPointF, Qt
from PySide6.QtGui import QMouseEvent, QWheelEvent
from PySide6.QtWidgets import QApplication


def wait_idle(qtbot, window, timeout=60_000):
    """Wait until no solve runs and its result has been delivered."""
    qtbot.waitUntil(lambda: not window.runner.busy and not window.jobs.running(), timeout=timeout)
    QApplication.processEvents()


class Mouse:
    """Mouse gestures on the canvas, aimed in document coordinates (y up). Events go to the
    view's viewport as real QMouseEvents, through pyqtgraph's scene, as a person's would."""

    def __init__(self, canvas):
        self.canvas = canvas
        self.vp = canvas.viewport()

    def px(self, xy) -> QPointF:
        return self.canvas.doc_to_widget(xy)

    def aim(self, xy):
        """The whole pixel nearest to a document point, and the document point the view maps
        that pixel to along the path a mouse event takes (scene -> ViewBox -> view)."""
        p = self.px(xy)
        pixel = QPoint(round(p.x()), round(p.y()))
        vb = self.canvas.vb
        v = vb.mapToView(vb.mapFromScene(self.canvas.mapToScene(pixel)))
        return QPointF(pixel), np.array([v.x(), v.y()])

    def drag_pixels(self, pixels, button=Qt.MouseButton.LeftButton, modifiers=Qt.KeyboardModifier.NoModifier):
        self._send(QEvent.Type.MouseMove, pixels[0], Qt.MouseButton.NoButton, Qt.MouseButton.NoButton, modifiers)
        self._send(QEvent.Type.MouseButtonPress, pixels[0], button, button, modifiers)
        for p in pixels[1:]:
            self._send(QEvent.Type.MouseMove, p, Qt.MouseButton.NoButton, button, modifiers)
        self._send(QEvent.Type.MouseButtonRelease, pixels[-1], button, Qt.MouseButton.NoButton, modifiers)
        QApplication.processEvents()

    def click_pixel(self, p, button=Qt.MouseButton.LeftButton):
        self._send(QEvent.Type.MouseMove, p, Qt.MouseButton.NoButton, Qt.MouseButton.NoButton)
        self._send(QEvent.Type.MouseButtonPress, p, button, button)
        self._send(QEvent.Type.MouseButtonRelease, p, button, Qt.MouseButton.NoButton)
        QApplication.processEvents()

    def double_click(self, xy, button=Qt.MouseButton.LeftButton):
        """Press, release, double-click, release: the event sequence Qt delivers."""
        p = self.px(xy)
        self.click_pixel(p, button)
        self._send(QEvent.Type.MouseButtonDblClick, p, button, button)
        self._send(QEvent.Type.MouseButtonRelease, p, button, Qt.MouseButton.NoButton)
        QApplication.processEvents()

    def _send(self, kind, pos: QPointF, button, buttons, modifiers=Qt.KeyboardModifier.NoModifier):
        ev = QMouseEvent(kind, pos, self.vp.mapToGlobal(pos), button, buttons, modifiers)
        QApplication.sendEvent(self.vp, ev)

    def drag(self, points, button=Qt.MouseButton.LeftButton, modifiers=Qt.KeyboardModifier.NoModifier):
        """Press at the first point, move through the others, release at the last."""
        self.drag_pixels([self.px(p) for p in points], button, modifiers)

    def click(self, xy, button=Qt.MouseButton.LeftButton):
        self.click_pixel(self.px(xy), button)

    def wheel(self, xy, steps: int, modifiers=Qt.KeyboardModifier.NoModifier):
        p = self.px(xy)
        ev = QWheelEvent(
            p, self.vp.mapToGlobal(p), QPoint(0, 0), QPoint(0, 120 * steps),
            Qt.MouseButton.NoButton, modifiers, Qt.ScrollPhase.NoScrollPhase, False,
        )
        QApplication.sendEvent(self.vp, ev)
        QApplication.processEvents()


def circle(radius=0.5, n=60, center=(0.0, 0.0)):
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.c_[center[0] + radius * np.cos(t), center[1] + radius * np.sin(t)]


#: Start of a script run in its own process under Xvfb (OpenGL tests): a shown window of
#: ``SIZE`` (format the string with ``size=(w, h)``) on the document named by ``sys.argv[1]``;
#: ``app``, ``host`` and ``w`` are defined for the rest of the script.
GL_WINDOW_PRELUDE = """
import sys
from sketchforge.qt.app import ensure_qapp, grab_window, plugin_host, settle
from sketchforge.qt.main_window import MainWindow
from sketchforge.document import fileformat as ff
from sketchforge.document.document import Document
app = ensure_qapp()
host = plugin_host()
w = MainWindow(Document(host=host), host=host)
w.resize{size}
w.adopt(ff.load(sys.argv[1], host=host), None)
w.show()
"""
