"""What the editing canvas shows: smooth per-pixel shading, like the headless renderer."""

from __future__ import annotations

import numpy as np
import pytest
from qt_helpers import wait_idle
from scipy import ndimage

from sketchforge.geometry.raster import render_top


def _grey(qimage) -> np.ndarray:
    from PySide6.QtGui import QImage

    img = qimage.convertToFormat(QImage.Format.Format_RGB888)
    w, h = img.width(), img.height()
    a = np.frombuffer(img.constBits(), np.uint8).reshape(h, img.bytesPerLine())[:, : 3 * w].reshape(h, w, 3)
    return a.astype(np.float64) @ np.array([0.299, 0.587, 0.114])


def high_pass_rms(grey: np.ndarray, shape: np.ndarray) -> float:
    """RMS of (grey - Gaussian blur of grey, σ = 2 px) over the shaded interior: ``shape`` eroded
    by 8 px, so neither the silhouette nor an outline drawn along it counts."""
    inner = ndimage.binary_erosion(shape, iterations=8)
    hp = grey - ndimage.gaussian_filter(grey, 2.0)
    return float(np.sqrt(np.mean(hp[inner] ** 2)))


def ellipse(n=90, a=0.7, b=0.4):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[a * np.cos(t), b * np.sin(t)]


def test_canvas_shading_is_as_smooth_as_the_headless_render(make_window, mouse, qtbot, host):
    """One ellipse at the default resolution, drawn like a user: the canvas's high-pass RMS over
    the shaded interior is within 2.5x of ``render_top``'s at the same pixel scale (it was 9x with
    one flat colour per triangle)."""
    w = make_window()
    pts = ellipse()
    mouse(w.canvas).drag(list(pts) + [pts[0]])
    wait_idle(qtbot, w)
    mesh = w.doc.layers[0].mesh
    if mesh is None:
        pytest.skip("no inflate plugin is installed")
    w.canvas.fit()
    w.canvas.render_now()
    w.canvas.handles.setVisible(False)  # the selected part's handles are lines, not shading
    grey = _grey(w.canvas.grab().toImage())
    bg = grey[2, 2]
    canvas_rms = high_pass_rms(grey, np.abs(grey - bg) > 1.5)
    view = w.canvas.current_view()
    ext = float(np.ptp(mesh.V[:, 0]))
    size = int(round(ext * view.scale / 0.9))  # render_top's 5% margins: same pixels per unit
    img = render_top([mesh], w.doc.light.direction, size)
    rgrey = img.astype(np.float64) @ np.array([0.299, 0.587, 0.114])
    render_rms = high_pass_rms(rgrey, np.abs(rgrey - rgrey[0, 0]) > 1.5)
    print(f"high-pass RMS: canvas {canvas_rms:.3f}, render {render_rms:.3f} grey levels")
    assert render_rms < 0.5  # the reference itself is smooth
    assert canvas_rms <= 2.5 * render_rms


def _window_with_ellipse(make_window, mouse, qtbot):
    """A window with one ellipse drawn by mouse and rendered (skips without an inflate plugin)."""
    w = make_window()
    pts = ellipse(40)
    mouse(w.canvas).drag(list(pts) + [pts[0]])
    wait_idle(qtbot, w)
    if w.doc.layers[0].mesh is None:
        pytest.skip("no inflate plugin is installed")
    w.canvas.render_now()
    return w


def test_a_view_change_rasterises_in_the_background_and_a_light_change_does_not(make_window, mouse, qtbot, host):
    w = _window_with_ellipse(make_window, mouse, qtbot)
    first = w.canvas._gbuf
    w.canvas.vb.translateBy(x=0.2, y=0.1)  # a pan
    assert w.canvas._gbuf is first  # nothing rasterised on the GUI thread during the gesture
    qtbot.waitUntil(lambda: w.canvas._raster_thread is not None, timeout=2000)
    qtbot.waitUntil(lambda: w.canvas._gbuf is not first and w.canvas._raster_thread is None, timeout=20_000)
    assert w.canvas._gbuf.view == w.canvas.current_view()
    panned = w.canvas._gbuf
    before = w.canvas.scene_item.pixels().copy()
    w.set_light_angle(200.0)
    assert w.canvas._gbuf is panned  # a new light re-shades the same buffer
    assert np.any(w.canvas.scene_item.pixels() != before)


def test_a_broken_shader_plugin_falls_back_to_lambert_with_a_message(make_window, mouse, qtbot, host):
    w = _window_with_ellipse(make_window, mouse, qtbot)
    good = w.canvas.scene_item.pixels().copy()

    class Broken:
        name = "broken"

        @staticmethod
        def shade(N, light):
            return np.zeros((3, 3))

    messages = []
    w.canvas.message.connect(messages.append)
    w.canvas._shader = lambda: Broken
    w.canvas.reshade()
    assert messages and "broken" in messages[-1] and "Lambertian" in messages[-1]
    np.testing.assert_array_equal(w.canvas.scene_item.pixels(), good)  # lambert is the default
