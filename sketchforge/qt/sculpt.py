"""The SCULPTURE state's interaction (thesis figure 4.3), driving the isophote tool plugin.

Click: pick the isophote under the mouse on the front-most visible layer there (white), and
show the band around it (orange, dashed). Wheel or the panel's slider: band radius. Drag: the
redrawn isophote (cyan). While the stroke is drawn, a live
preview of the edit is computed off the GUI thread (one at a time, always for the latest
stroke: throttled by the solve itself, ~50 ms at 5k vertices) and the picked layer is shown
with the previewed surface; Esc or a new pick drops it. A preview starts from the surface the
release will edit (before the last attempt, when that is replaced), and one crash record
covers a whole gesture's previews (not one disk write per mouse move). Release: a ``sculpt_isophote`` command
is built from (layer, pick, band radius, stroke), prepared off the GUI thread (progress +
cancel in the status bar) and pushed. Drawing again after an attempt replaces it: the attempt
is undone first, and redone if the new one fails. An edit that changes nothing reports the
plugin's reason.

The gesture's logic (pick, isophote, band, options, building the command) is the plugin's
``SculptIsophoteTool`` (``host.tools["sculpt_isophote"]``); this controller only draws its
``overlay`` on the canvas, runs the command on a worker thread, replaces the last attempt and
reports status. Without the plugin the panel says the tool is not installed.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QObject, Signal

from sketchforge.errors import SketchforgeError
from sketchforge.qt.command_runner import end_guard
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
        self.live_preview = True
        self.status = ""
        self._last_attempt = None
        self.last_info: dict = {}
        self.tool = self._make_tool()
        self._preview_job = None  # the job in flight (never cancelled: its native code runs on)
        self._preview_pending = None  # the latest stroke, waiting for the job in flight
        self._preview_generation = 0  # bumped to drop results of a finished gesture
        # Previews run native solvers too: one crash record (runner.guard) per gesture, ended
        # when the gesture is over and its last preview job has returned.
        self._preview_token = None
        self._preview_open = False
        #: the last preview's SculptResult (for tests and the status line), None if none shown
        self.preview_result = None

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
        self.stop_preview()
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
        self.stop_preview()
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
            stroke = self.tool.overlay.get("stroke")
            if self.live_preview and self.tool.pick is not None and stroke is not None and len(stroke) >= 2:
                self._request_preview(np.array(stroke))

    def cancel(self) -> None:
        self.stop_preview()
        if self.tool is not None:
            self.tool.cancel()
        self.canvas.set_overlay("stroke", [])

    # --- live preview ---------------------------------------------------------------------------
    def set_preview(self, on: bool) -> None:
        self.live_preview = bool(on)
        if not on:
            self.stop_preview()

    def _base_mesh(self):
        """The surface a release will edit: before the last attempt when that is replaced."""
        stack = self.doc.undo_stack
        last = self._last_attempt
        if last is not None and stack.index > 0 and stack.command(stack.index - 1) is last:
            replaced = getattr(last, "replaced", None)
            if replaced is not None and replaced.id == self.tool.layer_id:
                return replaced.mesh
        return None

    def _request_preview(self, stroke: np.ndarray) -> None:
        """Compute the edit for ``stroke`` off the GUI thread; while one is computing, only the
        latest stroke waits (moves in between are skipped: the solve is the throttle)."""
        if self._preview_job is not None:
            self._preview_pending = stroke
            return
        try:
            job = self.tool.preview_job(stroke, self._base_mesh())
        except SketchforgeError:
            return
        if not self._preview_open:
            guard = getattr(self.runner, "guard", None)
            if self._preview_token is None and guard is not None:
                self._preview_token = guard.before(None, text="Sculpt preview")
            self._preview_open = True
        generation, layer_id = self._preview_generation, self.tool.layer_id

        def done(result) -> None:
            self._preview_job = None
            if generation == self._preview_generation:
                self.preview_result = result
                self.canvas.show_preview(layer_id, result.mesh)
                self._set_status(f"preview: {result.describe()} — release to apply")
            self._next_preview()

        def failed(exc, tb) -> None:
            self._preview_job = None
            if generation == self._preview_generation:
                self.canvas.clear_preview()
                self.preview_result = None
                # A SketchforgeError is the edit's own answer; anything else is a plugin bug,
                # said as such rather than leaving a stale preview on screen.
                text = str(exc) if isinstance(exc, SketchforgeError) else f"the preview failed ({exc!r}); see the log"
                self._set_status(f"preview: {text}")
                if not isinstance(exc, SketchforgeError):
                    self.message.emit(text)
            self._next_preview()

        self._preview_job = self.runner.jobs.start(job, done, failed, label="Sculpt preview", background=True)

    def _next_preview(self) -> None:
        stroke, self._preview_pending = self._preview_pending, None
        if stroke is not None and self.live_preview and self._preview_open:
            self._request_preview(stroke)
        elif self._preview_job is None and not self._preview_open:
            end_guard(getattr(self.runner, "guard", None), self._preview_token)
            self._preview_token = None

    def stop_preview(self) -> None:
        """Drop the preview: the layer is shown as it is, results still in flight are ignored,
        and the gesture's crash record ends once the job in flight has returned."""
        self._preview_generation += 1
        self._preview_pending = None
        self._preview_open = False
        self.preview_result = None
        self.canvas.clear_preview()
        if self._preview_job is None:
            self._next_preview()

    def stroke_release(self, pos) -> None:
        if self.tool is None:
            self.message.emit(PLUGIN_MISSING)
            self._set_status(PLUGIN_MISSING)
            return
        stroke = self.tool.end_stroke(pos)
        self.stop_preview()
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
        if self.runner.busy:
            self.message.emit("a solve is already running")
            return
        stack = self.doc.undo_stack
        guard = getattr(self.runner, "guard", None)
        # The crash guard records the state before this gesture, the last attempt included:
        # it must run before that attempt is undone.
        token = guard.before(cmd) if guard is not None else None
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
            r = getattr(done_cmd, "result", None)
            if r is not None and callable(getattr(r, "new_isophotes", None)):
                # The isophote as it now runs (white), over the stroke that asked for it (cyan).
                self.canvas.set_overlay("isophote", r.new_isophotes())
            moved = f"{r.describe()}; " if callable(getattr(r, "describe", None)) else ""
            self._set_status(f"applied: {moved}draw again to replace this attempt, or click to pick another isophote")

        self._set_status("sculpting…")
        started = self.runner.run(
            cmd,
            label="Sculpting",
            on_done=on_done,
            on_error=on_error,
            on_cancel=lambda: (restore(), self._set_status("cancelled")),
            guard_token=token,
        )
        if not started:
            end_guard(guard, token)
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
        """Characteristics and regions of the last edit, from the plugin command's ``result``
        (a SculptResult: ``characteristics()`` polylines through the stroke, traced on request;
        ``edit_zone`` where the shading changed and ``support`` where heights may change)."""
        info = self.last_info
        strips: list = []
        rings: list = []
        if self.show_strips and "characteristics" in info:
            if info.get("_lines") is None:
                info["_lines"] = info["characteristics"]()
            strips.extend(np.asarray(s)[:, :2] for s in info["_lines"] if len(s) > 1)
        if self.show_regions:
            for geom in info.get("regions", []):
                rings.extend(polygon_rings(geom) if hasattr(geom, "geom_type") else [np.asarray(geom)])
        self.canvas.set_overlay("strips", strips)
        self.canvas.set_overlay("regions", rings)


def result_info(cmd) -> dict:
    """What the canvas can show of a finished sculpt command (empty if it reports nothing):
    ``characteristics`` (a callable giving polylines) and ``regions`` (shapely geometries)."""
    result = getattr(cmd, "result", None)
    if result is None:
        return {}
    info: dict = {}
    if callable(getattr(result, "characteristics", None)):
        info["characteristics"] = result.characteristics
    shapes = [g for g in (getattr(result, "edit_zone", None), getattr(result, "support", None)) if g is not None]
    info["regions"] = shapes
    return info
