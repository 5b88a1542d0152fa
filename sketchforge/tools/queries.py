"""Questions a tool (and a test) asks of a document: which layer lies under a point and which
isophote runs through a pick. No Qt; public through :mod:`sketchforge.plugin_api` (and the
pytest plugin's fixtures).

The isophote is computed as the app shows the shading and the isophote tool picks it: R of
the reflectance model at the slopes of the layer's display normals
(:func:`~sketchforge.geometry.heightfield.slopes_from_heights`), the isovalue at the pick (0
in shadow: the terminator), marching triangles, the component nearest to the pick.
"""

from __future__ import annotations

import numpy as np

from sketchforge.errors import SculptError


def layer_at(doc, point) -> str | None:
    """The id of the front-most visible layer whose surface lies under ``point``, or None.

    Parameters
    ----------
    doc : Document
    point : (2,) float64
        A point of the drawing plane (document units).

    Returns
    -------
    str or None
        A point in a layer's hole is not on that layer; a layer without a mesh is skipped.
    """
    import shapely

    p = np.asarray(point, dtype=np.float64).reshape(-1)
    if p.shape != (2,) or not np.all(np.isfinite(p)):
        return None
    where = shapely.Point(p)
    for layer in reversed(doc.layers):
        mesh = layer.mesh
        if not layer.visible or mesh is None or len(mesh.boundary) < 3:
            continue
        V2 = mesh.V[:, :2]
        try:
            region = shapely.Polygon(V2[mesh.boundary], [V2[h] for h in mesh.holes if len(h) >= 3])
        except (ValueError, shapely.errors.GEOSException):
            continue
        if region.is_valid and region.covers(where):
            return layer.id
    return None


def isophote_through(mesh, pick, light, model=None) -> tuple[float, np.ndarray]:
    """The isophote through a pick on a layer's surface.

    Parameters
    ----------
    mesh : Mesh
        A layer's front surface (a height field with its rim).
    pick : (2,) float64
        The picked point, on the layer.
    light : (3,) float64
        Unit direction towards the light (``doc.light.direction``).
    model : ReflectanceModel, optional
        The reflectance model (None: Lambertian).

    Returns
    -------
    c : float
        The isovalue: R at the pick, 0 for a pick in shadow (the terminator).
    polyline : (k, 2) float64
        The component of the level set R = c nearest to the pick, brighter side on its left.

    Raises
    ------
    SculptError
        A pick off the layer, or no isophote there.
    """
    from sketchforge.geometry.heightfield import slopes_from_heights
    from sketchforge.geometry.intensity import gradient_operators
    from sketchforge.geometry.isophotes import isophotes, isovalue_at, select_isophote
    from sketchforge.geometry.reflectance import LAMBERTIAN, evaluate_pq

    V2 = np.ascontiguousarray(mesh.V[:, :2], dtype=np.float64)
    Gp, Gq = gradient_operators(V2, mesh.F)
    p, q = slopes_from_heights(Gp, Gq, np.asarray(mesh.V[:, 2], dtype=np.float64))
    E, _, _ = evaluate_pq(model or LAMBERTIAN, p, q, np.asarray(light, dtype=np.float64).reshape(3))
    c = isovalue_at(mesh, E, pick)
    lines, _ = isophotes(V2, mesh.F, E, c)
    lines = [line for line in lines if len(line) > 1]
    if not lines:
        raise SculptError(f"no isophote runs through the pick at R = {c:.3g}")
    return c, np.asarray(lines[select_isophote(lines, np.asarray(pick, np.float64).reshape(2))], dtype=np.float64)
