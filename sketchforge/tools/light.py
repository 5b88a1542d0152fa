"""Drag the light: the segment from a centre to the mouse gives the in-plane direction
(thesis 4.1). One drag is one undo step (its SetLight commands share a gesture id)."""

from __future__ import annotations

import numpy as np

from sketchforge.document.commands import SetLight, new_gesture_id
from sketchforge.tools.base import Tool

#: Drags shorter than this (document units) do not change the light: the direction of a
#: near-zero vector is noise.
MIN_DRAG = 1e-9


class LightTool(Tool):
    name = "light"
    label = "Light"

    def __init__(self, doc, center=(0.0, 0.0)) -> None:
        super().__init__(doc)
        self.center = self.as_point(center)
        self._gesture: int | None = None

    def _apply(self, pos) -> None:
        v = self.as_point(pos) - self.center
        if float(np.hypot(*v)) <= MIN_DRAG:
            return
        self.doc.push(SetLight(direction=[float(v[0]), float(v[1]), 0.0], gesture=self._gesture))
        self.overlay = {"light_segment": np.array([self.center, self.as_point(pos)])}

    def press(self, pos) -> None:
        self._gesture = new_gesture_id()
        self._apply(pos)

    def move(self, pos) -> None:
        if self._gesture is not None:
            self._apply(pos)

    def release(self, pos):
        if self._gesture is None:
            return None
        self._apply(pos)
        self._gesture = None
        self.overlay = {}
        return None
