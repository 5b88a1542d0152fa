"""The light: a sky disc to drag the sun on (azimuth and elevation, as a sun-direction control
in a 3D app), and the two angles typed. Every change is one command; a drag on the disc is one
undo step (the window gives its commands one gesture id).

The disc is the hemisphere of directions facing the viewer (``sketchforge.tools.light``: the
centre is straight overhead, the rim the drawing plane, the radius falls linearly with the
elevation), drawn as a dome lit by the current light, brightest where the sun is.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QImage, QPainter, QPen
from PySide6.QtWidgets import QDoubleSpinBox, QFormLayout, QGroupBox, QHBoxLayout, QLabel, QVBoxLayout, QWidget

from sketchforge.document.layer import Light
from sketchforge.tools.light import disc_point, dome_shading, light_at_disc

#: Elevations of the dashed rings on the disc (degrees).
RINGS = (30.0, 60.0)


class LightDisc(QWidget):
    """The sky disc. Press, drag and release on it to move the sun; ``dragged`` gives the light
    under the mouse (outside the disc: on the rim, in the drawing plane)."""

    pressed = Signal()
    dragged = Signal(object)  # Light
    released = Signal()

    def __init__(self, parent=None, size: int = 124) -> None:
        super().__init__(parent)
        self.setFixedSize(size, size)
        self.setCursor(Qt.CursorShape.CrossCursor)
        self.setToolTip("Drag the sun: the centre is straight overhead, the rim the drawing plane (as in the thesis); "
                        f"dashed rings at {RINGS[0]:g}° and {RINGS[1]:g}° of elevation")
        self._light = Light()
        self._image: QImage | None = None
        self._pixels: np.ndarray | None = None  # keeps the QImage's buffer alive
        self._dragging = False

    # --- geometry -------------------------------------------------------------------------------
    def _disc(self) -> tuple[QPointF, float]:
        r = min(self.width(), self.height()) / 2.0 - 7.0
        return QPointF(self.width() / 2.0, self.height() / 2.0), r

    def widget_point(self, light: Light) -> QPointF:
        """Where the sun of ``light`` is drawn (widget pixels; Qt's y points down)."""
        c, r = self._disc()
        u, v = disc_point(light)
        return QPointF(c.x() + r * u, c.y() - r * v)

    def disc_at(self, pos) -> np.ndarray:
        """The disc point (2,) under widget position ``pos`` (y up)."""
        c, r = self._disc()
        return np.array([(pos.x() - c.x()) / r, (c.y() - pos.y()) / r])

    # --- state ----------------------------------------------------------------------------------
    def set_light(self, light: Light) -> None:
        if light != self._light:
            self._light = light
            self._image = None
            self.update()

    def _dome(self) -> QImage:
        if self._image is None:
            _, r = self._disc()
            n = max(int(2 * r), 8)
            shade = dome_shading(n, self._light)
            inside = np.isfinite(shade)
            v = np.where(inside, shade, 0.0)
            rgba = np.zeros((n, n, 4), np.uint8)
            # A warm sky: deep blue-grey in shadow to pale yellow at the sun.
            lo, hi = np.array([70, 82, 105]), np.array([255, 244, 200])
            rgba[..., :3] = (lo + (hi - lo) * v[..., None] ** 0.8).astype(np.uint8)
            rgba[..., 3] = np.where(inside, 255, 0)
            self._pixels = np.ascontiguousarray(rgba)
            self._image = QImage(self._pixels.data, n, n, 4 * n, QImage.Format.Format_RGBA8888)
        return self._image

    # --- painting -------------------------------------------------------------------------------
    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        c, r = self._disc()
        p.drawImage(QRectF(c.x() - r, c.y() - r, 2 * r, 2 * r), self._dome())
        p.setPen(QPen(QColor(120, 120, 120), 1))
        p.drawEllipse(c, r, r)
        dash = QPen(QColor(255, 255, 255, 120), 1, Qt.PenStyle.DashLine)
        p.setPen(dash)
        for el in RINGS:
            k = r * (1.0 - el / 90.0)
            p.drawEllipse(c, k, k)
        p.drawLine(QPointF(c.x() - r, c.y()), QPointF(c.x() + r, c.y()))
        p.drawLine(QPointF(c.x(), c.y() - r), QPointF(c.x(), c.y() + r))
        sun = self.widget_point(self._light)
        p.setPen(QPen(QColor(225, 160, 0), 2 if self._dragging else 1.5))
        p.drawLine(c, sun)
        p.setBrush(QColor(255, 215, 60))
        p.drawEllipse(sun, 6, 6)
        p.end()

    # --- the drag -------------------------------------------------------------------------------
    def _drag(self, pos) -> None:
        self.dragged.emit(light_at_disc(self.disc_at(pos)))

    def mousePressEvent(self, event) -> None:
        if event.button() != Qt.MouseButton.LeftButton:
            return
        self._dragging = True
        self.pressed.emit()
        self._drag(event.position())
        event.accept()

    def mouseMoveEvent(self, event) -> None:
        if self._dragging:
            self._drag(event.position())
            event.accept()

    def mouseReleaseEvent(self, event) -> None:
        if self._dragging and event.button() == Qt.MouseButton.LeftButton:
            self._drag(event.position())
            self._dragging = False
            self.released.emit()
            self.update()
            event.accept()


class LightPanel(QGroupBox):
    #: azimuth in degrees (counter-clockwise from +x) typed by the person
    angle_edited = Signal(float)
    #: elevation in degrees above the drawing plane typed by the person
    elevation_edited = Signal(float)

    def __init__(self, parent=None) -> None:
        super().__init__("Light", parent)
        self.disc = LightDisc()
        self.angle = QDoubleSpinBox()
        self.angle.setRange(-180.0, 180.0)
        self.angle.setDecimals(1)
        self.angle.setSuffix("°")
        self.angle.setWrapping(True)
        self.angle.setKeyboardTracking(False)
        self.angle.setToolTip("Azimuth: the light's direction in the drawing plane, counter-clockwise from +x")
        self.elevation = QDoubleSpinBox()
        self.elevation.setRange(0.0, 90.0)
        self.elevation.setDecimals(1)
        self.elevation.setSuffix("°")
        self.elevation.setKeyboardTracking(False)
        self.elevation.setToolTip("Elevation above the drawing plane: 0° in the plane (the thesis' light), 90° straight overhead")
        form = QFormLayout()
        form.setContentsMargins(0, 0, 0, 0)
        form.addRow("azimuth", self.angle)
        form.addRow("elevation", self.elevation)
        col = QVBoxLayout()
        col.addLayout(form)
        hint = QLabel("<small>drag the sun: centre =<br>overhead, rim = in the<br>plane. ☀ Light button:<br>"
                      "drag in the drawing</small>")
        col.addWidget(hint)
        col.addStretch(1)
        row = QHBoxLayout(self)
        row.addWidget(self.disc)
        row.addLayout(col)
        self._updating = False
        self.angle.valueChanged.connect(lambda v: self._updating or self.angle_edited.emit(float(v)))
        self.elevation.valueChanged.connect(lambda v: self._updating or self.elevation_edited.emit(float(v)))

    def show_light(self, light: Light) -> None:
        self._updating = True
        try:
            self.disc.set_light(light)
            overhead = light.elevation >= 90.0
            if not overhead:  # straight overhead has no azimuth: the field keeps the last one
                self.angle.setValue(round(light.angle, 1))
            self.angle.setEnabled(not overhead)
            self.elevation.setValue(round(light.elevation, 1))
        finally:
            self._updating = False
