"""Build the closed mesh: front and back faces, slits glued to junctions, rim bridges.

Topology (why it is a 2-manifold). A part's front face, back face and the rim bridge along the
non-junction part of its outline form a sleeve: a disc whose boundary is its front junction
chain followed by its back junction chain (the two chains share only the junction's end
vertices). The face it attaches to is cut along the same polyline into a slit, whose boundary
loop is the two lips sharing the slit's ends. Gluing the sleeve's loop to the slit's loop is
the connected sum of two spheres, a sphere again: every edge keeps exactly two triangles and
V - E + F = 2 for every tree of attached parts.

Which lip takes which chain (seen in a section across the junction, the part lying on the "+"
side): when the part sits on a front face, the face's "-" side continues into the part's front
face and its "+" side, under the part, folds back into the part's back face; behind a back face
it is the mirror image. Orientation then agrees on both lips without any flipping.
"""

from __future__ import annotations

import numpy as np

from .attach import FRONT, Attachment, lo_chain_index
from .sheet import Sheet, has_directed_edge, interior_on_left


def chain_sides(sheet: Sheet, chain: np.ndarray, F: np.ndarray | None = None):
    """Which side of an inserted polyline each incident triangle corner lies on.

    Parameters
    ----------
    sheet : Sheet
    chain : (c,) int64
        The polyline's vertices in order.
    F : (m, 3) int64, optional
        The face's triangulation the chain is cut into (default ``sheet.F``).

    Returns
    -------
    corners : (t, 2) int64
        (triangle, corner 0..2) pairs whose vertex is an interior vertex of the chain.
    position : (t,) int64
        Index of that vertex along the chain.
    left : (t,) bool
        True if the triangle lies to the left of the chain walked in order.
    """
    F = sheet.F if F is None else F
    pos = np.full(sheet.n, -1, np.int64)
    pos[chain[1:-1]] = np.arange(1, len(chain) - 1)
    tri, corner = np.nonzero(pos[F] >= 0)
    k = pos[F[tri, corner]]
    p = sheet.xy[chain[k]]
    a_next = np.arctan2(*(sheet.xy[chain[k + 1]] - p).T[::-1])
    a_prev = np.arctan2(*(sheet.xy[chain[k - 1]] - p).T[::-1])
    g = sheet.xy[F[tri]].mean(axis=1)
    a_t = np.arctan2(*(g - p).T[::-1])
    two_pi = 2.0 * np.pi
    left = np.mod(a_t - a_next, two_pi) < np.mod(a_prev - a_next, two_pi)
    return np.c_[tri, corner], k, left


