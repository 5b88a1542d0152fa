"""The isophote an edit acts on (thesis 4.3), on a layer's cached data.

The steps themselves are the core's: :func:`~sketchforge.geometry.isophotes.isovalue_at` (c, 0 for
a pick in shadow), :func:`~sketchforge.geometry.isophotes.isophotes` (marching triangles),
:func:`~sketchforge.geometry.isophotes.select_isophote` and
:func:`~sketchforge.geometry.band.band`. What is sculpt-specific is only feeding them the cached
:class:`~.layerdata.LayerData` (its locator, shading and outline) and handing the pipeline
shapely geometry.
"""

from __future__ import annotations

import numpy as np
import shapely

from sketchforge.plugin_api import band, guard, isophotes, isovalue_at, select_isophote

from .layerdata import LayerData


def picked_isophote(ld: LayerData, pick) -> tuple[float, shapely.LineString]:
    """The isovalue at a pick and the component of its isophote nearest to the pick.

    Parameters
    ----------
    ld : LayerData
    pick : (2,) float64

    Returns
    -------
    c : float
        E at the pick, 0 for a pick in shadow.
    isophote : shapely LineString
        Brighter side on its left (see :func:`~sketchforge.geometry.isophotes.isophotes`).

    Raises
    ------
    SculptError
        A pick that is not a finite point inside the layer, or no isophote at c.
    """
    c = isovalue_at(ld.mesh, ld.E, pick, ld.locator)
    lines, _ = isophotes(ld.V2, ld.mesh.F, ld.E, c)
    i = select_isophote(lines, np.asarray(pick, np.float64).reshape(2))
    return c, shapely.LineString(lines[i])


def band_around(ld: LayerData, isophote: shapely.LineString, radius: float):
    """The band isophote ⊕ disk(radius), clipped to the layer (shapely (Multi)Polygon).

    Raises
    ------
    SculptError
        For a radius that is not a positive number.
    """
    region = band(np.asarray(isophote.coords), radius, np.asarray(ld.outline.exterior.coords))
    if len(ld.outline.interiors):  # a holed layer: the band stops at the holes' rims too
        region = guard.geometry(region.intersection(ld.outline), "the band")
    return region
