"""Junction fairing (issue 12): the rings around every glued junction of the assembled mesh
smoothed by a bi-Laplacian with everything farther away fixed.

Which rings. ``fair`` rings around each junction's two ends and 60% of that around the rest
of its seam, held softly towards where they were the farther they are from the seam
(:func:`seam_zone`, :func:`hold_weights`); should that leave a bend over 90 degrees (a fold) or
a crossing, ``14/12 × fair`` rings around the whole seam, with a hard edge (:func:`wide_zone`,
the first blended default, 14 rings), and only where that crosses itself the plain sleeve
(see :mod:`.assemble`). Measured on the creature (16k vertices): the narrow zone moves 6.2k
vertices by at most 8.4 edge lengths (p95 2.9), the wide one 8.4k by up to 14.9 (p95 6.0),
so heads and tails keep their shape next to the junction; ``benchmarks/bench_junctions.py``
has the angles (every example and 59 random creatures meet the target in the narrow zone).

Why after the fillet. The fillet of :mod:`.blend` opens the U-turn under a part into a
crevice with a vertical strip, but it is built from per-vertex height offsets along the
distance to the junction, so where two of them meet (the junction's two ends, the strip's
top and bottom) the surface still bends by up to ~150 degrees over one edge. Minimising the
squared Laplacian of the positions in a few rings around the seam spreads each of those
bends over the rings (a bi-Laplacian surface is as smooth as its fixed surroundings allow),
while the surface beyond them keeps every vertex as the depth solve placed it.

Why not on the plain sleeve. Without the fillet the part's back face lies a margin above the
host, so the faired U-turn has to turn 180 degrees within that margin and the result crosses
itself; :func:`fair_seams` is only used with the fillet (see :mod:`.assemble`).

The uniform ("umbrella") Laplacian, not the cotangent one: the strip and the slit's ends have
needle triangles whose cotangent weights are huge or negative, and a graph operator keeps the
system positive definite whatever the triangles look like. It also moves vertices along the
surface, which evens out the needles the fillet leaves.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import shapely
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import splu

from sketchforge.plugin_api import FRONT, edge_angles, interior_edges

from .diagnostics import intersecting_pairs
from .sheet import directed_edges


def adjacency(F: np.ndarray, n: int) -> sp.csr_matrix:
    """(n, n) vertex adjacency of the triangles F (m, 3): 1 where an edge joins two vertices.

    From the directed half-edges, both ways, so no sort of the edge list is needed (np.unique
    over rows costs more than the whole fairing)."""
    D = directed_edges(F)
    A = sp.coo_matrix((np.ones(2 * len(D)), (np.r_[D[:, 0], D[:, 1]], np.r_[D[:, 1], D[:, 0]])), shape=(n, n)).tocsr()
    A.data[:] = 1.0
    return A


def ring_region(A: sp.csr_matrix, seed: np.ndarray, rings: int) -> np.ndarray:
    """(n,) bool: the vertices at most ``rings`` edges away from ``seed`` (k,) int64 over the
    vertex adjacency A (n, n) (see :func:`adjacency`)."""
    return rings_from(A, seed, rings) <= rings


#: The narrow zone (see :func:`seam_zone`): rings around the whole seam, as a share of the rings
#: around the junction's two ends.
SEAM_SHARE = 0.6
#: The wide zone that a fold left by the narrow one falls back to: rings around the whole seam,
#: as a multiple of the rings around the ends.
WIDE_SHARE = 14 / 12
#: Soft hold of the narrow zone (see :func:`hold_weights`): its weight at the zone's edge,
#: relative to a bi-Laplacian row (a vertex of degree 6 has ~7 on Q's diagonal), and where
#: in the zone (as a share of the way out) it starts. Chosen with ``fair`` = 12 on the
#: examples and 30 random creatures (a hold of 0.05, or 10 rings, left the toucan's head a
#: fold where it passes over the body's rim).
HOLD_WEIGHT = 0.02
HOLD_START = 0.3


#: Hold of a limb's own surface outside its host's outline (:func:`limb_hold`), relative to a
#: bi-Laplacian row like :data:`HOLD_WEIGHT`; it rises over :data:`LIMB_RAMP` edge lengths
#: past the outline and :data:`LIMB_SEAM_RINGS` rings from the seam. Chosen on the 60 seeded
#: creatures of ``benchmarks/bench_creatures.py`` (fair = 12): with no such hold 31 of them had
#: a limb thinner than 0.8 of mid-limb just outside its host; 0.1: 8, with as many junction
#: folds as before; 0.3: 4, with a worse fold (174 degrees) and one more creature folded.
LIMB_HOLD = 0.1
LIMB_RAMP = 1.5
LIMB_SEAM_RINGS = 4
#: For a limb the fairing still thinned under 0.8 of mid-limb where it leaves its host (the
#: neck try of :func:`sketchforge_assemble.assemble._fair`), the hold starts this many of its
#: edge lengths inside the host's outline: the thinning lies in the first two edge lengths
#: past it, where the hold was still rising (seed 16's tail: 0.76 of mid-tail, drawn 0.80;
#: started 0.75 edge lengths inside 0.79, 1.5 inside 0.80). Not for every limb: holding
#: there keeps a junction near its host's outline creased (the example creature's head: 1
#: edge over 45 degrees, 3 with the shift, and its assembly faired twice more).
NECK_SHIFT = 1.5


def limb_hold(V: np.ndarray, F: np.ndarray, face_layer: np.ndarray, limbs, zone: np.ndarray,
              seam_rings: np.ndarray, edges=None) -> np.ndarray:
    """(n,) float64 in [0, :data:`LIMB_HOLD`]: how strongly the fairing holds each vertex of
    a glued part's own surface where it has left its host (issue 34, point 5).

    Why. The bi-Laplacian pulls a tube's walls together (a thin-plate surface spanning a
    tube pinches it), so a limb whose junction lies close to its host's outline came out of
    the fairing with a neck just where it leaves the host: its thickness there fell to 0.62 of
    its own (the tail of seed 16). The fold the fairing is for lies at the seam, over the host;
    outside the host's outline the limb is the smooth inflated surface it was drawn as, so it
    is held there, the hold rising with the distance past the outline (a smoothstep over
    :data:`LIMB_RAMP` edge lengths of the part) and with the rings from the seam (over
    :data:`LIMB_SEAM_RINGS`: a seam vertex that lies past the outline must still move, or the
    junction keeps its fold). Both ramps are continuous in the positions.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    face_layer : (m,) int64
    limbs : list of (int, shapely geometry, float) or (int, shapely geometry, float, float)
        Per glued part: its layer, its host's region in the drawing plane, its edge length,
        and optionally how many of its edge lengths inside the host's outline the hold
        starts (default 0: at the outline; see :data:`NECK_SHIFT`).
    zone : (n,) bool
        The vertices the fairing may move; only these are looked at.
    seam_rings : (n,) int64
        Ring distance to the seam, capped at :data:`LIMB_SEAM_RINGS` + 1 (:func:`rings_from`).
    edges : tuple, optional
        :func:`interior_edges` of F. Given, the hold is let go where V is creased
        (:func:`crease_release`), so it keeps the limb's thickness and not the stitching's
        creases.
    """
    out = np.zeros(len(V))
    u = np.clip(np.asarray(seam_rings, np.float64) / LIMB_SEAM_RINGS, 0.0, 1.0)
    near_seam = u * u * (3.0 - 2.0 * u)
    for layer, host, h, *rest in limbs:
        shift = float(rest[0]) if rest else 0.0
        own = _on_layer(F, face_layer, layer, len(V))
        idx = np.flatnonzero(own & zone & (near_seam > 0))
        if len(idx) == 0:
            continue
        xy = V[idx, :2]
        outside = ~shapely.contains_xy(host, xy[:, 0], xy[:, 1])
        if shift > 0.0:
            # the hold starts inside the outline: distances signed, negative inside
            pts = shapely.points(xy)
            d = np.where(outside, shapely.distance(host, pts), -shapely.distance(host.boundary, pts))
            t = np.clip((d + shift * h) / (LIMB_RAMP * h), 0.0, 1.0)
            idx, t = idx[t > 0.0], t[t > 0.0]
        else:
            if not outside.any():
                continue
            idx = idx[outside]
            t = np.clip(shapely.distance(host, shapely.points(xy[outside])) / (LIMB_RAMP * h), 0.0, 1.0)
        out[idx] = np.maximum(out[idx], LIMB_HOLD * near_seam[idx] * t * t * (3.0 - 2.0 * t))
    if edges is None:
        return out
    return out * crease_release(V, F, edges, at=out > 0)


#: Where :func:`crease_release` lets go of a limb's hold: from the largest bend at a vertex
#: (degrees) of the first to none at the second, a smoothstep between.
CREASE_RELEASE = (30.0, 60.0)


def crease_release(V: np.ndarray, F: np.ndarray, edges=None, at: np.ndarray | None = None) -> np.ndarray:
    """(n,) float64 in [0, 1]: 1 at a vertex of V (n, 3), F (m, 3) whose edges all bend by at
    most ``CREASE_RELEASE[0]`` degrees, 0 where one bends by ``CREASE_RELEASE[1]`` or more, a
    smoothstep of the largest bend between (continuous in the positions). ``edges``:
    :func:`interior_edges` of F, if already made; ``at`` ((n,) bool, optional): only these
    vertices are looked at (1 elsewhere), the others' edges are not measured.

    Why. :func:`limb_hold` pulls a limb's surface past its host's outline towards where the
    stitching put it, so the fairing keeps the limb's thickness; but where the stitched
    surface is creased there (a tail glued near a wing's tip: its base crosses the wing's rim
    within a few edge lengths of the seam), the pull kept the crease too. Seed 40 of the
    drawn creatures kept 14 junction edges over 45 degrees, 9 at the tail's base (up to 65),
    one more than the 0.1% that issue 34 allows; released at its creases, 12 (the tail's 7),
    and no limb of the 60 creatures thinner than before (the creases are a few vertices:
    their neighbours still hold the tube). The ramp starts under the 45 degrees the issue
    counts and is smooth, so no hold jumps with a bend's round-off.
    """
    E, fa, fb = interior_edges(F) if edges is None else edges
    if at is not None:
        sel = at[E[:, 0]] | at[E[:, 1]]
        E, fa, fb = E[sel], fa[sel], fb[sel]
    bend = np.zeros(len(V))
    if len(E):
        ang = edge_angles(V, F, fa, fb)
        np.maximum.at(bend, E[:, 0], ang)
        np.maximum.at(bend, E[:, 1], ang)
    if at is not None:
        bend[~at] = 0.0
    lo, hi = CREASE_RELEASE
    u = np.clip((bend - lo) / (hi - lo), 0.0, 1.0)
    return 1.0 - u * u * (3.0 - 2.0 * u)


def rings_from(A: sp.csr_matrix, seed: np.ndarray, rings: int) -> np.ndarray:
    """(n,) int64: how many edges each vertex lies from ``seed`` (k,) int64 over the vertex
    adjacency A (n, n); ``rings + 1`` for every vertex farther than ``rings``."""
    n = A.shape[0]
    out = np.full(n, rings + 1, np.int64)
    region = np.zeros(n, bool)
    region[np.asarray(seed, np.int64)] = True
    out[region] = 0
    for r in range(1, rings + 1):
        grown = region | ((A @ region.astype(np.float64)) > 0)
        out[grown & ~region] = r
        region = grown
    return out


#: A part meshed finer than this share of the creature's largest edge length (a beak, an eye,
#: a bird's leg: :func:`sketchforge_inflate.inflate.edge_length_for`) is faired with its edges
#: weighted by their length (:func:`vertex_scale`); parts meshed within it count as alike.
FINE_SHARE = 0.8


def vertex_scale(F: np.ndarray, n: int, face_h: np.ndarray) -> np.ndarray | None:
    """(n,) float64 in (0, 1], or None where every part is meshed alike: each vertex's edge
    length as a share of the others', min(1, h / (FINE_SHARE · the largest h)), h the smallest
    edge length of the layers of its triangles (``face_h`` (m,) float64, per triangle of F
    (m, 3); a seam vertex counts with the finer part); for :func:`fair_seams`'s ``scale``.

    Why. The fairing's graph Laplacian weighs every edge alike, which is right where the edges
    are alike. Where a part meshed at a third of its host's edge length meets it (a bird's
    beak on its head), a seam vertex reads its bend mostly from neighbours three times farther
    on the host's side than on the beak's, and smoothing that misread bend creased the beak's
    first rings next to its junction by up to 82 degrees (seeds 19, 40, 58: edges bent 6-13
    degrees before the fairing) and folded seed 34's beak by 109 degrees. (It is not a slide:
    the whole small beak moves about one body edge length either way, and on a flat plane
    meshed at two densities the weights do not lessen the fairing's in-plane drift.) See
    :func:`fair_seams` for how the scale enters: inside a part the fairing is the same as
    before, only the weights across a change of edge length follow the edges' lengths.
    Continuous in each part's edge length; a creature without finer parts (None) is faired
    exactly as before.
    """
    face_h = np.asarray(face_h, np.float64)
    h_ref = FINE_SHARE * float(face_h.max(initial=0.0))
    if not h_ref > 0.0 or face_h.min() >= h_ref:
        return None
    vh = np.full(n, np.inf)
    np.minimum.at(vh, np.asarray(F, np.int64).ravel(), np.repeat(face_h, 3))
    vh[~np.isfinite(vh)] = h_ref
    return np.clip(vh / h_ref, 1e-3, 1.0)


def seam_zone(F: np.ndarray, n: int, seam: np.ndarray, ends: np.ndarray, rings: int, A: sp.csr_matrix | None = None,
              dist=None):
    """Where :func:`fair_seams` may move vertices, as a distance: ``rings`` edges around the
    ends of every junction, ``SEAM_SHARE`` of that around the rest of its seam.

    Why two reaches. The fillet of :mod:`.blend` opens the U-turn along the middle of a
    junction into a crevice whose bends span a few rings each, but at the junction's ends, where
    every amount fades to zero and the part's front and back meet in one vertex, the turn is
    still tight: only there does the fairing need many rings. A fixed ring count around the
    whole seam (14, the first blended default) refitted whole heads and tails around a short
    junction: the head joined the body through a wide web, a leg thinned to a neck, the body's
    silhouette got bumps where the zone ended.

    Parameters
    ----------
    F : (m, 3) int64
    n : int
        Vertex count.
    seam, ends : (k,) int64, (e,) int64
        From :func:`.stitch.build_mesh`.
    rings : int
        Rings around the ends (>= 1).
    A : (n, n) csr_matrix, optional
        The vertex adjacency of F (:func:`adjacency`), if already made.
    dist : callable, optional
        ``(seed, rings) -> (n,) float64`` rings from ``seed`` (:func:`glued_face_distance`);
        :func:`rings_from` over A when not given.

    Returns
    -------
    A : (n, n) csr_matrix
        The vertex adjacency (:func:`adjacency`), for :func:`fair_seams`.
    t : (n,) float64
        Ring distance to the seam as a share of its reach (the smaller of the two): the zone is
        ``t < 1``, ``t`` grows from 0 at the seam (see :func:`hold_weights`).
    """
    A = adjacency(F, n) if A is None else A
    near = max(1, int(round(SEAM_SHARE * rings)))
    if dist is None:
        def dist(seed, r):
            return rings_from(A, seed, r)
    t = np.minimum(dist(seam, near) / near, dist(ends, rings) / rings)
    return A, t


#: A host thicker than THIN_HOST[1] times the rings around a junction's ends (in its edge
#: lengths, the most within that many of them of an end) is faired over its rim like any
#: surface; one thinner than THIN_HOST[0] times them only over the face its part is glued on
#: (an edge on its rim or its other face counts FAR_BLOCK rings), smoothly in between.
#: Measured on the 460 attachments of the 60 creatures of ``benchmarks/bench_creatures.py``
#: (drawn thickness, 12 rings): the two tails glued on a wing near its tip see 1.07 and 1.1;
#: every other 1.81 or more (p5 2.0, median 3.4), so those are faired as before.
THIN_HOST = (1.25, 1.75)
FAR_BLOCK = 100.0


def far_weights(sheets, attachments, rings: int) -> dict:
    """{(host layer, side): weight > 1} for :func:`glued_face_distance`: the faces of thin
    hosts (:data:`THIN_HOST`) that the rings around their parts' junction ends should not wrap
    onto; a host face missing from it counts like any other. A host's thickness is its drawn
    one (twice its height field), the largest within ``rings`` of its edge lengths of an end,
    the smallest over the ends glued on that face.

    Why. The fairing's rings around a junction's end spread over whatever surface lies within
    that many edges, and a host thinner than the reach has its rim and other face there: the
    tail glued on a wing's back near its tip (seeds 1 and 40 of the benchmark) had its rings
    wrap over the wing's rim, squash the wing from 10 to 4 edge lengths thick and crease it by
    up to 85 degrees. Counted over the glued face only, those two creatures went from 99.68%
    and 99.77% of their junction edges under 45 degrees to 99.91% and 99.90%; the other 58 came
    out the same, vertex for vertex (no host of theirs is that thin).

    sheets: the :class:`.sheet.Sheet` list; attachments: :class:`.attach.Attachment` list.
    """
    thin: dict = {}
    for at in attachments:
        up, host = sheets[at.upper], sheets[at.lower]
        if len(up.junction) == 0 or host.n == 0:
            continue
        for end in up.xy[up.junction[[0, -1]]]:
            near = np.sum((host.xy - end) ** 2, axis=1) <= (rings * host.h) ** 2
            t = 2.0 * float(np.max(host.z[near], initial=0.0)) / host.h
            key = (at.lower, at.side)
            thin[key] = min(thin.get(key, np.inf), t / rings)
    out = {}
    for key in sorted(thin):
        u = float(np.clip((THIN_HOST[1] - thin[key]) / (THIN_HOST[1] - THIN_HOST[0]), 0.0, 1.0))
        if u > 0:
            out[key] = 1.0 + (FAR_BLOCK - 1.0) * u * u * (3.0 - 2.0 * u)
    return out


def junction_vertices(A: sp.csr_matrix, F: np.ndarray, face_layer: np.ndarray, attachments) -> list:
    """Per attachment, (n,) bool: the vertices of its junction, on both the part's faces and its
    host's, and the part's own chain next to them (a lip's strip joins that chain to the host's
    face, :func:`.stitch.build_mesh`, so it lies on the part's faces only). A (n, n) the vertex
    adjacency of F (m, 3) int64, face_layer (m,) int64."""
    n = A.shape[0]
    F = np.asarray(F, np.int64)
    out = []
    for at in attachments:
        own = _on_layer(F, face_layer, at.upper, n)
        both = own & _on_layer(F, face_layer, at.lower, n)
        out.append(both | (own & ((A @ both.astype(np.float64)) > 0)))
    return out


def _on_layer(F: np.ndarray, face_layer: np.ndarray, layer: int, n: int) -> np.ndarray:
    """(n,) bool: the vertices of layer ``layer``'s triangles."""
    out = np.zeros(n, bool)
    out[F[face_layer == layer].ravel()] = True
    return out


def glued_face_distance(A: sp.csr_matrix, F: np.ndarray, face_layer: np.ndarray, face_kind: np.ndarray,
                        attachments, weights: dict):
    """A function ``(seed, rings) -> (n,) float64``: how many rings each vertex lies from the
    vertices ``seed`` (k,) int64 (``rings + 1`` past ``rings``), where from a junction of a
    thin host (a key of ``weights``, :func:`far_weights`) an edge that lies only on that host's
    rim or its other face counts its weight in rings. Without weights: :func:`rings_from`.

    A (n, n) the vertex adjacency of F (m, 3) int64; face_layer, face_kind (m,) as
    :func:`.stitch.build_mesh` gives them; attachments a list of :class:`.attach.Attachment`.
    """
    from scipy.sparse.csgraph import dijkstra

    if not weights:  # no thin host: the plain count, without looking for junctions (3 ms)
        return lambda seed, rings: rings_from(A, np.asarray(seed, np.int64), rings)
    n = A.shape[0]
    F = np.asarray(F, np.int64)
    members: dict = {}
    for at, joint in zip(attachments, junction_vertices(A, F, face_layer, attachments)):
        key = (at.lower, at.side)
        if key in weights:
            members[key] = members.get(key, np.zeros(n, bool)) | joint
    weighted = {}
    for lower, side in members:
        far = (face_layer == lower) & (face_kind != side_kind(side))
        near_m, far_m = adjacency(F[~far], n), adjacency(F[far], n)
        only_far = far_m - far_m.multiply(near_m)
        only_far.eliminate_zeros()
        weighted[(lower, side)] = (near_m + weights[(lower, side)] * only_far).tocsr()

    def dist(seed, rings):
        seed = np.asarray(seed, np.int64)
        grouped = np.zeros(len(seed), bool)
        out = np.full(n, float(rings + 1))
        for key in sorted(members):
            inside = members[key][seed]
            grouped |= inside
            if inside.any():
                d = dijkstra(weighted[key], directed=False, indices=seed[inside], min_only=True, limit=rings + 0.5)
                out = np.minimum(out, d)
        if (~grouped).any():
            out = np.minimum(out, rings_from(A, seed[~grouped], rings))
        return np.minimum(out, rings + 1)

    return dist


def outline_distance(region, xy: np.ndarray, spacing: float) -> np.ndarray:
    """(k,) float64: the distance from each point xy (k, 2) outside ``region`` (a shapely
    Polygon or MultiPolygon, holes included) to its outline, measured to the outline resampled
    at most ``spacing`` apart: at most ``spacing²/(8d)`` over the true distance d (half the
    spacing at d = 0). What :func:`limb_necks` needs, ~6 times faster than
    ``shapely.distance`` (which measures every point against every edge: 1.5 ms a limb)."""
    from scipy.spatial import cKDTree

    samples = []
    for ring in shapely.get_rings(shapely.get_parts(region)):
        c = shapely.get_coordinates(ring)
        if len(c) < 2:
            continue
        a, b = c[:-1], c[1:]
        n = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / spacing).astype(np.int64))
        t = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
        samples.append(np.repeat(a, n, axis=0) + (t / np.repeat(n, n))[:, None] * np.repeat(b - a, n, axis=0))
    return cKDTree(np.vstack(samples)).query(np.asarray(xy, np.float64).reshape(-1, 2))[0]


