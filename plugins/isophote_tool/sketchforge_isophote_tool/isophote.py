"""Pick an isovalue, trace the isophote through the pick, build the band (thesis 4.3)."""

from __future__ import annotations

import numpy as np
import shapely

from sketchforge.errors import NothingToDoError, SculptError

from .layerdata import LayerData


def pick_value(ld: LayerData, pick: np.ndarray) -> float:
    """The isovalue c at a picked point: the signed shading there, 0 for a pick in shadow.

    Raises
    ------
    SculptError
        If the pick is not a finite point inside the layer.
    """
    pick = np.asarray(pick, np.float64).reshape(-1)
    if pick.shape != (2,) or not np.isfinite(pick).all():
        raise SculptError(f"the pick must be one finite point [x, y], got {pick.tolist()}")
    if not ld.outline.contains(shapely.Point(pick)):
        raise SculptError(f"the pick point ({pick[0]:.4g}, {pick[1]:.4g}) is outside the layer")
    e = float(ld.locator.interpolate(ld.E, pick[None])[0])
    # In shadow every point has R <= 0; the only isophote there that a stroke can move is the
    # terminator, so the edit acts on c = 0.
    return max(e, 0.0)


def isophote_lines(V2: np.ndarray, F: np.ndarray, E: np.ndarray, c: float) -> list[np.ndarray]:
    """Polylines of the piecewise-linear field E at value c (marching triangles).

    Parameters
    ----------
    V2 : (n, 2) float64
    F : (m, 3) int64
    E : (n,) float64
    c : float

    Returns
    -------
    list of (k, 2) float64 arrays, merged into maximal polylines.
    """
    s = E - c
    pos = s >= 0  # a vertex exactly at c counts as above: every crossing is well defined
    npos = pos[F].sum(axis=1)
    faces = F[(npos == 1) | (npos == 2)]
    if len(faces) == 0:
        return []
    pts = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        i, j = faces[:, a], faces[:, b]
        # Order each edge by vertex index so both triangles sharing it compute the same point.
        lo, hi = np.minimum(i, j), np.maximum(i, j)
        cross = pos[lo] != pos[hi]
        t = np.where(cross, s[lo] / np.where(cross, s[lo] - s[hi], 1.0), 0.0)
        p = V2[lo] + t[:, None] * (V2[hi] - V2[lo])
        pts.append((cross, p))
    segs = []
    for k in range(len(faces)):
        q = [p[k] for cross, p in pts if cross[k]]
        if len(q) == 2:
            segs.append(q)
    merged = shapely.line_merge(shapely.MultiLineString(segs))
    geoms = getattr(merged, "geoms", [merged])
    return [np.asarray(g.coords) for g in geoms if not g.is_empty]


def selected_isophote(lines: list[np.ndarray], pick: np.ndarray):
    """The isophote component nearest to the pick (shapely LineString)."""
    if not lines:
        raise NothingToDoError("the layer has no isophote at the picked value")
    geoms = [shapely.LineString(L) for L in lines if len(L) >= 2]
    d = shapely.distance(np.array(geoms, dtype=object), shapely.Point(pick))
    return geoms[int(np.argmin(d))]


def make_band(isophote, radius: float, outline):
    """Band = isophote ⊕ disk(radius), clipped to the layer (shapely Polygon/MultiPolygon)."""
    if not (np.isfinite(radius) and radius > 0):
        raise SculptError(f"the band radius must be a positive number, got {radius}")
    return isophote.buffer(radius, quad_segs=16).intersection(outline)
