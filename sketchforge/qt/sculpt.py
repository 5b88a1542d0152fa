"""The SCULPTURE state's interaction (thesis figure 4.3), driving the isophote tool plugin.

Click: pick the isophote under the mouse on the front-most visible layer there (white), and
show the band around it (orange, dashed). Wheel or the panel's slider: band radius. Drag: the
redrawn isophote (cyan). Release: a ``sculpt_isophote`` command is built from (layer, pick,
band radius, stroke), prepared off the GUI thread (progress + cancel in the status bar) and
pushed. Drawing again after an attempt replaces it: the attempt is undone first, and redone if
the new one fails. An edit that changes nothing reports the plugin's reason.

The gesture's logic (pick, isophote, band, options, building the command) is the plugin's
``SculptIsophoteTool`` (``host.tools["sculpt_isophote"]``); this controller only draws its
``overlay`` on the canvas, runs the command on a worker thread, replaces the last attempt and
reports status. Without the plugin the panel says the tool is not installed.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QObject, Signal

from sketchforge.errors import SketchforgeError
from sketchforge.qt.render2d import polygon_rings

TOOL_NAME = "sculpt_isophote"
PLUGIN_MISSING = "isophote tool plugin not installed: isophotes cannot be picked or redrawn"
#: Band radius limits, drawing units.
MIN_RADIUS, MAX_RADIUS = 0.005, 2.0


class SculptController(QObject):
    #: anything the panel shows changed (radius, status text, availability)
    changed = Signal()
    #: a layer was picked (the window selects it in the layers panel)
    layer_picked = Signal(str)
    message = Signal(str)

    def __init__(self, doc, host, canvas, runner) -> None:
        super().__init__()
        self.doc, self.host, self.canvas, self.runner = doc, host, canvas, runner
        self.radius = 0.15
        self.show_strips = False
        self.show_regions = False
        self.status = ""
        self._last_attempt = None
        self.last_info: dict = {}
        self.tool = self._make_tool()

    def _make_tool(self):
        try:
            cls = (getattr(self.host, "tools", None) or {}).get(TOOL_NAME)
        except SketchforgeError:
            cls = None
        return None if cls is None else cls(self.doc, band=self.radius)

    # --- availability -----------------------------------------------------------------------
    def available(self) -> bool:
        return self.tool is not None

    # --- the tool's state, for the panel, the window and tests ---------------------------------
    @property
    def layer_id(self) -> str | None:
        return None if self.tool is None else self.tool.layer_id

    @property
    def pick_point(self) -> np.ndarray | None:
        return None if self.tool is None else self.tool.pick

    @property
    def _isophote(self) -> np.ndarray | None:
        return None if self.tool is None else self.tool.isophote

    def set_options(self, options: dict) -> None:
        """Extra command fields from the panel (the reflectance model); re-shows the pick."""
        if self.tool is None:
            return
        try:
            self.tool.set_options(options)
        except SketchforgeError as exc:
            self._fail(exc)
            return
        self._show_pick()

    # --- state ------------------------------------------------------------------------------------
    def reset(self) -> None:
        if self.tool is not None:
            self.tool.reset()
        self._last_attempt = None
        self.last_info = {}
        for name in ("isophote", "band", "stroke", "strips", "regions"):
            self.canvas.set_overlay(name, [])
        self._set_status("click on a shape to pick an isophote" if self.available() else PLUGIN_MISSING)

    def _set_status(self, text: str) -> None:
        self.status = text
        self.changed.emit()

    def set_radius(self, radius: float) -> None:
        r = float(np.clip(radius, MIN_RADIUS, MAX_RADIUS))
        if r == self.radius:
            return
        if self.tool is not None and not self.tool.set_band(r):
            self.message.emit(self.tool.message)
            return
        self.radius = r
        self._show_band()
        self.changed.emit()

    def wheel(self, delta: int) -> bool:
        """The mouse wheel changes the band radius once an isophote is picked."""
        if self.pick_point is None:
            return False
        self.set_radius(self.radius * 1.1 ** (delta / 120.0))
        return True

    # --- overlays from the tool ---------------------------------------------------------------
    def _show_band(self) -> None:
        ov = {} if self.tool is None else self.tool.overlay
        self.canvas.set_overlay("band", list(ov.get("band", [])))

    def _show_pick(self) -> None:
        ov = {} if self.tool is None else self.tool.overlay
        iso = ov.get("isophote")
        self.canvas.set_overlay("isophote", [] if iso is None else [iso])
        self._show_band()

    def _show_stroke(self) -> None:
        stroke = None if self.tool is None else self.tool.overlay.get("stroke")
        self.canvas.set_overlay("stroke", [] if stroke is None else [stroke])

    # --- pick ---------------------------------------------------------------------------------
    def pick(self, point) -> bool:
        if self.tool is None:
            self.message.emit(PLUGIN_MISSING)
            self._set_status(PLUGIN_MISSING)
            return False
        self._last_attempt = None
        self.last_info = {}
        for name in ("stroke", "strips", "regions"):
            self.canvas.set_overlay(name, [])
        ok = self.tool.pick_at(point)
        self._show_pick()
        if not ok:
            self.message.emit(self.tool.message)
            self._set_status(self.tool.message)
            return False
        if self.tool.message:  # the band could not be made
            self.message.emit(self.tool.message)
        layer = self.doc.layer(self.tool.layer_id)
        self.layer_picked.emit(layer.id)
        self._set_status(f"isophote n·l = {self.tool.isovalue:.3f} on {layer.name}: draw its new course inside the band")
        return True

    # --- stroke -------------------------------------------------------------------------------
    def stroke_press(self, pos) -> None:
        if self.tool is not None:
            self.tool.press(pos)
            self._show_stroke()

    def stroke_move(self, pos) -> None:
        if self.tool is not None:
            self.tool.move(pos)
            self._show_stroke()

    def cancel(self) -> None:
        if self.tool is not None:
            self.tool.cancel()
        self.canvas.set_overlay("stroke", [])

    def stroke_release(self, pos) -> None:
        if self.tool is None:
            self.message.emit(PLUGIN_MISSING)
            self._set_status(PLUGIN_MISSING)
            return
        stroke = self.tool.end_stroke(pos)
        if not len(stroke):
            return
        self._show_stroke()
        try:
            cmd = self.tool.command_for(stroke)
        except SketchforgeError as exc:
            self._fail(exc)
            return
        self.apply(cmd)

    def apply(self, cmd) -> None:
        """Replace the last attempt (if it is still on top of the history) with ``cmd``."""
        stack = self.doc.undo_stack
        replaced = None
        if (
            self._last_attempt is not None
            and stack.index > 0
            and stack.command(stack.index - 1) is self._last_attempt
        ):
            replaced = self._last_attempt
            stack.undo()

        def restore(exc=None):
            if replaced is not None and stack.can_redo() and stack.command(stack.index) is replaced:
                stack.redo()
            return False

        def on_error(exc):
            restore()
            self._fail(exc)
            return True  # handled: a gesture's error goes to the panel and status bar

        def on_done(done_cmd):
            self._last_attempt = done_cmd
            self.last_info = result_info(done_cmd)
            self._show_debug()
            self._set_status("applied; draw again to replace this attempt, or click to pick another isophote")

        self._set_status("sculpting…")
        started = self.runner.run(
            cmd, label="Sculpting", on_done=on_done, on_error=on_error, on_cancel=lambda: (restore(), self._set_status("cancelled"))
        )
        if not started:
            restore()
            self.message.emit("a solve is already running")

    def _fail(self, exc) -> None:
        self._set_status(str(exc))
        self.message.emit(str(exc))

    def set_show(self, strips: bool | None = None, regions: bool | None = None) -> None:
        if strips is not None:
            self.show_strips = strips
        if regions is not None:
            self.show_regions = regions
        self._show_debug()

    def _show_debug(self) -> None:
        """Strips and regions of the last edit, from the plugin command's ``result`` (a
        SculptResult: ``result.strips`` characteristic strips (j, 5) with x, y first;
        ``result.regions`` with region ``strips`` and the shapely regions ``M`` (impacted,
        thesis M•) and ``B_star`` (B•*))."""
        info = self.last_info
        strips: list = []
        rings: list = []
        if self.show_strips:
            strips.extend(np.asarray(s)[:, :2] for s in info.get("strips", []) if len(s) > 1)
        if self.show_regions:
            for geom in info.get("regions", []):
                rings.extend(polygon_rings(geom) if hasattr(geom, "geom_type") else [np.asarray(geom)])
        self.canvas.set_overlay("strips", strips)
        self.canvas.set_overlay("regions", rings)


def result_info(cmd) -> dict:
    """What the canvas can show of a finished sculpt command (empty if it reports nothing)."""
    result = getattr(cmd, "result", None)
    if result is None:
        return {}
    regions = getattr(result, "regions", None)
    strips = list(getattr(regions, "strips", []) or []) + list(getattr(result, "strips", []) or [])
    shapes = [g for g in (getattr(regions, "M", None), getattr(regions, "B_star", None)) if g is not None]
    return {"strips": strips, "regions": shapes}
