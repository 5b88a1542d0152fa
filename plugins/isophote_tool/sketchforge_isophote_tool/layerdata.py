"""Per-layer data every step of an edit needs, computed once per (mesh, light, model).

p and q (from the vertex normals), the signed shading E per vertex, the outline polygon, the rim-margin region
Ω*, a point locator, and the smooth JAX grid fields (p, q and E). Cached on the mesh's bytes so
that a second edit on an unchanged layer (or undo/redo back to it) skips this work.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import scipy.ndimage as ndi
import shapely

from sketchforge.geometry import field_jax
from sketchforge.geometry.locate import TriangleLocator
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.normals import slopes, vertex_normals
from sketchforge.geometry.reflectance import evaluate_pq
from sketchforge.plugins.registry import ReflectanceModel


#: Smallest |n_z| used for p = -n_x/n_z: contour vertices' averaged normals are steep but must
#: stay finite (4.5: boundary normals come from the adjacent triangles). Twice the core's
#: default clamp: slopes at most 50, which the strip solvers' step sizes were tuned for.
MIN_NZ = 0.02


@dataclass
class LayerData:
    """Derived data of one layer under one light and reflectance model.

    Attributes
    ----------
    mesh : Mesh
    V2 : (n, 2) float64
    z : (n,) float64
    h : float
        Mean edge length (the mesh resolution).
    pq : (n, 2) float64
        Surface gradient from the area-weighted vertex normals.
    E : (n,) float64
        Signed shading R(n, l) per vertex.
    outline : shapely.Polygon
        The layer's contour.
    locator : TriangleLocator
        Point location on the layer (its ``interpolate`` snaps points just outside).
    raster : tuple
        ``(origin, spacing, face, bary)`` of the fixed-size grid (see field_jax).
    pq_field : field_jax.GridField
        Smooth p, q (2 channels).
    E_nodes : (G, G, 1) float64
        E sampled at the grid nodes (extended outside the outline).
    dist_nodes : (G, G) float64
        Approximate distance from each node to the outline, positive inside, 0 outside.
    is_contour : (n,) bool
    """

    mesh: Mesh
    V2: np.ndarray
    z: np.ndarray
    h: float
    pq: np.ndarray
    E: np.ndarray
    outline: object
    locator: TriangleLocator
    raster: tuple
    pq_field: object
    E_nodes: np.ndarray
    dist_nodes: np.ndarray
    is_contour: np.ndarray

    def omega_star(self, margin: float):
        """The layer minus a rim margin (shapely geometry)."""
        return self.outline.buffer(-margin)


_CACHE: "OrderedDict[tuple, LayerData]" = OrderedDict()
_CACHE_SIZE = 8


def mesh_key(mesh: Mesh) -> bytes:
    h = hashlib.blake2b(digest_size=16)
    for a in (mesh.V, mesh.F, mesh.boundary):
        h.update(a.tobytes())
    return h.digest()


def layer_data(mesh: Mesh, light: np.ndarray, model: ReflectanceModel) -> LayerData:
    """Cached :class:`LayerData` of ``mesh`` under ``light`` (3,) and ``model``."""
    key = (mesh_key(mesh), tuple(np.round(np.asarray(light, float), 15)), model.name, id(model.R))
    if key in _CACHE:
        _CACHE.move_to_end(key)
        return _CACHE[key]
    ld = _compute(mesh, np.asarray(light, np.float64), model)
    _CACHE[key] = ld
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return ld


def outline_polygon(mesh: Mesh):
    """The layer outline as a valid shapely Polygon."""
    loop = mesh.V[mesh.boundary, :2]
    poly = shapely.Polygon(loop)
    if not poly.is_valid:
        poly = shapely.make_valid(poly)
        if poly.geom_type != "Polygon":
            poly = max(getattr(poly, "geoms", [poly]), key=lambda g: g.area)
    return shapely.geometry.polygon.orient(poly, 1.0)


def _compute(mesh: Mesh, light: np.ndarray, model: ReflectanceModel) -> LayerData:
    V, F = mesh.V, mesh.F
    V2 = np.ascontiguousarray(V[:, :2])
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    h = float(np.linalg.norm(V2[e[:, 0]] - V2[e[:, 1]], axis=1).mean())
    N = vertex_normals(V, F)
    pq = np.column_stack(slopes(N, MIN_NZ))
    # E from the clamped slopes (not from N) so that E = R(p, q) holds exactly at every vertex.
    E = evaluate_pq(model, pq[:, 0], pq[:, 1], light)[0]
    raster = field_jax.layer_raster(V2, F)
    origin, spacing, face, bary = raster
    # p, q and E from the vertex normals, i.e. the shading the person sees. (Measured: strips
    # on this unchanged shading reproduce inflated layers' heights to 0.1-0.2% RMS, as well as
    # p, q, E derived from a B-spline of z; see the report in tests/test_sculpt.py.)
    nodes = field_jax.resample(np.column_stack([pq, E]), F, face, bary)
    pq_field = field_jax.grid_field_from_nodes(nodes[:, :, :2], origin, spacing)
    covered = face >= 0
    dist = ndi.distance_transform_edt(covered) * spacing
    is_contour = np.zeros(len(V), bool)
    is_contour[mesh.boundary] = True
    return LayerData(
        mesh=mesh,
        V2=V2,
        z=np.array(V[:, 2]),
        h=h,
        pq=pq,
        E=E,
        outline=outline_polygon(mesh),
        locator=TriangleLocator(V2, F),
        raster=raster,
        pq_field=pq_field,
        E_nodes=nodes[:, :, 2:3],
        dist_nodes=dist,
        is_contour=is_contour,
    )
