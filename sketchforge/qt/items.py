"""Graphics items of the drawing region (pyqtgraph view coordinates = document coordinates)."""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QColor, QImage, QPainter, QPainterPath, QPen

from sketchforge.qt.render2d import NO_MESH_FILL, points_polygon

# Overlay colours (figure 4.3 of the thesis).
STROKE_DRAW = QColor(30, 60, 160)
STROKE_SCULPT = QColor(0, 200, 230)  # cyan: the redrawn isophote
ISOPHOTE = QColor(255, 255, 255)  # white: the selected isophote
BAND = QColor(255, 140, 0)  # orange dashed: the band
STRIPS = QColor(110, 110, 110, 170)
REGION = QColor(20, 20, 20)
ISOLINES = QColor(35, 30, 30, 200)
CONTOUR = QColor(60, 50, 45)
SELECTED = QColor(40, 110, 220)
LIGHT = QColor(235, 170, 0)


def cosmetic_pen(colour: QColor, width: float = 1.0, style=Qt.PenStyle.SolidLine) -> QPen:
    pen = QPen(colour)
    pen.setWidthF(width)
    pen.setCosmetic(True)
    pen.setStyle(style)
    pen.setCapStyle(Qt.PenCapStyle.RoundCap)
    pen.setJoinStyle(Qt.PenJoinStyle.RoundJoin)
    return pen


class ShadedLayerItem(pg.GraphicsObject):
    """One layer's state on the canvas: the mesh it shows (the layer's, or a preview) and its
    visibility. The shaded surfaces of all layers are one picture (:class:`ShadedSceneItem`);
    this item draws only a bare stroke, for a layer without a mesh."""

    def __init__(self) -> None:
        super().__init__()
        self._mesh = None
        self._points = None
        self._rect = QRectF()

    def set_layer(self, layer) -> None:
        self.prepareGeometryChange()
        self._mesh = layer.mesh if (layer.mesh is not None and layer.mesh.n_faces) else None
        self._points = layer.points
        pts = self._points if self._mesh is None else None
        if pts is not None and len(pts):
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            self._rect = QRectF(float(lo[0]), float(lo[1]), float(hi[0] - lo[0]), float(hi[1] - lo[1]))
        else:
            self._rect = QRectF()
        self.update()

    def boundingRect(self) -> QRectF:
        return self._rect

    def paint(self, painter, option, widget=None) -> None:
        if self._mesh is None and self._points is not None and len(self._points) >= 2:
            painter.setPen(cosmetic_pen(CONTOUR, 1.5))
            painter.setBrush(NO_MESH_FILL)
            painter.drawPolygon(points_polygon(self._points))


class ShadedSceneItem(pg.GraphicsObject):
    """The shaded layers as one image rendered for a view (document rectangle, pixel grid).

    The image stays where it was rendered in document coordinates, so while the view pans or
    zooms the last image moves with the drawing until a fresh one for the new view arrives.
    """

    def __init__(self) -> None:
        super().__init__()
        self._image: QImage | None = None
        self._pixels: np.ndarray | None = None  # keeps the buffer the QImage reads alive
        self._x0 = 0.0
        self._y1 = 0.0
        self._scale = 1.0
        self._rect = QRectF()

    def set_image(self, bgrx: np.ndarray, view) -> None:
        """``bgrx``: (height, width, 4) uint8 in Format_RGB32 byte order; ``view``: its View."""
        self.prepareGeometryChange()
        h, w = bgrx.shape[:2]
        self._pixels = np.ascontiguousarray(bgrx)
        # A new QImage (no copy: it reads the array) even for pixels re-shaded in place, so
        # nothing that caches images by key shows the old shading.
        self._image = QImage(self._pixels.data, w, h, 4 * w, QImage.Format.Format_RGB32)
        self._x0, self._y1, self._scale = float(view.x0), float(view.y1), float(view.scale)
        self._rect = QRectF(self._x0, self._y1 - h / self._scale, w / self._scale, h / self._scale)
        self.update()

    def clear(self) -> None:
        self.prepareGeometryChange()
        self._image = None
        self._pixels = None
        self._rect = QRectF()
        self.update()

    def pixels(self) -> np.ndarray | None:
        """The image shown, (height, width, 4) uint8 B, G, R, 255 (tests read it)."""
        return self._pixels

    def boundingRect(self) -> QRectF:
        return self._rect

    def paint(self, painter, option, widget=None) -> None:
        if self._image is None:
            return
        painter.save()
        # The view points y up, image rows run down: row r sits at y1 - r / scale.
        painter.translate(self._x0, self._y1)
        painter.scale(1.0 / self._scale, -1.0 / self._scale)
        painter.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform, True)
        painter.drawImage(QPointF(0.0, 0.0), self._image)
        painter.restore()


