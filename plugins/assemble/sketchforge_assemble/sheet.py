"""A layer's planar mesh, shared by its front and back faces.

Every layer is a height field over the drawing plane, so its front face (heights ``+z``) and
back face (``-z``, reversed triangles) share one planar mesh; the assembly works on that planar
mesh ("sheet") and only builds 3D faces at the end (:mod:`.stitch`). A layer with parts glued
to both faces (a near leg in front of the body, a far leg behind it, issue 34) has one
triangulation per face over one vertex table (``F`` and ``Fb``), so the junctions cut into
the front never meet those cut into the back.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import shapely

from sketchforge.plugin_api import Mesh, SketchforgeError, guard


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
    marks : (j0,) int64 or None
        Where each vertex of the junction as drawn (the layer's mesh) sits in ``junction``
        when the sheet was re-meshed finer (:func:`refine_thin`); None: the junction is the
        one drawn.
    Fb : (mb, 3) int64 or None
        The back face's own triangulation (counter-clockwise seen from +z, like ``F``) when
        both faces have junctions cut in; None when the back face is ``F`` too. A vertex may
        then be used by one face only (a junction's points are on their face alone).
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
    Fb: np.ndarray | None = None
    marks: np.ndarray | None = None

    @property
    def n(self) -> int:
        return int(len(self.xy))

    def face(self, side: int) -> np.ndarray:
        """(m, 3) int64: the triangulation of the front face (``side`` 1) or the back face
        (-1), counter-clockwise seen from +z."""
        return self.F if side > 0 or self.Fb is None else self.Fb

    def on_face(self, side: int) -> np.ndarray:
        """(n,) bool: the vertices the face ``side`` uses (all of them on a sheet with one
        triangulation)."""
        if self.Fb is None:
            return np.ones(self.n, bool)
        used = np.zeros(self.n, bool)
        used[self.face(side)] = True
        return used

    def polygon(self) -> shapely.Polygon:
        """The layer's region Ω in the drawing plane, holes cut out (made valid by
        :func:`guard.polygon` if its outline touches itself); made once per sheet value."""
        got = self.__dict__.get("_polygon")
        if got is None:
            got = self._make_polygon()
            object.__setattr__(self, "_polygon", got)
        return got

    def _make_polygon(self) -> shapely.Polygon:
        outer = guard.polygon(self.xy[self.boundary], f"the outline of layer '{self.name}'")
        if not self.holes:
            return outer
        cut = shapely.union_all([guard.polygon(self.xy[h], f"a hole of layer '{self.name}'") for h in self.holes])
        return guard.geometry(shapely.difference(outer, cut), f"the outline of layer '{self.name}'")

    def drawn_junction(self) -> np.ndarray:
        """(j0,) int64: the vertices of the junction as drawn (every one of ``junction`` unless
        the sheet was re-meshed finer)."""
        return self.junction if self.marks is None else self.junction[self.marks]

    def glue_stretch(self, first: int, last: int) -> np.ndarray:
        """(k,) int64: the junction from drawn vertex ``first`` to ``last`` (inclusive), with the
        vertices a finer re-meshing put between them."""
        if self.marks is None:
            return self.junction[first:last + 1]
        return self.junction[self.marks[first]:self.marks[last] + 1]

    def evolve(self, **changes) -> Sheet:
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


#: A part's rim vertices (its outline off the glued junction, and its holes' rims) are lifted
#: off the drawing plane, front up and back down, by this share of the mean height of their
#: neighbours off the rim (issue 34: seen edge-on, a part's outline was a point). Why: the
#: inflated profile z ~ √distance turns by 90° between the rim and its first ring of vertices,
#: and with the rim's front and back vertices a margin (0.2 edge lengths) apart that turn fell
#: on one point of the silhouette, a corner of 26-33° on every limb (2-10° inside a part).
#: Lifted to a fifth of the first ring's height, which lies on the same profile (√ of a
#: distance 1/25 of the first ring's), the turn is split into two corners a band apart, each
#: ~15-20°: the polygon closest to the round profile without a vertex more (0.3: 20-23°).
RIM_LIFT = 0.2


def rim_lift(sheet: Sheet) -> np.ndarray:
    """(n,) float64 >= 0: how far each vertex of ``sheet`` is lifted off its plane on both faces
    for its rim (:data:`RIM_LIFT` times the mean height of a rim vertex's neighbours off the
    rim; at an ear's tip, with every neighbour on the rim, the highest of them), 0 off the rim
    and on the junction's inner vertices (glued, not bridged); apply :func:`taper` on top, as
    for the margin."""
    n = sheet.n
    rim = np.zeros(n, bool)
    rim[sheet.boundary] = True
    for hole in sheet.holes:
        rim[hole] = True
    if len(sheet.junction) > 2:
        rim[sheet.junction[1:-1]] = False
    E = np.vstack([sheet.F[:, [0, 1]], sheet.F[:, [1, 2]], sheet.F[:, [2, 0]]])
    E = np.vstack([E, E[:, ::-1]])
    E = E[rim[E[:, 0]]]
    inner = ~rim[E[:, 1]]
    total = np.bincount(E[inner, 0], weights=sheet.z[E[inner, 1]], minlength=n)
    count = np.bincount(E[inner, 0], minlength=n)
    top = np.zeros(n)
    np.maximum.at(top, E[:, 0], sheet.z[E[:, 1]])
    ring = np.where(count > 0, total / np.maximum(count, 1), top)
    return np.where(rim, RIM_LIFT * ring, 0.0)


def end_taper(xy: np.ndarray, ends: np.ndarray, radius: float) -> np.ndarray:
    """(n,) float64 in [0, 1]: 0 at the junction's two end points ``ends`` (2, 2), 1 from
    ``radius`` on."""
    d = np.min(np.linalg.norm(xy[:, None, :] - ends[None, :, :], axis=2), axis=1)
    return np.clip(d / radius, 0.0, 1.0)


#: A part whose height is less than this many of its edge lengths is re-meshed finer for the
#: assembly (:func:`refine_thin`).
THIN_HEIGHT_EDGES = 5.0
#: ... but never finer than this share of its own edge length.
MAX_REFINE = 4.0


def refine_thin(sheet: Sheet, min_height_edges: float = THIN_HEIGHT_EDGES) -> Sheet:
    """The sheet of a thin part, re-meshed so that its height spans ``min_height_edges`` edges.

    Why. A tail, an ear or a beak drawn at the document's resolution is often only three or
    four triangles across (its height z_max a few edge lengths). The junction's fillet and the
    fairing work over rings of triangles, so on such a part they reach across all of it: the
    fairing folded or crossed every thin part of the Monster-Mash-style corpus (issue 34; the
    parts 5 edge lengths high and more never did). Finer triangles give the blend room. Only
    the assembled model changes: the layer keeps its own mesh (and sculpt edits) in the
    document.

    How. The outline (and every hole) keeps its vertices and gets more between them, at the
    new edge length h' = max(z_max / ``min_height_edges``, h / :data:`MAX_REFINE`); Triangle
    meshes the inside at h' (:func:`sketchforge.geometry.triangulate.triangulate_polygon`); the
    new vertices take u = z² interpolated linearly from the old mesh (u is smooth where z ~ √d
    near the rim is not), z = √u. The junction is the same stretch of outline, with its new
    points. A sheet that is not thin, or has no junction, is returned as it is.
    """
    from sketchforge.plugin_api import TriangleLocator, triangulate_polygon

    if len(sheet.junction) < 2 or sheet.chains or sheet.Fb is not None:
        return sheet
    zmax = float(sheet.z.max(initial=0.0))
    h = sheet.h
    if zmax <= 0 or zmax >= min_height_edges * h:
        return sheet
    h2 = max(zmax / min_height_edges, h / MAX_REFINE)

    def densify(loop: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(points (k', 2), position of each old loop vertex in it)."""
        P = sheet.xy[loop]
        Q = np.roll(P, -1, axis=0)
        n = np.maximum(np.ceil(np.linalg.norm(Q - P, axis=1) / h2).astype(np.int64), 1)
        t = np.concatenate([np.arange(k) / k for k in n])
        src = np.repeat(np.arange(len(P)), n)
        pts = P[src] + t[:, None] * (Q[src] - P[src])
        return pts, np.r_[0, np.cumsum(n)[:-1]]

    outline, at = densify(sheet.boundary)
    rings = [densify(hole) for hole in sheet.holes]
    if not shapely.Polygon(outline, [r[0] for r in rings]).is_valid:
        return sheet  # a hand-edited snapshot's outline: the assembly's own checks say what is wrong
    try:
        tri = triangulate_polygon(outline, h2, holes=[r[0] for r in rings])
    except (SketchforgeError, RuntimeError):
        # Triangle refused a valid-looking outline (it raises here, after guard.pslg): the
        # part is assembled at its own resolution, as before this refinement existed
        return sheet
    xy = np.ascontiguousarray(tri.V2)
    F = ccw_triangles(xy, tri.F)
    xy, F = guard.mesh(xy, F, f"the mesh of layer '{sheet.name}', refined", planar=True)
    face, bary = TriangleLocator(sheet.xy, sheet.F).locate(xy, nearest=True)
    u = np.sum(bary * (sheet.z[sheet.F[np.maximum(face, 0)]] ** 2), axis=1)
    z = np.sqrt(np.maximum(u, 0.0))
    k = len(outline)
    z[:k] = 0.0  # the outline, junction included, stays at 0 like every inflated rim
    boundary = np.arange(k, dtype=np.int64)
    # the junction: the same stretch of the outline, walked the same way
    pos = {int(v): i for i, v in enumerate(sheet.boundary)}
    if any(int(v) not in pos for v in sheet.junction[[0, 1, -1]]):
        return sheet
    a, b = pos[int(sheet.junction[0])], pos[int(sheet.junction[1])]
    forward = (b - a) % len(sheet.boundary) == 1
    start, end = at[pos[int(sheet.junction[0])]], at[pos[int(sheet.junction[-1])]]
    if forward:
        junction = np.arange(start, start + (end - start) % k + 1) % k
    else:
        junction = (start - np.arange(0, (start - end) % k + 1)) % k
    where = {int(v): i for i, v in enumerate(junction)}
    marks = np.array([where.get(int(at[pos[int(v)]]), -1) if int(v) in pos else -1 for v in sheet.junction], np.int64)
    if np.any(marks < 0) or np.any(np.diff(marks) <= 0):
        # the junction is not one stretch of the outline walked in order (a hand-edited
        # snapshot): left as it is, for the attachment's checks to name
        return sheet
    holes = []
    first = k
    for pts, _ in rings:
        holes.append(oriented_loop(F, np.arange(first, first + len(pts), dtype=np.int64)))
        first += len(pts)
    if not has_directed_edge(F, boundary[0], boundary[1]):
        boundary = boundary[::-1].copy()
    E = directed_edges(F)
    h_new = float(np.median(np.linalg.norm(xy[E[:, 0]] - xy[E[:, 1]], axis=1)))
    return sheet.evolve(xy=xy, z=z, F=F, boundary=boundary, junction=junction.astype(np.int64), h=h_new,
                        holes=tuple(holes), marks=marks)
