"""The band around a selected isophote: where the person may redraw it (thesis 4.3)."""

from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LineString

from sketchforge.errors import GeometryError, SculptError
from sketchforge.geometry import guard


def band_radius(radius) -> float:
    """A band radius as a float: a positive number of at most the drawing's coordinate range.

    The one check of the sculpt tool, the pipeline and :func:`band`, so a radius is refused with
    the same sentence wherever it is given.

    Raises
    ------
    SculptError
        Not a number, not positive (NaN included), or above ``guard.MAX_COORDINATE`` (1e9).
    """
    try:
        r = float(radius)
    except (TypeError, ValueError, OverflowError):
        raise SculptError(f"the band radius must be a number, got {radius!r}") from None
    if not (math.isfinite(r) and r > 0.0):
        raise SculptError(f"the band radius must be a positive number, got {radius}")
    if r > guard.MAX_COORDINATE:
        raise SculptError(f"the band radius {r:.3g} is too large; it must be at most {guard.MAX_COORDINATE:.0e} drawing units")
    return r


def band(polyline: np.ndarray, radius: float, outline: np.ndarray):
    """Minkowski sum of the isophote with a disk, clipped to the layer's outline.

    Parameters
    ----------
    polyline : (k, 2+) float64
        The selected isophote in the drawing plane (extra columns ignored); a closed one repeats
        its first point at the end.
    radius : float
        Band radius in drawing units, > 0.
    outline : (b, 2+) float64
        The layer's outline polygon (e.g. ``mesh.V[mesh.boundary, :2]``), either orientation,
        closing point optional.

    Returns
    -------
    shapely Polygon or MultiPolygon
        The band; non-empty.

    Raises
    ------
    SculptError
        For a radius :func:`band_radius` refuses, an isophote with fewer than two distinct
        points, or a band that misses the outline.
    GeometryError
        Non-finite or huge coordinates in the isophote, the outline or the band (checked by
        :mod:`guard` before GEOS sees them).
    """
    r = band_radius(radius)
    line = guard.points(np.asarray(polyline, dtype=np.float64)[:, :2], "the selected isophote")
    if len(line) < 2 or not np.any(line != line[0]):
        raise SculptError("the selected isophote is a single point; pick another isophote")
    out = np.asarray(outline, dtype=np.float64)[:, :2]
    try:
        region = guard.polygon(out, "the layer's outline")
    except GeometryError:
        # Only a refused outline is looked at again: with finite coordinates it was refused
        # for having fewer than 3 distinct points, which is a layer with nothing to clip to.
        if len(np.unique(guard.points(out, "the layer's outline"), axis=0)) < 3:
            raise SculptError("the layer has no outline to clip the band to") from None
        raise
    # Round joins and caps make the buffer the exact Minkowski sum with a disk (up to the
    # polygonal approximation of the arcs, 16 segments per quarter circle). band_radius() keeps
    # the radius within the drawing's range (at 1e300 GEOS threw a TopologyException from inside
    # the buffer), but a disk of radius 1e9 around a point at x = 0.5 still reaches past it. A
    # band wider than twice the extent of the isophote and the outline together already covers
    # the whole layer (the polygonal arcs reach cos(π/64) > 0.99 of the radius), so the radius is
    # capped there: the same band, continuous in the radius, of the drawing's size.
    lo = np.minimum(line.min(axis=0), region.bounds[:2])
    hi = np.maximum(line.max(axis=0), region.bounds[2:])
    r = min(r, 2.0 * float(np.hypot(*(hi - lo))))
    swept = guard.geometry(LineString(line).buffer(r, quad_segs=16), "the band")
    result = swept.intersection(region)
    result = shapely.make_valid(result)
    parts = getattr(result, "geoms", [result])
    polys = [g for g in parts if g.geom_type in ("Polygon", "MultiPolygon")]
    if not polys or all(p.is_empty for p in polys):
        raise SculptError("the band does not overlap the layer")
    if len(polys) == 1:
        return polys[0]
    return shapely.union_all(polys)