def limb_necks(V: np.ndarray, twins, attachments, sheets, only=None) -> list:
    """Per attachment, the part's front and back vertices that face each other (``twins``:
    :func:`.stitch.build_mesh`'s pairs and their sheets) past its host's outline in V (n, 3)
    as stitched, as ((k,) int64, (k,) int64) pairs at its neck (within 2 of its edge lengths
    of the outline) and at mid-limb (40-60% of the farthest pair's distance), both empty where
    the part hardly leaves its host (under 6 edge lengths), for :func:`neck_ratio`. The way
    the creature benchmark measures a limb (issue 34, point 5), on the mesh's own vertices.
    ``only`` ((a,) bool, optional): measure those attachments, the others get empty pairs."""
    pairs, sheet_of = twins
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64))
    out = []
    for i, at in enumerate(attachments):
        mine = pairs[sheet_of == at.upper]
        if (only is not None and not only[i]) or len(mine) == 0:
            out.append((empty, empty))
            continue
        h = sheets[at.upper].h
        host = sheets[at.lower].polygon()
        xy = V[mine[:, 0], :2]
        past = ~shapely.contains_xy(host, xy[:, 0], xy[:, 1])
        d = outline_distance(host, xy[past], h / 4.0) if past.any() else np.zeros(0)
        if len(d) == 0 or d.max() < 6.0 * h:
            out.append((empty, empty))
            continue
        f, bk = mine[past, 0], mine[past, 1]
        neck, mid = d <= 2.0 * h, (d >= 0.4 * d.max()) & (d <= 0.6 * d.max())
        out.append(((f[neck], bk[neck]), (f[mid], bk[mid])))
    return out


