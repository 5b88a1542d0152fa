"""Benchmark of the animate plugin's ARAP posing: factorisation (once per pin set) and one
deformation frame (``FRAME_ITERATIONS`` local/global steps, warm-started), on the example
creature (~16k vertices, assembled from 8 layers) and on closed tubes from 4k to 100k
vertices. Prints figures, asserts nothing.

The machine is shared (2 cores, often a load of 4): the wall-clock minimum and the CPU time
(the solve is single-threaded) are the figures least disturbed by other processes.

Target (issue 13): <= 16 ms per frame at 16k vertices after the factorisation. Monster Mash
needs ~109 ms per frame on the 16k creature on this machine kind and re-factorises each frame.

    .venv/bin/python benchmarks/bench_animate.py [--quick]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from sketchforge.plugins import default_host
from sketchforge_animate.arap import ArapSolver
from sketchforge_animate.pose import FRAME_ITERATIONS

ROOT = Path(__file__).resolve().parents[1]


def tube(n_target: int):
    """A closed capped tube along x with about n_target vertices, (V, F)."""
    nr = max(8, int(np.sqrt(n_target / 8)))
    nx = max(3, n_target // nr)
    xs = np.linspace(0.0, 8.0, nx)
    th = 2 * np.pi * np.arange(nr) / nr
    V = np.c_[np.repeat(xs, nr), np.tile(np.cos(th), nx), np.tile(np.sin(th), nx)]
    a, b = np.meshgrid(np.arange(nx - 1), np.arange(nr), indexing="ij")
    i, j = (a * nr + b).ravel(), (a * nr + (b + 1) % nr).ravel()
    F = np.r_[np.c_[i, i + nr, j], np.c_[j, i + nr, j + nr]]
    c0, c1 = len(V), len(V) + 1
    V = np.r_[V, [[0, 0, 0], [8.0, 0, 0]]]
    ring = np.arange(nr)
    F = np.r_[
        F,
        np.c_[np.full(nr, c0), ring, (ring + 1) % nr],
        np.c_[np.full(nr, c1), (nx - 1) * nr + (ring + 1) % nr, (nx - 1) * nr + ring],
    ]
    return V, F.astype(np.int64)


def creature():
    from sketchforge.document import fileformat as ff

    m = ff.load(ROOT / "examples" / "creature.json", default_host()).export_mesh()
    return np.array(m.V), np.array(m.F)


def run(name, V, F, solvers=("llt", "splu"), frames=20):
    rng = np.random.default_rng(0)
    handles = rng.choice(len(V), 4, replace=False)
    for solver in solvers:
        t = time.perf_counter()
        s = ArapSolver(V, F, handles, solver=solver)
        t_factor = time.perf_counter() - t
        P = s.solve(V[handles], V, 1)
        line = f"{name}: {len(V):6d} vertices, {solver:5s} factor {1000 * t_factor:6.0f} ms"
        for iterations in sorted({1, FRAME_ITERATIONS}):
            times, cpu = [], []
            for f in range(frames):
                tg = V[handles] + [0.0, 0.3 * np.sin(f / 4), 0.1]
                t, c = time.perf_counter(), time.process_time()
                P = s.solve(tg, P, iterations)
                times.append(time.perf_counter() - t)
                cpu.append(time.process_time() - c)
            line += (f" | frame of {iterations} iteration(s): wall median {1000 * np.median(times):5.1f} ms, "
                     f"min {1000 * min(times):5.1f} ms, CPU median {1000 * np.median(cpu):5.1f} ms")
        print(line, flush=True)


if __name__ == "__main__":
    quick = "--quick" in sys.argv
    run("creature (8 layers, target <= 16 ms)", *creature())
    for n in (4_000, 16_000, 32_000) if quick else (4_000, 16_000, 32_000, 64_000, 100_000):
        run("tube", *tube(n), solvers=("llt",) if n > 32_000 else ("llt", "splu"))
