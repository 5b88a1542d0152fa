"""Drag the light: the segment from a centre to the mouse gives the light's direction in the
drawing plane (thesis 4.1). The light keeps the elevation it had when the drag started (an
in-plane light stays in the plane, as in the thesis; one raised in the Light panel stays
raised and turns about the view axis). One drag is one undo step (its SetLight commands
share a gesture id)."""

from __future__ import annotations

import numpy as np

from sketchforge.document.commands import SetLight, new_gesture_id
from sketchforge.document.layer import Light
from sketchforge.errors import ParameterError
from sketchforge.tools.base import Tool

#: Said when a drag cannot turn the light: straight overhead it has no direction in the plane.
OVERHEAD = ("the light is straight overhead: a drag in the drawing turns its direction in the plane, which it "
            "does not have; lower it in the Light panel first")


class LightTool(Tool):
    name = "light"
    label = "Light"

    def __init__(self, doc, center=(0.0, 0.0)) -> None:
        super().__init__(doc)
        self.center = self.as_point(center)
        self._gesture: int | None = None
        self._elevation = 0.0
        self.message = ""

    def _apply(self, pos) -> None:
        if self._elevation >= 90.0:
            return  # overhead: nothing to turn (the message says so), and no empty undo step
        try:
            light = Light.from_drag(self.center, self.as_point(pos), self._elevation)
        except ParameterError:
            return  # the mouse is on the centre: no direction yet, keep the current light
        self.doc.push(SetLight(direction=light.to_list(), gesture=self._gesture))
        self.overlay = {"light_segment": np.array([self.center, self.as_point(pos)])}

    def press(self, pos) -> None:
        self._gesture = new_gesture_id()
        light = self.doc.light
        self._elevation = 0.0 if light.in_plane else light.elevation
        self.message = OVERHEAD if self._elevation >= 90.0 else ""
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