#: See :func:`moved_past_host`.
NECK_STILL = 0.02


def moved_past_host(V0: np.ndarray, V: np.ndarray, F: np.ndarray, face_layer: np.ndarray, attachments,
                    sheets) -> np.ndarray:
    """(a,) bool: for each attachment, whether V (n, 3) moved any vertex of the part (from V0)
    that lies past its host's outline by more than :data:`NECK_STILL` of the part's edge
    length: where none did, its neck thickness (:func:`limb_necks`) changed by at most twice
    that, under 3% of a limb the neck measure looks at (one reaching 6 edge lengths past its
    host is seldom thinner than 1.3 of them), and measuring it (~1 ms a part) is skipped."""
    owner = np.full(len(V), -1, np.int64)
    owner[np.asarray(F, np.int64).ravel()] = np.repeat(np.asarray(face_layer, np.int64), 3)
    step = np.max(np.abs(V - V0), axis=1)
    out = np.zeros(len(attachments), bool)
    for i, at in enumerate(attachments):
        xy = V0[(step > NECK_STILL * sheets[at.upper].h) & (owner == at.upper), :2]
        if len(xy):
            out[i] = not shapely.contains_xy(sheets[at.lower].polygon(), xy[:, 0], xy[:, 1]).all()
    return out


def neck_ratio(V: np.ndarray, necks) -> np.ndarray:
    """(a,) float64: each part's largest thickness at its neck over its largest at mid-limb
    (:func:`limb_necks`), NaN where either is missing or flat."""
    out = np.full(len(necks), np.nan)
    for i, ((nf, nb), (mf, mb)) in enumerate(necks):
        if len(nf) and len(mf):
            mid = float(np.max(V[mf, 2] - V[mb, 2]))
            if mid > 0:
                out[i] = float(np.max(V[nf, 2] - V[nb, 2])) / mid
    return out


