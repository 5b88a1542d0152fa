"""The SCULPTURE state's interaction (thesis figure 4.3), driving the chosen tool plugin.

Click: pick the isophote under the mouse on the front-most visible layer there (white), and
show the band around it (orange, dashed). Wheel or the panel's slider: band radius. Drag: the
redrawn isophote (cyan). While the stroke is drawn, a live
preview of the edit is computed off the GUI thread (one at a time, always for the latest
stroke: throttled by the solve itself, ~50 ms at 5k vertices) and the picked layer is shown
with the previewed surface; Esc or a new pick drops it. A preview starts from the surface the
release will edit (before the last attempt, when that is replaced), and one crash record
covers a whole gesture's previews (not one disk write per mouse move). Release: the tool's command
is built from (layer, pick, band radius, stroke), prepared off the GUI thread (progress +
cancel in the status bar) and pushed. Drawing again after an attempt replaces it: the attempt
is undone first, and redone if the new one fails. An edit that changes nothing reports the
plugin's reason.

The gesture's logic (pick, isophote, band, options, building the command) is the tool
plugin's (the isophote tool's ``SculptIsophoteTool``); this controller only draws its
``overlay`` on the canvas, runs the command on a worker thread, replaces the last attempt and
reports status. The tool's own controls (model, solver, band radius...) are the plugin's
panel (``sketchforge_qt_panels``), which drives this controller. Without any tool plugin the
panel says so.

Any other registered tool (``host.tools``, chosen in the panel's tool palette or by its
shortcut) is driven through the same plumbing: press/move/release in document coordinates,
its ``overlay`` polylines drawn on the canvas, and the command its ``release`` pushes is
prepared on a worker thread (progress + cancel) and pushed on the GUI thread as one undo step
(:class:`DeferredPushDocument`). A tool that also has ``pick_at``/``command_for`` (a
"picking" tool, like the isophote tool) gets clicks as picks, the band radius, live previews
through ``preview_job`` and replace-the-last-attempt.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QObject, Signal

from sketchforge.errors import SketchforgeError
from sketchforge.qt.command_runner import end_guard
from sketchforge.qt.render2d import polygon_rings

PLUGIN_MISSING = "no sculpt tool is installed (no tool plugin): shapes cannot be sculpted here"
#: Band radius limits, drawing units.
MIN_RADIUS, MAX_RADIUS = 0.005, 2.0


class DeferredPushDocument:
    """The document as a plugin tool sees it in the app: every read goes to the document; the
    commands the tool pushes are collected instead, so the controller can prepare them on a
    worker (progress, cancel) and push them on the GUI thread as one undo step."""

    def __init__(self, doc) -> None:
        self._doc = doc
        self.pushed: list = []

    def __getattr__(self, name):
        return getattr(self._doc, name)

    def push(self, command):
        self.pushed.append(command)
        return command

    def execute(self, entry: dict):
        return self.push(self._doc.host.commands.from_dict(entry))

    def take(self) -> list:
        out, self.pushed = self.pushed, []
        return out


def is_picking_tool(tool) -> bool:
    """A tool with the isophote tool's richer protocol (click to pick, then stroke)."""
    return all(callable(getattr(tool, m, None)) for m in ("pick_at", "end_stroke", "command_for"))


