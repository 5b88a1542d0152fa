"""Drag the light: the segment from a centre to the mouse gives the in-plane direction
(thesis 4.1). One drag is one undo step (its SetLight commands share a gesture id)."""

from __future__ import annotations

import numpy as np

from sketchforge.document.commands import SetLight, new_gesture_id
from sketchforge.document.layer import Light
from sketchforge.errors import ParameterError
from sketchforge.tools.base import Tool


class LightTool(Tool):
    name = "light"
    label = "Light"

    def __init__(self, doc, center=(0.0, 0.0)) -> None:
        super().__init__(doc)
        self.center = self.as_point(center)
        self._gesture: int | None = None

    def _apply(self, pos) -> None:
        try:
            light = Light.from_drag(self.center, self.as_point(pos))
        except ParameterError:
            return  # the mouse is on the centre: no direction yet, keep the current light
        self.doc.push(SetLight(direction=[light.x, light.y, 0.0], gesture=self._gesture))
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
