"""The drawing region: a pyqtgraph view whose coordinates are the document's (x right, y up).

pyqtgraph's ViewBox already points y up, so ``ViewBox.mapSceneToView`` turns a mouse position
into document coordinates; :meth:`Canvas.doc_to_widget` is the inverse (tests use it to aim
mouse events). The canvas draws the document and turns mouse gestures into calls on the
interaction in use. Drawing: the visible layers' meshes are rasterised for the current view by
the geometry core (:mod:`sketchforge.geometry.gbuffer`: per-pixel normals, antialiased
silhouettes, layers back to front, the same code as ``sketchforge render``) into one image with
the isophote lines of the layers in front; a new light only re-shades that buffer, a new view or
mesh rasterises again (a view change after a short pause, showing the previous image meanwhile).
Over it: the selected layer's outline, the light indicator, an optional reference image.
Gestures:

- ``"draw"``: a left drag is a stroke (``DrawContourTool`` collects it); on release
  :attr:`stroke_finished` carries the points and the stroke's kind to the window, which runs
  the inflation off the GUI thread: ``"front"`` (a left drag), ``"behind"`` (a right drag, or
  Shift + left drag), ``"redraw"`` (Ctrl + left drag: the selected part's whole outline) or
  ``"hole"`` (Alt + left drag: a closed stroke cuts a hole in the selected part).
  A click picks the part under it (:attr:`part_clicked`), a double click duplicates it
  (:attr:`part_double_clicked`, with the button). The selected part shows handles
  (:mod:`sketchforge.tools.transform`): a left drag that starts on the centre marker moves
  it, on a corner scales it about the opposite corner, on the knob above rotates it; the
  outline follows the drag and its end asks for one ``transform_layer``
  (:attr:`transform_requested`).
- ``"light"``: a left drag turns the light with ``LightTool`` (its direction in the drawing
  plane; a raised light keeps its elevation; one undo step per drag); never a
  stroke.
- ``"sculpt"``: clicks, drags and the wheel go to the sculpt controller (``sculpt.py``).

Middle drag pans, right drag zooms (except in ``"draw"``, where it draws behind), the wheel zooms (in sculpture with a picked isophote the
wheel changes the band radius; Ctrl+wheel still zooms).
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QPointF, QRectF, Qt, QTimer, Signal
from PySide6.QtGui import QColor, QImage

from sketchforge.errors import SketchforgeError
from sketchforge.geometry import gbuffer as gb
from sketchforge.qt import items as it
from sketchforge.tools import DrawContourTool, LightTool
from sketchforge.tools import transform as tr

BACKGROUND = QColor(242, 240, 236)
#: Default visible region (document units) of an empty document.
HOME_RANGE = QRectF(-1.2, -1.2, 2.4, 2.4)
#: After an edit, a view of more triangles than this is rasterised in the background (the
#: previous picture stays meanwhile); a smaller one at once (~0.1 s at 20k triangles).
EDIT_RASTER_NOW_FACES = 20_000
#: Pause after the last pan/zoom step before the view is rasterised again (ms).
VIEW_SETTLE_MS = 60
#: Opacity of the thin lines along the layers' visible outlines.
OUTLINE_ALPHA = 0.45
#: Per-layer colour multipliers that tell touching layers apart (an eye on a head) without
#: hiding the shading: hue shifts of a few percent, cycled through the document's layer order.
LAYER_TINTS = np.array(
    [
        [1.00, 1.00, 1.00],
        [0.96, 0.99, 1.05],
        [1.04, 0.99, 0.94],
        [0.97, 1.03, 0.97],
        [1.03, 0.97, 1.01],
        [0.98, 0.98, 1.06],
        [1.03, 1.02, 0.93],
        [0.95, 1.02, 1.03],
    ]
)


class CanvasViewBox(pg.ViewBox):
    """A ViewBox that offers left drags, clicks and wheel turns to the canvas first."""

    def __init__(self, canvas: Canvas) -> None:
        super().__init__(lockAspect=True, enableMenu=False, invertY=False)
        self._canvas = canvas

    def mouseDragEvent(self, ev, axis=None):
        draws = self._canvas.interaction == "draw" and ev.button() == Qt.MouseButton.RightButton
        if (ev.button() == Qt.MouseButton.LeftButton or draws) and self._canvas.handle_left_drag(ev):
            ev.accept()
            return
        if ev.button() == Qt.MouseButton.LeftButton:
            ev.ignore()
            return
        super().mouseDragEvent(ev, axis)  # middle: pan, right: zoom

    def mouseClickEvent(self, ev):
        if ev.double() and self._canvas.handle_double_click(ev):
            ev.accept()
            return
        selects = self._canvas.interaction == "draw" and ev.button() == Qt.MouseButton.RightButton
        if (ev.button() == Qt.MouseButton.LeftButton or selects) and self._canvas.handle_click(ev):
            ev.accept()
            return
        super().mouseClickEvent(ev)

    def wheelEvent(self, ev, axis=None):
        if self._canvas.handle_wheel(ev):
            ev.accept()
            return
        super().wheelEvent(ev, axis)


class Canvas(pg.GraphicsView):
    #: points (n, 2) float64 in document coordinates and the kind ("front", "behind",
    #: "redraw"), at the end of a draw gesture
    stroke_finished = Signal(object, str)
    #: a click in "draw": the document point (2,) (the window selects the part there)
    part_clicked = Signal(object)
    #: a double click in "draw": the document point (2,) and "left" or "right"
    part_double_clicked = Signal(object, str)
    #: the end of a handle drag on the selected part: layer id and the (2, 3) affine of the
    #: whole drag (the window pushes one transform_layer)
    transform_requested = Signal(str, object)
    #: a one-line message for the status bar
    message = Signal(str)
    #: ((GBuffer | None, error | None), view, meshes) from the rasterising thread
    _raster_done = Signal(object, object, object)

    def __init__(self, doc, host, parent=None) -> None:
        # Every mouse move counts: a stroke drawn quickly must keep its points (pyqtgraph drops
        # moves closer than 1/mouseRateLimit seconds by default).
        pg.setConfigOption("mouseRateLimit", -1)
        super().__init__(parent, background=BACKGROUND)
        self.setAntialiasing(True)
        self.doc = doc
        self.host = host
        self.vb = CanvasViewBox(self)
        self.setCentralItem(self.vb)
        self.vb.setRange(HOME_RANGE, padding=0.0)
        self.interaction = "draw"
        self.sculpt = None  # the sculpt controller, set by the window
        self.busy = False  # a solve is running: gestures that edit are refused
        self.shader_name = "lambert"
        self.isoline_count = 0
        self.current_layer: str | None = None
        self._layer_items: dict[str, it.ShadedLayerItem] = {}
        self._tool: Any = None  # a Tool, or the sculpt controller: both take press/move/release
        self._stroke_kind = "front"
        self._reference: pg.ImageItem | None = None
        self._light_center = np.zeros(2)
        self._preview: tuple[str, object] | None = None  # (layer id, mesh) shown instead of the layer's
        self.layer_tint = True  # subtle per-layer tints (LAYER_TINTS)
        self.layer_outlines = True  # thin lines along the layers' visible outlines
        # The rasterised view: the GBuffer, and what it was made of (view, meshes) to know when
        # it is stale. A light change re-shades it; a view or mesh change rasterises again.
        self._gbuf: gb.GBuffer | None = None
        self._gbuf_meshes: list = []
        self._shaded_gbuf: gb.GBuffer | None = None  # the buffer the picture's pixels were shaded from
        self._raster_thread: threading.Thread | None = None
        self._raster_again = False
        self._raster_generation = 0  # requests made
        self._raster_adopted = 0  # the request whose buffer is shown
        self._raster_done.connect(self._on_raster_done)
        self.scene_item = it.ShadedSceneItem()
        self.scene_item.setZValue(-1)
        self._raster_timer = QTimer(self)
        self._raster_timer.setSingleShot(True)
        self._raster_timer.timeout.connect(self._render_async)
        self._edit_timer = QTimer(self)
        self._edit_timer.setSingleShot(True)
        self._edit_timer.timeout.connect(self.render_now)

        self.outline = it.PolylinesItem(it.cosmetic_pen(it.SELECTED, 1.5, Qt.PenStyle.DotLine), closed=True)
        #: the selected part's move / scale / rotate handles (sketchforge.tools.transform)
        self.handles = it.PolylinesItem(it.cosmetic_pen(it.SELECTED, 1.2))
        self._handle_drag: tuple | None = None  # (kind, start, Handles, outline) during a handle drag
        self.stroke = it.PolylinesItem(it.cosmetic_pen(it.STROKE_DRAW, 2.0))
        self.light_indicator = it.LightIndicator()
        self.overlays: dict[str, it.PolylinesItem] = {
            "strips": it.PolylinesItem(it.cosmetic_pen(it.STRIPS, 1.0)),
            "regions": it.PolylinesItem(it.cosmetic_pen(it.REGION, 1.5, Qt.PenStyle.DashLine), closed=True),
            "band": it.PolylinesItem(it.cosmetic_pen(it.BAND, 2.0, Qt.PenStyle.DashLine), closed=True),
            "isophote": it.PolylinesItem(it.cosmetic_pen(it.ISOPHOTE, 2.5)),
            "stroke": it.PolylinesItem(it.cosmetic_pen(it.STROKE_SCULPT, 2.5)),
        }
        z = 1000
        self.vb.addItem(self.scene_item)
        for item in (self.outline, self.handles, *self.overlays.values(), self.stroke, self.light_indicator):
            item.setZValue(z)
            z += 1
            self.vb.addItem(item)
        self.light_indicator.setVisible(False)

        doc.layer_inserted.connect(self._on_layers)
        doc.layer_removed.connect(self._on_layers)
        doc.layer_moved.connect(self._on_layers)
        doc.layer_changed.connect(self._on_layer_changed)
        doc.light_changed.connect(self._on_light)
        self.vb.sigRangeChanged.connect(lambda *a: self._update_light_indicator())
        self.vb.sigRangeChanged.connect(lambda *a: self._refresh_handles())  # sized in pixels
        self.vb.sigRangeChanged.connect(lambda *a: self._schedule_render(VIEW_SETTLE_MS))
        self.vb.sigResized.connect(lambda *a: self._schedule_render(VIEW_SETTLE_MS))
        self.rebuild()

    # --- coordinates ---------------------------------------------------------------------------
    def widget_to_doc(self, pos) -> np.ndarray:
        """Widget pixel (QPoint/QPointF, y down) -> document point (2,) (y up)."""
        p = self.vb.mapSceneToView(self.mapToScene(pos.toPoint() if hasattr(pos, "toPoint") else pos))
        return np.array([p.x(), p.y()])

    def doc_to_widget(self, xy) -> QPointF:
        """Document point -> widget pixel position (for tests and overlays)."""
        scene = self.vb.mapViewToScene(QPointF(float(xy[0]), float(xy[1])))
        return QPointF(self.mapFromScene(scene))

    def _event_doc(self, ev, pos=None) -> np.ndarray:
        p = self.vb.mapToView(ev.pos() if pos is None else pos)
        return np.array([p.x(), p.y()])

    def view_center(self) -> np.ndarray:
        r = self.vb.viewRect()
        return np.array([r.center().x(), r.center().y()])

    # --- document -> items -------------------------------------------------------------------
    def _shader(self):
        """The display shading chosen: a shader, or a reflectance model (``"model:NAME"``)."""
        shaders = self.host.display_shadings() if hasattr(self.host, "display_shadings") else self.host.shaders
        return shaders.get(self.shader_name) or next(iter(shaders.values()), None) or _FallbackShader

    def rebuild(self) -> None:
        """Recreate the layer items in back-to-front order."""
        for item in self._layer_items.values():
            self.vb.removeItem(item)
        self._layer_items = {}
        for z, layer in enumerate(self.doc.layers):
            item = it.ShadedLayerItem()
            item.setZValue(z)
            self.vb.addItem(item)
            self._layer_items[layer.id] = item
            self._refresh_layer(layer)
        self._refresh_decorations()

    def _refresh_layer(self, layer, background: bool = False) -> None:
        item = self._layer_items.get(layer.id)
        if item is None:
            return
        if self._preview is not None and self._preview[0] == layer.id:
            layer = layer.evolve(mesh=self._preview[1])
        item.set_layer(layer)
        item.setVisible(layer.visible)
        # An edit shows at once (on the next turn of the event loop, once for all layers that
        # changed together); view changes and live previews rasterise in the background, so
        # a stroke being drawn never waits for a picture. So does an edit of a big layer: its
        # rasterisation alone held the window 0.3-0.6 s at 24k-46k vertices (issue 30).
        if background or sum(m.n_faces for m in self._shown_meshes() if m is not None) > EDIT_RASTER_NOW_FACES:
            self._schedule_render(0)
        else:
            self._edit_timer.start(0)

    # --- the shaded picture ---------------------------------------------------------------------
    def current_view(self) -> gb.View | None:
        """The pixel grid of the drawing region now (device pixels), or None before layout."""
        rect = self.vb.viewRect()
        size = self.vb.size()
        dpr = float(self.devicePixelRatioF()) or 1.0
        w, h = int(round(size.width() * dpr)), int(round(size.height() * dpr))
        if w < 1 or h < 1 or rect.width() <= 0 or rect.height() <= 0:
            return None
        return gb.View(float(rect.left()), float(rect.top() + rect.height()), w / float(rect.width()), w, h)

    def _shown_meshes(self) -> list:
        """Per layer (back to front) the mesh drawn now: the preview's, the layer's, or None."""
        out: list = []
        for layer in self.doc.layers:
            item = self._layer_items.get(layer.id)
            out.append(item._mesh if (item is not None and layer.visible) else None)
        return out

    def _schedule_render(self, delay_ms: int) -> None:
        if not self._raster_timer.isActive() or delay_ms == 0:
            self._raster_timer.start(delay_ms)

    def _wanted(self):
        """(view, meshes) the picture should show now, or None before the first layout."""
        view = self.current_view()
        return None if view is None else (view, self._shown_meshes())

    def _is_current(self, view, meshes) -> bool:
        g = self._gbuf
        return (
            g is not None
            and g.view == view
            and len(meshes) == len(self._gbuf_meshes)
            and all(a is b for a, b in zip(meshes, self._gbuf_meshes))
        )

    def _adopt(self, gbuf, meshes, generation: int) -> None:
        if generation <= self._raster_adopted:
            return  # an older request than the buffer shown (render_now ran meanwhile)
        self._raster_adopted = generation
        self._gbuf = gbuf
        self._gbuf_meshes = meshes  # holds them: what the buffer shows
        self.reshade()

    def _render_async(self) -> None:
        """Rasterise on a worker thread (the GUI stays responsive during a pan or an edit); the
        previous picture stays in place, moving with the view, until the new one arrives."""
        wanted = self._wanted()
        if wanted is None or self._is_current(*wanted):
            return
        if self._raster_thread is not None:
            self._raster_again = True  # one more when the running one ends
            return
        view, meshes = wanted
        self._raster_generation += 1
        generation = self._raster_generation

        def work():
            try:
                result = (gb.rasterise(meshes, view), None)
            except Exception as exc:  # shown in the status bar, never lost in a thread
                result = (None, exc)
            try:
                self._raster_done.emit(result, meshes, generation)
            except RuntimeError:  # the canvas is gone
                pass

        self._raster_again = False
        self._raster_thread = threading.Thread(target=work, name="canvas-raster", daemon=True)
        self._raster_thread.start()

    def _on_raster_done(self, result, meshes, generation) -> None:
        self._raster_thread = None
        gbuf, exc = result
        if exc is not None:
            self.message.emit(f"cannot draw the layers: {exc}")
        else:
            # Newer than the picture shown even if the view moved on meanwhile: it is placed in
            # document coordinates, so it is drawn where it belongs until the next one.
            self._adopt(gbuf, meshes, generation)
        wanted = self._wanted()
        if self._raster_again or (wanted is not None and not self._is_current(*wanted)):
            self._schedule_render(0)

    def render_now(self) -> None:
        """Rasterise the view now (on this thread) if the view or a shown mesh changed, then
        shade it: after an edit, and for screenshots, which must show the current state."""
        self._raster_timer.stop()
        self._edit_timer.stop()
        wanted = self._wanted()
        if wanted is None:
            return
        if self._is_current(*wanted):
            self.reshade()
            return
        view, meshes = wanted
        self._raster_generation += 1
        self._adopt(gb.rasterise(meshes, view), meshes, self._raster_generation)

    def reshade(self) -> None:
        """Shade the current buffer with the document's light and shader (no rasterisation)."""
        if self._gbuf is None:
            return
        n = self._gbuf.n_layers
        tints = np.resize(LAYER_TINTS, (n, 3)) if (self.layer_tint and n > 1) else None
        shader = self._shader()
        try:
            img = self._shade(shader, tints)
        except ValueError as exc:  # a broken shader plugin: say so, draw with the built-in one
            self.message.emit(f"shader '{getattr(shader, 'name', '?')}': {exc}; showing Lambertian shading")
            img = self._shade(_FallbackShader, tints)
        self.scene_item.set_image(img, self._gbuf.view)

    def _shade(self, shader, tints) -> np.ndarray:
        # Re-shading the buffer shown writes into the picture's own pixels (its background
        # never changes); a new buffer starts a new picture.
        shown = self.scene_item.pixels()
        reuse = shown if (shown is not None and self._shaded_gbuf is self._gbuf) else None
        self._shaded_gbuf = self._gbuf
        return gb.shade(
            self._gbuf,
            np.asarray(self.doc.light.direction, dtype=np.float64),
            shader.shade,
            np.array([BACKGROUND.redF(), BACKGROUND.greenF(), BACKGROUND.blueF()]),
            tints=tints,
            isophotes=int(self.isoline_count),
            line_colour=(it.ISOLINES.redF(), it.ISOLINES.greenF(), it.ISOLINES.blueF()),
            line_alpha=it.ISOLINES.alphaF(),
            bgrx=True,
            outline_alpha=OUTLINE_ALPHA if self.layer_outlines else 0.0,
            out=reuse,
            intensity=getattr(shader, "intensity", None),  # a reflectance model's own isophote lines
        )

    def show_preview(self, layer_id: str, mesh) -> None:
        """Draw ``mesh`` in place of the layer's surface until :meth:`clear_preview` (a view
        state only: the document is not touched)."""
        if layer_id not in self.doc.layer_ids():
            return
        self._preview = (layer_id, mesh)
        self._refresh_layer(self.doc.layer(layer_id), background=True)

    def clear_preview(self) -> None:
        if self._preview is None:
            return
        layer_id, self._preview = self._preview[0], None
        if layer_id in self.doc.layer_ids():
            self._refresh_layer(self.doc.layer(layer_id), background=True)

    def _on_layers(self, *args) -> None:
        self.rebuild()

    def _on_layer_changed(self, index, new, old) -> None:
        if new.id not in self._layer_items:
            self.rebuild()
            return
        self._refresh_layer(new)
        self._refresh_decorations()

    def _on_light(self, light) -> None:
        self.reshade()
        self._update_light_indicator()

    def _refresh_decorations(self) -> None:
        self._refresh_outline()
        self._update_light_indicator()

    def _refresh_outline(self) -> None:
        lines = []
        if self.current_layer is not None and self.current_layer in self.doc.layer_ids():
            layer = self.doc.layer(self.current_layer)
            if layer.visible:
                if layer.mesh is not None and len(layer.mesh.boundary):
                    lines.append(layer.mesh.V[layer.mesh.boundary, :2])
                    lines += [layer.mesh.V[h, :2] for h in layer.mesh.holes]
                elif layer.points is not None:
                    lines.append(layer.points)
        self.outline.set_lines(lines)
        self._refresh_handles()

    def selected_outline(self) -> np.ndarray | None:
        """The selected visible part's outline (n, 2) as drawn, or None."""
        if self.current_layer is None or self.current_layer not in self.doc.layer_ids():
            return None
        layer = self.doc.layer(self.current_layer)
        if not layer.visible:
            return None
        if layer.mesh is not None and len(layer.mesh.boundary):
            return np.asarray(layer.mesh.V[layer.mesh.boundary, :2])
        return None if layer.points is None else np.asarray(layer.points)

    def current_handles(self):
        """The selected part's handle set at this zoom (None without one, or outside "draw")."""
        if self.interaction != "draw":
            return None
        return tr.handles_for(self.selected_outline(), self.pixel_size())

    def _refresh_handles(self) -> None:
        if self._handle_drag is None:
            self.handles.set_lines(tr.handle_lines(self.current_handles()))

    def _drag_handle(self, ev) -> None:
        """A drag that started on a handle: preview the transformed outline, and at the end ask
        for one transform_layer with the whole drag's matrix."""
        kind, start, h, outline = self._handle_drag
        A = tr.drag_matrix(h, kind, start, self._event_doc(ev))
        if not ev.isFinish():
            self.outline.set_lines([tr.apply(A, outline)])
            self.handles.set_lines(tr.handle_lines(tr.handles_for(tr.apply(A, h.corners), h.pixel)))
            return
        self._handle_drag = None
        self._refresh_outline()
        if not tr.is_identity(A) and self.current_layer is not None:
            self.transform_requested.emit(self.current_layer, A)

    def _update_light_indicator(self) -> None:
        visible = self.interaction == "light"
        self.light_indicator.setVisible(visible)
        if not visible:
            return
        r = self.vb.viewRect()
        length = 0.35 * min(r.width(), r.height())
        center = self._light_center if self._tool is not None else self.view_center()
        self.light_indicator.set_state(center, self.doc.light.direction, length, active=self._tool is not None)

    # --- settings from the panels ------------------------------------------------------------
    def set_current_layer(self, layer_id: str | None) -> None:
        self.current_layer = layer_id
        self._refresh_outline()

    def set_shader(self, name: str) -> None:
        self.shader_name = name
        self.reshade()

    def set_isoline_count(self, k: int) -> None:
        """K isophote lines at n·l = j/(K+1), j = 1..K, of the layer in front at each pixel."""
        self.isoline_count = int(k)
        self.reshade()

    def set_layer_tint(self, on: bool) -> None:
        self.layer_tint = bool(on)
        self.reshade()

    def set_layer_outlines(self, on: bool) -> None:
        self.layer_outlines = bool(on)
        self.reshade()

    def set_interaction(self, name: str) -> None:
        if self._tool is not None:
            self._tool.cancel()
            self._tool = None
        self.interaction = name
        self._handle_drag = None
        self.stroke.set_lines([])
        self._refresh_handles()
        cursor = Qt.CursorShape.CrossCursor if name in ("draw", "sculpt", "light") else Qt.CursorShape.ArrowCursor
        self.viewport().setCursor(cursor)
        for item in self.overlays.values():
            item.setVisible(name == "sculpt")
        self._update_light_indicator()

    def set_overlay(self, name: str, lines) -> None:
        self.overlays[name].set_lines(lines)

    def set_reference_image(self, path: str | None) -> None:
        """Show an image under the drawing, fitted to the current view (None removes it)."""
        img = QImage(path) if path else None
        if img is not None and img.isNull():  # checked first: a bad file keeps the old image
            raise SketchforgeError(f"cannot read the image {path}")
        if self._reference is not None:
            self.vb.removeItem(self._reference)
            self._reference = None
        if img is None:
            return
        img = img.convertToFormat(QImage.Format.Format_RGBA8888)
        w, h = img.width(), img.height()
        arr = np.frombuffer(img.constBits(), dtype=np.uint8).reshape(h, img.bytesPerLine() // 4, 4)[:, :w].copy()
        # ImageItem indexes [x, y] with y up: transpose and flip the rows (Qt's y points down).
        item = pg.ImageItem(arr[::-1].transpose(1, 0, 2))
        item.setOpacity(0.45)
        item.setZValue(-100)
        r = self.vb.viewRect()
        scale = min(r.width() / w, r.height() / h)
        item.setRect(QRectF(r.center().x() - 0.5 * w * scale, r.center().y() - 0.5 * h * scale, w * scale, h * scale))
        self.vb.addItem(item)
        self._reference = item

    def fit(self) -> None:
        """Zoom to show every layer (or the home range for an empty document)."""
        from sketchforge.qt.render2d import bounds_rect

        rect = bounds_rect(
            [l.mesh.V if l.mesh is not None else l.points for l in self.doc.layers]
        )
        if rect is None or rect.width() <= 0 or rect.height() <= 0:
            rect = HOME_RANGE
        self.vb.setRange(rect, padding=0.15)

    # --- gestures -------------------------------------------------------------------------------
    def handle_left_drag(self, ev) -> bool:
        mode = self.interaction
        if self._handle_drag is not None:
            self._drag_handle(ev)
            return True
        if (ev.isStart() and mode == "draw" and not self.busy and ev.button() == Qt.MouseButton.LeftButton
                and ev.modifiers() == Qt.KeyboardModifier.NoModifier):
            start = self._event_doc(ev, ev.buttonDownPos())
            h = self.current_handles()
            kind = tr.hit(h, start)
            if kind is not None:
                self._handle_drag = (kind, start, h, self.selected_outline())
                self._drag_handle(ev)
                return True
        if ev.isStart():
            # A stroke may be drawn while the last one inflates (the window queues it).
            if self.busy and mode not in ("light", "draw"):
                self.message.emit("a solve is running: wait for it or cancel it")
                return True
            start = self._event_doc(ev, ev.buttonDownPos())
            if mode == "draw":
                self._stroke_kind = _stroke_kind(ev.button(), ev.modifiers())
                self._tool = DrawContourTool(self.doc)
                self._tool.press(start)
            elif mode == "light":
                self._light_center = self.view_center()
                self._tool = LightTool(self.doc, center=self._light_center)
                self._gesture_call(self._tool.press, start)
                if self._tool.message:  # straight overhead: nothing to turn, and why
                    self.message.emit(self._tool.message)
            elif mode == "sculpt" and self.sculpt is not None:
                self.sculpt.stroke_press(start)
                self._tool = self.sculpt
        if self._tool is None:
            return True
        pos = self._event_doc(ev)
        if ev.isFinish():
            tool, self._tool = self._tool, None
            if mode == "draw":
                pts = np.asarray(tool.overlay.get("stroke", np.zeros((0, 2))))
                tool.cancel()
                self.stroke.set_lines([])
                pts = np.vstack([pts, pos[None]]) if len(pts) else pos[None]
                if self._pixel_extent(pts) < MIN_STROKE_PIXELS:
                    self.message.emit(
                        f"the stroke is shorter than {MIN_STROKE_PIXELS} pixels, so no part was made: "
                        "press, drag around the shape and release"
                    )
                    return True
                self.stroke_finished.emit(pts, self._stroke_kind)
            elif mode == "light":
                self._gesture_call(tool.release, pos)
                self._update_light_indicator()
            elif mode == "sculpt":
                tool.stroke_release(pos)
        else:
            if mode == "draw":
                self._tool.move(pos)
                self.stroke.set_lines([self._tool.overlay.get("stroke")])
            elif mode == "light":
                self._gesture_call(self._tool.move, pos)
            elif mode == "sculpt":
                self._tool.stroke_move(pos)
        return True

    def _gesture_call(self, fn, pos) -> None:
        """A gesture's error goes to the status bar (a dialog mid-drag would be rude)."""
        try:
            fn(pos)
        except SketchforgeError as exc:
            self.message.emit(str(exc))

    def pixel_size(self) -> float:
        """Drawing units per screen pixel at the current zoom."""
        a, b = self.widget_to_doc(QPointF(0, 0)), self.widget_to_doc(QPointF(100, 0))
        return float(np.linalg.norm(b - a)) / 100.0

    def _pixel_extent(self, pts) -> float:
        pts = np.asarray(pts, dtype=np.float64)
        return float(np.max(np.ptp(pts, axis=0))) / max(self.pixel_size(), 1e-300)

    def handle_double_click(self, ev) -> bool:
        if self.interaction != "draw":
            return False
        button = {Qt.MouseButton.LeftButton: "left", Qt.MouseButton.RightButton: "right"}.get(ev.button())
        if button is None:
            return False
        self.part_double_clicked.emit(self._event_doc(ev), button)
        return True

    def handle_click(self, ev) -> bool:
        if self.interaction == "draw":
            self.part_clicked.emit(self._event_doc(ev))
            return True
        if self.interaction == "sculpt" and self.sculpt is not None:
            if self.busy:
                self.message.emit("a solve is running: wait for it or cancel it")
                return True
            add = bool(ev.modifiers() & Qt.KeyboardModifier.ShiftModifier)  # Shift+click: another isophote
            self.sculpt.pick(self._event_doc(ev), add=add)
            return True
        return False

    def handle_wheel(self, ev) -> bool:
        if self.interaction != "sculpt" or self.sculpt is None:
            return False
        if ev.modifiers() & Qt.KeyboardModifier.ControlModifier:
            return False
        return self.sculpt.wheel(ev.delta())


#: A draw gesture spanning fewer screen pixels than this is refused with a message (a slip).
MIN_STROKE_PIXELS = 8


def _stroke_kind(button, modifiers) -> str:
    """Which part a draw gesture makes: Alt cuts a hole in the selected part, right button or
    Shift draws behind, Ctrl redraws the selected part's whole outline, a plain left drag
    draws in front."""
    if modifiers & Qt.KeyboardModifier.AltModifier:
        return "hole"
    if button == Qt.MouseButton.RightButton or modifiers & Qt.KeyboardModifier.ShiftModifier:
        return "behind"
    if modifiers & Qt.KeyboardModifier.ControlModifier:
        return "redraw"
    return "front"


class _FallbackShader:
    """Grey Lambertian, used only if no shader is registered at all."""

    name = "grey"

    @staticmethod
    def shade(N, light):
        from sketchforge.geometry.shaders import lambert_shade

        return lambert_shade(N, light)
