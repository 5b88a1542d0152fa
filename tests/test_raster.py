"""Headless top-view rendering and PNG output."""

import struct
import time
import zlib

import numpy as np
import pytest
from meshes import gaussian_bump, hemisphere

from sketchforge.document.layer import Light
from sketchforge.errors import ExportError
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.raster import BACKGROUND, encode_png, render_top, write_png
from sketchforge.geometry.shaders import CEL_TONES

BG = np.round(np.array(BACKGROUND) * 255).astype(np.uint8)


def _covered(img):
    return np.any(img != BG, axis=2)


def _is(pixel, colour):
    """Equal up to the display buffer's float32 rounding (one grey level)."""
    return np.max(np.abs(pixel.astype(int) - np.asarray(colour, dtype=int))) <= 1


def test_hemisphere_brightens_towards_the_light():
    m = hemisphere(1.0, 0.05)
    img = render_top([m], np.array([1.0, 0.0, 0.0]), 128)
    assert img.shape == (128, 128, 3) and img.dtype == np.uint8
    assert np.all(img[0, 0] == BG) and np.all(img[-1, -1] == BG)
    cov = _covered(img)
    # Equal-aspect framing with a 5% margin: the disk spans ~90% of the width.
    cols = np.nonzero(cov.any(axis=0))[0]
    assert cols[0] in (6, 7) and cols[-1] in (120, 121)
    lum = img.astype(float).sum(axis=2)
    row = lum[64, cols[0] + 2 : cols[-1] - 1]
    lit = row[len(row) // 2 + 2 :]
    assert np.all(np.diff(lit) >= -1)  # brighter towards +x (allow 1/255 rounding)
    assert lit[-1] - lit[0] > 200
    assert np.ptp(row[: len(row) // 2 - 2]) == 0  # shadow side: flat ambient


def test_y_up_and_light_object():
    m = hemisphere(1.0, 0.1)
    img = render_top([m], Light.from_angle(90), 64)  # light from +y: top rows bright
    lum = img.astype(float).sum(axis=2)
    assert lum[12, 32] > lum[32, 32] + 100
    small = Mesh(m.V * 0.2 + [0.0, 0.8, 0.0], m.F)
    img = render_top([m, small], Light.from_angle(0), 64)
    # The small part sits above the disk's top edge in y: it must appear in the top rows.
    top_rows = np.nonzero(_covered(img).any(axis=1))[0]
    assert top_rows[0] < 6


def test_within_a_mesh_the_nearest_surface_wins():
    """A folded mesh (two sheets over the same pixels): the higher sheet is what shows."""
    m = hemisphere(1.0, 0.1)
    flat_V = np.c_[m.V[:, :2], np.full(m.n_vertices, 0.5)]  # plane z = 0.5, n = +z
    both = Mesh(np.r_[m.V, flat_V], np.r_[m.F, m.F + m.n_vertices])
    img = render_top([both], np.array([1.0, 0, 0]), 64, cel=True)
    # Flat plane (n·l = 0: shadow tone) wins where the sphere is below 0.5, i.e. near the rim;
    # the dome (z > 0.5 for r < 0.866) wins in the middle on its lit side.
    tone = np.round(CEL_TONES * 255).astype(np.uint8)
    assert _is(img[32, 58], tone[0])
    assert _is(img[32, 40], tone[1]) or _is(img[32, 40], tone[2])


def test_cel_has_three_tones_and_isophote_lines_follow_chords():
    m = hemisphere(1.0, 0.04)
    l = np.array([1.0, 0.0, 0.0])
    cel = render_top([m], l, 200, cel=True)
    # Inside the silhouette (its antialiased rim blends into the background) only three tones.
    cov = _covered(cel)
    inner = cov.copy()
    for axis in (0, 1):
        for shift in (-2, 2):
            inner &= np.roll(cov, shift, axis=axis)
    tones = np.round(CEL_TONES * 255).astype(int)
    px = cel[inner].astype(int)
    nearest = np.abs(px[:, None, :] - tones[None]).max(axis=2).min(axis=1)
    assert inner.sum() > 20000 and np.all(nearest <= 1)
    assert {int(np.argmin(np.abs(p - tones).max(axis=1))) for p in px[::97]} == {0, 1, 2}
    plain = render_top([m], l, 200)
    lines = render_top([m], l, 200, isophotes=3)
    dark = np.any(lines != plain, axis=2)
    assert dark.sum() > 100
    # Lines at n·l = x = 0.25, 0.5, 0.75: pixel columns 100 + x * 90 (scale 90 px per unit).
    cols = np.nonzero(dark[60:140].any(axis=0))[0]
    for x in (0.25, 0.5, 0.75):
        assert np.min(np.abs(cols - (100 + 90 * x))) <= 3
    assert np.all(np.abs(cols[:, None] - (100 + 90 * np.array([0.25, 0.5, 0.75]))).min(axis=1) <= 4)


def test_render_speed_10k_triangles_512px():
    m = gaussian_bump(1.0, 0.033)
    assert m.n_faces >= 10_000
    t0 = time.perf_counter()
    img = render_top([m], np.array([0.6, 0.8, 0.0]), 512, isophotes=5)
    dt = time.perf_counter() - t0
    assert dt < 1.0, dt  # measured ~0.15 s
    assert _covered(img).mean() > 0.5


def test_empty_scene_and_bad_arguments():
    img = render_top([], np.array([1.0, 0, 0]), 16, background=(0, 0, 0))
    assert img.shape == (16, 16, 3) and not img.any()
    with pytest.raises(ValueError):
        render_top([], np.zeros(3), 16)
    with pytest.raises(ValueError):
        render_top([], np.array([1.0, 0, 0]), 0)


def _decode_png(data):
    """A minimal PNG reader: every chunk's CRC, the whole header, an empty IEND."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks, order = 8, {}, []
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + n]
        (crc,) = struct.unpack(">I", data[pos + 8 + n : pos + 12 + n])
        assert crc == zlib.crc32(kind + body) & 0xFFFFFFFF
        chunks[kind] = chunks.get(kind, b"") + body
        order.append(kind)
        pos += 12 + n
    assert order[0] == b"IHDR" and order[-1] == b"IEND" and chunks[b"IEND"] == b""
    assert len(chunks[b"IHDR"]) == 13
    w, h, depth, ctype, method, filt, interlace = struct.unpack(">IIBBBBB", chunks[b"IHDR"])
    # 8-bit RGB, deflate, adaptive filtering, no interlace: the only header a reader accepts
    assert (depth, ctype, method, filt, interlace) == (8, 2, 0, 0, 0)
    raw = np.frombuffer(zlib.decompress(chunks[b"IDAT"]), np.uint8).reshape(h, 1 + 3 * w)
    assert np.all(raw[:, 0] == 0)
    return raw[:, 1:].reshape(h, w, 3)


def test_write_png_roundtrip_and_atomic_replace(tmp_path):
    rgb = np.random.default_rng(0).integers(0, 256, (7, 5, 3), dtype=np.uint8)
    path = tmp_path / "a.png"
    path.write_bytes(b"old")
    write_png(path, rgb)
    np.testing.assert_array_equal(_decode_png(path.read_bytes()), rgb)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]  # no temp file left
    with pytest.raises(ExportError, match="cannot write"):
        write_png(tmp_path / "missing" / "b.png", rgb)
    with pytest.raises(ValueError):
        encode_png(rgb.astype(np.float64))


def test_later_mesh_covers_earlier_one_whatever_its_height():
    """Layers are drawn back to front: a flat layer in front hides a tall dome behind it."""
    dome = hemisphere(1.0, 0.1)
    tall = Mesh(np.c_[dome.V[:, :2], 3.0 * dome.V[:, 2]], dome.F)
    flat = Mesh(np.c_[dome.V[:, :2] * 0.5, np.zeros(dome.n_vertices)], dome.F)  # n·l = 0: shadow
    light = np.array([1.0, 0.0, 0.0])
    tone = np.round(CEL_TONES * 255).astype(np.uint8)
    front = render_top([tall, flat], light, 64, cel=True)
    behind = render_top([flat, tall], light, 64, cel=True)
    # Pixel at x = +0.3 (lit side of the dome, inside the small flat disk).
    assert _is(front[32, 32 + 9], tone[0])
    assert not _is(behind[32, 32 + 9], tone[0])
