"""SCULPTURE controls: the tool, the band radius (slider, or the mouse wheel in the drawing),
the live preview, what to show (characteristics, the edit region) and what the last edit said."""

from __future__ import annotations

import math

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QColor, QFont, QIcon, QPainter, QPixmap
from PySide6.QtWidgets import QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QGroupBox, QLabel, QSlider

from sketchforge.qt.sculpt import MAX_RADIUS, MIN_RADIUS

_STEPS = 1000


def letter_icon(label: str, size: int = 20) -> QIcon:
    """A tool without its own icon gets its label's first letter in a rounded square."""
    pix = QPixmap(size, size)
    pix.fill(Qt.GlobalColor.transparent)
    p = QPainter(pix)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    p.setBrush(QColor("#3b6ea5"))
    p.setPen(Qt.PenStyle.NoPen)
    p.drawRoundedRect(0, 0, size, size, 4, 4)
    p.setPen(QColor("white"))
    font = QFont()
    font.setBold(True)
    font.setPixelSize(int(size * 0.7))
    p.setFont(font)
    p.drawText(pix.rect(), Qt.AlignmentFlag.AlignCenter, (label.strip()[:1] or "?").upper())
    p.end()
    return QIcon(pix)


class SculptPanel(QGroupBox):
    #: the palette's choice (a tool's registry name)
    tool_selected = Signal(str)
    radius_changed = Signal(float)
    model_changed = Signal(str)
    show_changed = Signal(bool, bool)  # characteristics, edit region
    preview_changed = Signal(bool)

    def __init__(self, parent=None) -> None:
        super().__init__("Sculpture", parent)
        form = QFormLayout(self)
        self.tool = QComboBox()
        self.tool.setToolTip("Every tool the installed plugins provide (Tools menu: the same list, with shortcuts)")
        self.tool.currentIndexChanged.connect(self._tool_chosen)
        form.addRow("Tool", self.tool)
        self.model = QComboBox()
        self.model.setToolTip("Reflectance model the height solve inverts (plugins can add models)")
        self.model.currentTextChanged.connect(lambda t: t and self.model_changed.emit(t))
        form.addRow("Reflectance", self.model)
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(0, _STEPS)
        self.spin = QDoubleSpinBox()
        self.spin.setRange(MIN_RADIUS, MAX_RADIUS)
        self.spin.setDecimals(3)
        self.spin.setSingleStep(0.01)
        self.spin.setKeyboardTracking(False)
        form.addRow("Band radius", self.slider)
        form.addRow("", self.spin)
        self.preview = QCheckBox("live preview")
        self.preview.setChecked(True)
        self.preview.setToolTip("Recompute the edit while the stroke is drawn (the surface shown is not applied until release)")
        self.strips = QCheckBox("show characteristics")
        self.strips.setToolTip("The characteristic directions (thesis 3.1) through the stroke: along them a shading change becomes a height change")
        self.regions = QCheckBox("show edit region")
        self.regions.setToolTip("Where the shading changed (the band near the stroke) and where heights may change (its ring)")
        form.addRow(self.preview)
        form.addRow(self.strips)
        form.addRow(self.regions)
        self.status = QLabel()
        self.status.setWordWrap(True)
        self.status.setMinimumHeight(48)
        self.status.setAlignment(Qt.AlignmentFlag.AlignTop)
        form.addRow(self.status)
        self._updating = False
        self.slider.valueChanged.connect(lambda v: self._emit(self._from_slider(v)))
        self.spin.valueChanged.connect(self._emit)
        self.strips.toggled.connect(lambda _: self.show_changed.emit(self.strips.isChecked(), self.regions.isChecked()))
        self.regions.toggled.connect(lambda _: self.show_changed.emit(self.strips.isChecked(), self.regions.isChecked()))
        self.preview.toggled.connect(self.preview_changed.emit)

    def set_tools(self, entries, current: str | None = None, icons: dict | None = None) -> None:
        """The palette: ``entries`` = [(name, label, shortcut)]; ``icons`` {name: QIcon} for
        tools that bring one (the others get their label's letter)."""
        self.tool.blockSignals(True)
        self.tool.clear()
        for name, label, shortcut in entries:
            icon = (icons or {}).get(name) or letter_icon(label)
            self.tool.addItem(icon, f"{label} ({shortcut})" if shortcut else label, name)
        if current is not None:
            i = self.tool.findData(current)
            if i >= 0:
                self.tool.setCurrentIndex(i)
        self.tool.blockSignals(False)

    def show_tool(self, name: str) -> None:
        i = self.tool.findData(name)
        if i >= 0 and i != self.tool.currentIndex():
            self.tool.blockSignals(True)
            self.tool.setCurrentIndex(i)
            self.tool.blockSignals(False)

    def _tool_chosen(self, index: int) -> None:
        name = self.tool.itemData(index)
        if name:
            self.tool_selected.emit(name)

    def set_models(self, names) -> None:
        self.model.blockSignals(True)
        self.model.clear()
        self.model.addItems(list(names) or ["lambertian"])
        self.model.setCurrentText("lambertian")
        self.model.blockSignals(False)

    @staticmethod
    def _from_slider(v: int) -> float:  # logarithmic: fine control of small bands
        return MIN_RADIUS * (MAX_RADIUS / MIN_RADIUS) ** (v / _STEPS)

    @staticmethod
    def _to_slider(r: float) -> int:
        return round(_STEPS * math.log(r / MIN_RADIUS) / math.log(MAX_RADIUS / MIN_RADIUS))

    def _emit(self, r: float) -> None:
        if not self._updating:
            self.radius_changed.emit(float(r))

    def show_state(self, controller) -> None:
        self._updating = True
        try:
            self.slider.setValue(self._to_slider(controller.radius))
            self.spin.setValue(controller.radius)
            self.status.setText(controller.status)
            self.setEnabled(True)
            self.tool.setEnabled(self.tool.count() > 0)
            self.show_tool(controller.tool_name)
            # Radius and reflectance belong to a picking tool (the isophote tool).
            plain = controller.available() and not controller.picking
            self.model.setEnabled(controller.available() and not plain)
            self.slider.setEnabled(not plain)
            self.spin.setEnabled(not plain)
        finally:
            self._updating = False
