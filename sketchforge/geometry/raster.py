"""Headless software rendering of the top view (the drawing plane seen from +z), and PNG output.

Pure numpy, so the CLI, tests and thumbnails render without OpenGL. The rasterisation and the
shading are :mod:`sketchforge.geometry.gbuffer`'s, the very ones the editing canvas uses: normals
interpolated per pixel, antialiased silhouettes, layers composited back to front, isophote lines
from the per-pixel n·l of the layer in front.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

from sketchforge.atomic import write_bytes_atomic
from sketchforge.errors import LimitError
from sketchforge.geometry.gbuffer import View, rasterise, shade
from sketchforge.geometry.shaders import cel_shade, lambert_shade

#: Default background: a light warm grey.
BACKGROUND = (0.95, 0.94, 0.92)
#: Isophote line colour and opacity.
LINE_COLOUR = np.array([0.12, 0.10, 0.10])
LINE_ALPHA = 0.85
#: Largest raster cost: twice the image's pixels plus the bounding-box pixels of every
#: triangle (the candidate fragments; overdraw counts once per layer covering a pixel),
#: checked before anything of the image's size exists. At the cap a render peaks near
#: 1.2 GB (benchmarks/bench_reliability.py); 2000 overlapping full-frame triangles at 512 do
#: not fit.
MAX_RASTER_COST = 25_000_000
_PIXEL_COST = 2


def render_top(
    meshes: list,
    light,
    size: int,
    isophotes: int = 0,
    cel: bool = False,
    background=BACKGROUND,
    margin: float = 0.05,
    shader=None,
    tints=None,
    max_cost: int = MAX_RASTER_COST,
    model=None,
) -> np.ndarray:
    """Render meshes seen from above, shaded by a directional light.

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
        Three-tone cel shading instead of clay Lambertian (ignored when ``shader`` is given).
    background : (3,) float in [0, 1]
    margin : float
        Fraction of the image left empty on each side, in [0, 0.5).
    shader : callable or None
        ``shader(normals (k, 3), light (3,)) -> (k, 3)`` colours in [0, 1] (a registered display
        shader's ``shade``); None: Lambert or cel as ``cel`` says.
    tints : (len(meshes), 3) float or None
        Per-layer colour multipliers.
    max_cost : int
        Refuse (LimitError, before any fragment is made) when twice the image's pixels plus
        the triangles' bounding-box pixels exceed this: memory and time grow with both.
    model : ReflectanceModel or None
        Shade with this reflectance model's own R(n, l) (clay lit by it, its isophote lines at
        R = j / (K + 1); :mod:`sketchforge.geometry.model_shading`) instead of ``shader``.

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
    shown = [m for m in meshes if m is not None and m.n_faces > 0]
    if not shown:
        image = np.empty((size, size, 3))
        image[:] = bg
        return _to_uint8(image)
    view = View.framing(shown, size, size, margin)
    check_raster_cost(shown, view, max_cost)
    gbuf = rasterise(list(meshes), view)
    intensity = None
    if model is not None:
        from sketchforge.geometry.model_shading import model_shader

        shader, intensity = model_shader(model).shade, model_shader(model).intensity
    elif shader is None:
        shader = cel_shade if cel else lambert_shade
    return shade(gbuf, l, shader, bg, tints=tints, isophotes=K, line_colour=LINE_COLOUR, line_alpha=LINE_ALPHA,
                 intensity=intensity)


def _to_uint8(image: np.ndarray) -> np.ndarray:
    return np.round(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)


def check_raster_cost(meshes, view, max_cost: int = MAX_RASTER_COST) -> None:
    """Refuse (LimitError) a render whose cost, twice the view's pixels plus the pixels of every
    triangle's bounding box inside the view, exceeds ``max_cost``: memory and time grow with both."""
    W, H = int(view.width), int(view.height)
    cost = _PIXEL_COST * W * H
    for m in meshes:
        P = view.to_pixels(np.asarray(m.V))
        T = P[np.asarray(m.F, dtype=np.int64)]
        lo = np.clip(np.floor(T.min(axis=1)), 0, [W, H])
        hi = np.clip(np.ceil(T.max(axis=1)), 0, [W, H])
        cost += int(np.prod(np.maximum(hi - lo, 0.0), axis=1).sum())
        if cost > max_cost:
            raise LimitError(
                f"this render would test about {cost / 1e6:.0f} M pixels, over the rendering limit of "
                f"{max_cost / 1e6:.0f} M (overlapping layers count once each): use a smaller size"
            )


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
