"""A layer's planar mesh, shared by its front and back faces.

Every layer is a height field over the drawing plane, so its front face (heights ``+z``) and
back face (``-z``, reversed triangles) share one planar mesh; the assembly works on that planar
mesh ("sheet") and only builds 3D faces at the end (:mod:`.stitch`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import shapely

from sketchforge.plugin_api import guard
from sketchforge.plugin_api import Mesh


@dataclass(frozen=True, eq=False)
class Sheet:
    """One layer's planar mesh and heights.

    Attributes
    ----------
    layer : int
        Index of the layer in the back-to-front list.
    name : str
        The layer's name, for messages.
    xy : (n, 2) float64
        Vertex positions in the drawing plane.
    z : (n,) float64
        The layer's height field (z >= 0, 0 on the outline).
    F : (m, 3) int64
        Triangles, counter-clockwise seen from +z.
    boundary : (k,) int64
        Outline loop, ordered so that ``(boundary[i], boundary[i+1])`` is an edge of ``F`` as
        ``F`` orients it (counter-clockwise).
    junction : (j,) int64
        This layer's own junction Γ_conn in order along the boundary; empty when the layer is
        a free part (closed outline, or a junction over empty space).
    chains : tuple of (c,) int64
        Junctions of other layers inserted into this sheet (see :mod:`.remesh`), in the order
        of the attachments that created them.
    h : float
        Median edge length, the sheet's resolution.
    holes : tuple of (k_i,) int64
        Hole loops, each ordered like ``boundary`` (``(hole[i], hole[i+1])`` is an edge of
        ``F`` as ``F`` orients it): the rim is bridged front to back along them too.
    """

    layer: int
    name: str
    xy: np.ndarray
    z: np.ndarray
    F: np.ndarray
    boundary: np.ndarray
    junction: np.ndarray
    h: float
    chains: tuple = field(default_factory=tuple)
    holes: tuple = field(default_factory=tuple)

    @property
    def n(self) -> int:
        return int(len(self.xy))

    def polygon(self) -> shapely.Polygon:
        """The layer's region Ω in the drawing plane, holes cut out (made valid by
        :func:`guard.polygon` if its outline touches itself)."""
        outer = guard.polygon(self.xy[self.boundary], f"the outline of layer '{self.name}'")
        if not self.holes:
            return outer
        cut = shapely.union_all([guard.polygon(self.xy[h], f"a hole of layer '{self.name}'") for h in self.holes])
        return guard.geometry(shapely.difference(outer, cut), f"the outline of layer '{self.name}'")

    def evolve(self, **changes) -> "Sheet":
        return replace(self, **changes)


def directed_edges(F: np.ndarray) -> np.ndarray:
    """(3m, 2) int64 directed half-edges of the triangles F (m, 3)."""
    return F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)


def unique_edges(F: np.ndarray) -> np.ndarray:
    """(e, 2) int64 undirected edges of the triangles F (m, 3), each sorted, no repeats."""
    return np.unique(np.sort(directed_edges(F), axis=1), axis=0)


def has_directed_edge(F: np.ndarray, a: int, b: int) -> bool:
    """Whether some triangle of F (m, 3) walks the edge a -> b."""
    E = directed_edges(F)
    return bool(np.any((E[:, 0] == a) & (E[:, 1] == b)))


def ccw_triangles(xy: np.ndarray, F: np.ndarray) -> np.ndarray:
    """F (m, 3) with every triangle turned counter-clockwise in the plane xy (n, 2)."""
    F = np.array(F, dtype=np.int64)
    e1 = xy[F[:, 1]] - xy[F[:, 0]]
    e2 = xy[F[:, 2]] - xy[F[:, 0]]
    cw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    F[cw] = F[cw][:, ::-1]
    return F


def sheet_from_mesh(layer: int, name: str, mesh: Mesh, free: bool) -> Sheet:
    """Build the sheet of one layer mesh.

    Parameters
    ----------
    layer : int
        Index in the back-to-front list.
    name : str
        The layer's name, for messages.
    mesh : Mesh
        The layer's front surface (``V`` (n,3), ``F`` (m,3), ``boundary``, ``junction``).
    free : bool
        Treat the part as free (ignore its junction).

    Raises
    ------
    GeometryError
        A vertex with a non-finite or huge coordinate, a face index out of range, or a triangle
        of zero area in the drawing plane (a hand-edited snapshot, see :func:`guard.mesh`):
        the sheet's coordinates go to GEOS, Triangle, libigl and OSQP, so they are checked
        once, here, in the plane where the sheet's operators live (every layer is a height
        field over it); the sheet keeps the checked arrays.
    """
    V, F = guard.mesh(mesh.V, mesh.F, f"the mesh of layer '{name}'", planar=True)
    xy = np.ascontiguousarray(V[:, :2])
    z = np.maximum(V[:, 2], 0.0)
    F = ccw_triangles(xy, F)
    boundary = np.array(mesh.boundary, dtype=np.int64)
    if len(boundary) >= 2 and not has_directed_edge(F, boundary[0], boundary[1]):
        boundary = boundary[::-1].copy()
    junction = np.zeros(0, np.int64) if free else np.array(mesh.junction, dtype=np.int64)
    if len(junction) < 2:
        junction = np.zeros(0, np.int64)
    holes = tuple(oriented_loop(F, np.array(r, dtype=np.int64)) for r in mesh.holes)
    E = directed_edges(F)
    h = float(np.median(np.linalg.norm(xy[E[:, 0]] - xy[E[:, 1]], axis=1)))
    return Sheet(layer, name, xy, z, F, boundary, junction, h, holes=holes)


def oriented_loop(F: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """``loop`` (k,) int64, reversed if needed so that its first edge is walked by F (m, 3)."""
    if len(loop) >= 2 and not has_directed_edge(F, loop[0], loop[1]):
        return loop[::-1].copy()
    return loop


def interior_on_left(sheet: Sheet) -> bool:
    """Whether the part lies to the left of its own junction walked in the stored order."""
    j = sheet.junction
    return has_directed_edge(sheet.F, j[0], j[1])


def taper(sheet: Sheet, radius_in_h: float = 3.0) -> np.ndarray:
    """(n,) float64 in [0, 1]: how much of the front/back margin a vertex gets.

    1 everywhere on a free part. On an attached part it falls to 0 at the two ends of the
    junction, where the front and back faces share one vertex (the ends of the slit they are
    glued into), over ``radius_in_h`` edge lengths so the rim does not kink.
    """
    if len(sheet.junction) == 0:
        return np.ones(sheet.n)
    return end_taper(sheet.xy, sheet.xy[sheet.junction[[0, -1]]], radius_in_h * sheet.h)


def end_taper(xy: np.ndarray, ends: np.ndarray, radius: float) -> np.ndarray:
    """(n,) float64 in [0, 1]: 0 at the junction's two end points ``ends`` (2, 2), 1 from
    ``radius`` on."""
    d = np.min(np.linalg.norm(xy[:, None, :] - ends[None, :, :], axis=2), axis=1)
    return np.clip(d / radius, 0.0, 1.0)
