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

from sketchforge.errors import GeometryError
from sketchforge.geometry import guard

from .errors import AttachmentError
from .sheet import Sheet, ccw_triangles, has_directed_edge


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


def insert_chains(sheet: Sheet, chains_xy: list[np.ndarray], names: list[str], owners: list[int]) -> Sheet:
    """Insert junction polylines into a sheet as constrained edges.

    Parameters
    ----------
    sheet : Sheet
        The lower layer.
    chains_xy : list of (c, 2) float64
        One polyline per part attached to this sheet (either face).
    names : list of str
        Layer names, for messages.
    owners : list of int
        Layer index of each chain's part, for messages.

    Returns
    -------
    Sheet
        Same layer, re-triangulated, with ``chains`` holding the new vertex indices of each
        polyline in the given order.

    Raises
    ------
    AttachmentError
        If two junctions on this layer cross or touch, or a junction crosses or touches the
        layer's outline.
    GeometryError
        A junction with non-finite or huge coordinates or fewer than 2 distinct points.
    """
    if not chains_xy:
        return sheet
    h = sheet.h
    lines = [guard.linestring(c, f"the junction of layer '{names[o]}'") for c, o in zip(chains_xy, owners)]
    for a in range(len(lines)):
        for b in range(a + 1, len(lines)):
            if lines[a].distance(lines[b]) < 0.5 * h:
                raise AttachmentError(
                    f"The junctions of layers '{names[owners[a]]}' and '{names[owners[b]]}' "
                    f"cross or touch on layer '{names[sheet.layer]}'; move one of them apart."
                )
    # Drop interior vertices closer than ~half an edge to a junction: they would make slivers.
    on_boundary = np.zeros(sheet.n, bool)
    on_boundary[sheet.boundary] = True
    zone = shapely.union_all([ln.buffer(0.55 * h) for ln in lines])
    near = shapely.contains_xy(zone, sheet.xy[:, 0], sheet.xy[:, 1]) & ~on_boundary
    kept = np.flatnonzero(~near)
    new_index = np.full(sheet.n, -1, np.int64)
    new_index[kept] = np.arange(len(kept))

    pts = [sheet.xy[kept]]
    segs = [np.c_[new_index[sheet.boundary], np.roll(new_index[sheet.boundary], -1)]]
    chains = []
    start = len(kept)
    for c in chains_xy:
        idx = np.arange(start, start + len(c))
        pts.append(np.asarray(c, np.float64))
        segs.append(np.c_[idx[:-1], idx[1:]])
        chains.append(idx)
        start += len(c)
    P = np.vstack(pts)
    lower = names[sheet.layer]
    # Triangle's behaviour on crossing segments or duplicate vertices is undefined (it
    # segfaults), so the graph is checked first: a junction that crosses or touches the
    # outline is the person's to fix, and is reported as such.
    try:
        data = guard.pslg(P, np.vstack(segs), None, what=f"layer '{lower}' with its junctions cut in")
    except GeometryError as exc:
        raise AttachmentError(
            f"A junction crosses or touches the outline of layer '{lower}' ({exc}); redraw the part "
            "so its ends lie inside the layer."
        ) from None
    if len(data["vertices"]) != len(P):
        raise AttachmentError(
            f"A junction touches the outline of layer '{lower}' (two of their points coincide); redraw the "
            "part so its ends lie inside the layer."
        )
    # 'p': constrained Delaunay of the given points and segments, no quality refinement, so no
    # vertex is added (the segments were checked not to cross).
    out = triangle.triangulate(data, "pQ")
    if "triangles" not in out or len(out["vertices"]) != len(P) or not np.allclose(out["vertices"], P):
        raise AttachmentError(
            f"A junction crosses the outline of layer '{lower}'; redraw the part "
            "so its ends lie inside the layer."
        )
    F = ccw_triangles(P, out["triangles"].astype(np.int64))
    z = np.empty(len(P))
    z[: len(kept)] = sheet.z[kept]
    z[len(kept):] = rbf_heights(sheet.xy, sheet.z, P[len(kept):])
    boundary = new_index[sheet.boundary]
    if not has_directed_edge(F, boundary[0], boundary[1]):
        boundary = boundary[::-1].copy()
    return sheet.evolve(
        xy=P, z=z, F=F, boundary=boundary, junction=new_index[sheet.junction], chains=tuple(chains)
    )
