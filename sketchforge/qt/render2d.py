"""Qt helpers for drawing the document: layer thumbnails, polygons, bounds.

A thumbnail's shading is the geometry core's software renderer (the same per-pixel shading as
the canvas and ``sketchforge render``); this module only wraps its pixels in a QPixmap and fits
strokes into a box (a coordinate mapping, flipping the document's upward y to Qt's downward one).
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF
from PySide6.QtGui import QColor, QImage, QPainter, QPen, QPixmap, QPolygonF, QTransform

from sketchforge.geometry.raster import render_top

THUMB_BACKGROUND = QColor(250, 249, 246)

#: Fill for a layer that has a stroke but no mesh (no inflate plugin, or a failed inflation).
NO_MESH_FILL = QColor(200, 200, 210, 90)


def points_polygon(points) -> QPolygonF:
    return QPolygonF([QPointF(float(x), float(y)) for x, y in np.asarray(points)[:, :2]])


def thumbnail_pixels(layer, light, shader, size: int = 48):
    """The shaded pixels of a layer's thumbnail, (size, size, 3) uint8, or None without a mesh.
    Numpy only, so it may run off the GUI thread (a big layer's takes a few tenths of a second)."""
    if layer.mesh is None or not layer.mesh.n_faces:
        return None
    bg = (THUMB_BACKGROUND.redF(), THUMB_BACKGROUND.greenF(), THUMB_BACKGROUND.blueF())
    return render_top([layer.mesh], np.asarray(light.direction), size, shader=shader.shade, background=bg,
                      margin=4.0 / size)


def layer_thumbnail(layer, light, shader, size: int = 48, rgb=None, placeholder: bool = False) -> QPixmap:
    """A small picture of one layer: its shaded mesh, or its stroke, fitted with a margin.
    ``rgb``: the pixels from :func:`thumbnail_pixels`, computed already; ``placeholder``: draw
    the stroke only, until they are."""
    image = QImage(size, size, QImage.Format.Format_ARGB32_Premultiplied)
    image.fill(THUMB_BACKGROUND)
    if rgb is None and not placeholder:
        rgb = thumbnail_pixels(layer, light, shader, size)
    if rgb is not None:
        shaded = QImage(np.ascontiguousarray(rgb).data, size, size, 3 * size, QImage.Format.Format_RGB888)
        image = shaded.convertToFormat(QImage.Format.Format_ARGB32_Premultiplied)  # a copy: rgb may go
    painter = QPainter(image)
    painter.setPen(QPen(QColor(180, 180, 180)))
    painter.drawRect(0, 0, size - 1, size - 1)
    pts = None
    if rgb is None and layer.points is not None and len(layer.points):
        pts = layer.points
    if pts is not None:
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        ext = float(max(hi[0] - lo[0], hi[1] - lo[1], 1e-9))
        k = (size - 8) / ext
        cx, cy = 0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])
        # document (x right, y up) -> pixels (x right, y down), centred
        painter.setTransform(QTransform(k, 0, 0, -k, size / 2 - k * cx, size / 2 + k * cy))
        pen = QPen(QColor(40, 60, 120))
        pen.setCosmetic(True)
        painter.setPen(pen)
        painter.setBrush(NO_MESH_FILL)
        painter.drawPolygon(points_polygon(pts))
    painter.end()
    return QPixmap.fromImage(image)


def polygon_rings(geom) -> list[np.ndarray]:
    """Exterior and interior rings of a shapely (Multi)Polygon as (k, 2) arrays."""
    if geom is None or getattr(geom, "is_empty", True):
        return []
    rings = []
    for poly in getattr(geom, "geoms", [geom]):
        if poly.geom_type == "Polygon":
            rings.append(np.asarray(poly.exterior.coords))
            rings.extend(np.asarray(r.coords) for r in poly.interiors)
        elif hasattr(poly, "geoms") or poly.geom_type in ("MultiPolygon", "GeometryCollection"):
            rings.extend(polygon_rings(poly))
        elif poly.geom_type in ("LineString", "LinearRing"):
            rings.append(np.asarray(poly.coords))
    return rings


def bounds_rect(arrays) -> QRectF | None:
    pts = [np.asarray(a)[:, :2] for a in arrays if a is not None and len(a)]
    if not pts:
        return None
    allp = np.concatenate(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    return QRectF(float(lo[0]), float(lo[1]), float(hi[0] - lo[0]), float(hi[1] - lo[1]))
