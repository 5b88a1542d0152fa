"""Junction folds (issue 12, point 1): dihedral angles of assembled meshes, plain sleeve
against the blended junction (``fillet``), on the examples and on seeded random creatures.
Prints figures, asserts nothing. Targets: no dihedral angle above 90 degrees, 99.9% of them at
most 45, with the mesh closed, oriented, Euler characteristic 2 per group, no intersection.

    .venv/bin/python benchmarks/bench_junctions.py [--seeds 30] [--pictures docs/screenshots]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from sketchforge.geometry.mesh import Mesh
from sketchforge_assemble import assemble_detailed
from sketchforge_assemble import diagnostics as dg
from sketchforge_assemble.testing import meshes_from_journal, random_creature

ROOT = Path(__file__).resolve().parents[1]
SETTINGS = {"plain": {}, "fillet 4": {"fillet": 4.0}}


def measure(meshes, closed, params):
    t = time.perf_counter()
    res = assemble_detailed(meshes, closed, params=params)
    t = time.perf_counter() - t
    V, F = res.mesh.V, res.mesh.F
    d = dg.dihedral_angles(V, F)
    _, count = dg.edge_counts(F)
    ok = bool(np.all(count == 2) and dg.is_consistently_oriented(F)
              and dg.euler_characteristics(F) == [2] * res.components)
    inter = len(dg.intersecting_pairs(V, F))
    return res, {"max": float(d.max()), "over90": int(np.sum(d > 90)), "le45": float(np.mean(d <= 45)),
                 "closed": ok, "inter": inter, "time": t,
                 "target": bool(d.max() <= 90 and np.mean(d <= 45) >= 0.999 and ok and inter == 0)}


def line(name, m):
    return (f"  {name:9s} max {m['max']:5.1f} deg, {m['over90']:3d} edges > 90, {100 * m['le45']:.3f}% <= 45, "
            f"closed/oriented/chi2 {m['closed']}, intersecting pairs {m['inter']}, {m['time']:.2f} s")


def picture(mesh: Mesh, path: Path, size: int = 480) -> None:
    """A three-quarter view (turned 55 degrees about x, 25 about y) of an assembled mesh."""
    from sketchforge.geometry.raster import render_top, write_png

    a, b = np.radians(-55.0), np.radians(25.0)
    Rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    Ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    V = (mesh.V - mesh.V.mean(axis=0)) @ (Ry @ Rx).T
    write_png(path, render_top([Mesh(V, mesh.F)], np.array([0.5, 0.6, 0.62]), size))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--pictures", type=Path, default=None)
    args = ap.parse_args()
    for name in ("creature", "toucan", "separate"):
        _, meshes, closed = meshes_from_journal(ROOT / "examples" / f"{name}.json")
        print(f"{name} ({sum(m.n_vertices for m in meshes)} layer vertices)")
        for label, params in SETTINGS.items():
            res, m = measure(meshes, closed, params)
            print(line(label, m))
            if args.pictures is not None:
                args.pictures.mkdir(parents=True, exist_ok=True)
                picture(res.mesh, args.pictures / f"junction-{name}-{label.split()[0]}.png")
    rates = {label: [] for label in SETTINGS}
    for seed in range(args.seeds):
        _, meshes, closed = meshes_from_journal(random_creature(seed))
        print(f"random creature {seed} ({len(meshes)} layers, {sum(m.n_vertices for m in meshes)} layer vertices)")
        for label, params in SETTINGS.items():
            _, m = measure(meshes, closed, params)
            rates[label].append(m)
            print(line(label, m))
    for label, ms in rates.items():
        if not ms:
            continue
        print(f"{label}: {sum(m['target'] for m in ms)}/{len(ms)} random creatures meet the target; "
              f"edges > 90 per creature: median {np.median([m['over90'] for m in ms]):.0f}, "
              f"max angle median {np.median([m['max'] for m in ms]):.1f}; "
              f"<= 45: median {100 * np.median([m['le45'] for m in ms]):.3f}%; "
              f"with an intersection: {sum(m['inter'] > 0 for m in ms)}; "
              f"time median {np.median([m['time'] for m in ms]):.2f} s")


if __name__ == "__main__":
    main()
