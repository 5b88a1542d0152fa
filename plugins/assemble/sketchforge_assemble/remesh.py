"""Cut the junctions of attached parts into the face below (thesis 4.7, "make a hole").

The upper part's junction polyline is inserted into the lower sheet as constrained edges;
:mod:`.stitch` later splits the lower face along it into a slit whose two lips are glued to the
upper part's front and back junction chains. Only the lower layer's vertices within about half
an edge of a junction are removed, every other vertex keeps its position and its (possibly
sculpted) height; the inserted vertices get heights by a local RBF fit of the lower mesh.
"""

from __future__ import annotations

import numpy as np
import shapely
import triangle
from scipy.interpolate import RBFInterpolator

from sketchforge.plugin_api import format_point, guard

from .errors import AttachmentError
from .sheet import Sheet, ccw_triangles, has_directed_edge, oriented_loop


def rbf_heights(xy: np.ndarray, z: np.ndarray, query: np.ndarray, neighbors: int = 24) -> np.ndarray:
    """Heights at ``query`` (q, 2) from samples ``xy`` (n, 2), ``z`` (n,).

    A thin-plate-spline RBF with a linear term, fitted locally on the ``neighbors`` nearest
    samples (scipy builds one small system per query neighbourhood, so the cost stays linear
    in the number of queries). Thin-plate needs no kernel scale, unlike the multiquadric of
    thesis 4.6, and no smoothing: the inserted vertices must lie on the lower surface.
    """
    k = int(min(neighbors, len(xy)))
    rbf = RBFInterpolator(xy, z, neighbors=k, kernel="thin_plate_spline", degree=1)
    return np.maximum(rbf(query), 0.0)