class PolylinesItem(pg.GraphicsObject):
    """Several polylines with one pen (isophotes, band outline, strips, overlays)."""

    def __init__(self, pen: QPen, closed: bool = False) -> None:
        super().__init__()
        self._pen = pen
        self._closed = closed
        self._path = QPainterPath()

    def set_lines(self, lines) -> None:
        self.prepareGeometryChange()
        path = QPainterPath()
        for line in lines or []:
            arr = np.asarray(line, dtype=np.float64)
            if arr.ndim != 2 or len(arr) < 1:
                continue
            path.moveTo(QPointF(float(arr[0, 0]), float(arr[0, 1])))
            for x, y in arr[1:, :2].tolist():
                path.lineTo(QPointF(x, y))
            if self._closed:
                path.closeSubpath()
        self._path = path
        self.update()

    def is_empty(self) -> bool:
        return self._path.isEmpty()

    def boundingRect(self) -> QRectF:
        return self._path.boundingRect()

    def shape(self):
        return self._path

    def paint(self, painter, option, widget=None) -> None:
        painter.setRenderHint(painter.RenderHint.Antialiasing, True)
        painter.setPen(self._pen)
        painter.setBrush(Qt.BrushStyle.NoBrush)
        painter.drawPath(self._path)


class LightIndicator(pg.GraphicsObject):
    """A sun and an arrow from the centre of the drawing region towards the light."""

    def __init__(self) -> None:
        super().__init__()
        self._center = np.zeros(2)
        self._direction = np.array([1.0, 0.0])
        self._length = 1.0
        self._active = False

    def set_state(self, center, direction, length: float, active: bool = False) -> None:
        self.prepareGeometryChange()
        self._center = np.asarray(center, dtype=np.float64)[:2]
        self._direction = np.asarray(direction, dtype=np.float64)[:2]
        self._length = float(length)
        self._active = active
        self.update()

    def _tip(self) -> np.ndarray:
        return self._center + self._length * self._direction

    def boundingRect(self) -> QRectF:
        r = 0.2 * self._length
        c, t = self._center, self._tip()
        lo = np.minimum(c, t) - r
        hi = np.maximum(c, t) + r
        return QRectF(float(lo[0]), float(lo[1]), float(hi[0] - lo[0]), float(hi[1] - lo[1]))

    def paint(self, painter, option, widget=None) -> None:
        painter.setRenderHint(painter.RenderHint.Antialiasing, True)
        c, t = self._center, self._tip()
        width = 2.5 if self._active else 1.5
        painter.setPen(cosmetic_pen(LIGHT, width, Qt.PenStyle.DashLine))
        painter.drawLine(QPointF(*c), QPointF(*t))
        # arrow head (document units, so it scales with the arrow)
        d = self._direction
        n = np.array([-d[1], d[0]])
        h = 0.08 * self._length
        a = t - h * d + 0.5 * h * n
        b = t - h * d - 0.5 * h * n
        painter.setPen(cosmetic_pen(LIGHT, width))
        painter.drawLine(QPointF(*t), QPointF(*a))
        painter.drawLine(QPointF(*t), QPointF(*b))
        # the sun at the tip
        r = 0.05 * self._length
        painter.setBrush(QColor(255, 215, 60))
        painter.drawEllipse(QPointF(*(t + 1.3 * r * d)), r, r)
        # the centre
        painter.setBrush(LIGHT)
        painter.drawEllipse(QPointF(*c), 0.25 * r, 0.25 * r)