def side_kind(side: int) -> int:
    """The face_kind (0 front, 1 back) of the face a part is glued on, from its attachment's
    ``side`` (:data:`sketchforge.plugin_api.FRONT` or ``BACK``)."""
    return 0 if side == FRONT else 1


def wide_zone(A: sp.csr_matrix, seam: np.ndarray, rings: int, dist=None) -> np.ndarray:
    """(n,) bool: the fallback zone, ``WIDE_SHARE * rings`` rings around the whole seam (what
    the fairing moved before the narrow zone, 14 rings at the default 12), counted by ``dist``
    where given (as in :func:`seam_zone`)."""
    r = max(1, int(round(WIDE_SHARE * rings)))
    if dist is not None:
        return dist(np.asarray(seam, np.int64), r) <= r
    return ring_region(A, np.asarray(seam, np.int64), r)


def hold_weights(t: np.ndarray) -> np.ndarray:
    """(n,) float64 >= 0: how strongly each vertex of the narrow zone is held where it was
    (:func:`fair_seams`'s ``hold``), from its ring distance ``t`` (:func:`seam_zone`): 0 up to
    ``HOLD_START`` of the way out, rising smoothly to ``HOLD_WEIGHT`` at the zone's edge.

    Why. With the zone's edge simply fixed, the smoothest surface inside meets the untouched
    one at an angle, and a narrow zone ends close to where the parts keep their shape: the
    toucan's head creased there. Held softly, the faired surface eases into the fixed one.
    """
    s = np.clip((np.asarray(t, np.float64) - HOLD_START) / (1.0 - HOLD_START), 0.0, 1.0)
    return HOLD_WEIGHT * s * s * (3.0 - 2.0 * s)