def insert_chains(sheet: Sheet, chains_xy: list[np.ndarray], names: list[str], owners: list[int],
                  sides: list[int] | None = None) -> Sheet:
    """Insert junction polylines into a sheet as constrained edges.

    Parameters
    ----------
    sheet : Sheet
        The lower layer.
    chains_xy : list of (c, 2) float64
        One polyline per part attached to this sheet, in the order of the attachments.
    names : list of str
        Layer names, for messages.
    owners : list of int
        Layer index of each chain's part, for messages.
    sides : list of int, optional
        The face each chain is cut into (:data:`.attach.FRONT` or ``BACK``; default all
        FRONT). Junctions on one face must keep apart (the attachment rule sees to it); a
        junction on the front and one on the back may overlap, cross or lie on one line (a
        near leg and a far leg on one body, issue 34): when both faces get junctions, each is
        triangulated with its own (``F`` and ``Fb``), over one vertex table.

    Returns
    -------
    Sheet
        Same layer, re-triangulated, with ``chains`` holding the new vertex indices of each
        polyline in the given order (and ``Fb`` when both faces have junctions).

    Raises
    ------
    AttachmentError
        If the graph of the outline and one face's junctions is one Triangle cannot take,
        naming what is wrong and where: two junctions on one face of this layer cross or
        touch, a junction crosses or touches the layer's outline, a junction crosses or
        touches itself or passes through one point twice, or the layer's own outline crosses
        or touches itself or two of its vertices coincide (the last two only in a hand-edited
        snapshot).
    GeometryError
        A junction with non-finite or huge coordinates or fewer than 2 distinct points; a
        re-triangulation with a zero-area triangle (see :func:`guard.mesh`).
    """
    if not chains_xy:
        return sheet
    sides = [1] * len(chains_xy) if sides is None else list(sides)
    h = sheet.h
    lines = [guard.linestring(c, f"the junction of layer '{names[o]}'") for c, o in zip(chains_xy, owners)]
    for a in range(len(lines)):
        for b in range(a + 1, len(lines)):
            if sides[a] == sides[b] and lines[a].distance(lines[b]) < 0.5 * h:
                raise AttachmentError(
                    f"The junctions of layers '{names[owners[a]]}' and '{names[owners[b]]}' "
                    f"cross or touch on layer '{sheet.name}'; move one of them apart.", [owners[b]]
                )
    on_boundary = np.zeros(sheet.n, bool)
    on_boundary[sheet.boundary] = True
    for hole in sheet.holes:
        on_boundary[hole] = True
    faces = sorted(set(sides), reverse=True)  # FRONT (1) first
    # Interior vertices closer than ~half an edge to a junction make slivers: each face drops
    # the ones near its own junctions (a vertex dropped by one face only stays for the other).
    near = {}
    for f in faces:
        zone = shapely.union_all([ln.buffer(0.55 * h) for ln, sd in zip(lines, sides) if sd == f])
        near[f] = shapely.contains_xy(zone, sheet.xy[:, 0], sheet.xy[:, 1]) & ~on_boundary
    used = ~np.logical_and.reduce([near[f] for f in faces])
    kept = np.flatnonzero(used)
    new_index = np.full(sheet.n, -1, np.int64)
    new_index[kept] = np.arange(len(kept))
    # One vertex table: the kept vertices, then every chain's points in order.
    start = len(kept)
    chains, chain_pts = [], []
    for c in chains_xy:
        chains.append(np.arange(start, start + len(c)))
        chain_pts.append(np.asarray(c, np.float64))
        start += len(c)
    P_all = np.vstack([sheet.xy[kept]] + chain_pts)
    tris = {}
    for f in faces:
        mine = [i for i, sd in enumerate(sides) if sd == f]
        base = np.flatnonzero(~near[f])  # old indices of the vertices this face keeps
        tris[f] = _triangulate_face(sheet, base, [chains_xy[i] for i in mine], [owners[i] for i in mine], names,
                                    new_index, [chains[i] for i in mine])
    what = f"the mesh of layer '{sheet.name}' with its junctions cut in"
    P, F = guard.mesh(P_all, ccw_triangles(P_all, tris[faces[0]]), what)
    Fb = guard.mesh(P, ccw_triangles(P, tris[-1]), what)[1] if len(faces) == 2 else None
    z = np.empty(len(P))
    z[: len(kept)] = sheet.z[kept]
    z[len(kept):] = rbf_heights(sheet.xy, sheet.z, P[len(kept):])
    boundary = new_index[sheet.boundary]
    if not has_directed_edge(F, boundary[0], boundary[1]):
        boundary = boundary[::-1].copy()
    holes = tuple(oriented_loop(F, new_index[r]) for r in sheet.holes)
    return sheet.evolve(
        xy=P, z=z, F=F, Fb=Fb, boundary=boundary, junction=new_index[sheet.junction], chains=tuple(chains),
        holes=holes
    )


