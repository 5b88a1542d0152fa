"""The main window's light control: the light panel's typed angle and elevation and its disc's
drags, each a ``set_light`` (one drag is one undo step)."""

from __future__ import annotations

from sketchforge.document import commands as C
from sketchforge.document.layer import Light


class LightControl:
    """Turns the light panel's edits into ``set_light`` commands on the window's (``win``)
    document."""

    def __init__(self, win) -> None:
        self.win = win

    def _on_light(self, light) -> None:
        self.win.light_panel.show_light(light)
        self.win._thumbnail_timer.start()

    def _azimuth(self) -> float:
        """The light's azimuth; straight overhead (which has none), the one the panel shows."""
        light = self.win.doc.light
        return self.win.light_panel.angle.value() if light.elevation >= 90.0 else light.angle

    def set_light_angle(self, degrees: float) -> None:
        """A typed azimuth: the light turns about the view axis, keeping its elevation."""
        light = Light.from_angle(degrees, 0.0 if self.win.doc.light.in_plane else self.win.doc.light.elevation)
        if light != self.win.doc.light:
            self.win.push(C.SetLight(direction=light.to_list()))

    def set_light_elevation(self, degrees: float) -> None:
        """A typed elevation (0: in the drawing plane, 90: overhead), keeping the azimuth."""
        light = Light.from_angle(self.win._azimuth(), degrees)
        if light != self.win.doc.light:
            self.win.push(C.SetLight(direction=light.to_list()))

    def _light_drag_started(self) -> None:
        self.win._light_gesture = C.new_gesture_id()

    def _light_dragged(self, light) -> None:
        """A step of a drag on the light disc: commands of one drag share a gesture id, so the
        drag is one undo step."""
        gesture = getattr(self.win, "_light_gesture", None)
        if gesture is not None and light != self.win.doc.light:
            if not self.win.push(C.SetLight(direction=light.to_list(), gesture=gesture)):
                self.win._light_gesture = None  # refused (a solve runs): the rest of the drag too
                self.win.light_panel.show_light(self.win.doc.light)

    def _light_drag_ended(self) -> None:
        self.win._light_gesture = None
