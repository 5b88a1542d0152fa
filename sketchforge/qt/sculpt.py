"""The SCULPTURE state's interaction (thesis figure 4.3), driving the isophote tool plugin.

Click: pick the isophote under the mouse on the front-most visible layer there (white), and
show the band around it (orange, dashed). Wheel or the panel's slider: band radius. Drag: the
redrawn isophote (cyan). Release: a ``sculpt_isophote`` command is built from (layer, pick,
band radius, stroke), prepared off the GUI thread (progress + cancel in the status bar) and
pushed. Drawing again after an attempt replaces it: the attempt is undone first, and redone if
the new one fails. An edit that changes nothing reports the plugin's reason.

The preview (isophote and band) uses the geometry core's own functions; the edit itself is
entirely the plugin's command. Without the plugin, picking still previews and the panel says
the tool is not installed.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QObject, Signal

from sketchforge.errors import SketchforgeError
from sketchforge.geometry.band import band as make_band
from sketchforge.geometry.intensity import vertex_intensity
from sketchforge.geometry.isophotes import isophotes, isovalue_at, select_isophote
from sketchforge.qt.render2d import polygon_rings

COMMAND_NAME = "sculpt_isophote"
PLUGIN_MISSING = "isophote tool plugin not installed: picking previews the band, but strokes cannot be applied"
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
        self.options: dict = {}  # extra command fields from the panel (the reflectance model)
        self.status = ""
        self.layer_id: str | None = None
        self.pick_point: np.ndarray | None = None
        self.isovalue: float | None = None
        self._isophote: np.ndarray | None = None
        self._stroke: list[np.ndarray] = []
        self._last_attempt = None
        self.last_info: dict = {}

    # --- availability -----------------------------------------------------------------------
    def command_class(self):
        try:
            return self.host.command_class(COMMAND_NAME)
        except SketchforgeError:
            return None

    def available(self) -> bool:
        return self.command_class() is not None

    # --- state ------------------------------------------------------------------------------------
    def reset(self) -> None:
        self.layer_id = None
        self.pick_point = None
        self.isovalue = None
        self._isophote = None
        self._stroke = []
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
        self.radius = r
        self._update_band()
        self.changed.emit()

    def wheel(self, delta: int) -> bool:
        """The mouse wheel changes the band radius once an isophote is picked."""
        if self._isophote is None:
            return False
        self.set_radius(self.radius * 1.1 ** (delta / 120.0))
        return True

    # --- pick ---------------------------------------------------------------------------------
    def pick(self, point) -> bool:
        point = np.asarray(point, dtype=np.float64)
        light = self.doc.light.direction
        for layer in reversed(self.doc.layers):  # front-most first
            mesh = layer.mesh
            if not layer.visible or mesh is None or mesh.n_faces == 0:
                continue
            E = vertex_intensity(mesh.V, mesh.F, light)
            try:
                c = isovalue_at(mesh, E, point)
            except SketchforgeError:
                continue  # not on this layer
            try:
                lines, _ = isophotes(mesh.V[:, :2], mesh.F, E, c)
                line = lines[select_isophote(lines, point)]
            except SketchforgeError as exc:
                self.message.emit(str(exc))
                self._set_status(str(exc))
                return False
            self.layer_id, self.pick_point, self.isovalue, self._isophote = layer.id, point, c, line
            self._stroke = []
            self._last_attempt = None
            self.canvas.set_overlay("isophote", [line])
            self.canvas.set_overlay("stroke", [])
            self.canvas.set_overlay("strips", [])
            self.canvas.set_overlay("regions", [])
            self._update_band()
            self.layer_picked.emit(layer.id)
            if self.available():
                self._set_status(f"isophote n·l = {c:.3f} on {layer.name}: draw its new course inside the band")
            else:
                self._set_status(PLUGIN_MISSING)
            return True
        self.message.emit("the pick is not on a visible shape: click on a shape to choose an isophote")
        return False

    def _update_band(self) -> None:
        if self._isophote is None or self.layer_id not in self.doc.layer_ids():
            self.canvas.set_overlay("band", [])
            return
        mesh = self.doc.layer(self.layer_id).mesh
        try:
            geom = make_band(self._isophote, self.radius, mesh.V[mesh.boundary, :2])
        except SketchforgeError as exc:
            self.message.emit(str(exc))
            self.canvas.set_overlay("band", [])
            return
        self.canvas.set_overlay("band", polygon_rings(geom))

    # --- stroke -------------------------------------------------------------------------------
    def stroke_press(self, pos) -> None:
        self._stroke = [np.asarray(pos, dtype=np.float64)]
        self.canvas.set_overlay("stroke", [np.array(self._stroke)])

    def _add(self, pos) -> None:
        p = np.asarray(pos, dtype=np.float64)
        if not self._stroke or not np.array_equal(p, self._stroke[-1]):  # the release repeats the last move
            self._stroke.append(p)

    def stroke_move(self, pos) -> None:
        if self._stroke:
            self._add(pos)
            self.canvas.set_overlay("stroke", [np.array(self._stroke)])

    def cancel(self) -> None:
        self._stroke = []
        self.canvas.set_overlay("stroke", [])

    def stroke_release(self, pos) -> None:
        if not self._stroke:
            return
        self._add(pos)
        stroke = np.array(self._stroke)
        self.canvas.set_overlay("stroke", [stroke])
        if self.pick_point is None or self.layer_id not in self.doc.layer_ids():
            self.message.emit("pick an isophote first (click on the shape), then redraw it")
            return
        cls = self.command_class()
        if cls is None:
            self.message.emit(PLUGIN_MISSING)
            self._set_status(PLUGIN_MISSING)
            return
        try:
            cmd = cls.from_dict(self.command_dict(stroke))
        except SketchforgeError as exc:
            self._fail(exc)
            return
        self.apply(cmd)

    def command_dict(self, stroke) -> dict:
        """The journal entry of an edit: what replay needs (the light is the document's)."""
        d = {
            "command": COMMAND_NAME,
            "layer": self.layer_id,
            "pick": [float(v) for v in self.pick_point],
            "band": float(self.radius),
            "stroke": np.asarray(stroke, dtype=np.float64).tolist(),
        }
        d.update(self.options)
        return d

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
