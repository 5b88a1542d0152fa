"""The Animation panel (OBSERVATION): Pins toggle, Record, Play/Pause, the timeline with the
frame number, and the selected pin's actions."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QHBoxLayout, QLabel, QPushButton, QSlider, QVBoxLayout, QWidget

from ..state import FPS
from .controller import AnimationController


class AnimationPanel(QWidget):
    """Pins toggle, Record, Play/Pause, the timeline with the frame number, pin actions."""

    def __init__(self, controller: AnimationController, parent=None) -> None:
        super().__init__(parent)
        self.c = controller
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 8, 0, 0)
        lay.addWidget(QLabel("<b>Animation</b>"))
        row = QHBoxLayout()
        self.pins = QPushButton("Pins")
        self.pins.setCheckable(True)
        self.pins.setToolTip("Click the model to add a pin, drag a pin to pose (Shift: record)")
        self.record = QPushButton("Record")
        self.record.setCheckable(True)
        self.play = QPushButton("Play")
        self.play.setCheckable(True)
        for b in (self.pins, self.record, self.play):
            row.addWidget(b)
        lay.addLayout(row)
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.frame_label = QLabel("")
        lay.addWidget(self.slider)
        lay.addWidget(self.frame_label)
        row2 = QHBoxLayout()
        self.hold = QPushButton("Pin in place")
        self.remove = QPushButton("Remove")
        self.copy = QPushButton("Copy motion")
        self.paste = QPushButton("Paste")
        for b in (self.hold, self.remove, self.copy, self.paste):
            row2.addWidget(b)
        lay.addLayout(row2)
        self.record.toggled.connect(lambda on: setattr(self.c, "recording", on))
        self.play.toggled.connect(self.c.set_playing)
        self.slider.valueChanged.connect(lambda v: self.c.set_frame(v) if v != self.c.frame else None)
        self.hold.clicked.connect(self.c.hold_selected)
        self.remove.clicked.connect(self.c.remove_selected)
        self.copy.clicked.connect(self.c.copy_motion)
        self.paste.clicked.connect(self.c.paste_motion)
        self.c.changed.connect(self.sync)
        self.sync()

    def sync(self) -> None:
        loop = self.c.loop
        self.slider.blockSignals(True)
        self.slider.setRange(0, max(0, loop - 1))
        self.slider.setValue(self.c.frame)
        self.slider.setEnabled(loop > 1)
        self.slider.blockSignals(False)
        self.play.blockSignals(True)
        self.play.setChecked(self.c.playing)
        self.play.setText("Pause" if self.c.playing else "Play")
        self.play.blockSignals(False)
        n = len(self.c.animation().pins)
        sel = f", selected {self.c.selected}" if self.c.selected else ""
        if loop:
            self.frame_label.setText(f"frame {self.c.frame} / {loop} ({loop / FPS:.2f} s at {FPS} fps), {n} pins{sel}")
        else:
            self.frame_label.setText(f"no motion recorded, {n} pins{sel}")
        for b in (self.hold, self.remove, self.copy):
            b.setEnabled(self.c.selected is not None)
        self.paste.setEnabled(self.c.selected is not None and self.c.clipboard is not None)