def supports(V: np.ndarray, F: np.ndarray, face_layer: np.ndarray, face_kind: np.ndarray, part: int,
             footprint, zone: np.ndarray, by_side: bool = False):
    """(n,) bool: the vertices within ``zone`` of the faces a free part rests on; with
    ``by_side``, two such masks: the faces below it and the faces above it.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    face_layer, face_kind : (m,) int64, int8
        As :func:`.stitch.build_mesh` gives them (kind 0 front, 1 back).
    part : int
        The free part's layer.
    footprint : shapely geometry
        Where in the drawing plane it may rest on something (its outline, a little widened).
    zone : (n,) bool
        The vertices that would move (:func:`seam_zone`); only these are looked at.

    Every layer is a height field with its front face above its back face, so below the part
    only a front face can hold it and, of those, the one nearest to it in z (the median gap
    over the footprint); above it, the nearest back face (a part settled behind a layer).
    """
    from scipy.spatial import cKDTree

    sides = [np.zeros(len(V), bool), np.zeros(len(V), bool)]
    out = sides[0]
    cand = np.flatnonzero(zone)
    cand = cand[shapely.contains_xy(footprint, V[cand, 0], V[cand, 1])]
    own = np.unique(F[face_layer == part])
    if len(cand) == 0 or len(own) == 0:
        return tuple(sides) if by_side else out
    mark = np.zeros(len(V), bool)
    mark[cand] = True
    near = np.flatnonzero(mark[F].any(axis=1))  # the faces with a candidate vertex
    tree = cKDTree(V[own, :2])
    for kind, sign in ((0, 1.0), (1, -1.0)):
        best, best_gap = None, np.inf
        mine = near[face_kind[near] == kind]
        for layer in np.unique(face_layer[mine]):
            if layer == part:
                continue
            v = np.unique(F[mine[face_layer[mine] == layer]])
            v = v[mark[v]]
            # the part's front and back vertex share their xy: the two nearest are both
            _, nn = tree.query(V[v, :2], k=2)
            z = V[own[nn], 2]
            gap = sign * ((z.min(axis=1) if sign > 0 else z.max(axis=1)) - V[v, 2])
            g = float(np.median(gap))
            if 0 <= g < best_gap:
                best, best_gap = v, g
        if best is not None:
            sides[kind][best] = True
    return tuple(sides) if by_side else sides[0] | sides[1]