def build_mesh(sheets: list[Sheet], attachments: list[Attachment], delta: list[np.ndarray],
               front_off: list[np.ndarray], back_off: list[np.ndarray], lips=None):
    """The assembled mesh.

    Parameters
    ----------
    sheets : list of Sheet
        After junction insertion.
    attachments : list of Attachment
    delta : list of (n_i,) float64
        Depth offset of each sheet's vertices.
    front_off, back_off : list of (n_i,) float64
        Front z = δ + front_off, back z = δ - back_off.
    lips : list of (c,) float64, optional
        Per attachment, how far the lower face's "+" lip lies off that face towards the part
        (:func:`.blend.blend_junctions`). With it the "+" lip gets its own vertices and a strip
        of triangles joins them to the part's chain (a rim bridge along the junction); without
        it the lip is the part's chain itself.

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64
        Outward-oriented (front faces counter-clockwise seen from +z).
    face_layer : (m,) int64
        Layer index of each triangle.
    face_kind : (m,) int8
        0 front face, 1 back face, 2 rim bridge.
    seam : (k,) int64
        The vertices along the glued junctions (every part's front and back junction chains
        and the lips' own vertices), for :func:`.fair.fair_seams`.
    ends : (e,) int64
        The two ends of every glued junction, where the part's front and back faces meet the
        slit's end (:func:`.fair.seam_zone` fairs more rings around them).
    rim_pairs : (r, 2) int64, (r,) int64
        A part's front and back vertex at each point of its bridged rim (outline and holes,
        not a glued junction), kept apart by the margin and the rim's lift (see
        :attr:`sketchforge.geometry.mesh.AssembledMesh.rim_pairs`), and the sheet's index.
    twins : (t, 2) int64, (t,) int64
        Every sheet vertex's front and back vertex (same xy as stitched; not where they are
        one vertex, at a junction's ends), and the sheet's index: where a part is thick.
    """
    sizes = np.array([s.n for s in sheets])
    base = np.r_[0, np.cumsum(2 * sizes)]
    front = [base[i] + np.arange(s.n) for i, s in enumerate(sheets)]
    back = [base[i] + s.n + np.arange(s.n) for i, s in enumerate(sheets)]
    V = np.zeros((int(base[-1]), 3))
    for i, s in enumerate(sheets):
        V[front[i], :2] = s.xy
        V[back[i], :2] = s.xy
        V[front[i], 2] = delta[i] + front_off[i]
        V[back[i], 2] = delta[i] - back_off[i]

    # An attached part's front and back faces share the two ends of its junction.
    remap = np.arange(len(V))
    attached = {at.upper for at in attachments}
    for i in attached:
        ends = sheets[i].junction[[0, -1]]
        remap[back[i][ends]] = front[i][ends]

    extra = []  # (k, 3) rows of lip vertices appended after V
    seam = [np.r_[front[i][sheets[i].junction], back[i][sheets[i].junction]] for i in attached]
    strips = []  # (t, 3) strip triangles, with the layer of the part
    n_v = len(V)

    faces_front = [front[i][s.F] for i, s in enumerate(sheets)]
    faces_back = [back[i][s.face(-1)[:, ::-1]] for i, s in enumerate(sheets)]

    # Slits: re-point the lower face's triangles at the part's junction chains.
    for a_i, at in enumerate(attachments):
        lo = sheets[at.lower]
        chain = lo.chains[lo_chain_index(attachments, a_i)]
        up = sheets[at.upper]
        j = up.junction
        faces = faces_front[at.lower] if at.side == FRONT else faces_back[at.lower]
        # Ends of the slit: the part's shared end vertices.
        for e in (0, len(chain) - 1):
            lo_v = (front if at.side == FRONT else back)[at.lower][chain[e]]
            faces[faces == lo_v] = front[at.upper][j[e]]
        corners, pos, left = chain_sides(lo, chain, lo.face(at.side))
        plus = left == interior_on_left(up)  # same side as the part's interior
        # On a front face the "+" lip joins the part's back chain, on a back face its front chain.
        plus_chain = back[at.upper] if at.side == FRONT else front[at.upper]
        minus_chain = front[at.upper] if at.side == FRONT else back[at.upper]
        # back faces store each triangle reversed, so corner c sits in column 2 - c
        col = corners[:, 1] if at.side == FRONT else 2 - corners[:, 1]
        if lips is None:
            faces[corners[:, 0], col] = np.where(plus, plus_chain[j[pos]], minus_chain[j[pos]])
            continue
        # the "+" lip's own vertices, on the lower face lifted by the lip's height; its ends
        # are the part's shared end vertices
        sgn = 1.0 if at.side == FRONT else -1.0
        face_z = delta[at.lower][chain] + (front_off[at.lower][chain] if at.side == FRONT
                                           else -back_off[at.lower][chain])
        lip = np.r_[front[at.upper][j[0]], n_v + np.arange(len(chain) - 2), front[at.upper][j[-1]]]
        extra.append(np.c_[lo.xy[chain[1:-1]], face_z[1:-1] + sgn * lips[a_i][1:-1]])
        seam.append(n_v + np.arange(len(chain) - 2))
        n_v += len(chain) - 2
        faces[corners[:, 0], col] = np.where(plus, lip[pos], minus_chain[j[pos]])
        # The strip runs against the lower face's "+" triangles along the lip, so it walks the
        # lip the other way round.
        P = plus_chain[j]
        a, b = lip[:-1], lip[1:]
        k = len(a) // 2  # an edge of two interior vertices when there is one
        if has_directed_edge(faces, a[k], b[k]):  # the face walks a -> b
            strips.append((np.c_[b, a, P[:-1]], at.upper))
            strips.append((np.c_[b, P[:-1], P[1:]], at.upper))
        else:
            strips.append((np.c_[a, b, P[1:]], at.upper))
            strips.append((np.c_[a, P[1:], P[:-1]], at.upper))

    # Rim bridges along the outline, except along a glued junction.
    bridges = []
    rims, rim_of = [], []  # (k, 2) front and back vertex of each bridged rim point, its sheet
    for i, s in enumerate(sheets):
        b = s.boundary
        a_, b_ = b, np.roll(b, -1)
        if i in attached:
            jset = np.zeros(s.n, bool)
            jset[s.junction] = True
            # junction edges: both ends on the junction and consecutive along it
            jpos = np.full(s.n, -1)
            jpos[s.junction] = np.arange(len(s.junction))
            is_j = jset[a_] & jset[b_] & (np.abs(jpos[a_] - jpos[b_]) == 1)
            a_, b_ = a_[~is_j], b_[~is_j]
        # Every hole's rim is bridged the same way: its loop runs with the face on its left
        # like the outline, so the same two triangles per edge close it, outward-facing.
        for hole in s.holes:
            a_, b_ = np.r_[a_, hole], np.r_[b_, np.roll(hole, -1)]
        af, bf, ab, bb = front[i][a_], front[i][b_], back[i][a_], back[i][b_]
        rim = np.unique(np.r_[a_, b_])
        rims.append(np.c_[front[i][rim], back[i][rim]])
        rim_of.append(np.full(len(rim), i))
        bridges.append(np.c_[bf, af, ab])
        bridges.append(np.c_[bf, ab, bb])

    parts, layer, kind = [], [], []
    for i in range(len(sheets)):
        for faces, kd in ((faces_front[i], 0), (faces_back[i], 1), (np.vstack(bridges[2 * i:2 * i + 2]), 2)):
            parts.append(faces)
            layer.append(np.full(len(faces), i))
            kind.append(np.full(len(faces), kd, np.int8))
    for faces, i in strips:  # a strip belongs to its part, as its rim bridge does
        parts.append(faces)
        layer.append(np.full(len(faces), i))
        kind.append(np.full(len(faces), 2, np.int8))
    if extra:
        V = np.vstack([V] + extra)
        remap = np.r_[remap, np.arange(len(remap), len(V))]
    F = remap[np.vstack(parts)]
    face_layer = np.concatenate(layer)
    face_kind = np.concatenate(kind)
    ok = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])
    F, face_layer, face_kind = F[ok], face_layer[ok], face_kind[ok]
    used = np.zeros(len(V), bool)
    used[F] = True
    new = np.cumsum(used) - 1
    seam = np.unique(remap[np.concatenate(seam)]) if seam else np.zeros(0, np.int64)
    ends = np.unique([front[i][sheets[i].junction[e]] for i in sorted(attached) for e in (0, -1)]).astype(np.int64)
    def kept(pairs):  # a junction's end is one vertex of front and back already (remap)
        pairs = remap[pairs]
        ok = (pairs[:, 0] != pairs[:, 1]) & used[pairs].all(axis=1)
        return new[pairs[ok]].astype(np.int64), ok

    rim_pairs, ok = kept(np.vstack(rims) if rims else np.zeros((0, 2), np.int64))
    rim_sheet = np.concatenate(rim_of)[ok] if rims else np.zeros(0, np.int64)
    twins, ok = kept(np.vstack([np.c_[front[i], back[i]] for i in range(len(sheets))]))
    twin_sheet = np.repeat(np.arange(len(sheets)), sizes)[ok]
    return (V[used], new[F].astype(np.int64), face_layer.astype(np.int64), face_kind, new[seam].astype(np.int64),
            new[ends].astype(np.int64), (rim_pairs, rim_sheet), (twins, twin_sheet))


