"""Narrow parts meshed finer (issue 34; ``sketchforge_inflate.inflate.edge_length_for``), on
strokes nobody chose: 300 seeded shapes whose sizes span 0.02-0.5 (wobbly blobs, stars, thin
ellipses of aspect 3-30) and the 79 letter and animal silhouettes of ``tests/data``, each
scaled at random, inflated at resolution 0.03 as asked and as the inflater now meshes them.

    .venv/bin/python benchmarks/bench_narrow_parts.py

Per kind: strokes refused either way, the share meshed differently, vertices (new over asked:
median, p90, max), the largest bend between neighbouring triangles of the layer (median, p90,
as asked -> now), the strokes inflated flat (every vertex on the rim: height 0), CPU time of
both passes and the machine's load. Prints figures, asserts nothing.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np

import sketchforge_inflate.inflate as inflate_module
from sketchforge.errors import SketchforgeError
from sketchforge.geometry.mesh_edges import edge_angles, interior_edges

ROOT = Path(__file__).resolve().parents[1]
KINDS = ("blob", "star", "thin", "silhouette")


def corpus(seed: int = 2026, count: int = 300) -> list[tuple[int, np.ndarray]]:
    """(kind index, (n, 2) closed stroke) pairs, deterministic for ``seed``."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 2.0 * np.pi, 80, endpoint=False)
    shapes = []
    for i in range(count):
        kind = i % 3
        R = float(np.exp(rng.uniform(np.log(0.02), np.log(0.5))))
        if kind == 0:
            r = R * (1 + 0.15 * np.sin(3 * t + rng.uniform(0, 6)) + 0.01 * rng.standard_normal(len(t)))
            P = np.c_[r * np.cos(t), r * np.sin(t)]
        elif kind == 1:
            k = int(rng.integers(4, 8))
            r = R * np.where(np.arange(len(t)) % (len(t) // k) < len(t) // (2 * k), 1.0, 0.45)
            P = np.c_[r * np.cos(t), r * np.sin(t)]
        else:
            P = np.c_[R * np.cos(t), R / float(rng.uniform(3, 30)) * np.sin(t)]
        shapes.append((kind, P))
    for s in json.loads((ROOT / "tests" / "data" / "silhouettes.json").read_text())["silhouettes"]:
        P = np.asarray(s["points"], float)
        shapes.append((3, (P - P.mean(axis=0)) * float(np.exp(rng.uniform(np.log(0.05), 0.0)))))
    return shapes


def inflate_all(shapes, as_asked: bool):
    """[(kind, vertices or -1 if refused, largest bend, height)], CPU seconds."""
    finer = inflate_module.edge_length_for
    if as_asked:
        inflate_module.edge_length_for = lambda size, h: h
    out, t0 = [], time.process_time()
    try:
        for kind, P in shapes:
            try:
                m = inflate_module.inflate_stroke(P, True, {"resolution": 0.03})
            except SketchforgeError:
                out.append((kind, -1, float("nan"), 0.0))
                continue
            E, fa, fb = interior_edges(m.F)
            out.append((kind, len(m.V), float(edge_angles(m.V, m.F, fa, fb).max(initial=0.0)), float(m.V[:, 2].max())))
    finally:
        inflate_module.edge_length_for = finer
    return out, time.process_time() - t0


def main() -> None:
    shapes = corpus()
    asked, t_asked = inflate_all(shapes, True)
    now, t_now = inflate_all(shapes, False)
    print(f"load {os.getloadavg()[0]:.1f}; {len(shapes)} strokes at resolution 0.03")
    for k, name in enumerate(KINDS):
        pairs = [(a, b) for a, b in zip(asked, now) if a[0] == k]
        both = [(a, b) for a, b in pairs if a[1] > 0 and b[1] > 0]
        ratio = np.array([b[1] / a[1] for a, b in both])
        before, after = np.array([a[2] for a, _ in both]), np.array([b[2] for _, b in both])
        print(f"{name:10s} {len(pairs):3d} strokes: refused as asked {sum(a[1] < 0 for a, _ in pairs)}, now "
              f"{sum(b[1] < 0 for _, b in pairs)}; meshed differently {100 * np.mean(ratio != 1):.0f}%; vertices now/asked "
              f"median {np.median(ratio):.2f}, p90 {np.percentile(ratio, 90):.2f}, max {ratio.max():.1f}; largest bend "
              f"median {np.median(before):.1f} -> {np.median(after):.1f}, p90 {np.percentile(before, 90):.1f} -> "
              f"{np.percentile(after, 90):.1f} degrees; flat (no vertex off the rim) {sum(a[3] == 0 for a, _ in both)} -> "
              f"{sum(b[3] == 0 for _, b in both)}")
    print(f"CPU: as asked {t_asked:.2f} s, now {t_now:.2f} s")


if __name__ == "__main__":
    main()
