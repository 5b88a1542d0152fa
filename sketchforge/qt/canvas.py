"""The drawing region: a pyqtgraph view whose coordinates are the document's (x right, y up).

pyqtgraph's ViewBox already points y up, so ``ViewBox.mapSceneToView`` turns a mouse position
into document coordinates; :meth:`Canvas.doc_to_widget` is the inverse (tests use it to aim
mouse events). The canvas draws the document (one flat-shaded item per layer, back to front,
optional isophote lines, the light indicator, an optional reference image) and turns mouse
gestures into calls on the interaction in use:

- ``"draw"``: a left drag is a stroke (``DrawContourTool`` collects it); on release
  :attr:`stroke_finished` carries the points and the stroke's kind to the window, which runs
  the inflation off the GUI thread: ``"front"`` (a left drag), ``"behind"`` (a right drag, or
  Shift + left drag) or ``"redraw"`` (Ctrl + left drag: the selected part's whole outline).
  A click picks the part under it (:attr:`part_clicked`), a double click duplicates it
  (:attr:`part_double_clicked`, with the button).
- ``"light"``: a left drag sets the light with ``LightTool`` (one undo step per drag); never a
  stroke.
- ``"sculpt"``: clicks, drags and the wheel go to the sculpt controller (``sculpt.py``).

Middle drag pans, right drag zooms (except in ``"draw"``, where it draws behind), the wheel zooms (in sculpture with a picked isophote the
wheel changes the band radius; Ctrl+wheel still zooms).
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QImage

from sketchforge.errors import SketchforgeError
from sketchforge.geometry.intensity import vertex_intensity
from sketchforge.geometry.isophotes import isophotes
from sketchforge.qt import items as it
from sketchforge.tools import DrawContourTool, LightTool

BACKGROUND = QColor(242, 240, 236)
#: Default visible region (document units) of an empty document.
HOME_RANGE = QRectF(-1.2, -1.2, 2.4, 2.4)


class CanvasViewBox(pg.ViewBox):
    """A ViewBox that offers left drags, clicks and wheel turns to the canvas first."""

    def __init__(self, canvas: "Canvas") -> None:
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
    #: a one-line message for the status bar
    message = Signal(str)

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
        self._tool = None
        self._stroke_kind = "front"
        self._reference: pg.ImageItem | None = None
        self._light_center = np.zeros(2)
        self._preview: tuple[str, object] | None = None  # (layer id, mesh) shown instead of the layer's

        self.isolines = it.PolylinesItem(it.cosmetic_pen(it.ISOLINES, 1.0))
        self.outline = it.PolylinesItem(it.cosmetic_pen(it.SELECTED, 1.5, Qt.PenStyle.DotLine), closed=True)
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
        for item in (self.isolines, self.outline, *self.overlays.values(), self.stroke, self.light_indicator):
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
        shaders = self.host.shaders
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

    def _refresh_layer(self, layer) -> None:
        item = self._layer_items.get(layer.id)
        if item is None:
            return
        if self._preview is not None and self._preview[0] == layer.id:
            layer = layer.evolve(mesh=self._preview[1])
        item.set_layer(layer, self.doc.light, self._shader())
        item.setVisible(layer.visible)

    def show_preview(self, layer_id: str, mesh) -> None:
        """Draw ``mesh`` in place of the layer's surface until :meth:`clear_preview` (a view
        state only: the document is not touched)."""
        if layer_id not in self.doc.layer_ids():
            return
        self._preview = (layer_id, mesh)
        self._refresh_layer(self.doc.layer(layer_id))

    def clear_preview(self) -> None:
        if self._preview is None:
            return
        layer_id, self._preview = self._preview[0], None
        if layer_id in self.doc.layer_ids():
            self._refresh_layer(self.doc.layer(layer_id))

    def _on_layers(self, *args) -> None:
        self.rebuild()

    def _on_layer_changed(self, index, new, old) -> None:
        if new.id not in self._layer_items:
            self.rebuild()
            return
        self._refresh_layer(new)
        self._refresh_decorations()

    def _on_light(self, light) -> None:
        shader = self._shader()
        for layer in self.doc.layers:
            item = self._layer_items.get(layer.id)
            if item is not None:
                item.set_shading(light, shader)
        self._refresh_isolines()
        self._update_light_indicator()

    def _refresh_decorations(self) -> None:
        self._refresh_isolines()
        self._refresh_outline()
        self._update_light_indicator()

    def _refresh_isolines(self) -> None:
        """K isophote lines per visible layer at n·l = j/(K+1), j = 1..K."""
        lines = []
        K = int(self.isoline_count)
        if K > 0:
            light = self.doc.light.direction
            for layer in self.doc.layers:
                mesh = layer.mesh
                if not layer.visible or mesh is None or mesh.n_faces == 0:
                    continue
                E = vertex_intensity(mesh.V, mesh.F, light)
                for j in range(1, K + 1):
                    polylines, _ = isophotes(mesh.V[:, :2], mesh.F, E, j / (K + 1))
                    lines.extend(polylines)
        self.isolines.set_lines(lines)

    def _refresh_outline(self) -> None:
        lines = []
        if self.current_layer is not None and self.current_layer in self.doc.layer_ids():
            layer = self.doc.layer(self.current_layer)
            if layer.visible:
                if layer.mesh is not None and len(layer.mesh.boundary):
                    lines.append(layer.mesh.V[layer.mesh.boundary, :2])
                elif layer.points is not None:
                    lines.append(layer.points)
        self.outline.set_lines(lines)

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
        self._on_light(self.doc.light)

    def set_isoline_count(self, k: int) -> None:
        self.isoline_count = int(k)
        self._refresh_isolines()

    def set_interaction(self, name: str) -> None:
        if self._tool is not None:
            self._tool.cancel()
            self._tool = None
        self.interaction = name
        self.stroke.set_lines([])
        cursor = Qt.CursorShape.CrossCursor if name in ("draw", "sculpt", "light") else Qt.CursorShape.ArrowCursor
        self.viewport().setCursor(cursor)
        for key, item in self.overlays.items():
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
            self.sculpt.pick(self._event_doc(ev))
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
    """Which part a draw gesture makes: right button or Shift draws behind, Ctrl redraws the
    selected part's whole outline, a plain left drag draws in front."""
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
