"""Display costs on examples/creature.json (8 layers) in a 1280x800 canvas.

Run: QT_QPA_PLATFORM=offscreen .venv/bin/python benchmarks/bench_display.py
Prints figures only (no assertions):

- rasterise: the per-pixel buffer for the view (normals, layer ids, coverage); paid when the
  view or a mesh changes, never during a light drag;
- shade: display shader + compositing + isophote lines from that buffer (numpy only);
- light-drag step: what one mouse move of a light drag costs in the app: the SetLight command
  through the document, the canvas re-shading its buffer into a QImage, and a synchronous
  repaint of the canvas (offscreen platform, so no compositor or vsync).

Each figure is the median (and the worst) over STEPS light directions around the circle.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "creature.json"
SIZE = (1280, 800)
STEPS = 60


def _figures(name, seconds) -> None:
    ms = [1e3 * s for s in seconds]
    print(f"{name:<34} median {statistics.median(ms):7.2f} ms   p90 {np.percentile(ms, 90):7.2f} ms   "
          f"worst {max(ms):7.2f} ms")


def core() -> None:
    from sketchforge.document import fileformat as ff
    from sketchforge.geometry import gbuffer as gb
    from sketchforge.geometry.shaders import cel_shade, lambert_shade

    doc = ff.load(EXAMPLE)
    meshes = [l.mesh if l.visible else None for l in doc.layers]
    view = gb.View.framing([m for m in meshes if m is not None], *SIZE, margin=0.1)
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        g = gb.rasterise(meshes, view)
        times.append(time.perf_counter() - t0)
    print(f"{len(doc.layers)} layers, {sum(m.n_faces for m in meshes if m is not None)} triangles, "
          f"{SIZE[0]}x{SIZE[1]} px, {len(g.pix)} fragments ({len(g.pix) / (SIZE[0] * SIZE[1]):.0%} of the pixels)")
    _figures("rasterise (view/mesh change)", times)
    bg = np.array([0.95, 0.94, 0.92])
    for label, shader, K in (("shade lambert", lambert_shade, 0), ("shade lambert + 8 isophotes", lambert_shade, 8),
                             ("shade cel", cel_shade, 0)):
        times = []
        for a in np.linspace(0, 2 * np.pi, STEPS, endpoint=False):
            l = np.array([np.cos(a), np.sin(a), 0.0])
            t0 = time.perf_counter()
            gb.shade(g, l, shader, bg, isophotes=K, bgrx=True, outline_alpha=0.45)
            times.append(time.perf_counter() - t0)
        _figures(label, times)


def app() -> None:
    from sketchforge.document import commands as C
    from sketchforge.document import fileformat as ff
    from sketchforge.qt.app import ensure_qapp, plugin_host
    from sketchforge.qt.canvas import Canvas

    qapp = ensure_qapp()
    host = plugin_host()
    doc = ff.load(EXAMPLE, host=host)
    canvas = Canvas(doc, host)
    canvas.resize(*SIZE)
    canvas.show()
    qapp.processEvents()
    canvas.fit()
    canvas.render_now()
    vw, vh = canvas.current_view().width, canvas.current_view().height
    for K in (0, 8):
        canvas.set_isoline_count(K)
        times = []
        for a in np.linspace(0, 360, STEPS, endpoint=False):
            t0 = time.perf_counter()
            doc.push(C.SetLight(direction=[float(np.cos(np.radians(a))), float(np.sin(np.radians(a))), 0.0],
                                gesture="bench"))
            canvas.viewport().repaint()
            times.append(time.perf_counter() - t0)
        _figures(f"light-drag step, {K} isophotes ({vw}x{vh})", times)
    canvas.close()


def main() -> None:
    core()
    try:
        app()
    except ImportError as exc:  # pragma: no cover - Qt missing
        print(f"app figures skipped: {exc}", file=sys.stderr)


if __name__ == "__main__":
    main()