def tool_shortcut(cls) -> str:
    return getattr(cls, "shortcut", "") or ""


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
        self._strokes_applied = False  # the strokes kept for several picks are what the last edit applied
        self.last_info: dict = {}
        self._options: dict = {}
        tools = self._tools()
        # The first picking tool is the default (the richer protocol is what SCULPTURE is
        # laid out for: pick, band, redraw); else the first tool; None without any.
        picking = [name for name, cls in tools.items() if is_picking_tool(cls)]
        self.tool_name = (picking or list(tools) or [None])[0]
        self._proxy = None
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

    def _tools(self) -> dict:
        try:
            return dict(getattr(self.host, "tools", None) or {})
        except SketchforgeError:
            return {}

    def tool_entries(self) -> list[tuple[str, str, str]]:
        """(name, label, shortcut) of every registered tool, for the palette."""
        return [(name, getattr(cls, "label", "") or name, tool_shortcut(cls)) for name, cls in self._tools().items()]

    def _make_tool(self):
        cls = self._tools().get(self.tool_name)
        self._proxy = None
        if cls is None:
            return None
        if all(callable(getattr(cls, m, None)) for m in ("pick_at", "end_stroke", "command_for")):
            tool = cls(self.doc, band=self.radius)
            if self._options and callable(getattr(tool, "set_options", None)):
                tool.set_options(self._options)
            return tool
        self._proxy = DeferredPushDocument(self.doc)
        return cls(self._proxy)

    def select_tool(self, name: str) -> bool:
        """Make ``name`` the active tool (the palette, a shortcut); False if it is unknown."""
        if name not in self._tools():
            self.message.emit(f"no tool {name!r} is installed")
            return False
        if name == self.tool_name and self.tool is not None:
            return True
        if self.tool is not None:
            self.cancel()
        self.tool_name = name
        try:
            self.tool = self._make_tool()
        except Exception as exc:  # noqa: BLE001 - a plugin's constructor
            who = getattr(self.host, "provider_of", lambda c: None)(self._tools().get(name))
            self.tool = None
            self._fail(SketchforgeError(f"tool {name!r} (plugin {who!r}) could not start: {type(exc).__name__}: {exc}"))
            return False
        self.reset()
        return True

    @property
    def picking(self) -> bool:
        return self.tool is not None and is_picking_tool(self.tool)

    # --- availability -----------------------------------------------------------------------
    def available(self) -> bool:
        return self.tool is not None

    # --- the tool's state, for the panel, the window and tests ---------------------------------
    @property
    def layer_id(self) -> str | None:
        return getattr(self.tool, "layer_id", None)

    @property
    def pick_point(self) -> np.ndarray | None:
        return getattr(self.tool, "pick", None) if self.picking else None

    @property
    def _isophote(self) -> np.ndarray | None:
        return getattr(self.tool, "isophote", None)

    def set_options(self, options: dict) -> None:
        """Extra command fields from the panel (the reflectance model); re-shows the pick."""
        if self.tool is None or not callable(getattr(self.tool, "set_options", None)):
            self._options = dict(options)  # for the picking tool, when it is chosen again
            return
        try:
            self.tool.set_options(options)
        except SketchforgeError as exc:
            self._fail(exc)
            return
        self._options = dict(options)
        self._show_pick()

    # --- state ------------------------------------------------------------------------------------
    def reset(self) -> None:
        self.stop_preview()
        if self.tool is not None:
            (getattr(self.tool, "reset", None) or self.tool.cancel)()
        self._last_attempt = None
        self._strokes_applied = False
        self.last_info = {}
        for name in ("isophote", "band", "stroke", "strips", "regions"):
            self.canvas.set_overlay(name, [])
        if not self.available():
            self._set_status(PLUGIN_MISSING)
        elif self.picking:
            self._set_status("click on a shape to pick an isophote")
        else:
            self._set_status(f"{self.tool_label()}: drag on the drawing")

    def tool_label(self) -> str:
        return (getattr(self.tool, "label", "") or self.tool_name) if self.tool is not None else ""

    def _set_status(self, text: str) -> None:
        self.status = text
        self.changed.emit()

    def set_radius(self, radius: float) -> None:
        r = float(np.clip(radius, MIN_RADIUS, MAX_RADIUS))
        if r == self.radius:
            return
        if self.picking and callable(getattr(self.tool, "set_band", None)) and not self.tool.set_band(r):
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
        ov = {} if not self.picking else self.tool.overlay
        self.canvas.set_overlay("band", list(ov.get("band", [])))

    def _show_pick(self) -> None:
        ov = {} if self.tool is None else self.tool.overlay
        iso = ov.get("isophote")
        # Several picked (Shift+click): every one of them, each with its band.
        self.canvas.set_overlay("isophote", list(ov.get("isophotes", [])) + ([] if iso is None else [iso]))
        self._show_band()

    def _show_stroke(self) -> None:
        if self.tool is not None and not self.picking:
            self.canvas.set_overlay("stroke", overlay_lines(self.tool.overlay))
            return
        ov = {} if self.tool is None else self.tool.overlay
        stroke = ov.get("stroke")
        # The strokes kept for the other picked isophotes, and the one being drawn.
        self.canvas.set_overlay("stroke", list(ov.get("strokes", [])) + ([] if stroke is None else [stroke]))

    @property
    def pick_count(self) -> int:
        """Isophotes picked for the next edit (several after Shift+clicks)."""
        return len(getattr(self.tool, "picks", None) or []) if self.picking else int(self.pick_point is not None)

    @property
    def strokes_to_apply(self) -> int:
        """Strokes drawn for several picked isophotes and not applied as they are: what Enter
        (or the panel's Apply) would apply; 0 right after the edit was applied."""
        return 0 if self._strokes_applied else self.strokes_drawn

    @property
    def strokes_drawn(self) -> int:
        """Of those, how many have a stroke kept (several picked: before the edit is applied)."""
        picks = (getattr(self.tool, "picks", None) or []) if self.picking else []
        return sum(getattr(p, "stroke", None) is not None for p in picks)

    # --- pick ---------------------------------------------------------------------------------
    def pick(self, point, add: bool = False) -> bool:
        """A click: pick the isophote there. ``add`` (Shift+click, with a tool that has
        ``add_pick_at``): pick another one of the same part while one is picked, each with its
        band; its stroke is drawn next, and the edit is applied when every picked isophote has
        one (or with Enter / the panel's Apply)."""
        if self.tool is None:
            self.message.emit(PLUGIN_MISSING)
            self._set_status(PLUGIN_MISSING)
            return False
        if not self.picking:  # a click is a press and release in place
            self._tool_call(self.tool.press, point)
            self.stroke_release(point)
            return True
        if add and self.pick_point is not None and callable(getattr(self.tool, "add_pick_at", None)):
            return self._add_pick(point)
        self.stop_preview()
        self._last_attempt = None
        self._strokes_applied = False
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
        self._set_status(f"isophote n·l = {self.tool.isovalue:.3f} on {layer.name}: draw its new course inside the band "
                         "(Shift+click picks another to redraw with it)")
        return True

    def _add_pick(self, point) -> bool:
        """Shift+click: one more isophote for the same edit. The last attempt (if any) stays:
        the next edit replaces it, with every picked isophote."""
        self.stop_preview()
        ok = self.tool.add_pick_at(point)
        self._show_pick()
        self._show_stroke()
        if not ok:
            self.message.emit(self.tool.message)
            self._set_status(self.tool.message)
            return False
        n = self.pick_count
        values = ", ".join(f"{p.isovalue:.3f}" for p in self.tool.picks)
        self._set_status(f"{n} isophotes picked (n·l = {values}): draw the new course of each inside its band; the edit "
                         "is applied when each has one, or press Enter")
        return True

    # --- stroke -------------------------------------------------------------------------------
    def _tool_call(self, fn, pos) -> bool:
        """A plugin tool's gesture method: its error goes to the status bar, naming the
        plugin when it is a bug rather than the tool's own answer."""
        try:
            fn(pos)
            return True
        except SketchforgeError as exc:
            self._fail(exc)
        except Exception as exc:  # noqa: BLE001 - foreign code must not end the gesture loop
            who = getattr(self.host, "provider_of", lambda c: None)(type(self.tool))
            self._fail(SketchforgeError(f"tool {self.tool_name!r} (plugin {who!r}) failed: {type(exc).__name__}: {exc}"))
        if self._proxy is not None:
            self._proxy.take()
        return False

    def stroke_press(self, pos) -> None:
        if self.tool is not None:
            self._tool_call(self.tool.press, pos)
            self._show_stroke()

    def stroke_move(self, pos) -> None:
        if self.tool is not None:
            self._tool_call(self.tool.move, pos)
            self._show_stroke()
            if not self.picking:
                return
            stroke = self.tool.overlay.get("stroke")
            if self.live_preview and self.tool.pick is not None and stroke is not None and len(stroke) >= 2:
                self._request_preview(np.array(stroke))

    def cancel(self) -> None:
        self.stop_preview()
        if self.tool is not None:
            try:
                self.tool.cancel()
            except Exception:  # noqa: BLE001 - Esc must always work
                self.tool.overlay = {}
        if self._proxy is not None:
            self._proxy.take()
        self.canvas.set_overlay("stroke", [])

    # --- live preview ---------------------------------------------------------------------------
    def set_preview(self, on: bool) -> None:
        self.live_preview = bool(on)
        if not on:
            self.stop_preview()
        self.changed.emit()

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
        if not callable(getattr(self.tool, "preview_job", None)):
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
                who = getattr(self.host, "provider_of", lambda c: None)(type(self.tool)) if self.tool is not None else None
                text = str(exc) if isinstance(exc, SketchforgeError) else f"the preview of plugin {who!r} failed ({exc!r}); see the log"
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
        if not self.picking:
            self._release_plain(pos)
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
        self._strokes_applied = False
        if cmd is None:  # several isophotes picked: the stroke is kept until each has one
            self._show_stroke()
            self._set_status(self.tool.message)
            return
        self.apply(cmd)

    def apply_drawn(self) -> bool:
        """Enter or the panel's Apply: apply the strokes drawn so far for the picked isophotes
        as one edit (those without a stroke are left out)."""
        if not self.picking or not callable(getattr(self.tool, "command_for_drawn", None)):
            return False
        if self.strokes_drawn == 0:
            text = "nothing to apply: draw the new course of a picked isophote first" if self.pick_point is not None \
                else "nothing to apply: click on a shape to pick an isophote, then redraw it"
            self._set_status(text)
            self.message.emit(text)
            return False
        try:
            cmd = self.tool.command_for_drawn()
        except SketchforgeError as exc:
            self._fail(exc)
            return False
        self.apply(cmd)
        return True

    def _release_plain(self, pos) -> None:
        """A plain tool's release: the command(s) it pushes are prepared on a worker and
        pushed as one undo step (a macro named after the tool when there are several)."""
        from sketchforge.document.commands import MacroCommand

        ok = self._tool_call(self.tool.release, pos)
        pushed = self._proxy.take() if self._proxy is not None else []
        self._show_stroke()
        if not ok:
            return
        if not pushed:
            self._set_status(getattr(self.tool, "message", "") or f"{self.tool_label()}: nothing to apply")
            return
        cmd = pushed[0] if len(pushed) == 1 else MacroCommand(text=self.tool_label(), children=pushed)
        self.apply(cmd, replace_attempt=False)

    def apply(self, cmd, replace_attempt: bool = True) -> None:
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
            replace_attempt
            and self._last_attempt is not None
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
            self._strokes_applied = True
            self.last_info = result_info(done_cmd)
            self._show_debug()
            r = getattr(done_cmd, "result", None)
            if r is not None and callable(getattr(r, "new_isophotes", None)):
                # The isophote as it now runs (white), over the stroke that asked for it (cyan).
                self.canvas.set_overlay("isophote", r.new_isophotes())
            moved = f"{r.describe()}; " if callable(getattr(r, "describe", None)) else ""
            if not replace_attempt:
                self._last_attempt = None
                self.canvas.set_overlay("stroke", [])
                self._set_status(f"applied {done_cmd.text()}: {moved}drag again for another")
                return
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
        self.changed.emit()

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


def overlay_lines(overlay: dict) -> list:
    """Every polyline of a tool's overlay ((k, 2) arrays, alone or in lists), for the canvas."""
    lines: list = []
    for value in overlay.values():
        items = value if isinstance(value, (list, tuple)) else [value]
        for item in items:
            a = np.asarray(item) if isinstance(item, (np.ndarray, list, tuple)) else None
            if a is not None and a.ndim == 2 and a.shape[1] >= 2 and len(a) >= 1 and np.issubdtype(a.dtype, np.number):
                lines.append(a[:, :2].astype(np.float64))
    return lines


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
