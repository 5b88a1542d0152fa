"""The light: a dial showing the in-plane direction, and its angle (editing it is one command)."""

from __future__ import annotations

from PySide6.QtCore import QPointF, Signal
from PySide6.QtGui import QColor, QPainter, QPen
from PySide6.QtWidgets import QDoubleSpinBox, QGroupBox, QHBoxLayout, QLabel, QVBoxLayout, QWidget


class LightDial(QWidget):
    """A circle with an arrow towards the light (document y up drawn upwards)."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.setFixedSize(64, 64)
        self._dir = (1.0, 0.0)

    def set_direction(self, x: float, y: float) -> None:
        self._dir = (x, y)
        self.update()

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        c = QPointF(self.width() / 2, self.height() / 2)
        r = min(self.width(), self.height()) / 2 - 6
        p.setPen(QPen(QColor(150, 150, 150), 1))
        p.drawEllipse(c, r, r)
        tip = QPointF(c.x() + r * self._dir[0], c.y() - r * self._dir[1])  # Qt's y points down
        p.setPen(QPen(QColor(225, 160, 0), 2))
        p.drawLine(c, tip)
        p.setBrush(QColor(255, 215, 60))
        p.drawEllipse(tip, 5, 5)
        p.end()


class LightPanel(QGroupBox):
    #: angle in degrees (counter-clockwise from +x) typed by the person
    angle_edited = Signal(float)

    def __init__(self, parent=None) -> None:
        super().__init__("Light", parent)
        self.dial = LightDial()
        self.angle = QDoubleSpinBox()
        self.angle.setRange(-180.0, 180.0)
        self.angle.setDecimals(1)
        self.angle.setSuffix("°")
        self.angle.setWrapping(True)
        self.angle.setKeyboardTracking(False)
        self.angle.setToolTip("Direction towards the light in the drawing plane, counter-clockwise from +x")
        col = QVBoxLayout()
        col.addWidget(QLabel("in-plane direction"))
        col.addWidget(self.angle)
        col.addWidget(QLabel("<small>☀ Light button: drag<br>from the centre</small>"))
        row = QHBoxLayout(self)
        row.addWidget(self.dial)
        row.addLayout(col)
        self._updating = False
        self.angle.valueChanged.connect(self._edited)

    def show_light(self, light) -> None:
        self._updating = True
        try:
            self.dial.set_direction(light.x, light.y)
            self.angle.setValue(round(light.angle, 1))
        finally:
            self._updating = False

    def _edited(self, value: float) -> None:
        if not self._updating:
            self.angle_edited.emit(float(value))
