"""Shared helpers for the isophote sculpt tests: strokes offset from an isophote, fidelity."""

from __future__ import annotations

import numpy as np
import shapely
import shapely.ops

from sketchforge.geometry.isophotes import isophotes
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool.isophote import picked_isophote
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.testing import LIGHT


def isophote_stroke(mesh, pick, offset=0.0, half=0.25, light=LIGHT):
    """A stroke along the isophote through ``pick`` (length 2·half), offset sideways (> 0: towards
    the darker side)."""
    ld = layer_data(mesh, light, LAMBERTIAN)
    c, iso = picked_isophote(ld, pick)
    s0 = iso.project(shapely.Point(pick))
    seg = shapely.ops.substring(iso, max(s0 - half, 0.0), min(s0 + half, iso.length))
    if offset:
        # The isophote runs with the brighter side on its left (core convention), so a
        # positive offset moves the stroke towards the darker side.
        seg = seg.offset_curve(-offset)
        # GEOS can leave a stray 2-point fragment on the concave side: keep the main curve.
        seg = max(getattr(seg, "geoms", [seg]), key=lambda g: g.length)
    return np.asarray(seg.coords), c, iso


def stroke_points(stroke_geom, step):
    return np.concatenate([np.asarray(shapely.segmentize(g, step).coords) for g in getattr(stroke_geom, "geoms", [stroke_geom])])


def fidelity(result, light=LIGHT):
    """(mean distance stroke -> old isophote, mean distance stroke -> new c-isophote, h, new lines),
    measured at stroke samples inside B•*."""
    ld = layer_data(result.mesh, light, LAMBERTIAN)
    lines = [L for L in isophotes(ld.V2, result.mesh.F, ld.E, result.c)[0] if len(L) > 1]
    new = shapely.MultiLineString(lines)
    P = stroke_points(result.stroke, 0.5 * ld.h)
    P = P[shapely.contains_xy(result.regions.B_star, P[:, 0], P[:, 1])]
    pts = shapely.points(P)
    return float(shapely.distance(pts, result.isophote).mean()), float(shapely.distance(pts, new).mean()), ld.h, lines