def reseat(V: np.ndarray, V2: np.ndarray, F: np.ndarray, face_layer: np.ndarray, rests) -> np.ndarray | None:
    """(n, 3) float64: the faired mesh ``V2`` (from ``V``, both (n, 3)) with every free part
    that rests on a faired face moved in z by how much its support moved, or None when a part
    so moved would cross anything (or is pinched between a support that rose above it and one
    that sank below it).

    Why. The free parts (an eye on a head) are settled on the solved surface a gap clear of it
    (:func:`.depth.settle_free_parts`). Holding the faces under them out of the fairing kept
    them resting but left the fillet's folds there unfaired (an eye beside a snout's junction:
    a 145-163 degree fold at the snout's end, 4 of 60 drawn creatures); faired like any other,
    the part follows them: up by the most its faces below rose, down by the least its faces
    above sank, so it rests where it rested, never inside.

    Parameters
    ----------
    F : (m, 3) int64
    face_layer : (m,) int64
    rests : list of (int, (n,) bool, (n,) bool)
        Per free part: its layer, the vertices of the faces below it and above it
        (:func:`supports` with ``by_side``).
    """
    V2 = V2.copy()
    moved_faces = []
    for part, below, above in rests:
        if not (below.any() or above.any()):
            continue
        dz = V2[:, 2] - V[:, 2]  # again per part: a free part may rest on one moved before it
        up = float(dz[below].max()) if below.any() else -np.inf
        down = float(dz[above].min()) if above.any() else np.inf
        if up > down:
            return None
        shift = up if below.any() else down
        faces = np.flatnonzero(face_layer == part)
        V2[np.unique(F[faces]), 2] += shift
        moved_faces.append(faces)
    if moved_faces and len(intersecting_pairs(V2, F, among=np.concatenate(moved_faces), split=False)):
        return None
    return V2


