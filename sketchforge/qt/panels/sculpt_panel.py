"""SCULPTURE controls: the tool, the band radius (slider, or the mouse wheel in the drawing),
the live preview, what to show (characteristics, the edit region) and what the last edit said."""

from __future__ import annotations

import math

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QGroupBox, QLabel, QSlider

from sketchforge.qt.sculpt import MAX_RADIUS, MIN_RADIUS

_STEPS = 1000


class SculptPanel(QGroupBox):
    radius_changed = Signal(float)
    model_changed = Signal(str)
    show_changed = Signal(bool, bool)  # characteristics, edit region
    preview_changed = Signal(bool)

    def __init__(self, parent=None) -> None:
        super().__init__("Sculpture", parent)
        form = QFormLayout(self)
        self.tool = QComboBox()
        self.tool.addItem("Redraw isophote")
        self.tool.setToolTip("Sculpt tools from plugins (thesis 4.1: one tool so far)")
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
            self.tool.setEnabled(controller.available())
            self.model.setEnabled(controller.available())
        finally:
            self._updating = False
