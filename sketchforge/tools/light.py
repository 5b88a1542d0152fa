"""Drag the light: the segment from a centre to the mouse gives the light's direction in the
drawing plane (thesis 4.1). The light keeps the elevation it had when the drag started (an
in-plane light stays in the plane, as in the thesis; one raised in the Light panel stays
raised and turns about the view axis). One drag is one undo step (its SetLight commands
share a gesture id)."""

from __future__ import annotations

import math

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


# --- the Light panel's sky disc ------------------------------------------------------------------
# The hemisphere of directions facing the viewer drawn as a disc (an azimuthal equidistant
# chart, as a sun-direction control): the centre is straight overhead, the rim the drawing
# plane, the radius falls linearly with the elevation (so every 10 degrees take the same
# width, the low lights of the thesis included), the angle is the azimuth (x right, y up).


def disc_point(light: Light) -> np.ndarray:
    """(2,) float64: where ``light`` lies on the unit sky disc (radius 1 − elevation/90)."""
    r = 1.0 - light.elevation / 90.0
    if r == 0.0:
        return np.zeros(2)
    a = math.radians(light.angle)
    return np.array([r * math.cos(a), r * math.sin(a)])


def light_at_disc(point) -> Light:
    """The light at a point (2,) of the unit sky disc (the inverse of :func:`disc_point`); a
    point on or outside the rim is a light in the drawing plane (exactly z = 0), the centre
    straight overhead. Raises ParameterError for a point that is not finite."""
    p = np.asarray(point, dtype=np.float64).reshape(-1)
    if p.shape != (2,) or not np.all(np.isfinite(p)):
        raise ParameterError("a point on the light disc needs two finite coordinates")
    r = math.hypot(p[0], p[1])
    if r == 0.0:
        return Light(0.0, 0.0, 1.0)
    azimuth = math.degrees(math.atan2(p[1], p[0]))
    return Light.from_angle(azimuth, 90.0 * max(0.0, 1.0 - r))


def dome_shading(size: int, light: Light) -> np.ndarray:
    """(size, size) float64: the sky disc as a lit dome for the panel's picture: at each pixel
    the direction the disc maps there, shaded by ``light`` (n·l, clamped at 0; brightest at
    the light itself); NaN outside the disc. Row 0 is the top (y up)."""
    t = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    X, Y = np.meshgrid(t, -t)
    R = np.hypot(X, Y)
    el = np.radians(90.0 * np.clip(1.0 - R, 0.0, 1.0))
    az = np.arctan2(Y, X)
    N = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=-1)
    out = np.maximum(N @ light.direction, 0.0)
    out[R > 1.0] = np.nan
    return out
