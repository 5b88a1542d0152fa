"""One software rasteriser for every top view: a per-pixel buffer of normals, then shading.

:func:`rasterise` turns layers (meshes, back to front) seen from +z into a :class:`GBuffer`:
one fragment per pixel and layer that shows there, with the unit normal interpolated from the
vertex normals at the pixel centre and the layer's coverage of the pixel (antialiased
silhouettes). :func:`shade` applies a display shader to the fragments and composites them back
to front; it never touches the geometry, so a new light costs a dot product and a blend, not a
rasterisation (it lives in :mod:`sketchforge.geometry.composite`, re-exported here). The
headless renderer (``sketchforge render``) and the editing canvas both go through these two
functions.

Coverage: a pixel whose centre lies inside a layer's outline is covered by
``clip(0.5 + d, 0, 1)`` and one whose centre lies outside by ``clip(0.5 - d, 0, 1)``, where d is
the distance in pixels from the centre to the outline (the mesh's boundary edges). Outside the
outline the fragment takes the normal of the nearest outline point (linear along the edge), so
a silhouette blends the rim's own shade into what lies behind. Fragments hidden under an opaque
fragment of a layer in front are dropped, so shading costs about one fragment per covered pixel.

Isophote lines (:func:`isophote_coverage`) are drawn from the same per-pixel field, n·l of the
front fragment, with a constant width in pixels (the distance to the level divided by the
screen-space gradient), so they are smooth and antialiased, and a layer in front hides the lines
of the layers behind it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sketchforge.cache import LRUCache

# shading lives in composite; re-exported here, where the canvas and the renderer find it
from sketchforge.geometry.composite import _dot, _model_coverage, _pack, isophote_coverage, shade  # noqa: F401
from sketchforge.geometry.heightfield import layer_normals

#: Views whose fragments are kept per mesh (see :func:`_layer_fragments`).
VIEWS_KEPT = 3
#: Bytes of the per-mesh cache below. The undo history keeps old meshes alive, and with a
#: cache bounded per mesh only, their fragments stayed with them: 19 MB a step for 200 moves of
#: a 36k-vertex layer drawn on a 1000x800 canvas (issue 39). The canvas draws every visible
#: layer at each frame, so the meshes shown are always the most recently used.
MESH_CACHE_BYTES = 256 * 2**20
# Per mesh (meshes are immutable, keys are held weakly): vertex normals, outline edges and the
# fragments of its last VIEWS_KEPT views, so a new view of the same meshes (pan, zoom) only
# rasterises and a change to one layer rasterises that layer alone.
_mesh_cache = LRUCache(max_bytes=MESH_CACHE_BYTES, weak_keys=True, name="mesh fragments")

# Outline edges longer than this (pixels) are split before testing the pixels around them, so
# the work stays proportional to the outline's length, not to its bounding box.
_EDGE_PIECE = 8.0


@dataclass(frozen=True)
class View:
    """An orthographic top view: document point (x, y) -> pixel (column, row).

    column = (x - x0) * scale, row = (y1 - y) * scale, where (x0, y1) is the document point at the
    top-left corner of the image; pixel (r, c) has its centre at column c + 0.5, row r + 0.5.
    """

    x0: float
    y1: float
    scale: float  # pixels per document unit
    width: int
    height: int

    def __post_init__(self) -> None:
        if not (np.isfinite(self.x0) and np.isfinite(self.y1) and np.isfinite(self.scale) and self.scale > 0):
            raise ValueError(f"a view needs a finite origin and a positive scale, got {self}")
        if int(self.width) < 1 or int(self.height) < 1:
            raise ValueError(f"a view needs at least one pixel, got {self.width}x{self.height}")

    @classmethod
    def framing(cls, meshes, width: int, height: int, margin: float = 0.05) -> View:
        """The view that shows every mesh, centred, equal aspect, ``margin`` empty on each side."""
        pts = np.concatenate([np.asarray(m.V)[:, :2] for m in meshes])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        centre = 0.5 * (lo + hi)
        ext = hi - lo
        avail = np.array([width, height], dtype=np.float64) * (1.0 - 2.0 * margin)
        ratios = [avail[i] / ext[i] for i in range(2) if ext[i] > 0]
        scale = float(min(ratios)) if ratios else 1.0
        return cls(
            float(centre[0] - 0.5 * width / scale),
            float(centre[1] + 0.5 * height / scale),
            scale,
            int(width),
            int(height),
        )

    def to_pixels(self, xy: np.ndarray) -> np.ndarray:
        """(n, >=2) document points -> (n, 2) float64 (column, row) continuous pixel coordinates."""
        xy = np.asarray(xy, dtype=np.float64)
        return np.column_stack([(xy[:, 0] - self.x0) * self.scale, (self.y1 - xy[:, 1]) * self.scale])


@dataclass(frozen=True, eq=False)
class GBuffer:
    """Fragments of a rasterised view, back to front (ascending ``layer``), and what shading
    needs to composite them quickly.

    Attributes
    ----------
    view : View
    pix : (k,) int64
        Flat pixel index row * width + column.
    layer : (k,) int32
        Index of the mesh (layer) in the list given to :func:`rasterise`.
    alpha : (k,) float32
        Coverage of the pixel by the layer, in (0, 1].
    normal : (k, 3) float32
        Unit normal at the pixel centre (or at the nearest outline point outside the outline).
    front : (height * width,) int64
        Per pixel, the fragment whose layer is in front at the pixel centre, or -1: the owner of
        the pixel for isophote lines and picking.
    bounds : (n_layers + 1,) int64
        Fragments of layer i are ``bounds[i]:bounds[i + 1]``.
    stack_pixels : (p,) int64
        Covered pixels where fragments blend (an outline, a layer over another), each once;
        every other covered pixel holds one opaque fragment, whose colour is the pixel's.
    stack_frag, stack_slot : (q,) int64
        The fragments over those pixels, back to front, and the index of their pixel in
        ``stack_pixels``.
    stack_bounds : (n_layers + 1,) int64
        ``stack_frag[stack_bounds[i]:stack_bounds[i + 1]]`` are layer i's.
    front_frag : (f,) int64
        The fragments that own a pixel (``front[front >= 0]``, same order).
    edge_pix : (e,) int64
        Pixels near a layer's outline where that outline is not hidden by a layer in front.
    edge_dist : (e,) float32
        Distance in pixels from those pixel centres to the nearest such outline.
    """

    view: View
    pix: np.ndarray
    layer: np.ndarray
    alpha: np.ndarray
    normal: np.ndarray
    front: np.ndarray
    bounds: np.ndarray
    stack_pixels: np.ndarray
    stack_frag: np.ndarray
    stack_slot: np.ndarray
    stack_bounds: np.ndarray
    front_frag: np.ndarray
    edge_pix: np.ndarray
    edge_dist: np.ndarray

    @property
    def n_layers(self) -> int:
        return len(self.bounds) - 1

    def _line_data(self):
        """dn_dx, dn_dy, the owners' normals column by column, and per owned pixel a bound on
        |∇(n·l)| for any unit l (so lines are only evaluated where they can be)."""
        cache = self.__dict__.setdefault("_derivatives", [])
        if not cache:
            W, H = self.view.width, self.view.height
            dx, dy = _normal_derivatives(self.front, self.normal, self.layer, W, H)
            cols = tuple(np.ascontiguousarray(np.take(self.normal[:, j], self.front_frag)) for j in range(3))
            bound = np.sqrt(np.einsum("ij,ij->i", dx, dx) + np.einsum("ij,ij->i", dy, dy)).astype(np.float32)
            cache.extend((dx, dy, cols, bound))
        return cache

    def _stencil(self):
        """Per owned pixel (``front_frag`` order), for x then y: the indices of its neighbour
        after and before it that belong to the same layer (itself where none does) and the
        divisor (2: central, 1: one-sided or none), so that (v[hi] - v[lo]) / div is a field's
        difference per pixel; kept with the buffer."""
        cache = self.__dict__.setdefault("_stencil_cache", [])
        if not cache:
            W, H = self.view.width, self.view.height
            owned = np.nonzero(self.front >= 0)[0]
            own_layer = np.full(W * H, -1, dtype=np.int32)
            own_layer[owned] = self.layer[self.front[owned]]
            index = np.full(W * H, -1, dtype=np.int64)
            index[owned] = np.arange(len(owned))
            r, c = np.divmod(owned, W)
            mine = own_layer[owned]
            me = np.arange(len(owned))
            for step, lo_ok, hi_ok in ((1, c > 0, c < W - 1), (W, r > 0, r < H - 1)):
                q_hi = np.where(hi_ok, owned + step, owned)
                q_lo = np.where(lo_ok, owned - step, owned)
                same_hi = hi_ok & (own_layer[q_hi] == mine)
                same_lo = lo_ok & (own_layer[q_lo] == mine)
                hi = np.where(same_hi, index[q_hi], me)
                lo = np.where(same_lo, index[q_lo], me)
                div = np.maximum(same_hi.astype(np.float32) + same_lo, 1.0).astype(np.float32)
                cache.append((hi, lo, div))
        return cache

    def front_layer(self) -> np.ndarray:
        """(height, width) int32: the layer in front at each pixel centre, -1 for none."""
        out = np.full(self.front.shape, -1, dtype=np.int32)
        ok = self.front >= 0
        out[ok] = self.layer[self.front[ok]]
        return out.reshape(self.view.height, self.view.width)


def scan_triangles(P: np.ndarray, F: np.ndarray, width: int, height: int):
    """Pixel centres inside each triangle, by scanlines (no wasted tests).

    Parameters
    ----------
    P : (n, 2) float64
        Vertex positions in continuous pixel coordinates (column, row).
    F : (m, 3) int64
    width, height : int

    Returns
    -------
    pix : (k,) int64
        Flat pixel index; a centre exactly on an edge shared by two triangles appears for both.
    tri : (k,) int64
    bary : (k, 3) float64
        Barycentric coordinates of the pixel centre in its triangle, each in [0, 1], summing to 1.
    """
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3)))
    if len(F) == 0:
        return empty
    T = P[F]  # (m, 3, 2)
    a = T[:, 0]
    e1 = T[:, 1] - a
    e2 = T[:, 2] - a
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    ymin, ymax = T[:, :, 1].min(axis=1), T[:, :, 1].max(axis=1)
    r0 = np.clip(np.ceil(ymin - 0.5), 0, height).astype(np.int64)
    r1 = np.clip(np.floor(ymax - 0.5), -1, height - 1).astype(np.int64)
    nrow = np.where(np.abs(det) > 1e-12, np.maximum(r1 - r0 + 1, 0), 0)
    if nrow.sum() == 0:
        return empty
    # One (triangle, row) pair per scanline crossing the triangle.
    t = np.repeat(np.arange(len(F)), nrow)
    start = np.cumsum(nrow) - nrow
    row = r0[t] + (np.arange(len(t)) - start[t])
    yc = row + 0.5
    xlo = np.full(len(t), np.inf)
    xhi = np.full(len(t), -np.inf)
    for i, j in ((0, 1), (1, 2), (2, 0)):
        pa, pb = T[t, i], T[t, j]
        dy = pb[:, 1] - pa[:, 1]
        lo_y = np.minimum(pa[:, 1], pb[:, 1])
        hi_y = np.maximum(pa[:, 1], pb[:, 1])
        ok = (yc >= lo_y) & (yc <= hi_y) & (dy != 0)
        s = np.where(ok, (yc - pa[:, 1]) / np.where(dy != 0, dy, 1.0), 0.0)
        x = pa[:, 0] + s * (pb[:, 0] - pa[:, 0])
        xlo = np.where(ok, np.minimum(xlo, x), xlo)
        xhi = np.where(ok, np.maximum(xhi, x), xhi)
    c0 = np.clip(np.ceil(xlo - 0.5), 0, width).astype(np.int64)
    c1 = np.clip(np.floor(xhi - 0.5), -1, width - 1).astype(np.int64)
    ncol = np.maximum(c1 - c0 + 1, 0)
    ncol[~np.isfinite(xlo)] = 0
    tri = np.repeat(t, ncol)
    start = np.cumsum(ncol) - ncol
    k = np.arange(len(tri)) - np.repeat(start, ncol)
    col = np.repeat(c0, ncol) + k
    rows = np.repeat(row, ncol)
    dx = col + 0.5 - a[tri, 0]
    dy = rows + 0.5 - a[tri, 1]
    inv = 1.0 / det[tri]
    l1 = np.clip((dx * e2[tri, 1] - dy * e2[tri, 0]) * inv, 0.0, 1.0)
    l2 = np.clip((e1[tri, 0] * dy - e1[tri, 1] * dx) * inv, 0.0, 1.0)
    s = l1 + l2
    over = s > 1.0
    l1[over] /= s[over]
    l2[over] /= s[over]
    bary = np.column_stack([1.0 - l1 - l2, l1, l2])
    return rows * width + col, tri, bary


def boundary_edges(F: np.ndarray) -> np.ndarray:
    """(b, 2) int64 edges used by exactly one triangle (the outline, holes included)."""
    F = np.asarray(F, dtype=np.int64)
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(E, axis=1)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return E[count[inv.ravel()] == 1]


def _outline_distance(P, N, edges, width, height):
    """Pixels within 1.5 px of the outline: (pix, distance in px, normal at the nearest point)."""
    if len(edges) == 0:
        return np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 3))
    a, b = P[edges[:, 0]], P[edges[:, 1]]
    na, nb = N[edges[:, 0]], N[edges[:, 1]]
    length = np.linalg.norm(b - a, axis=1)
    pieces = np.maximum(1, np.ceil(length / _EDGE_PIECE).astype(np.int64))
    e = np.repeat(np.arange(len(edges)), pieces)
    start = np.cumsum(pieces) - pieces
    j = np.arange(len(e)) - start[e]
    t0 = j / pieces[e]
    t1 = (j + 1) / pieces[e]
    pa = a[e] + t0[:, None] * (b[e] - a[e])
    pb = a[e] + t1[:, None] * (b[e] - a[e])
    reach = 1.5
    lo = np.minimum(pa, pb) - reach
    hi = np.maximum(pa, pb) + reach
    c0 = np.clip(np.ceil(lo[:, 0] - 0.5), 0, width).astype(np.int64)
    c1 = np.clip(np.floor(hi[:, 0] - 0.5), -1, width - 1).astype(np.int64)
    r0 = np.clip(np.ceil(lo[:, 1] - 0.5), 0, height).astype(np.int64)
    r1 = np.clip(np.floor(hi[:, 1] - 0.5), -1, height - 1).astype(np.int64)
    bw, bh = np.maximum(c1 - c0 + 1, 0), np.maximum(r1 - r0 + 1, 0)
    n = bw * bh
    s = np.repeat(np.arange(len(e)), n)
    if len(s) == 0:
        return np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 3))
    k = np.arange(len(s)) - np.repeat(np.cumsum(n) - n, n)
    rr, cc = np.divmod(k, bw[s])
    row, col = r0[s] + rr, c0[s] + cc
    q = np.column_stack([col + 0.5, row + 0.5])
    d = pb[s] - pa[s]
    dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
    u = np.clip(np.einsum("ij,ij->i", q - pa[s], d) / dd, 0.0, 1.0)
    dist = np.linalg.norm(pa[s] + u[:, None] * d - q, axis=1)
    pix = row * width + col
    # Nearest piece per pixel.
    order = np.lexsort((dist, pix))
    pix, dist, s, u = pix[order], dist[order], s[order], u[order]
    first = np.r_[True, pix[1:] != pix[:-1]]
    pix, dist, s, u = pix[first], dist[first], s[first], u[first]
    ok = dist < reach
    pix, dist, s, u = pix[ok], dist[ok], s[ok], u[ok]
    tt = t0[s] + u * (t1[s] - t0[s])
    es = e[s]
    nrm = (1.0 - tt)[:, None] * na[es] + tt[:, None] * nb[es]
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    return pix, dist, nrm


def rasterise(meshes: list, view: View, antialias: bool = True, normals: list | None = None) -> GBuffer:
    """Rasterise layers back to front into per-pixel fragments (normals, coverage, layer ids).

    Parameters
    ----------
    meshes : list of Mesh or None
        Back to front: a later mesh covers earlier ones at every pixel it covers, whatever the
        heights; within one mesh the largest z wins (a folded or assembled mesh). None or an
        empty mesh keeps its index and draws nothing.
    view : View
    antialias : bool
        Coverage from the distance to each outline; False gives hard pixel-centre silhouettes.
    normals : list of (n_i, 3) float64 or None
        Vertex normals to interpolate instead of the display's own
        (:func:`sketchforge.geometry.heightfield.layer_normals`), one per mesh (None for
        that mesh's own): for comparing normal fields; such fragments are not cached.

    Returns
    -------
    GBuffer
    """
    pix_l, lay_l, alpha_l, nrm_l = [], [], [], []
    edges_l = []  # per layer (its index, outline pixels, their distances)
    for li, mesh in enumerate(meshes):
        if mesh is None or mesh.n_faces == 0:
            continue
        own = None if normals is None else normals[li]
        pix, alpha, n, edges = _layer_fragments(mesh, view, antialias, own)
        if edges is not None:
            edges_l.append((li, *edges))
        pix_l.append(pix)
        lay_l.append(np.full(len(pix), li, dtype=np.int32))
        alpha_l.append(alpha)
        nrm_l.append(n)
    return _assemble(view, len(meshes), pix_l, lay_l, alpha_l, nrm_l, edges_l)


def _layer_fragments(mesh, view: View, antialias: bool, normals=None):
    """One mesh's fragments in a view: (pix, alpha, normal, (outline pixels, distances) or None).

    Kept per mesh for the last few views (:data:`VIEWS_KEPT`: the canvas's, the layer
    thumbnail's, the one before a pan), so a change to one layer (an edit, a live preview)
    rasterises only that layer again, and redrawing a thumbnail does not evict the canvas's."""
    cached = _mesh_cache.get(mesh)
    V, F = np.asarray(mesh.V), np.asarray(mesh.F, dtype=np.int64)
    if normals is not None:
        cached = {"N": np.asarray(normals, dtype=np.float64).reshape(len(V), 3), "outline": boundary_edges(F),
                  "fragments": LRUCache(VIEWS_KEPT)}
    elif cached is None:
        cached = _mesh_cache.put(mesh, {"N": layer_normals(mesh), "outline": boundary_edges(F),
                                        "fragments": LRUCache(VIEWS_KEPT)})
    kept = cached["fragments"]
    hit = kept.get((view, antialias))
    if hit is not None:
        return hit
    N, outline = cached["N"], cached["outline"]
    W, H = int(view.width), int(view.height)
    npx = W * H
    P = view.to_pixels(V)
    pix, tri, bary = scan_triangles(P, F, W, H)
    if len(pix):
        count = np.bincount(pix, minlength=npx)
        dup = count[pix] > 1
        if dup.any():
            # Several fragments of one mesh at a pixel: shared edges (same surface) or a
            # folded mesh. The largest z wins: write them in ascending z, the last one stays.
            z = np.einsum("kj,kj->k", bary, V[F[tri], 2])
            order = np.r_[np.nonzero(~dup)[0], np.nonzero(dup)[0][np.argsort(z[dup], kind="stable")]]
            pix, tri, bary = pix[order], tri[order], bary[order]
            owner = np.full(npx, -1, dtype=np.int64)
            owner[pix] = np.arange(len(pix))
            keep = owner[pix] == np.arange(len(pix))
            pix, tri, bary = pix[keep], tri[keep], bary[keep]
        n = np.einsum("kj,kjd->kd", bary, N[F[tri]])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    else:
        n = np.zeros((0, 3))
    alpha = np.ones(len(pix))
    edges = None
    if antialias:
        opix, dist, onrm = _outline_distance(P, N, outline, W, H)
        edges = (opix, dist)
        inside = np.zeros(npx, dtype=bool)
        inside[pix] = True
        ins = inside[opix]
        # Inside the outline: less than full coverage within half a pixel of it.
        where = np.full(npx, -1, dtype=np.int64)
        where[pix] = np.arange(len(pix))
        k = where[opix[ins]]
        alpha[k] = np.clip(0.5 + dist[ins], 0.0, 1.0)
        # Outside: the part of the pixel the outline still reaches, shaded like the rim.
        cov = np.clip(0.5 - dist[~ins], 0.0, 1.0)
        grow = cov > 1.0 / 512.0
        pix = np.r_[pix, opix[~ins][grow]]
        n = np.r_[n, onrm[~ins][grow]]
        alpha = np.r_[alpha, cov[grow]]
    result = (pix, alpha.astype(np.float32), n.astype(np.float32), edges)
    for a in (result[0], result[1], result[2], *(edges or ())):
        a.flags.writeable = False  # shared between buffers
    kept.put((view, antialias), result)
    if normals is None:
        _mesh_cache.put(mesh, cached)  # weighed again with its new view
    return result


def _assemble(view, L, pix_l, lay_l, alpha_l, nrm_l, edges_l) -> GBuffer:
    W, H = int(view.width), int(view.height)
    npx = W * H
    i64, f32 = np.int64, np.float32
    if pix_l:
        pix = np.concatenate(pix_l)
        lay = np.concatenate(lay_l)
        alpha = np.concatenate(alpha_l)
        nrm = np.concatenate(nrm_l)
    else:
        pix, lay, alpha, nrm = np.zeros(0, i64), np.zeros(0, np.int32), np.zeros(0, f32), np.zeros((0, 3), f32)
    # Drop what an opaque fragment of a layer in front hides: per pixel, the last opaque layer.
    top = np.full(npx, -1, dtype=np.int32)
    opaque = alpha >= 1.0
    top[pix[opaque]] = lay[opaque]  # ascending layers: the frontmost writes last
    keep = lay >= top[pix]
    pix, lay, alpha, nrm = pix[keep], lay[keep], alpha[keep], nrm[keep]
    # Outlines: where no opaque fragment of a layer in front hides them; the nearest wins.
    edge = np.full(npx, np.inf, dtype=np.float32)
    for li, opix, dist in edges_l:
        seen = top[opix] <= li
        np.minimum.at(edge, opix[seen], dist[seen].astype(np.float32))
    edge_pix = np.nonzero(np.isfinite(edge))[0]
    edge_dist = edge[edge_pix]
    # Owner at the pixel centre: the frontmost fragment whose layer covers the centre (alpha >=
    # 0.5 means the centre is inside that layer's outline).
    front = np.full(npx, -1, dtype=i64)
    centre = alpha >= 0.5
    front[pix[centre]] = np.nonzero(centre)[0]
    bounds = np.searchsorted(lay, np.arange(L + 1), side="left").astype(i64)
    count = np.bincount(pix, minlength=npx)
    alone = (count[pix] == 1) & (alpha >= 1.0)
    stack_frag = np.nonzero(~alone)[0]  # already back to front
    stack_pixels, stack_slot = np.unique(pix[stack_frag], return_inverse=True)
    front_frag = front[front >= 0]
    # Column-major: the shaders' per-component products run on contiguous columns.
    nrm = np.asfortranarray(nrm, dtype=np.float32)
    return GBuffer(view, pix, lay, alpha, nrm, front, bounds, stack_pixels.astype(i64),
                   stack_frag.astype(i64), stack_slot.reshape(-1).astype(i64),
                   np.searchsorted(lay[stack_frag], np.arange(L + 1)).astype(i64), front_frag,
                   edge_pix, edge_dist)


def _normal_derivatives(front, nrm, lay, W, H):
    """Finite differences of the owner's normal at each owned pixel: central where both
    neighbours belong to the same layer, one-sided where one does, 0 where none does."""
    owned = np.nonzero(front >= 0)[0]
    f = front[owned]
    own_layer = np.full(W * H, -1, dtype=np.int32)
    own_layer[owned] = lay[f]
    comp = [np.take(nrm[:, j], f) for j in range(3)]  # per component: contiguous gathers
    img = np.zeros((3, W * H), dtype=np.float32)
    for j in range(3):
        img[j, owned] = comp[j]
    r, c = np.divmod(owned, W)
    mine = own_layer[owned]
    out = []
    for step, lo_ok, hi_ok in ((1, c > 0, c < W - 1), (W, r > 0, r < H - 1)):
        grads = np.zeros((len(owned), 3), dtype=np.float32, order="F")
        count = np.zeros(len(owned), dtype=np.float32)
        for sign, ok in ((1, hi_ok), (-1, lo_ok)):
            q = np.where(ok, owned + sign * step, owned)
            same = (ok & (np.take(own_layer, q) == mine)).astype(np.float32)
            for j in range(3):
                grads[:, j] += same * sign * (np.take(img[j], q) - comp[j])
            count += same
        out.append(grads / np.maximum(count, 1.0)[:, None])
    return out[0], out[1]


@dataclass(frozen=True, eq=False)
class SurfaceMaps:
    """The surface seen at each pixel centre, unblended (no antialiasing, no background): what
    must hold exactly pixel by pixel, such as a shape-from-shading sample's normal and depth.

    Attributes
    ----------
    view : View
    mask : (height, width) bool
        Pixels whose centre lies on a layer.
    normal : (height, width, 3) float32
        The front layer's unit normal there (x right, y up, z towards the viewer), the very
        normal :func:`shade` shades; (0, 0, 0) outside the mask.
    height : (height, width) float64
        The front layer's z there (document units, towards the viewer), the largest z of that
        layer at the pixel as in :func:`rasterise`; 0 outside the mask.
    layer : (height, width) int32
        The front layer's index, -1 outside the mask.
    """

    view: View
    mask: np.ndarray
    normal: np.ndarray
    height: np.ndarray
    layer: np.ndarray


def front_surface(meshes: list, view: View) -> SurfaceMaps:
    """Per-pixel normal and height of the front surface, from :func:`rasterise`'s fragments.

    Parameters
    ----------
    meshes : list of Mesh or None
        Back to front, as for :func:`rasterise` (a later mesh covers earlier ones; within one
        mesh the largest z wins, so an assembled model shows its front).
    view : View

    Returns
    -------
    SurfaceMaps
    """
    gbuf = rasterise(list(meshes), view, antialias=False)
    W, H = int(view.width), int(view.height)
    owned = np.nonzero(gbuf.front >= 0)[0]
    frag = gbuf.front[owned]
    normal = np.zeros((H * W, 3), dtype=np.float32)
    normal[owned] = gbuf.normal[frag]
    layer = np.full(H * W, -1, dtype=np.int32)
    layer[owned] = gbuf.layer[frag]
    height = np.zeros(H * W, dtype=np.float64)
    for li in np.unique(layer[owned]):
        mesh = meshes[int(li)]
        V, F = np.asarray(mesh.V), np.asarray(mesh.F, dtype=np.int64)
        # The same pixel centres, triangles and barycentric weights as the fragments: the
        # largest z per pixel is the fragment rasterise kept there.
        pix, tri, bary = scan_triangles(view.to_pixels(V), F, W, H)
        z = np.einsum("kj,kj->k", bary, V[F[tri], 2])
        top = np.full(H * W, -np.inf)
        np.maximum.at(top, pix, z)
        mine = owned[layer[owned] == li]
        height[mine] = top[mine]
    return SurfaceMaps(
        view,
        (layer >= 0).reshape(H, W),
        normal.reshape(H, W, 3),
        height.reshape(H, W),
        layer.reshape(H, W),
    )


def reflectance_image(maps: SurfaceMaps, light, reflectance) -> np.ndarray:
    """Shading as a number per pixel, max(0, R(n, l)) of :attr:`SurfaceMaps.normal` inside the
    mask and 0 outside: the display's Lambertian is ``reflectance = lambda N, l: N @ l``.

    Parameters
    ----------
    maps : SurfaceMaps
    light : (3,) float64
        Unit direction towards the light.
    reflectance : callable
        ``reflectance(N (k, 3) float64, l (3,) float64) -> (k,)`` signed values; it gets every
        pixel (normals outside the mask are (0, 0, 1), so a model compiled per input size
        sees one size per image size).

    Returns
    -------
    (height, width) float64
    """
    direction = np.asarray(light, dtype=np.float64).reshape(3)
    N = maps.normal.reshape(-1, 3).astype(np.float64)
    outside = ~maps.mask.reshape(-1)
    N[outside] = (0.0, 0.0, 1.0)
    R = np.asarray(reflectance(N, direction), dtype=np.float64).reshape(-1)
    if R.shape != (len(N),) or not np.all(np.isfinite(R)):
        raise ValueError(f"the reflectance returned {R.shape} values for {len(N)} normals; it must return one finite value per normal")
    out = np.maximum(R, 0.0)
    out[outside] = 0.0
    return out.reshape(maps.mask.shape)
