"""Per-layer data every step of an edit needs, computed once and cached.

Two levels, because an edit changes only heights:

:class:`PlanarData` depends on the layer's triangulation in the drawing plane (V2, F) only,
so it survives every edit of that layer: the gradient operators the slopes p, q come from,
the squared Laplacian, the lumped mass, the outline, a point locator, the distance of each
vertex to the outline and the layer's local width there, and the rim margin.

:class:`LayerData` adds what depends on the heights, the light and the reflectance model:
the shading E at every vertex.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.ndimage as ndi
import scipy.sparse as sp
import shapely
from scipy.spatial import cKDTree

from sketchforge.plugin_api import (
    LRUCache,
    Mesh,
    ReflectanceModel,
    TriangleLocator,
    array_key,
    evaluate_pq,
    gradient_operators,
    guard,
    laplacian_and_mass,
    slopes_from_heights,
    squared_laplacian_matrix,
)

#: Default rim margin: max(RIM_EDGES · h, RIM_SIZE · size), size = 2·area/perimeter.
RIM_EDGES = 3.0
RIM_SIZE = 0.12
#: Where the layer is thin, the rim margin is at most this fraction of the local half-width,
#: so a limb 0.2 wide keeps an editable middle (thesis ch. 5: Ω* vanished on thin parts).
RIM_WIDTH_FRACTION = 0.2


@dataclass
class PlanarData:
    """What an edit needs from a layer's triangulation in the drawing plane.

    Attributes
    ----------
    V2 : (n, 2) float64
    F : (m, 3) int64
    h : float
        Mean edge length.
    Gp, Gq : (n, n) scipy.sparse.csr_matrix float64
        Area-weighted vertex gradients
        (:func:`sketchforge.geometry.intensity.gradient_operators`); the slopes the app
        shades with are p = Gp z² / 2z, q = Gq z² / 2z
        (:func:`sketchforge.geometry.heightfield.slopes_from_heights`).
    Q : (n, n) scipy.sparse.csr_matrix float64
        Squared Laplacian Lᵀ M⁻¹ L (cotangent L, lumped M).
    mass : (n,) float64
        Lumped vertex areas.
    outline : shapely.Polygon
    locator : TriangleLocator
    is_contour : (n,) bool
    d_rim : (n,) float64
        Distance of each vertex to the outline.
    margin : float
        The layer's rim margin: max(3h, 0.12·size).
    margin_v : (n,) float64
        The rim margin at each vertex: ``margin``, or less where the layer is thin.
    width_grid : tuple
        ``(origin (2,), spacing, W (gx, gy))``: the local half-width sampled on a grid, for
        :meth:`margin_at`.
    """

    V2: np.ndarray
    F: np.ndarray
    h: float
    Gp: sp.csr_matrix
    Gq: sp.csr_matrix
    Q: sp.csr_matrix
    mass: np.ndarray
    outline: Any  # a shapely polygon (untyped)
    locator: TriangleLocator
    is_contour: np.ndarray
    d_rim: np.ndarray
    margin: float
    margin_v: np.ndarray
    width_grid: tuple

    def rim_distance(self, P: np.ndarray) -> np.ndarray:
        """Distance (k,) from points P (k, 2) to the outline (see :func:`distance_to_ring`)."""
        return distance_to_rim(np.asarray(P, np.float64).reshape(-1, 2), self.outline)

    def margin_at(self, P: np.ndarray) -> np.ndarray:
        """The rim margin (k,) at points P (k, 2) (see :func:`local_margin`)."""
        return local_margin(self.width_grid, self.margin, P)


@dataclass
class LayerData:
    """A layer under one light and reflectance model.

    Attributes
    ----------
    mesh : Mesh
    planar : PlanarData
    z : (n,) float64
    E : (n,) float64
        Signed shading R(p, q) per vertex: what the app shows.
    light : (3,) float64
    model : ReflectanceModel
    """

    mesh: Mesh
    planar: PlanarData
    z: np.ndarray
    E: np.ndarray
    light: np.ndarray
    model: ReflectanceModel

    # Shorthands for the planar fields the pipeline reads most.
    @property
    def V2(self) -> np.ndarray:
        return self.planar.V2

    @property
    def h(self) -> float:
        return self.planar.h

    @property
    def outline(self):
        return self.planar.outline

    @property
    def locator(self) -> TriangleLocator:
        return self.planar.locator

    @property
    def is_contour(self) -> np.ndarray:
        return self.planar.is_contour


def local_margin(width_grid: tuple, margin: float, P: np.ndarray) -> np.ndarray:
    """The rim margin (k,) at points P (k, 2): ``margin``, or RIM_WIDTH_FRACTION of the local
    half-width where that is less; bilinear in the width grid, so continuous in P."""
    origin, spacing, W = width_grid
    u = (np.asarray(P, np.float64).reshape(-1, 2) - origin) / spacing
    rho = ndi.map_coordinates(W, u.T, order=1, mode="nearest")
    return np.minimum(margin, RIM_WIDTH_FRACTION * rho)


def _width_grid(outline, h: float, reach: float) -> tuple:
    """Local half-width of the layer on a grid of spacing ~h/2: the largest distance to the
    outline within ``reach`` of each node (a max filter of the distance transform), so a thin
    limb reads its own half-width even next to its rim, and a large body reads at least
    ``reach``."""
    lo = np.array(outline.bounds[:2]) - 2 * h
    hi = np.array(outline.bounds[2:]) + 2 * h
    spacing = 0.5 * h
    # A grid of at most ~600² nodes whatever the layer: coarser spacing on huge layers.
    spacing = max(spacing, float((hi - lo).max()) / 600.0)
    nx, ny = (np.ceil((hi - lo) / spacing).astype(int) + 1).tolist()
    X, Y = np.meshgrid(lo[0] + spacing * np.arange(nx), lo[1] + spacing * np.arange(ny), indexing="ij")
    inside = shapely.contains_xy(outline, X, Y)
    D = ndi.distance_transform_edt(inside) * spacing
    r = max(int(np.ceil(reach / spacing)), 1)
    W = ndi.maximum_filter(D, size=2 * r + 1, mode="constant")
    return lo, spacing, W


def distance_to_ring(P: np.ndarray, ring: np.ndarray, k: int = 8) -> np.ndarray:
    """Distance (n,) from points P (n, 2) to a closed polyline ``ring`` (m+1, 2) (first point
    repeated): exact point-segment distances to the k segments with the nearest midpoints.
    Exact whenever the ring is sampled finer than the points are far from it, as a layer's
    outline is (shapely.distance took 150 ms for 19k vertices; this takes ~10)."""
    a, b = ring[:-1], ring[1:]
    tree = cKDTree(0.5 * (a + b))
    _, idx = tree.query(P, k=min(k, len(a)))
    idx = idx.reshape(len(P), -1)
    A, D = a[idx], (b - a)[idx]  # (n, k, 2)
    rel = P[:, None, :] - A
    t = np.clip(np.einsum("nkd,nkd->nk", rel, D) / np.maximum(np.einsum("nkd,nkd->nk", D, D), 1e-300), 0.0, 1.0)
    return np.linalg.norm(rel - t[..., None] * D, axis=2).min(axis=1)


def distance_to_rim(P: np.ndarray, outline) -> np.ndarray:
    """Distance (n,) from points P (n, 2) to the nearest ring of ``outline`` (a shapely
    Polygon): its exterior or any hole; every ring is rim, where the surface meets z = 0."""
    d = distance_to_ring(P, np.asarray(outline.exterior.coords))
    for hole in outline.interiors:
        d = np.minimum(d, distance_to_ring(P, np.asarray(hole.coords)))
    return d


def outline_polygon(mesh: Mesh):
    """The layer outline as a valid, counter-clockwise shapely Polygon, holes cut out."""
    poly = guard.polygon(mesh.V[mesh.boundary, :2], "the layer's outline")
    if poly.geom_type != "Polygon":
        poly = max(getattr(poly, "geoms", [poly]), key=lambda g: g.area)
    if mesh.holes:
        shell = np.asarray(poly.exterior.coords)
        poly = shapely.Polygon(shell, [mesh.V[h, :2] for h in mesh.holes])
        poly = guard.geometry(poly, "the layer's outline")
        if poly.geom_type != "Polygon":
            poly = max(getattr(poly, "geoms", [poly]), key=lambda g: g.area)
    return shapely.geometry.polygon.orient(poly, 1.0)


def _planar(mesh: Mesh) -> PlanarData:
    V2 = np.ascontiguousarray(mesh.V[:, :2])
    F = np.ascontiguousarray(mesh.F, dtype=np.int64)
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    h = float(np.linalg.norm(V2[e[:, 0]] - V2[e[:, 1]], axis=1).mean())
    # First: its guard refuses non-finite positions and zero-area faces before anything divides.
    L, M = laplacian_and_mass(V2, F, what="the layer's mesh")
    Gp, Gq = gradient_operators(V2, F)  # the display slopes are Gp z² / 2z (heightfield)
    outline = outline_polygon(mesh)
    is_contour = np.zeros(len(V2), bool)
    is_contour[mesh.rims] = True
    d_rim = distance_to_rim(V2, outline)
    d_rim[is_contour] = 0.0
    size = 2.0 * outline.area / outline.length
    margin = max(RIM_EDGES * h, RIM_SIZE * size)
    grid = _width_grid(outline, h, margin / RIM_WIDTH_FRACTION)
    return PlanarData(
        V2=V2,
        F=F,
        h=h,
        Gp=Gp,
        Gq=Gq,
        Q=squared_laplacian_matrix(L, M).tocsr(),
        mass=np.asarray(M.diagonal(), dtype=np.float64),
        outline=outline,
        locator=TriangleLocator(V2, F),
        is_contour=is_contour,
        d_rim=d_rim,
        margin=margin,
        margin_v=local_margin(grid, margin, V2),
        width_grid=grid,
    )


#: The app runs edits on worker threads (a preview still finishing while the command's solve
#: starts): the caches are thread-safe; the computations run outside their lock.
_PLANAR = LRUCache(8, name="planar data")
_CACHE = LRUCache(8, name="layer data")


def planar_data(mesh: Mesh) -> PlanarData:
    """Cached :class:`PlanarData` of a layer (keyed on its planar positions and triangles)."""
    return _PLANAR.get_or_make(array_key(mesh.V[:, :2], mesh.F, mesh.boundary), lambda: _planar(mesh))


def mesh_key(mesh: Mesh) -> bytes:
    return array_key(mesh.V, mesh.F, mesh.boundary)


def vertex_shading(pd: PlanarData, z: np.ndarray, light: np.ndarray, model: ReflectanceModel):
    """Shading E (n,) at the vertices for heights z (n,), with its slope gradient R_p, R_q (n,):
    R at the slopes of the layer's display normals
    (:func:`sketchforge.geometry.heightfield.slopes_from_heights`), what the app shows."""
    p, q = slopes_from_heights(pd.Gp, pd.Gq, z)
    return evaluate_pq(model, p, q, light)


def layer_data(mesh: Mesh, light: np.ndarray, model: ReflectanceModel) -> LayerData:
    """Cached :class:`LayerData` of ``mesh`` under ``light`` (3,) and ``model``."""
    light = np.asarray(light, np.float64).reshape(3)
    key = (mesh_key(mesh), light.tobytes(), model.name, id(model.R))

    def make() -> LayerData:
        pd = planar_data(mesh)
        z = np.array(mesh.V[:, 2])
        E, _, _ = vertex_shading(pd, z, light, model)
        return LayerData(mesh, pd, z, E, light, model)

    return _CACHE.get_or_make(key, make)