def fair_seams(V: np.ndarray, F: np.ndarray, moved: np.ndarray, A: sp.csr_matrix | None = None,
               hold: np.ndarray | None = None, scale: np.ndarray | None = None) -> np.ndarray:
    """Bi-Laplacian fairing of the vertices ``moved``.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions of a closed mesh.
    F : (m, 3) int64
        Its triangles.
    moved : (n,) bool
        The vertices that move (:func:`seam_zone`, less those a free part rests on, see
        :func:`supports`); every other vertex is fixed.
    A : (n, n) csr_matrix, optional
        The vertex adjacency, if already built (:func:`seam_zone`).
    hold : (n,) float64, optional
        Weight >= 0 of a pull of each moved vertex towards where it is (:func:`hold_weights`);
        default none.

    Returns
    -------
    (n, 3) float64
        ``V`` with the moved vertices replaced; every other vertex is bit-identical (and so is
        every vertex of a component that ``moved`` covers whole).

    Solves  min Σ_i |(L x)_i|² / d_i + Σ_i hold_i |x_i - v_i|²  over the moved vertices (L the
    graph Laplacian, d_i the vertex degree, the usual lumped mass), the others fixed: one
    sparse LDLᵀ of the moved block (:func:`_spd_solve`), three right-hand sides.

    With ``scale`` ((n,) float64 > 0, :func:`vertex_scale`: each vertex's edge length as a
    share) the Laplacian's edge weights are 1/(s_i s_j), the masses s_i²/d_i and the holds
    hold_i/s_i²: inside a part of one scale s every term is the plain one over s², so the same
    surface; where the scale changes, a vertex's bend is read with its near neighbours weighing
    more than its far ones.
    """
    A = adjacency(F, len(V)) if A is None else A
    # A component with no fixed vertex (a small model inside the rings) has no boundary to
    # hold it: its system would be singular, so it keeps its place.
    _, label = connected_components(A, directed=False)
    held = np.zeros(label.max() + 1, bool)
    held[label[~moved]] = True
    moved = moved & held[label]
    free = np.flatnonzero(moved)
    if len(free) == 0:
        return V.copy()
    deg = np.asarray(A.sum(axis=1)).ravel()
    s = None if scale is None else np.asarray(scale, np.float64)
    if s is None:
        W, mass = A, 1.0 / deg
    else:
        C = A.tocoo()
        W = sp.csr_matrix((1.0 / (s[C.row] * s[C.col]), (C.row, C.col)), shape=A.shape)
        mass = s * s / deg
    L = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()
    # Only the rows of L near the moved vertices matter: restrict before squaring.
    near = ring_region(A, free, 1)
    Ln = L[np.flatnonzero(near)]
    Q = (Ln.T @ sp.diags(mass[near]) @ Ln).tocsr()
    fixed = np.flatnonzero(~moved)
    Qf = Q[free]
    rhs = -(Qf[:, fixed] @ V[fixed])
    K = Qf[:, free]
    if hold is not None:
        w = np.asarray(hold, np.float64)[free] / (1.0 if s is None else s[free] ** 2)
        K = K + sp.diags(w)
        rhs = rhs + w[:, None] * V[free]
    X = _spd_solve(K.tocsc(), rhs)
    V2 = V.copy()
    V2[free] = X
    return V2


def _spd_solve(K: sp.csc_matrix, rhs: np.ndarray) -> np.ndarray:
    """(k, 3) solution of K X = rhs for the symmetric positive definite K (k, k), rhs (k, 3).

    libigl's sparse LDLᵀ (Eigen's, AMD ordering): on the creature's 8.4k moved vertices
    ~60 ms against ~85-130 ms for SuperLU's LU, same answer to 2e-12; SuperLU if the binding
    fails. K is a graph bi-Laplacian block with finite entries (degrees >= 1), so libigl only
    ever sees validated input.
    """
    import igl

    try:
        X = np.asarray(igl.min_quad_with_fixed(K, -rhs, np.zeros(0, np.int64), np.zeros((0, rhs.shape[1])),
                                               sp.csc_matrix((0, K.shape[0])), np.zeros((0, rhs.shape[1])),
                                               True))
    except (RuntimeError, ValueError, TypeError):  # failed factorisation, other binding: SuperLU
        X = None
    if X is not None and X.shape == rhs.shape and np.all(np.isfinite(X)):
        return X
    return splu(K, permc_spec="COLAMD").solve(rhs)


def largest_bend(V: np.ndarray, F: np.ndarray, moved: np.ndarray, A: sp.csr_matrix) -> float:
    """Largest dihedral angle, in degrees, over the edges whose bend the moved vertices
    (``moved`` (n,) bool) can have changed: those of the triangles within one ring of them.
    V (n, 3), F (m, 3), A the vertex adjacency (:func:`adjacency`)."""
    from .diagnostics import dihedral_angles

    near = ring_region(A, np.flatnonzero(moved), 1)
    sub = F[near[F].any(axis=1)]
    return float(np.max(dihedral_angles(V, sub), initial=0.0))


def fairing_is_fit(V: np.ndarray, F: np.ndarray, moved: np.ndarray, A: sp.csr_matrix, h: float,
                   bend_limit: float = 180.0) -> bool:
    """Whether the faired mesh V (n, 3), F (m, 3) bends by at most ``bend_limit`` degrees over
    any edge the moved vertices (``moved`` (n,) bool) reach (:func:`largest_bend`) and is safe
    (:func:`fairing_is_safe`). A the vertex adjacency, h the layers' edge length.

    The bend is measured on a worker thread while this one starts the crossing check (which
    splits its own work over the same two workers, see
    :func:`.diagnostics.intersecting_pairs`): the creature's two checks took 55-58 ms instead
    of 60-67 on the idle 2-core machine. A plain function of its arguments: the answer does
    not depend on the threads.
    """
    from .diagnostics import _pool

    bend = _pool().submit(largest_bend, V, F, moved, A) if bend_limit < 180.0 else None
    safe = fairing_is_safe(V, F, moved, h)
    return safe and (bend is None or bend.result() <= bend_limit)


def fairing_is_safe(V: np.ndarray, F: np.ndarray, moved: np.ndarray, h: float) -> bool:
    """Whether the faired mesh V (n, 3), F (m, 3) is still fit to hand out: no triangle with a
    moved vertex (``moved`` (n,) bool) of area below 1e-6 h² (h: the layers' edge length), and
    none that crosses another triangle."""
    touched = np.flatnonzero(moved[F].any(axis=1))
    T = V[F[touched]]
    area = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    if not np.all(np.isfinite(T)) or np.any(area < 1e-6 * h * h):
        return False
    return len(intersecting_pairs(V, F, among=touched)) == 0


