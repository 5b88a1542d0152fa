"""Shading a GBuffer (:mod:`sketchforge.geometry.gbuffer`): a display shader applied to the
fragments, composited back to front over the background, with the isophote lines and the
layers' outlines drawn over them. It never touches the geometry, so a new light costs a dot
product and a blend, not a rasterisation. (``gbuffer`` re-exports every name.)"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from sketchforge.geometry.gbuffer import GBuffer


def shade(
    gbuf: GBuffer,
    light,
    shader,
    background,
    tints=None,
    isophotes: int = 0,
    line_colour=(0.12, 0.10, 0.10),
    line_alpha: float = 0.85,
    line_width: float = 1.2,
    bgrx: bool = False,
    outline_alpha: float = 0.0,
    outline_width: float = 1.0,
    out: np.ndarray | None = None,
    intensity=None,
) -> np.ndarray:
    """Shade a GBuffer and composite it back to front over the background.

    Parameters
    ----------
    gbuf : GBuffer
    light : (3,) float64
        Unit direction towards the light.
    shader : callable
        ``shader(normals (k, 3) float32, light (3,) float64) -> (k, 3)`` colours in [0, 1].
    background : (3,) float in [0, 1]
    tints : (n_layers, 3) float or None
        Per-layer colour multiplier (telling layers apart); None for none.
    isophotes : int
        K lines at n·l = j / (K + 1), j = 1..K, over the front layer; 0 for none.
    line_colour, line_alpha, line_width
        The lines' colour, opacity and width in pixels.
    bgrx : bool
        Return (height, width, 4) uint8 in Qt's ``Format_RGB32`` byte order (B, G, R, 255)
        instead of RGB.
    outline_alpha, outline_width
        Opacity (0: none) and width in pixels of the layers' visible outlines, drawn in the
        isophote line colour: where a layer lies over another one, the eye finds its edge.
    out : (height, width, 4) uint8 or None
        With ``bgrx``: the result of an earlier ``shade`` of this very buffer with the same
        background, written over in place. Pixels no fragment reaches never change between
        lights, so only the others are written (a light drag at 10^6 pixels).
    intensity : callable or None
        ``intensity(normals (k, 3), light (3,)) -> E (k,)``: the reflectance the isophote lines
        follow (a model's, called before ``shader`` so that it may reuse E:
        :mod:`sketchforge.geometry.model_shading`); None: n·l.

    Returns
    -------
    (height, width, 3) or (height, width, 4) uint8

    Raises
    ------
    ValueError
        If the shader returns the wrong shape or non-finite colours.
    """
    view = gbuf.view
    W, H = view.width, view.height
    l = np.asarray(light, dtype=np.float64).reshape(3)
    bg = np.clip(np.asarray(background, dtype=np.float32).reshape(3), 0.0, 1.0)
    bg32 = _pack(bg[None, :] * 255.0 + 0.5)[0]
    if out is not None and bgrx and out.shape == (H, W, 4) and out.dtype == np.uint8 and out.flags.c_contiguous:
        out = out.reshape(-1).view("<u4")
        out[gbuf.edge_pix] = bg32  # outlines reach past the fragments: start them afresh
    else:
        out = np.empty(H * W, dtype=np.uint32)
        out[:] = bg32
    if len(gbuf.pix):
        lines = intensity(gbuf.normal, l) if intensity is not None and isophotes > 0 else None
        colour = np.asarray(shader(gbuf.normal, l), dtype=np.float32)  # a model's reuses the R of ``lines``
        # one summing pass: a NaN or an infinity anywhere makes the sum non-finite
        if colour.shape != (len(gbuf.pix), 3) or not np.isfinite(colour.sum(dtype=np.float64)):
            raise ValueError(
                f"the display shader returned an array of shape {colour.shape} for {len(gbuf.pix)} "
                "normals; it must return one finite RGB row per normal"
            )
        if not colour.flags.writeable or np.may_share_memory(colour, gbuf.normal):
            colour = colour.copy()  # scaled in place below: never write into the buffer
        scale = np.full((gbuf.n_layers, 3), 255.0, dtype=np.float32)
        if tints is not None:
            scale *= np.asarray(tints, dtype=np.float32).reshape(-1, 3)[: gbuf.n_layers]
        b = gbuf.bounds
        for li in range(gbuf.n_layers):  # fragments are grouped by layer: slices, no gather
            if b[li + 1] > b[li]:
                colour[b[li] : b[li + 1]] *= scale[li]
        if isophotes > 0:
            cov = isophote_coverage(gbuf, l, isophotes, line_width, lines)
            hit = np.nonzero(cov > 0)[0]
            f = gbuf.front_frag[hit]
            lc = np.asarray(line_colour, dtype=np.float32).reshape(3) * 255.0
            colour[f] += (line_alpha * cov[hit])[:, None] * (lc - colour[f])
        colour += 0.5
        # every fragment's own colour first (most pixels hold one: done), then the pixels
        # where several blend are overwritten below
        out[gbuf.pix] = _pack(colour)
        if len(gbuf.stack_pixels):
            acc = np.empty((len(gbuf.stack_pixels), 3), dtype=np.float32)
            acc[:] = bg * 255.0 + 0.5
            fr, slot, sb = gbuf.stack_frag, gbuf.stack_slot, gbuf.stack_bounds
            # A pixel holds at most one fragment per layer: blend layer by layer, back to front
            # (stack_frag ascends, so it is grouped by layer).
            for li in range(gbuf.n_layers):
                k, q = fr[sb[li] : sb[li + 1]], slot[sb[li] : sb[li + 1]]
                if len(k):
                    acc[q] += gbuf.alpha[k, None] * (colour[k] - acc[q])
            out[gbuf.stack_pixels] = _pack(acc)
    if outline_alpha > 0 and len(gbuf.edge_pix):
        cov = np.clip(np.float32(0.5 * outline_width + 0.5) - gbuf.edge_dist, 0.0, 1.0) * outline_alpha
        hit = cov > 0
        p = gbuf.edge_pix[hit]
        px = out[p]
        cur = np.column_stack([(px >> 16) & 255, (px >> 8) & 255, px & 255]).astype(np.float32)
        lc = np.asarray(line_colour, dtype=np.float32).reshape(3) * 255.0
        out[p] = _pack(cur + cov[hit, None] * (lc - cur) + 0.5)
    bytes_ = out.view(np.uint8).reshape(H, W, 4)  # little-endian: B, G, R, 255
    if bgrx:
        return bytes_
    return bytes_[:, :, 2::-1].copy()


def _pack(c: np.ndarray) -> np.ndarray:
    """(k, 3) float32 0..255.5 RGB (clipped in place) -> (k,) uint32 0xffRRGGBB (Qt's
    Format_RGB32), written byte by byte (B, G, R, 255 in little-endian memory)."""
    c = np.clip(c, 0.0, 255.0, out=c if c.dtype == np.float32 and c.flags.writeable else None)
    c8 = c.astype(np.uint8)
    p4 = np.empty((len(c8), 4), dtype=np.uint8)
    p4[:, 0] = c8[:, 2]
    p4[:, 1] = c8[:, 1]
    p4[:, 2] = c8[:, 0]
    p4[:, 3] = 255
    return p4.view("<u4").ravel()


def isophote_coverage(gbuf: GBuffer, light, K: int, width: float = 1.2, intensity=None) -> np.ndarray:
    """Antialiased isophote lines n·l = j/(K+1) of the front layers, as coverage per owning
    fragment (``gbuf.front_frag``).

    The distance of a pixel to the nearest level, |E - c| / |∇E|, uses the screen-space gradient
    of the front layer's own E (normal differences that never cross into another layer), so a
    line keeps ``width`` pixels whatever the zoom, and stops where a layer in front begins.
    ``intensity``: E (k,) per fragment, a reflectance model's (lines at E = j/(K+1), their
    distance in pixels from E's differences between neighbouring pixels); None: E = n·l.

    Returns
    -------
    (f,) float32 in [0, 1]
    """
    l = np.asarray(light, dtype=np.float32).reshape(3)
    K = int(K)
    if intensity is not None:
        return _model_coverage(gbuf, K, width, intensity)
    dn_dx, dn_dy, (nx, ny, nz), bound = gbuf._line_data()
    t = nx * (l[0] * (K + 1))
    t += ny * (l[1] * (K + 1))
    t += nz * (l[2] * (K + 1))
    d = np.abs(t - np.clip(np.rint(t), 1, K))  # distance to the nearest level, in level units
    reach = np.float32(0.5 * width + 0.5)
    # |∇t| <= (K + 1) * bound: pixels farther than ``reach`` from a line even at that slope are
    # skipped (most of them), the others get the exact distance.
    cand = np.nonzero(d < reach * (K + 1) * bound)[0]
    cov = np.zeros(len(t), dtype=np.float32)
    if len(cand):
        gx = _dot(dn_dx[cand], l) * (K + 1)
        gy = _dot(dn_dy[cand], l) * (K + 1)
        g = np.sqrt(gx * gx + gy * gy)
        cov[cand] = np.clip(reach - d[cand] / np.maximum(g, 1e-6), 0.0, 1.0)
    return cov


def _model_coverage(gbuf: GBuffer, K: int, width: float, E) -> np.ndarray:
    """:func:`isophote_coverage` of a reflectance model's E per fragment: the distance to a
    level in pixels from E's own differences between neighbouring pixels of the same layer
    (central where both belong to it, one-sided where one does: :meth:`GBuffer._stencil`)."""
    f = gbuf.front_frag
    t = np.take(E, f).astype(np.float32)
    t *= np.float32(K + 1)
    d = np.abs(t - np.clip(np.rint(t), 1, K))
    reach = np.float32(0.5 * width + 0.5)
    (hx, lx, dx), (hy, ly, dy) = gbuf._stencil()
    gx = (np.take(t, hx) - np.take(t, lx)) / dx
    gy = (np.take(t, hy) - np.take(t, ly)) / dy
    g = np.sqrt(gx * gx + gy * gy)
    return np.clip(reach - d / np.maximum(g, np.float32(1e-6)), 0.0, 1.0)


def _dot(N: np.ndarray, l: np.ndarray) -> np.ndarray:
    """Row-wise N·l for (k, 3) N; column by column (numpy's float32 matvec is ~20x slower)."""
    return N[:, 0] * l[0] + N[:, 1] * l[1] + N[:, 2] * l[2]
