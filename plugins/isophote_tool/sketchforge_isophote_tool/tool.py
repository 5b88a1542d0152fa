"""The isophote sculpt gesture: click to pick an isophote, then draw its new path.

State machine (document coordinates, no Qt):
  press/release without moving  -> pick: the isovalue, the isophote and the band go to
                                   ``overlay`` for display
  press-move-release after a pick -> the stroke; on release a ``sculpt_isophote`` command is
                                   pushed and the tool returns to picking.
"""

from __future__ import annotations

import numpy as np

from sketchforge.tools.base import Tool

from .command import SculptIsophote


class SculptIsophoteTool(Tool):
    name = "sculpt_isophote"
    label = "Redraw isophote"

    def __init__(self, doc, layer: str | None = None, band: float = 0.3) -> None:
        super().__init__(doc)
        self.layer = layer
        self.band = float(band)
        self.pick: np.ndarray | None = None
        self._stroke: list[np.ndarray] = []
        self._pressed = False

    def _target(self, pos) -> str | None:
        if self.layer is not None:
            return self.layer
        import shapely

        from .layerdata import outline_polygon

        for lay in reversed(self.doc.layers):  # front first
            if lay.visible and lay.mesh is not None and outline_polygon(lay.mesh).contains(shapely.Point(pos)):
                return lay.id
        return None

    def press(self, pos) -> None:
        p = self.as_point(pos)
        self._pressed = True
        if self.pick is None:
            return
        self._stroke = [p]

    def move(self, pos) -> None:
        if self._pressed and self.pick is not None and self._stroke:
            self._stroke.append(self.as_point(pos))
            self.overlay["stroke"] = np.array(self._stroke)

    def release(self, pos):
        p = self.as_point(pos)
        self._pressed = False
        if self.pick is None:
            self._select(p)
            return None
        if len(self._stroke) < 2:  # a click after a pick re-picks
            self._stroke = []
            self._select(p)
            return None
        self._stroke.append(p)
        cmd = SculptIsophote(layer=self._active, pick=self.pick.tolist(), band=self.band,
                             stroke=np.array(self._stroke).tolist())
        self.pick, self._stroke, self.overlay = None, [], {}
        return self.doc.push(cmd)

    def _select(self, p) -> None:
        from sketchforge.geometry.reflectance import LAMBERTIAN

        from .isophote import band_around, picked_isophote
        from .layerdata import layer_data

        target = self._target(p)
        if target is None:
            self.overlay = {}
            return
        mesh = self.doc.layer(target).mesh
        ld = layer_data(mesh, self.doc.light.direction, LAMBERTIAN)
        c, iso = picked_isophote(ld, p)
        band = band_around(ld, iso, self.band)
        self._active, self.pick = target, p
        rings = [np.asarray(g.exterior.coords) for g in getattr(band, "geoms", [band]) if g.geom_type == "Polygon"]
        self.overlay = {"isovalue": c, "isophote": np.asarray(iso.coords), "band": rings}

    def cancel(self) -> None:
        self.pick, self._stroke, self.overlay = None, [], {}