def _triangulate_face(sheet: Sheet, base: np.ndarray, chains_xy: list, owners: list[int], names: list[str],
                      new_index: np.ndarray, chain_ids: list[np.ndarray]) -> np.ndarray:
    """(m, 3) int64 triangles of one face, numbered in the sheet's new vertex table: a
    constrained Delaunay triangulation of the face's kept vertices ``base`` (old indices) and
    its junction polylines ``chains_xy`` (their new indices ``chain_ids``), with the outline and
    the holes as constrained loops."""
    local = np.full(sheet.n, -1, np.int64)
    local[base] = np.arange(len(base))
    pts = [sheet.xy[base]]
    rims = [sheet.boundary, *sheet.holes]  # the holes are kept as constrained loops too
    segs = [np.c_[local[r], np.roll(local[r], -1)] for r in rims]
    start = len(base)
    to_new = [new_index[base]]
    for c, ids in zip(chains_xy, chain_ids):
        idx = np.arange(start, start + len(c))
        pts.append(np.asarray(c, np.float64))
        segs.append(np.c_[idx[:-1], idx[1:]])
        to_new.append(ids)
        start += len(c)
    P = np.vstack(pts)
    S = np.vstack(segs)
    to_new = np.concatenate(to_new)
    chain_names = [names[o] for o in owners]
    # Who each vertex and segment of the graph belongs to, to name the culprit: chain c >= 0,
    # the outline (-1), an interior vertex of the lower layer (-2).
    part = np.r_[np.full(len(base), -2), np.repeat(np.arange(len(chains_xy)), [len(c) for c in chains_xy])]
    for r in rims:
        part[local[r]] = -1
    seg_part = np.r_[np.full(sum(len(r) for r in rims), -1),
                     np.repeat(np.arange(len(chains_xy)), [len(c) - 1 for c in chains_xy])]
    # Triangle's behaviour on crossing segments or duplicate vertices is undefined (it
    # segfaults), so the graph is checked first and what is wrong is reported with its owner.
    try:
        data, index = guard.pslg(P, S, None, what=f"layer '{sheet.name}' with its junctions cut in",
                                 return_index=True)
    except guard.PslgError as exc:
        if exc.points:  # a point on a segment that does not end there
            a, b = seg_part[exc.segments[0]], part[exc.points[0]]
        else:  # two segments that cross
            a, b = seg_part[exc.segments[0]], seg_part[exc.segments[1]]
        kind = "touch" if exc.points else "cross"
        raise AttachmentError(_culprit(kind, a, b, exc.at, sheet.name, chain_names),
                              [owners[c] for c in (a, b) if c >= 0]) from None
    if len(data["vertices"]) != len(P):
        # Every vertex must survive: the chains are glued vertex by vertex to their parts.
        i = int(np.argmax(index != np.arange(len(P))))  # the first point that merged into an earlier one
        j = int(np.argmax(index == index[i]))  # that earlier point
        raise AttachmentError(_culprit("merge", part[j], part[i], P[j], sheet.name, chain_names, guard.tolerance(P)),
                              [owners[c] for c in (part[j], part[i]) if c >= 0])
    if sheet.holes:
        # Triangle eats the triangles around one point strictly inside each hole.
        data["holes"] = guard.finite(
            [guard.polygon(sheet.xy[r], f"a hole of layer '{sheet.name}'").representative_point().coords[0]
             for r in sheet.holes], (len(sheet.holes), 2), "the hole points")
    # 'p': constrained Delaunay of the given points and segments, no quality refinement, so no
    # vertex is added (the segments were checked not to cross, no vertex lies on a segment).
    out = triangle.triangulate(data, "pQ")
    if "triangles" not in out:  # segments that enclose nothing: Triangle eats every triangle
        raise AttachmentError(
            f"The outline of layer '{sheet.name}' encloses no area once the junctions are cut in; redraw the layer."
        )
    return to_new[np.asarray(out["triangles"], np.int64)]


def _culprit(kind: str, a: int, b: int, at, lower: str, chain_names: list[str], tol: float = 0.0) -> str:
    """One sentence for a graph Triangle cannot take, naming who is at fault.

    ``kind``: "cross" (two segments cross), "touch" (a point lies on a segment that does not
    end there) or "merge" (two points coincide); ``a``, ``b``: the owners of the two things
    involved (chain c >= 0, the outline -1, an interior vertex of the lower layer -2); ``at``:
    where; ``tol``: the distance below which two points merge.
    """
    near = f" near {format_point(at)}"
    verb = "crosses" if kind == "cross" else "touches"
    if a >= 0 and a == b:
        what = {"cross": "crosses itself", "touch": "touches itself",
                "merge": f"has two points closer than {tol:.3g}"}[kind]
        return f"The junction of layer '{chain_names[a]}' {what}{near}; redraw the part."
    if a >= 0 and b >= 0:
        return (f"The junctions of layers '{chain_names[a]}' and '{chain_names[b]}' "
                f"{'cross' if kind == 'cross' else 'touch'} on layer '{lower}'{near}; move one of them apart.")
    if a < 0 and b < 0:
        if kind == "merge":
            return f"Two vertices of layer '{lower}' are closer than {tol:.3g}{near}; redraw the layer."
        if a == b == -1:
            return f"The outline of layer '{lower}' {verb} itself{near}; redraw the layer."
        return f"A vertex of layer '{lower}' lies on its outline{near}; redraw the layer."
    c, other = (a, b) if a >= 0 else (b, a)
    target = f"the outline of layer '{lower}'" if other == -1 else f"a vertex of layer '{lower}'"
    return (f"The junction of layer '{chain_names[c]}' {verb} {target}{near}; redraw the part so its ends lie "
            "inside the layer.")
