"""Creatures as people draw them (issue 34, point 7): the seeded Monster-Mash-style corpus
(``sketchforge_assemble.drawn``: quadrupeds with far legs behind and overlapping the near ones,
birds with a wing behind and one in front, bipeds, twin ears touching, heads and tails as
open strokes) assembled, and checked by ``tests/mesh_checks.py`` (written apart from the
assembler). Prints figures, asserts nothing.

    .venv/bin/python benchmarks/bench_creatures.py [--seeds 60] [--first 0] [--pictures DIR]

Per creature: assembled or the error; parts glued / free; components; boundary edges;
self-intersecting triangle pairs; the largest dihedral angle across the junctions (edges
within 8 edge lengths of a glued seam, the layers' edge length taken by area) and its 99.9th
percentile, the share under 45 degrees, and both again away from the corners drawn sharp on a
part itself (within 3 edge lengths of a beak's tip: it bends so in the layer as inflated); the
largest over the whole mesh; the smallest limb depth ratio (a limb's thickness just outside
its host over its thickness at mid-limb, for limbs whose region reaches 6 edge lengths past
the host) and the same ratio of that limb's own inflated layer (under 0.8 where it is drawn
narrower there); CPU time of the assembly. Then the corpus summary: rates and percentiles.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import mesh_checks as mc  # noqa: E402

from sketchforge.geometry import guard  # noqa: E402
from sketchforge_assemble import assemble_detailed  # noqa: E402
from sketchforge_assemble.drawn import drawn_creature  # noqa: E402
from sketchforge_assemble.testing import meshes_from_journal  # noqa: E402

#: Assembly parameters (--params '{"fair": 8}').
PARAMS: dict = {}
#: Edges within this many edge lengths (:func:`mesh_checks.layers_edge_length`) of a glued
#: seam count as "across a junction".
ZONE_EDGES = 8.0
#: Edges within this many edge lengths of a corner drawn sharp on their own layer are also
#: counted apart (:func:`mesh_checks.at_drawn_tips`).
TIP_EDGES = 3.0


def region(mesh):
    return guard.polygon(mesh.V[mesh.boundary, :2], "outline")


def measure(seed: int):
    doc = drawn_creature(seed)
    layers, meshes, closed = meshes_from_journal(doc)
    names = [l.name for l in layers]
    parts = sum(1 for l, m in zip(layers, meshes) if not l.closed and len(m.junction))
    c0, w0 = time.process_time(), time.perf_counter()
    try:
        r = assemble_detailed(meshes, closed, names=names, params=PARAMS)
    except Exception as exc:  # noqa: BLE001 - a benchmark reports every failure and goes on
        return {"seed": seed, "ok": False, "error": f"{type(exc).__name__}: {exc}", "parts": parts}
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    V, F = r.mesh.V, r.mesh.F
    h = mc.layers_edge_length(meshes)
    # mc.junction_angles' edges, the bends measured once; then the same edges less those at a
    # corner drawn sharp on their own layer (a beak's tip: it bends like that in the layer as
    # inflated, whatever the junction does)
    key, ang_all = mc.dihedral(V, F)
    zone = mc.seam_zone(V, F, r.face_layer, ZONE_EDGES * h)
    inz = zone[key[:, 0]] & zone[key[:, 1]]
    tip = mc.at_drawn_tips(V, F, r.face_layer, [mc.drawn_tips(m) for m in meshes], TIP_EDGES * h)
    ang_j, ang_t, ang_a = ang_all[inz], ang_all[inz & tip], ang_all[inz & ~tip]
    ratios = []
    for a in r.attachments:
        part, host, hp = region(meshes[a.upper]), region(meshes[a.lower]), guard_h(meshes[a.upper])
        ratio = mc.limb_depth_ratio(V, F, r.face_layer, r.face_kind, a.upper, part, host, hp)
        if np.isfinite(ratio):
            ratios.append((ratio, names[a.upper],
                           mc.own_layer_depth_ratio(meshes[a.upper].V, meshes[a.upper].F, part, host, hp)))
    return {
        "seed": seed, "ok": True, "parts": parts, "glued": len(r.attachments), "free": len(r.warnings),
        "notes": len(r.notes), "components": mc.components(F, len(V)),
        # a forest: every glued part joins its host's component; a part left out is not there
        "components_expected": len(layers) - len(r.attachments) - len(r.left_out),
        "boundary": mc.boundary_edges(F), "inter": mc.self_intersections(V, F),
        "j_max": float(ang_j.max(initial=0.0)), "j_999": float(np.percentile(ang_j, 99.9)) if len(ang_j) else 0.0,
        "j_over90": int(np.sum(ang_j > 90)), "j_le45": float(np.mean(ang_j <= 45)) if len(ang_j) else 1.0,
        "a_max": float(ang_a.max(initial=0.0)), "a_le45": float(np.mean(ang_a <= 45)) if len(ang_a) else 1.0,
        "t_over90": int(np.sum(ang_t > 90)), "t_max": float(ang_t.max(initial=0.0)),
        "all_max": float(ang_all.max()), "ratio": min(ratios) if ratios else (float("nan"), "-", float("nan")),
        "cpu": cpu, "wall": wall, "vertices": len(V), "layer_vertices": sum(m.n_vertices for m in meshes),
        "warnings": r.warnings, "fair": r.solver.get("fair_zone"), "result": r, "meshes": meshes,
    }


def guard_h(mesh) -> float:
    return mc.edge_length(mesh.V, mesh.F)


def speed(seed: int = 0, resolution: float = 0.0275, repeats: int = 5) -> None:
    """Issue 34, point 6: a 12-part creature of about 16k vertices assembles in at most 0.3 s
    of CPU. The quadruped of ``seed`` at a finer ``resolution`` (12 parts, 15.9k assembled
    vertices; 0.026 until the inflater meshed narrow parts finer, which made it 17.2k),
    assembled from scratch (no cache) after one warm-up run; CPU time of the process (every
    thread), least and median of ``repeats``, and the machine's load."""
    doc = drawn_creature(seed, resolution=resolution)
    layers, meshes, closed = meshes_from_journal(doc)
    names = [l.name for l in layers]
    r = assemble_detailed(meshes, closed, names=names, params=PARAMS)
    cpu, wall = [], []
    for _ in range(repeats):
        c, w = time.process_time(), time.perf_counter()
        assemble_detailed(meshes, closed, names=names, params=PARAMS)
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    print(f"12-part creature (seed {seed}, resolution {resolution}: {len(layers)} layers, {len(r.mesh.V)} vertices; "
          f"target <= 0.3 s CPU): CPU least {min(cpu):.3f} s, median {np.median(cpu):.3f} s; wall median "
          f"{np.median(wall):.3f} s; load {os.getloadavg()[0]:.1f}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=60)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--pictures", type=Path, default=None, help="write three views of the first creatures here")
    ap.add_argument("--params", default="{}", help="assembly parameters, JSON")
    args = ap.parse_args(argv)
    import json

    PARAMS.update(json.loads(args.params))
    print(f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; seeds {args.first}..{args.first + args.seeds - 1}")
    rows = []
    for seed in range(args.first, args.first + args.seeds):
        m = measure(seed)
        rows.append(m)
        if not m["ok"]:
            print(f"{seed:4d} FAILED {m['error'][:160]}")
            continue
        ratio, who, own = m["ratio"]
        print(f"{seed:4d} {m['glued']:2d}/{m['parts']:2d} glued, {m['free']} free, comps {m['components']} "
              f"(exp {m['components_expected']}), boundary {m['boundary']}, inter {m['inter']}, junction max "
              f"{m['j_max']:5.1f} p99.9 {m['j_999']:5.1f} >90 {m['j_over90']} <=45 {100 * m['j_le45']:.2f}%, "
              f"[away from drawn tips: max {m['a_max']:5.1f} <=45 {100 * m['a_le45']:.2f}%; at them: max {m['t_max']:5.1f}], "
              f"whole max {m['all_max']:5.1f}, depth ratio {ratio:.2f} ({who}; own layer {own:.2f}), {m['cpu']:.2f} s CPU "
              f"({m['vertices']} v), fair {m['fair']}")
        for w in m["warnings"]:
            print(f"       free: {w[:150]}")
    ok = [m for m in rows if m["ok"]]
    n = len(rows)

    def pct(vals, q):
        return float(np.percentile(vals, q)) if len(vals) else float("nan")

    print()
    print(f"assembled: {len(ok)} of {n} ({100 * len(ok) / n:.1f}%)")
    if not ok:
        return
    whole = [m for m in ok if m["free"] == 0]
    print(f"every part glued: {len(whole)} of {n}; parts glued {sum(m['glued'] for m in ok)} of "
          f"{sum(m['parts'] for m in ok)}, free {sum(m['free'] for m in ok)}; glued by a stretch only "
          f"{sum(m['notes'] for m in ok)}")
    print(f"components as expected: {sum(m['components'] == m['components_expected'] for m in ok)} of {len(ok)}; "
          f"boundary edges: total {sum(m['boundary'] for m in ok)}; self-intersecting pairs: total "
          f"{sum(m['inter'] for m in ok)} (creatures with any: {sum(m['inter'] > 0 for m in ok)})")
    jm = [m["j_max"] for m in ok]
    print(f"junction dihedral max: median {pct(jm, 50):.1f}, p90 {pct(jm, 90):.1f}, worst {max(jm):.1f}; creatures "
          f"with an edge > 90: {sum(m['j_over90'] > 0 for m in ok)}; p99.9 per creature: median "
          f"{pct([m['j_999'] for m in ok], 50):.1f}, worst {max(m['j_999'] for m in ok):.1f}; share <= 45 under 99.9%: "
          f"{sum(m['j_le45'] < 0.999 for m in ok)}, worst {100 * min(m['j_le45'] for m in ok):.3f}%")
    am = [m["a_max"] for m in ok]
    print(f"  the same away from corners drawn sharp on the part itself (a beak's tip): max median {pct(am, 50):.1f}, "
          f"worst {max(am):.1f}; creatures with an edge > 90: {sum(a > 90 for a in am)}; share <= 45 under 99.9%: "
          f"{sum(m['a_le45'] < 0.999 for m in ok)}, worst {100 * min(m['a_le45'] for m in ok):.3f}%; at those "
          f"corners: creatures with an edge > 90: {sum(m['t_over90'] > 0 for m in ok)}, worst {max(m['t_max'] for m in ok):.1f}")
    print(f"whole-mesh dihedral max: median {pct([m['all_max'] for m in ok], 50):.1f}, worst "
          f"{max(m['all_max'] for m in ok):.1f}")
    rs = [m["ratio"][0] for m in ok if np.isfinite(m["ratio"][0])]
    if rs:
        print(f"limb depth ratio (smallest per creature): median {pct(rs, 50):.2f}, p10 {pct(rs, 10):.2f}, "
              f"worst {min(rs):.2f}; creatures under 0.8: {sum(r < 0.8 for r in rs)} of {len(rs)}")
        thin = [m for m in ok if np.isfinite(m["ratio"][0]) and m["ratio"][0] < 0.8]
        drawn = [m for m in thin if m["ratio"][2] < 0.8]
        kept = [m["ratio"][0] / m["ratio"][2] for m in ok if np.isfinite(m["ratio"][0]) and m["ratio"][2] > 0]
        print(f"  of those, drawn narrower where they leave the host (own layer's ratio under 0.8 too): "
              f"{len(drawn)}; kept/own ratio of the limb at worst {min(kept, default=float('nan')):.2f}")
    cpu = [m["cpu"] for m in ok]
    print(f"assembly CPU: median {pct(cpu, 50):.2f} s, p90 {pct(cpu, 90):.2f} s, worst {max(cpu):.2f} s "
          f"(layer vertices median {int(pct([m['layer_vertices'] for m in ok], 50))})")
    speed()
    if args.pictures:
        sys.path.insert(0, str(ROOT / "examples"))
        from creature_views import three_views  # noqa: E402

        args.pictures.mkdir(parents=True, exist_ok=True)
        for m in ok[:3]:
            three_views(m["result"].mesh, args.pictures / f"creature-drawn-{m['seed']}.png")


if __name__ == "__main__":
    main()
