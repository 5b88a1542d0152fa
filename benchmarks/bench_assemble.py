"""Benchmark of the assemble plugin: a 3-layer (~5k vertices) and an 8-layer (~8k layer
vertices, ~16k assembled) creature, inflated from strokes with the real inflate plugin; the
re-assembly after one layer changed, with the per-layer cache; seeded random creatures;
``--scaling``: cost against vertices and layers. Prints figures (wall and CPU time, load),
asserts nothing.

Targets (issue 6): <= 0.5 s and <= 1 s; issue 12: the 8-layer creature <= 0.3 s. Monster
Mash's native C++ needs ~0.3 s / ~0.6 s to build plus ~0.5 s / ~2 s for its depth solve.

    .venv/bin/python benchmarks/bench_assemble.py [--random 20] [--scaling]
"""

from __future__ import annotations

import json
import os
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


def run(name, doc, repeats=7):
    """Assemble from scratch (no cache) ``repeats`` times; wall and CPU time, machine load."""
    layers, meshes, closed = meshes_from_journal(doc)
    assemble_detailed(meshes, closed)  # warm-up (imports, first OSQP call)
    times, cpu, res = [], [], None
    load = os.getloadavg()[0]
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        res = assemble_detailed(meshes, closed)
        times.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    n_in = sum(m.n_vertices for m in meshes)
    inter = intersecting_pairs(res.mesh.V, res.mesh.F, res.face_layer)
    stages = {k: round(1000 * v, 1) for k, v in res.timings.items()}
    print(f"{name}: {len(layers)} layers, {n_in} layer vertices -> {res.mesh.n_vertices} vertices, "
          f"{res.mesh.n_faces} faces")
    print(f"  assemble: median {1000 * np.median(times):.0f} ms, min {1000 * min(times):.0f} ms, CPU median "
          f"{1000 * np.median(cpu):.0f} ms, load {load:.1f} -> {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores "
          f"(stages of the last run, ms: {stages})")
    print(f"  depth rows {res.n_inequalities} ({res.n_active} active), glue rows {res.n_equalities}, "
          f"OSQP iterations {res.solver.get('osqp_iterations')}, max violation {res.max_violation:.1e}, "
          f"intersecting triangle pairs between layers {len(inter)}")


def one_layer_changed(doc, layer_ids=("arm_front", "eye", "body"), repeats=5) -> None:
    """Re-assembly after one layer changed (its heights scaled by 1.05, as a sculpt stroke
    would), with the per-layer cache of a previous assembly, against from scratch."""
    from sketchforge.geometry.mesh import Mesh
    from sketchforge_assemble.cache import AssemblyCache

    layers, meshes, closed = meshes_from_journal(doc)
    ids = [layer.id for layer in layers]
    for lid in layer_ids:
        i = ids.index(lid)
        wall, cpu, scratch, same = [], [], [], 0
        for r in range(repeats):
            cache = AssemblyCache()
            assemble_detailed(meshes, closed, cache=cache)
            m = meshes[i]
            V = m.V.copy()
            V[:, 2] *= 1.05 + 0.01 * r
            edited = list(meshes)
            edited[i] = Mesh(V, m.F, boundary=m.boundary, junction=m.junction, holes=m.holes)
            t, c = time.perf_counter(), time.process_time()
            res = assemble_detailed(edited, closed, cache=cache)
            wall.append(time.perf_counter() - t)
            cpu.append(time.process_time() - c)
            t = time.perf_counter()
            ref = assemble_detailed(edited, closed)
            scratch.append(time.perf_counter() - t)
            same += res.mesh.identical(ref.mesh)
        print(f"  {lid} changed: re-assembly median {1000 * np.median(wall):.0f} ms "
              f"(CPU {1000 * np.median(cpu):.0f} ms) vs {1000 * np.median(scratch):.0f} ms from scratch; "
              f"{same} of {repeats} meshes bit-identical to scratch; load {os.getloadavg()[0]:.1f}")


def random_creatures(n: int) -> None:
    """Median and p90 assembly time (no cache) of the first ``n`` seeded random creatures."""
    from sketchforge_assemble.testing import random_creature

    wall, cpu, verts, bad = [], [], [], 0
    for seed in range(n):
        _, meshes, closed = meshes_from_journal(random_creature(seed))
        t, c = time.perf_counter(), time.process_time()
        res = assemble_detailed(meshes, closed)
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
        verts.append(sum(m.n_vertices for m in meshes))
        bad += res.max_violation > 0 or len(intersecting_pairs(res.mesh.V, res.mesh.F, res.face_layer)) > 0
    print(f"  {n} random creatures ({min(verts)}-{max(verts)} layer vertices): median {np.median(wall):.2f} s, "
          f"p90 {np.percentile(wall, 90):.2f} s (CPU median {np.median(cpu):.2f} s, "
          f"p90 {np.percentile(cpu, 90):.2f} s; "
          f"load {os.getloadavg()[0]:.1f}); {bad} with a violated depth row or an intersection")


