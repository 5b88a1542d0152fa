"""The left menu (thesis figure 4.1): modes EDITING / OBSERVATION, and in EDITING the states
CREATION / SCULPTURE plus the light button; in OBSERVATION the assembled / per-layer toggle."""

from __future__ import annotations

from PySide6.QtCore import Signal
from PySide6.QtWidgets import QButtonGroup, QComboBox, QFrame, QLabel, QPushButton, QRadioButton, QVBoxLayout


class ModePanel(QFrame):
    #: "editing" or "observation"
    mode_changed = Signal(str)
    #: "creation" or "sculpture"
    state_changed = Signal(str)
    #: the light button (figure 4.2) was toggled
    light_toggled = Signal(bool)
    #: observation shows the "assembled" model or each "layers" mesh
    observe_changed = Signal(str)
    #: the 3D view's display style: "shaded", "cel" or "isophotes"
    display3d_changed = Signal(str)
    fit_requested = Signal()

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.setObjectName("ModePanel")
        self.setFrameShape(QFrame.Shape.StyledPanel)
        self.setFixedWidth(150)
        lay = QVBoxLayout(self)
        title = QLabel("<b>sketchforge</b>")
        lay.addWidget(title)

        self.editing = QRadioButton("EDITING")
        self.observation = QRadioButton("OBSERVATION")
        self._modes = QButtonGroup(self)
        for b in (self.editing, self.observation):
            self._modes.addButton(b)
        self.editing.setChecked(True)

        self.creation = QRadioButton("CREATION")
        self.sculpture = QRadioButton("SCULPTURE")
        self._states = QButtonGroup(self)
        for b in (self.creation, self.sculpture):
            self._states.addButton(b)
            b.setStyleSheet("margin-left: 16px")
        self.creation.setChecked(True)

        self.light = QPushButton("☀ Light")
        self.light.setCheckable(True)
        self.light.setToolTip("Drag in the drawing region to turn the light (L)")
        self.light.setStyleSheet("margin-left: 16px")

        self.assembled = QRadioButton("Assembled")
        self.per_layer = QRadioButton("Per layer")
        self._observe = QButtonGroup(self)
        for b in (self.assembled, self.per_layer):
            self._observe.addButton(b)
            b.setStyleSheet("margin-left: 16px")
        self.assembled.setChecked(True)

        self.display3d = QComboBox()
        self.display3d.addItems(["shaded", "cel", "isophotes"])
        self.display3d.setToolTip("3D display: smooth shading, the light's cel tones, or its isophote lines")
        self.display3d.setStyleSheet("margin-left: 16px")

        self.fit = QPushButton("Fit view")

        lay.addWidget(self.editing)
        lay.addWidget(self.creation)
        lay.addWidget(self.sculpture)
        lay.addWidget(self.light)
        lay.addSpacing(12)
        lay.addWidget(self.observation)
        lay.addWidget(self.assembled)
        lay.addWidget(self.per_layer)
        lay.addWidget(self.display3d)
        lay.addStretch(1)
        lay.addWidget(self.fit)

        self.editing.toggled.connect(lambda on: on and self._mode("editing"))
        self.observation.toggled.connect(lambda on: on and self._mode("observation"))
        self.creation.toggled.connect(lambda on: on and self.state_changed.emit("creation"))
        self.sculpture.toggled.connect(lambda on: on and self.state_changed.emit("sculpture"))
        self.light.toggled.connect(self.light_toggled.emit)
        self.assembled.toggled.connect(lambda on: on and self.observe_changed.emit("assembled"))
        self.per_layer.toggled.connect(lambda on: on and self.observe_changed.emit("layers"))
        self.display3d.currentTextChanged.connect(self.display3d_changed.emit)
        self.fit.clicked.connect(self.fit_requested.emit)
        self._enable("editing")

    def _mode(self, mode: str) -> None:
        self._enable(mode)
        self.mode_changed.emit(mode)

    def _enable(self, mode: str) -> None:
        editing = mode == "editing"
        for w in (self.creation, self.sculpture, self.light):
            w.setEnabled(editing)
        for w in (self.assembled, self.per_layer, self.display3d):
            w.setEnabled(not editing)
