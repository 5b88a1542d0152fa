"""Shared helpers for the isophote sculpt tests: strokes offset from an isophote, fidelity."""

from __future__ import annotations

import numpy as np
import shapely
import shapely.ops

from sketchforge.plugin_api import LAMBERTIAN, isophote_through, isophotes, layer_normals
from sketchforge_isophote_tool.fidelity import honoured_samples, mean_distance
from sketchforge_isophote_tool.isophote import picked_isophote
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.testing import LIGHT


def isophote_stroke(mesh, pick, offset=0.0, half=0.25, light=LIGHT):
    """A stroke along the isophote through ``pick`` (length 2·half), offset sideways (> 0: towards
    the darker side)."""
    c, line = isophote_through(mesh, pick, light)  # the public helper (as the isophote tool picks)
    iso = shapely.LineString(line)
    s0 = iso.project(shapely.Point(pick))
    seg = shapely.ops.substring(iso, max(s0 - half, 0.0), min(s0 + half, iso.length))
    if offset:
        # The isophote runs with the brighter side on its left (core convention), so a
        # positive offset moves the stroke towards the darker side.
        seg = seg.offset_curve(-offset)
        # GEOS can leave a stray 2-point fragment on the concave side: keep the main curve.
        seg = max(getattr(seg, "geoms", [seg]), key=lambda g: g.length)
    return np.asarray(seg.coords), c, iso


def fidelity(result, light=LIGHT):
    """(mean distance stroke -> old isophote, mean distance stroke -> new c-isophote, h) at the
    stroke samples the edit honours. The new shading is the one the app draws (the display's
    vertex normals, ``layer_normals``), marched with the core's ``isophotes``: not the
    solver's own slope operators, so a mismatch between the two would show here."""
    pd = result.layer.planar
    pieces = [np.asarray(g.coords) for g in getattr(result.stroke, "geoms", [result.stroke])]
    P = honoured_samples(pd, pieces, result.band)
    E = layer_normals(result.mesh) @ np.asarray(light, dtype=np.float64)
    lines = [L for L in isophotes(result.mesh.V[:, :2], result.mesh.F, E, result.c)[0] if len(L) > 1]
    return mean_distance(P, result.isophote), mean_distance(P, shapely.MultiLineString(lines)), pd.h


def stroke_moving_only_in_the_margin(mesh, pick, shift_edges):
    """The isophote through ``pick`` from the pick to the rim, the part inside the rim margin
    moved sideways by ``shift_edges`` edge lengths, the rest left on the isophote."""
    ld = layer_data(mesh, LIGHT, LAMBERTIAN)
    pd = ld.planar
    _, iso = picked_isophote(ld, pick)
    s0 = iso.project(shapely.Point(pick))
    seg = shapely.ops.substring(iso, s0, iso.length)
    P = np.array([seg.interpolate(t, normalized=True).coords[0] for t in np.linspace(0, 1, 200)])
    d = np.gradient(P, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    normal = np.column_stack([-d[:, 1], d[:, 0]])
    inside_margin = pd.rim_distance(P) < pd.margin_at(P)
    # The move fades in over the margin's first edge length (a hand would not jump).
    depth = pd.margin_at(P) - pd.rim_distance(P)
    move = np.clip(depth / pd.h, 0.0, 1.0) * shift_edges * pd.h
    assert inside_margin.any() and (~inside_margin).sum() > 10
    return P + move[:, None] * normal, ld
