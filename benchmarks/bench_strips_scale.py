"""How the strips sculpt solver's work grows with the mesh (issue 36, point 4): one edit against
one sparse factor + solve of the same mesh.

Run: ``.venv/bin/python benchmarks/bench_strips_scale.py [resolutions...]`` (default ellipses of
about 5k, 20k and 80k vertices). For each: the CPU time of one libigl LLT factorisation and
solve of the mesh's Dirichlet cotangent Laplacian (what inflating it costs once), and of a warm
isophote edit with ``strips`` and with ``gauss_newton`` (the same stroke: the isophote through
[0.2, 0.1] moved 4 edge lengths, band 0.3), medians of 3; the strips edit split by stage. The
edit is bounded by the fresh layer's creases as in the app (``reference``: the layer itself,
fresh), the bounds found in the warm-up edit.
Target: the strips edit at most 10× one factor + solve at 80k vertices. The work of a strips
edit grows with the strips' sweep (the strips through the stroke, from rim to rim), not with
the mesh: its stroke and band are fixed here in drawing units.

CPU time (``time.process_time``, all threads of the process); the load is printed.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from sculpt_helpers import isophote_stroke  # noqa: E402

from sketchforge.geometry.dirichlet import DirichletSolver  # noqa: E402
from sketchforge.geometry.laplacian import laplacian_and_mass  # noqa: E402
from sketchforge_isophote_tool import sculpt  # noqa: E402
from sketchforge_isophote_tool.testing import LIGHT, inflated  # noqa: E402
from sketchforge_strips.solver import STRIPS  # noqa: E402

RESOLUTIONS = (0.03, 0.0145, 0.0072)


def _cpu(f, repeat: int = 3) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeat):
        t = time.process_time()
        out = f()
        times.append(time.process_time() - t)
    return float(np.median(times)), out


def factor_solve(mesh) -> float:
    """CPU seconds of one LLT factorisation + solve of the Dirichlet Laplacian (rim fixed)."""
    L, M = laplacian_and_mass(mesh.V[:, :2], mesh.F)

    def run():
        s = DirichletSolver(-L, np.asarray(mesh.boundary, np.int64), "the Laplacian")
        return s.solve(M @ np.ones(mesh.n_vertices))

    return _cpu(run)[0]


def main(resolutions=RESOLUTIONS) -> None:
    pick = [0.2, 0.1]
    print(f"load {os.getloadavg()[0]:.1f}")
    print(f"{'vertices':>8} {'factor+solve':>12} {'strips':>8} {'ratio':>6} {'gauss_newton':>12} {'ratio':>6}   strips stages (ms)")
    for res in resolutions:
        mesh = inflated("ellipse", res)
        stroke, _, _ = isophote_stroke(mesh, pick, 4.0 * res)  # the mean edge length is about the resolution
        sculpt(mesh, LIGHT, pick, 0.3, stroke, solver=STRIPS, reference=mesh)  # compile, build the layer's data
        sculpt(mesh, LIGHT, pick, 0.3, stroke)
        fs = factor_solve(mesh)
        t_s, r = _cpu(lambda: sculpt(mesh, LIGHT, pick, 0.3, stroke, solver=STRIPS, reference=mesh))  # noqa: B023 - called in this iteration
        t_g, _ = _cpu(lambda: sculpt(mesh, LIGHT, pick, 0.3, stroke, reference=mesh))  # noqa: B023 - called in this iteration
        stages = " ".join(f"{k} {1e3 * v:.0f}" for k, v in r.solution.info["timings"].items())
        print(f"{mesh.n_vertices:>8} {1e3 * fs:>10.0f}ms {1e3 * t_s:>6.0f}ms {t_s / fs:>5.1f}x {1e3 * t_g:>10.0f}ms {t_g / fs:>5.1f}x   "
              f"{stages}; strips {r.solution.info['strips']}, isophote {r.before / r.h:.1f} -> {r.after / r.h:.2f} h", flush=True)


if __name__ == "__main__":
    main(tuple(float(a) for a in sys.argv[1:]) or RESOLUTIONS)