def crowd(n_creatures: int, resolution: float = 0.03) -> dict:
    """Random creatures side by side (2.6 apart in x), one document: layers grow with the crowd."""
    from sketchforge_assemble.testing import random_creature

    journal = []
    for k in range(n_creatures):
        doc = random_creature(k, resolution)
        for c in doc["journal"]:
            c = dict(c)
            for key in ("id", "layer"):
                if key in c:
                    c[key] = f"c{k}_{c[key]}"
            if "points" in c:
                c["points"] = (np.asarray(c["points"]) + [2.6 * k, 0.0]).tolist()
            if c["command"] == "move_layer":
                continue  # keep each creature's own order: drawn in sequence, back to front
            journal.append(c)
    return dict(random_creature(0), journal=journal)


def scaling(max_vertices: int, max_layers: int) -> None:
    """Cost against layer vertices (the example creature at finer resolutions) and against
    layer count (crowds of random creatures), with the fitted growth exponent."""

    def fit(xs, ts):
        return float(np.polyfit(np.log(xs), np.log(ts), 1)[0]) if len(xs) > 1 else float("nan")

    base = json.loads((ROOT / "examples" / "creature.json").read_text())
    xs, ts, cs = [], [], []
    for res in (0.03, 0.021, 0.015, 0.0106, 0.0087):
        doc = json.loads(json.dumps(base))
        for c in doc["journal"]:
            if c["command"] == "set_inflate_params":
                c["params"] = dict(c["params"], resolution=res * (0.5 if c["layer"] == "eye" else 1.0))
        _, meshes, closed = meshes_from_journal(doc)
        n = sum(m.n_vertices for m in meshes)
        if n > max_vertices:
            break
        t, c = time.perf_counter(), time.process_time()
        res = assemble_detailed(meshes, closed)
        xs.append(n)
        ts.append(time.perf_counter() - t)
        cs.append(time.process_time() - c)
        print(f"  8 layers, {n:6d} layer vertices: {ts[-1]:.2f} s (CPU {cs[-1]:.2f} s; "
              f"solve {res.timings['solve']:.2f} s, OSQP {res.solver.get('osqp_iterations')} iterations; "
              f"load {os.getloadavg()[0]:.1f})", flush=True)
    print(f"  cost ~ vertices^{fit(xs, ts):.2f} (CPU time: vertices^{fit(xs, cs):.2f})")
    xs, ts, cs = [], [], []
    for k in (1, 2, 3, 4, 5, 6):
        _, meshes, closed = meshes_from_journal(crowd(k))
        if len(meshes) > max_layers:
            break
        t, c = time.perf_counter(), time.process_time()
        assemble_detailed(meshes, closed)
        xs.append(len(meshes))
        ts.append(time.perf_counter() - t)
        cs.append(time.process_time() - c)
        print(f"  {len(meshes):2d} layers, {sum(m.n_vertices for m in meshes):6d} layer vertices: {ts[-1]:.2f} s "
              f"(CPU {cs[-1]:.2f} s; load {os.getloadavg()[0]:.1f})", flush=True)
    print(f"  cost ~ layers^{fit(xs, ts):.2f} (CPU time: layers^{fit(xs, cs):.2f}; vertices grow with the layers)")


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--scaling", action="store_true", help="also print cost against vertices and layers")
    ap.add_argument("--max-vertices", type=int, default=100_000)
    ap.add_argument("--max-layers", type=int, default=30)
    ap.add_argument("--random", type=int, default=20, help="random creatures to time (0: none)")
    args = ap.parse_args()
    run("3-layer creature (target <= 0.5 s)", three_layer_doc())
    run("8-layer creature (target <= 1 s; issue 12: <= 0.3 s)",
        json.loads((ROOT / "examples" / "creature.json").read_text()))
    creature = json.loads((ROOT / "examples" / "creature.json").read_text())
    print("one layer changed (issue 12: re-solve only what depends on it)")
    one_layer_changed(creature)
    if args.random:
        print("random creatures (issue 12 background: median 3.1 s before)")
        random_creatures(args.random)
    if args.scaling:
        print("scaling (issue 12: up to 100k vertices and 30 layers)")
        scaling(args.max_vertices, args.max_layers)
