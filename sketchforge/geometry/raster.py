"""Headless software rendering of the top view (the drawing plane seen from +z), and PNG output.

Pure numpy, so the CLI, tests and thumbnails render without OpenGL. Triangles are rasterised in
buckets of equal (padded) bounding-box size: each bucket tests all of its triangles against all
pixel centres of their boxes at once, and a z-buffer keeps the nearest fragment (largest z).
Shading is per pixel from the barycentrically interpolated vertex normals, so cel bands stay
crisp; isophote lines come from a per-pixel level-crossing test of the linearly interpolated
vertex intensity, the same field the isophote polylines are extracted from.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

from sketchforge.atomic import write_bytes_atomic
from sketchforge.errors import LimitError
from sketchforge.geometry.merge import merge_meshes
from sketchforge.geometry.normals import vertex_normals
from sketchforge.geometry.shaders import cel_shade, lambert_shade

#: Default background: a light warm grey.
BACKGROUND = (0.95, 0.94, 0.92)
#: Isophote line colour and opacity.
LINE_COLOUR = np.array([0.12, 0.10, 0.10])
LINE_ALPHA = 0.85
# Upper bound on candidate pixels tested at once (memory ~ 60 bytes each).
_CHUNK = 1 << 21
#: Largest raster cost: twice the image's pixels (about 90 bytes each at the peak, with the
#: isophote buffers) plus the bounding-box pixels of every triangle (the candidate fragments,
#: about 50 bytes each: overdraw counts once per layer covering a pixel). At the cap a render
#: peaks near 1.2 GB (benchmarks/bench_reliability.py); --size 3500 of examples/creature.json
#: fits, 2000 overlapping full-frame triangles at 512 do not.
MAX_RASTER_COST = 25_000_000
_PIXEL_COST = 2


def _frame(meshes, size: int, margin: float):
    pts = np.concatenate([m.V[:, :2] for m in meshes])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = 0.5 * (lo + hi)
    ext = float(np.max(hi - lo))
    scale = size * (1.0 - 2.0 * margin) / ext if ext > 0 else 1.0
    return centre, scale


def render_top(
    meshes: list,
    light,
    size: int,
    isophotes: int = 0,
    cel: bool = False,
    background=BACKGROUND,
    margin: float = 0.05,
    max_cost: int = MAX_RASTER_COST,
) -> np.ndarray:
    """Render meshes seen from above with an in-plane light.

    Parameters
    ----------
    meshes : list of Mesh
        Back to front: a later mesh covers earlier ones (layer depth order); within a mesh the
        largest z wins. Framed jointly with equal aspect and a margin.
    light : (3,) float64 or Light
        Direction towards the light (normalised here).
    size : int
        Image width and height in pixels.
    isophotes : int
        Number K of isophote lines, at n·l = j / (K + 1) for j = 1..K; 0 for none.
    cel : bool
        Three-tone cel shading instead of clay Lambertian.
    background : (3,) float in [0, 1]
    margin : float
        Fraction of the image left empty on each side, in [0, 0.5).
    max_cost : int
        Refuse (LimitError, before any fragment is made) when twice the image's pixels plus
        the triangles' bounding-box pixels exceed this: memory and time grow with both.

    Returns
    -------
    (size, size, 3) uint8
        Row 0 is the top of the drawing (largest y); column 0 its left (smallest x).
    """
    size = int(size)
    if size < 1:
        raise ValueError(f"image size must be at least 1 pixel, got {size}")
    if _PIXEL_COST * size * size > max_cost:  # before the image is allocated (8192² is 1.6 GB of float64)
        raise LimitError(
            f"a {size}x{size} image is over the rendering limit of {max_cost // _PIXEL_COST:,} pixels; use a smaller size"
        )
    if not 0.0 <= margin < 0.5:
        raise ValueError(f"margin must be in [0, 0.5), got {margin}")
    K = int(isophotes)
    if K < 0:
        raise ValueError(f"the number of isophotes must be >= 0, got {isophotes}")
    l = np.asarray(getattr(light, "direction", light), dtype=np.float64).reshape(3)
    nl = np.linalg.norm(l)
    if not np.isfinite(nl) or nl == 0:
        raise ValueError("the light direction must be a finite non-zero vector")
    l = l / nl
    bg = np.clip(np.asarray(background, dtype=np.float64).reshape(3), 0.0, 1.0)
    image = np.empty((size, size, 3))
    image[:] = bg
    meshes = [m for m in meshes if m is not None and m.n_faces > 0]
    if not meshes:
        return _to_uint8(image)

    centre, scale = _frame(meshes, size, margin)
    # One vertex/triangle list for every mesh; keep which mesh each triangle came from.
    merged = merge_meshes(meshes)
    V, F = merged.V, merged.F
    N = vertex_normals(V, F)
    tri_mesh = np.repeat(np.arange(len(meshes)), [m.n_faces for m in meshes])
    E = N @ l

    # Continuous pixel coordinates: column = u, row = v, pixel (r, c) has its centre at
    # (c + 0.5, r + 0.5); y grows upwards, rows downwards.
    u = (V[:, 0] - centre[0]) * scale + 0.5 * size
    v = 0.5 * size - (V[:, 1] - centre[1]) * scale
    pix, depth, tri, b1, b2 = _rasterise(u, v, V[:, 2], F, size, max_cost - _PIXEL_COST * size * size)

    if len(pix):
        # Per pixel the later mesh wins (meshes are layers back to front: a layer drawn in
        # front covers those behind whatever their heights); within a mesh, the largest z.
        order = np.lexsort((-depth, -tri_mesh[tri], pix))
        pix, tri, b1, b2 = pix[order], tri[order], b1[order], b2[order]
        first = np.ones(len(pix), dtype=bool)
        first[1:] = pix[1:] != pix[:-1]
        pix, tri, b1, b2 = pix[first], tri[first], b1[first], b2[first]
        w = np.stack([1.0 - b1 - b2, b1, b2], axis=1)
        corners = F[tri]
        n = np.einsum("kj,kjd->kd", w, N[corners])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        colour = (cel_shade if cel else lambert_shade)(n, l)
        flat = image.reshape(-1, 3)
        flat[pix] = colour
        if K > 0:
            e = np.einsum("kj,kj->k", w, E[corners])
            level = np.full(size * size, -1, dtype=np.int64)
            level[pix] = np.clip(np.floor(e * (K + 1)), 0, K).astype(np.int64)
            owner = np.full(size * size, -1, dtype=np.int64)
            owner[pix] = tri_mesh[tri]
            level = level.reshape(size, size)
            owner = owner.reshape(size, size)
            line = np.zeros((size, size), dtype=bool)
            # A level change between a pixel and its right or lower neighbour on the same mesh;
            # silhouettes and occlusion edges are not isophotes.
            line[:, :-1] |= (owner[:, :-1] >= 0) & (owner[:, :-1] == owner[:, 1:]) & (
                level[:, :-1] != level[:, 1:]
            )
            line[:-1, :] |= (owner[:-1, :] >= 0) & (owner[:-1, :] == owner[1:, :]) & (
                level[:-1, :] != level[1:, :]
            )
            image[line] = (1.0 - LINE_ALPHA) * image[line] + LINE_ALPHA * LINE_COLOUR
    return _to_uint8(image)


def _to_uint8(image: np.ndarray) -> np.ndarray:
    return np.round(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)


def _rasterise(u, v, z, F, size, max_candidates=None):
    """Fragments (pixel index, depth, triangle, b1, b2) of all triangles at pixel centres.
    Raises LimitError, before making any, when the triangles' bounding boxes hold more than
    ``max_candidates`` pixels."""
    P = np.stack([u, v], axis=1)
    tri = P[F]  # (m, 3, 2)
    a = tri[:, 0]
    e1 = tri[:, 1] - a
    e2 = tri[:, 2] - a
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    lo = tri.min(axis=1)
    hi = tri.max(axis=1)
    # Pixel centres c + 0.5 inside [lo, hi]: c from ceil(lo - 0.5) to floor(hi - 0.5).
    c0 = np.clip(np.ceil(lo[:, 0] - 0.5), 0, size).astype(np.int64)
    c1 = np.clip(np.floor(hi[:, 0] - 0.5), -1, size - 1).astype(np.int64)
    r0 = np.clip(np.ceil(lo[:, 1] - 0.5), 0, size).astype(np.int64)
    r1 = np.clip(np.floor(hi[:, 1] - 0.5), -1, size - 1).astype(np.int64)
    bw = c1 - c0 + 1
    bh = r1 - r0 + 1
    keep = (np.abs(det) > 1e-12) & (bw > 0) & (bh > 0)
    ids = np.nonzero(keep)[0]
    if max_candidates is not None:
        candidates = int(np.sum(bw[ids] * bh[ids]))
        if candidates > max_candidates:
            raise LimitError(
                f"rendering {len(F):,} triangles at {size}x{size} would test {candidates:,} pixels "
                f"(overlapping layers count once each); the limit is {max(max_candidates, 0):,}: use a smaller size"
            )
    out = ([], [], [], [], [])
    if len(ids) == 0:
        return tuple(np.zeros(0, dtype=t) for t in (np.int64, float, np.int64, float, float))
    # Bucket by bounding box padded to powers of two: few buckets, at most 4x wasted tests.
    pw = 1 << np.ceil(np.log2(bw[ids])).astype(np.int64)
    ph = 1 << np.ceil(np.log2(bh[ids])).astype(np.int64)
    key = pw * (4 * size + 4) + ph
    order = np.argsort(key, kind="stable")
    ids, key, pw, ph = ids[order], key[order], pw[order], ph[order]
    bounds = np.nonzero(np.r_[True, key[1:] != key[:-1], True])[0]
    inv_det = 1.0 / np.where(keep, det, 1.0)
    for s, t in zip(bounds[:-1], bounds[1:]):
        W, H = int(pw[s]), int(ph[s])
        oy, ox = np.divmod(np.arange(W * H), W)
        step = max(1, _CHUNK // (W * H))
        for cs in range(s, t, step):
            g = ids[cs : min(t, cs + step)]
            cols = c0[g, None] + ox[None, :]
            rows = r0[g, None] + oy[None, :]
            dx = cols + 0.5 - a[g, 0, None]
            dy = rows + 0.5 - a[g, 1, None]
            l1 = (dx * e2[g, 1, None] - dy * e2[g, 0, None]) * inv_det[g, None]
            l2 = (e1[g, 0, None] * dy - e1[g, 1, None] * dx) * inv_det[g, None]
            inside = (
                (l1 >= -1e-12) & (l2 >= -1e-12) & (l1 + l2 <= 1.0 + 1e-12)
                & (cols <= c1[g, None]) & (rows <= r1[g, None])
            )
            gi, ki = np.nonzero(inside)
            l1 = l1[gi, ki]
            l2 = l2[gi, ki]
            tg = g[gi]
            fz = z[F[tg]]
            out[0].append(rows[gi, ki] * size + cols[gi, ki])
            out[1].append((1.0 - l1 - l2) * fz[:, 0] + l1 * fz[:, 1] + l2 * fz[:, 2])
            out[2].append(tg)
            out[3].append(l1)
            out[4].append(l2)
    return tuple(np.concatenate(x) for x in out)


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    crc = zlib.crc32(kind + data) & 0xFFFFFFFF
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)


def encode_png(rgb: np.ndarray) -> bytes:
    """PNG bytes (8-bit RGB, no filter, zlib level 6) of an (H, W, 3) uint8 image."""
    rgb = np.asarray(rgb)
    if rgb.dtype != np.uint8 or rgb.ndim != 3 or rgb.shape[2] != 3 or min(rgb.shape[:2]) < 1:
        raise ValueError(f"write_png needs an (H, W, 3) uint8 image, got {rgb.shape} {rgb.dtype}")
    h, w, _ = rgb.shape
    raw = np.zeros((h, 1 + 3 * w), dtype=np.uint8)  # filter byte 0 (None) on each row
    raw[:, 1:] = rgb.reshape(h, 3 * w)
    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + _png_chunk(b"IHDR", header)
        + _png_chunk(b"IDAT", zlib.compress(raw.tobytes(), 6))
        + _png_chunk(b"IEND", b"")
    )


def write_png(path, rgb: np.ndarray) -> None:
    """Write an RGB image as PNG atomically (temp file in the same folder, fsync, rename).

    Parameters
    ----------
    path : str or Path
    rgb : (H, W, 3) uint8

    Raises
    ------
    ValueError
        For an image of the wrong shape or dtype.
    ExportError
        If the file cannot be written (missing folder, no permission); an existing file at
        ``path`` is then left untouched.
    """
    write_bytes_atomic(path, encode_png(rgb))
