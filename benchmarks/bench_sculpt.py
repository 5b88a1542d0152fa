"""Time one isophote edit on inflated ellipses of about 1k, 5k and 20k vertices, by step.

Run: ``.venv/bin/python benchmarks/bench_sculpt.py``. Three situations, times in ms:

``new layer``  the first edit on a layer just inflated: builds the layer's planar data
               (slope operators, squared Laplacian, locator, local width), median of 3;
``warm``       an edit on a layer that was edited before (its triangulation is cached, its
               heights are new): what every further edit pays, median of 5;
``redraw``     the same pick with another stroke (the app's live preview while drawing, and
               "draw again" to replace an attempt), median of 5.

The first call of the process also compiles the reflectance evaluation (JAX), shown apart.
Targets (issue 16): warm ≤ 150 ms and redraw ≤ 60 ms at 5k vertices.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from sculpt_helpers import isophote_stroke  # noqa: E402

from sketchforge_isophote_tool import layerdata, pipeline, sculpt  # noqa: E402
from sketchforge_isophote_tool.testing import LIGHT, inflated  # noqa: E402

SIZES = {"1k": 0.063, "5k": 0.03, "20k": 0.0145}
STEPS = ["layer", "stroke", "zones", "shading", "heights", "check", "total"]


def _timed(mesh, stroke, clear_planar: bool, clear_layer: bool):
    if clear_planar:
        layerdata._PLANAR.clear()
    if clear_layer:
        layerdata._CACHE.clear()
        pipeline._PICKS.clear()
    t = time.perf_counter()
    r = sculpt(mesh, LIGHT, [0.2, 0.1], 0.3, stroke)
    r.timings["total"] = time.perf_counter() - t
    return r


def main() -> None:
    t = time.perf_counter()
    mesh = inflated("ellipse", 0.063)
    st, _, _ = isophote_stroke(mesh, [0.2, 0.1], 0.1)
    sculpt(mesh, LIGHT, [0.2, 0.1], 0.3, st)
    print(f"first edit of the process (JAX compile of R, R_p, R_q included): {1e3 * (time.perf_counter() - t):.0f} ms\n")
    print(f"{'layer':>6} {'verts':>6} {'situation':>10} " + " ".join(f"{s:>8}" for s in STEPS) + "   changed  before→after (h)")
    for name, res in SIZES.items():
        mesh = inflated("ellipse", res)
        strokes = [isophote_stroke(mesh, [0.2, 0.1], off)[0] for off in (0.1, 0.08, 0.06, -0.06, -0.08, -0.1)]
        situations = {
            "new layer": [_timed(mesh, strokes[0], True, True) for _ in range(3)],
            "warm": [_timed(mesh, strokes[k], False, True) for k in range(5)],
            "redraw": [_timed(mesh, strokes[k + 1], False, False) for k in range(5)],
        }
        for label, rows in situations.items():
            T = {s: float(np.median([r.timings.get(s, 0.0) for r in rows])) for s in STEPS}
            r = rows[-1]
            print(
                f"{name:>6} {mesh.n_vertices:>6} {label:>10} " + " ".join(f"{1e3 * T[s]:8.1f}" for s in STEPS)
                + f"   {int(r.changed.sum()):>7}  {r.before / r.h:.1f}→{r.after / r.h:.2f}"
            )


if __name__ == "__main__":
    main()
