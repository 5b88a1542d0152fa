"""Benchmark of the assemble plugin: a 3-layer (~5k vertices) and an 8-layer (~8k vertices)
creature, inflated from strokes with the real inflate plugin. Prints figures, asserts nothing.

Targets (issue 6): <= 0.5 s and <= 1 s. Monster Mash's native C++ needs ~0.3 s / ~0.6 s to
build plus ~0.5 s / ~2 s for its depth solve.

    .venv/bin/python benchmarks/bench_assemble.py
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from sketchforge_assemble import assemble_detailed
from sketchforge_assemble.diagnostics import intersecting_pairs
from sketchforge_assemble.testing import meshes_from_journal

ROOT = Path(__file__).resolve().parents[1]


def three_layer_doc() -> dict:
    """Body, head and front arm of examples/creature.json, at a resolution giving ~5k layer vertices."""
    doc = json.loads((ROOT / "examples" / "creature.json").read_text())
    keep = {"body", "head", "arm_front"}
    journal = [c for c in doc["journal"] if c.get("id", c.get("layer")) in keep]
    for c in journal:
        if c["command"] == "set_inflate_params":
            c["params"] = dict(c["params"], resolution=0.031)
    return dict(doc, journal=journal)


def run(name, doc, repeats=5):
    layers, meshes, closed = meshes_from_journal(doc)
    assemble_detailed(meshes, closed)  # warm-up (imports, first OSQP call)
    times, res = [], None
    for _ in range(repeats):
        t = time.perf_counter()
        res = assemble_detailed(meshes, closed)
        times.append(time.perf_counter() - t)
    n_in = sum(m.n_vertices for m in meshes)
    inter = intersecting_pairs(res.mesh.V, res.mesh.F, res.face_layer)
    stages = {k: round(1000 * v, 1) for k, v in res.timings.items()}
    print(f"{name}: {len(layers)} layers, {n_in} layer vertices -> {res.mesh.n_vertices} vertices, "
          f"{res.mesh.n_faces} faces")
    print(f"  assemble: median {1000 * np.median(times):.0f} ms, min {1000 * min(times):.0f} ms "
          f"(stages of the last run, ms: {stages})")
    print(f"  depth rows {res.n_inequalities} ({res.n_active} active), glue rows {res.n_equalities}, "
          f"OSQP iterations {res.solver.get('osqp_iterations')}, max violation {res.max_violation:.1e}, "
          f"intersecting triangle pairs between layers {len(inter)}")


if __name__ == "__main__":
    run("3-layer creature (target <= 0.5 s)", three_layer_doc())
    run("8-layer creature (target <= 1 s)", json.loads((ROOT / "examples" / "creature.json").read_text()))