#: A rim pair shares its normals (:attr:`sketchforge.geometry.mesh.AssembledMesh.rim_weights`)
#: fully while the assembly after the stitching (the junctions' fairing) changed the vector
#: between its two vertices by at most the first of these, not at all from the second on, in
#: the part's edge lengths (see :func:`rim_share`).
RIM_KEPT = (0.05, 0.25)


def rim_share(V0: np.ndarray, V: np.ndarray, pairs: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(r,) float64 in [0, 1]: how much each rim pair (r, 2) of the stitched V0 (n, 3) shares
    its normals in V (n, 3), the same mesh after fairing: 1 where the rim is as stitched (a
    band straight across the rim, standing for its round profile), 0 where the fairing has
    reshaped it into a surface of its own (its own normals are right there), a smoothstep of
    how far the vector across the pair moved, in edge lengths ``h`` (r,) of its part, between
    :data:`RIM_KEPT`'s two values. A part moved as a whole (a free part reseated) keeps 1."""
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        return np.zeros(0)
    across0 = V0[pairs[:, 1]] - V0[pairs[:, 0]]
    across = V[pairs[:, 1]] - V[pairs[:, 0]]
    moved = np.linalg.norm(across - across0, axis=1) / np.asarray(h, np.float64)
    lo, hi = RIM_KEPT
    t = np.clip((hi - moved) / (hi - lo), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)
