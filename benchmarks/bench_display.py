"""Display costs on examples/creature.json (8 layers) in a 1280x800 canvas.

Run: QT_QPA_PLATFORM=offscreen .venv/bin/python benchmarks/bench_display.py
Prints figures only (no assertions):

- rasterise: the per-pixel buffer for the view (normals, layer ids, coverage); paid when the
  view changes (every layer) or a mesh changes (that layer, the others' fragments are kept),
  never during a light drag;
- shade: display shader + compositing + isophote lines from that buffer (numpy only);
- light-drag step: what one mouse move of a light drag costs in the app: the SetLight command
  through the document, the canvas re-shading its buffer into a QImage, and a synchronous
  repaint of the canvas (offscreen platform, so no compositor or vsync);
- shade / light-drag step with a reflectance model (issue 37: one BRDF definition for the
  sculpt and the display): the model's own jax.numpy R(n, l) and dR/dn evaluated, compiled, on
  the buffer's normals (``geometry/model_shading.py``), for the example plugin's soft Lambert
  (when installed) and a rim-lit model that is not a function of n·l; the first call (the
  compile, once per model) is printed apart.

Each figure is the median (p90, worst) over STEPS light directions around the circle, in wall
time and in CPU time of this process: on a shared machine (other processes on the cores) the
wall time includes waiting for a core, the CPU time does not. The load average is printed.
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "creature.json"
SIZE = (1280, 800)
STEPS = 60


def _figures(name, seconds, cpu) -> None:
    ms = [1e3 * s for s in seconds]
    cms = [1e3 * s for s in cpu]
    print(f"{name:<40} wall median {statistics.median(ms):7.2f} p90 {np.percentile(ms, 90):7.2f} "
          f"worst {max(ms):7.2f} ms | cpu median {statistics.median(cms):7.2f} p90 "
          f"{np.percentile(cms, 90):7.2f} ms")


class _Timer:
    def __init__(self):
        self.wall, self.cpu = [], []

    def __enter__(self):
        self._w, self._c = time.perf_counter(), time.process_time()

    def __exit__(self, *exc):
        self.wall.append(time.perf_counter() - self._w)
        self.cpu.append(time.process_time() - self._c)


def core() -> None:
    from sketchforge.document import fileformat as ff
    from sketchforge.geometry import gbuffer as gb
    from sketchforge.geometry.model_shading import model_shader
    from sketchforge.geometry.shaders import cel_shade, lambert_shade
    from sketchforge.plugins import default_host

    doc = ff.load(EXAMPLE, default_host())
    meshes = [l.mesh if l.visible else None for l in doc.layers]
    view = gb.View.framing([m for m in meshes if m is not None], *SIZE, margin=0.1)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    timer = _Timer()
    for _ in range(3):
        gb._mesh_cache.clear()  # cold: a new view of every layer
        with timer:
            g = gb.rasterise(meshes, view)
    one = _Timer()
    biggest = max(range(len(meshes)), key=lambda i: 0 if meshes[i] is None else meshes[i].n_faces)
    for k in range(3):
        changed = list(meshes)
        m = meshes[biggest]
        changed[biggest] = type(m)(m.V + [0.0, 0.0, 0.001 * (k + 1)], m.F, m.boundary, m.junction)
        with one:
            gb.rasterise(changed, view)
    print(f"{len(doc.layers)} layers, {sum(m.n_faces for m in meshes if m is not None)} triangles, "
          f"{SIZE[0]}x{SIZE[1]} px, {len(g.pix)} fragments ({len(g.pix) / (SIZE[0] * SIZE[1]):.0%} of the pixels)")
    _figures("rasterise (new view)", timer.wall, timer.cpu)
    _figures("rasterise (largest layer changed)", one.wall, one.cpu)
    bg = np.array([0.95, 0.94, 0.92])
    for label, shader, K in (("shade lambert", lambert_shade, 0), ("shade lambert + 8 isophotes", lambert_shade, 8),
                             ("shade cel", cel_shade, 0)):
        timer = _Timer()
        picture = None
        for a in np.linspace(0, 2 * np.pi, STEPS, endpoint=False):
            l = np.array([np.cos(a), np.sin(a), 0.0])
            with timer:  # as the canvas does: over the previous picture of this buffer
                picture = gb.shade(g, l, shader, bg, isophotes=K, bgrx=True, outline_alpha=0.45, out=picture)
        _figures(label, timer.wall, timer.cpu)
    for model in _models():
        shader = model_shader(model)
        t0, c0 = time.perf_counter(), time.process_time()
        gb.shade(g, np.array([1.0, 0.0, 0.0]), shader.shade, bg, intensity=shader.intensity)
        print(f"model {model.name}: first shade (compile) wall {1e3 * (time.perf_counter() - t0):.0f} ms, "
              f"cpu {1e3 * (time.process_time() - c0):.0f} ms")
        for K in (0, 8):
            timer = _Timer()
            picture = None
            for a in np.linspace(0, 2 * np.pi, STEPS, endpoint=False):
                l = np.array([np.cos(a), np.sin(a), 0.0])
                with timer:
                    picture = gb.shade(g, l, shader.shade, bg, isophotes=K, bgrx=True, outline_alpha=0.45, out=picture,
                                       intensity=shader.intensity)
            _figures(f"shade model {model.name}" + (f" + {K} isophotes" if K else ""), timer.wall, timer.cpu)


def _rim(n, l):
    import jax.numpy as jnp

    c = jnp.dot(n, l)
    return 0.7 * (c + 0.3) / 1.3 + 0.2 * n[2] * c - 0.1 * n[0] * n[1]


def _models() -> list:
    """Reflectance models to time: the example soft Lambert (if installed) and a rim-lit one."""
    from sketchforge.geometry.reflectance_model import ReflectanceModel

    out = []
    try:
        from sketchforge_soft_brdf import SOFT_LAMBERT

        out.append(SOFT_LAMBERT)
    except ImportError:
        pass
    return out + [ReflectanceModel("rim_wrap", _rim)]


def app() -> None:
    from sketchforge.document import commands as C
    from sketchforge.document import fileformat as ff
    from sketchforge.geometry.model_shading import model_shader
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
        timer = _Timer()
        for a in np.linspace(0, 360, STEPS, endpoint=False):
            with timer:
                doc.push(C.SetLight(direction=[float(np.cos(np.radians(a))), float(np.sin(np.radians(a))), 0.0],
                                    gesture="bench"))
                canvas.viewport().repaint()
        _figures(f"light-drag step, {K} isophotes ({vw}x{vh})", timer.wall, timer.cpu)
    for model in _models():
        name = f"model:{model.name}"
        canvas.host.display_shadings = (lambda real=host.display_shadings, m=model, n=name: {**real(), n: model_shader(m)})
        canvas.set_shader(name)
        for K in (0, 8):
            canvas.set_isoline_count(K)
            timer = _Timer()
            for a in np.linspace(0, 360, STEPS, endpoint=False):
                with timer:
                    doc.push(C.SetLight(direction=[float(np.cos(np.radians(a))), float(np.sin(np.radians(a))), 0.0],
                                        gesture="bench"))
                    canvas.viewport().repaint()
            _figures(f"light-drag step, {model.name}, {K} isophotes", timer.wall, timer.cpu)
    canvas.close()


def main() -> None:
    core()
    try:
        app()
    except ImportError as exc:  # pragma: no cover - Qt missing
        print(f"app figures skipped: {exc}", file=sys.stderr)


if __name__ == "__main__":
    main()
