"""Drawing a layer's shaded mesh with QPainter: the canvas items and the layer thumbnails.

The colours come from the geometry core (face normals) and a registered display shader; this
module only turns arrays into Qt polygons and colours, and fits a drawing into a thumbnail
(a coordinate mapping, flipping the document's upward y to Qt's downward one).
"""

from __future__ import annotations

import weakref

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QBrush, QColor, QImage, QPainter, QPen, QPixmap, QPolygonF, QTransform

from sketchforge.geometry.normals import face_normals

#: Fill for a layer that has a stroke but no mesh (no inflate plugin, or a failed inflation).
NO_MESH_FILL = QColor(200, 200, 210, 90)

_polygon_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_normal_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def mesh_polygons(mesh) -> list[QPolygonF]:
    """One QPolygonF per triangle (document coordinates), cached per Mesh object."""
    polys = _polygon_cache.get(mesh)
    if polys is None:
        tri = mesh.V[mesh.F][:, :, :2].tolist()
        polys = [QPolygonF([QPointF(a[0], a[1]), QPointF(b[0], b[1]), QPointF(c[0], c[1])]) for a, b, c in tri]
        _polygon_cache[mesh] = polys
    return polys


def mesh_face_normals(mesh) -> np.ndarray:
    N = _normal_cache.get(mesh)
    if N is None:
        N, _ = face_normals(mesh.V, mesh.F)
        _normal_cache[mesh] = N
    return N


def face_colours(mesh, light, shader) -> list[QColor]:
    """Flat shading: ``shader.shade`` of the face normals, as QColors."""
    rgb = shader.shade(mesh_face_normals(mesh), np.asarray(light.direction, dtype=np.float64))
    rgb8 = np.clip(np.rint(np.asarray(rgb) * 255.0), 0, 255).astype(np.int64).tolist()
    return [QColor(r, g, b) for r, g, b in rgb8]


def paint_mesh(painter: QPainter, polygons: list[QPolygonF], colours: list[QColor]) -> None:
    """Fill triangles with their colours. Antialiasing is off so shared edges leave no seams."""
    painter.save()
    painter.setRenderHint(QPainter.RenderHint.Antialiasing, False)
    painter.setPen(Qt.PenStyle.NoPen)
    brush = QBrush(Qt.BrushStyle.SolidPattern)
    for poly, colour in zip(polygons, colours):
        brush.setColor(colour)
        painter.setBrush(brush)
        painter.drawPolygon(poly)
    painter.restore()


def points_polygon(points) -> QPolygonF:
    return QPolygonF([QPointF(float(x), float(y)) for x, y in np.asarray(points)[:, :2]])


def layer_thumbnail(layer, light, shader, size: int = 48) -> QPixmap:
    """A small picture of one layer: its shaded mesh, or its stroke, fitted with a margin."""
    image = QImage(size, size, QImage.Format.Format_ARGB32_Premultiplied)
    image.fill(QColor(250, 249, 246))
    painter = QPainter(image)
    painter.setPen(QPen(QColor(180, 180, 180)))
    painter.drawRect(0, 0, size - 1, size - 1)
    pts = None
    if layer.mesh is not None and layer.mesh.n_faces:
        pts = layer.mesh.V[:, :2]
    elif layer.points is not None and len(layer.points):
        pts = layer.points
    if pts is not None:
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        ext = float(max(hi[0] - lo[0], hi[1] - lo[1], 1e-9))
        k = (size - 8) / ext
        cx, cy = 0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])
        # document (x right, y up) -> pixels (x right, y down), centred
        painter.setTransform(QTransform(k, 0, 0, -k, size / 2 - k * cx, size / 2 + k * cy))
        if layer.mesh is not None and layer.mesh.n_faces:
            paint_mesh(painter, mesh_polygons(layer.mesh), face_colours(layer.mesh, light, shader))
        else:
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