def fairing_faults(V: np.ndarray, F: np.ndarray, moved: np.ndarray, h: float,
                   ignore: np.ndarray | None = None) -> np.ndarray:
    """(k,) int64: the vertices of the triangles that make the faired mesh V (n, 3), F (m, 3)
    unfit to hand out (:func:`fairing_is_safe`): those with a moved vertex (``moved`` (n,)
    bool) and an area below 1e-6 h², and both triangles of every crossing pair among the
    triangles with a moved vertex; a pair with a triangle in ``ignore`` ((m,) bool, optional: a
    free part that :func:`reseat` moves and checks afterwards) does not count. Empty when it is
    fit."""
    touched = np.flatnonzero(moved[F].any(axis=1))
    T = V[F[touched]]
    area = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    bad = touched[~np.isfinite(area) | (area < 1e-6 * h * h)]
    # In one thread: the split of intersecting_pairs saves wall time but costs CPU, and the
    # assembly's target is CPU time (issue 34: 0.3 s for a 12-part, 16k-vertex creature).
    pairs = intersecting_pairs(V, F, among=touched, split=False)
    if ignore is not None and len(pairs):
        pairs = pairs[~ignore[pairs].any(axis=1)]
    return np.unique(F[np.r_[bad, pairs.ravel()]].ravel())


def _part_way(V: np.ndarray, V2: np.ndarray, full: np.ndarray, F: np.ndarray, kept: np.ndarray,
              h: float, ignore: np.ndarray | None = None) -> np.ndarray:
    """(n, 3) float64: ``V2`` with the kept-back vertices (``kept`` (n,) bool, at their solved
    place ``V``) moved part of the way to where the whole fairing put them (``full``), the
    largest share of :data:`KEPT_SHARES` that crosses nothing; ``V2`` when none is clear.

    Why. A kept-back ring keeps the fillet's bend as solved, so the fold it was faired for
    stays (a snout's back next to its junction's end, 104-163 degrees); part of the way, it
    is gentler and still clear of what the whole way crossed (seed 27's last fold, 118 -> 66
    degrees). V, V2, full (n, 3), F (m, 3), h the layers' edge length.
    """
    for share in KEPT_SHARES:
        Vt = V2.copy()
        Vt[kept] = V[kept] + share * (full[kept] - V[kept])
        if len(fairing_faults(Vt, F, kept, h, ignore)) == 0:
            return Vt
    return V2


#: Shares of the way to the whole fairing that :func:`_part_way` tries for kept-back rings.
KEPT_SHARES = (0.75, 0.5, 0.25)
#: Rounds of :func:`fair_clear`: each keeps back the rings around what the previous one left
#: crossing.
CLEAR_ROUNDS = 4
#: Rings kept back around a crossing per round.
CLEAR_RINGS = 2


def bent_vertices(V: np.ndarray, F: np.ndarray, moved: np.ndarray, A: sp.csr_matrix, limit: float,
                  edges=None) -> np.ndarray:
    """(k,) int64: the vertices of the edges, within one ring of the moved vertices (``moved``
    (n,) bool), that bend by more than ``limit`` degrees in V (n, 3), F (m, 3). ``edges``:
    :func:`interior_edges` of F, if already made."""
    E, fa, fb = interior_edges(F) if edges is None else edges
    near = ring_region(A, np.flatnonzero(moved), 1)
    sel = near[E[:, 0]] | near[E[:, 1]]
    if not sel.any():
        return np.zeros(0, np.int64)
    return np.unique(E[sel][edge_angles(V, F, fa[sel], fb[sel]) > limit].ravel())


def fair_clear(V: np.ndarray, F: np.ndarray, moved: np.ndarray, A: sp.csr_matrix, h: float,
               hold: np.ndarray | None = None, bend_limit: float = 180.0, edges=None,
               ignore: np.ndarray | None = None, scale: np.ndarray | None = None):
    """(V2, clear, bent, kept back): :func:`fair_seams` of ``moved`` (with ``scale``), where it
    crosses itself again with the crossing's rings kept where they were, up to
    :data:`CLEAR_ROUNDS` times.

    Why. Where two parts lie close (a far wing pressed against the body's back a gap apart,
    twin ears side by side), the fairing of one junction moves vertices by more than the gap
    and the faired surface crosses the other part. Those few rings are better left as the
    depth solve placed them (which keeps every part clear of the others) than the whole model
    handed out with plain folds; the rest of the junction is still faired, and the rings kept
    back go part of the way where that is clear (:func:`_part_way`). ``edges``:
    :func:`interior_edges` of F, if made. ``clear``: no
    crossing or flat triangle left; ``bent``: (k,) int64 the vertices of the edges the vertices
    of ``moved`` (kept back or not) reach that bend by more than ``bend_limit`` degrees; ``kept back``: (n,) bool,
    the vertices held back.
    """
    kept = np.zeros(len(V), bool)
    first = None
    for _ in range(CLEAR_ROUNDS):
        now = moved & ~kept
        V2 = fair_seams(V, F, now, A, hold=hold, scale=scale)
        first = V2 if first is None else first
        faults = fairing_faults(V2, F, now, h, ignore)
        if len(faults) == 0:
            if kept.any():
                V2 = _part_way(V, V2, first, F, kept, h, ignore)
            # over every vertex asked to move, the kept-back rings too: a fold left there is a
            # fold (seed 15's 106 degrees went unseen when only the moved ones were looked at)
            bent = bent_vertices(V2, F, moved, A, bend_limit, edges) if bend_limit < 180.0 else np.zeros(0, np.int64)
            return V2, True, bent, kept
        grow = ring_region(A, faults, CLEAR_RINGS) & moved
        if not (grow & ~kept).any():
            break
        kept |= grow
    return V2, False, np.zeros(0, np.int64), kept

