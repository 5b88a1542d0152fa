"""Junction folds (issue 12, point 1): dihedral angles of assembled meshes, plain sleeve
(``fillet: 0``) against the fillet alone (``fair: 0``) and the default blended junction (fillet
and fairing), on the examples and on seeded random creatures. Prints figures, asserts nothing.
Targets: no dihedral angle above 90 degrees, 99.9% of them at most 45, with the mesh closed,
oriented, Euler characteristic 2 per group, no intersection.

    .venv/bin/python benchmarks/bench_junctions.py [--seeds 30] [--first 0] [--pictures docs/screenshots]
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
SETTINGS = {"plain": {"fillet": 0.0}, "fillet": {"fair": 0}, "blended": {}}


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
    fair = res.timings.get("fair", 0.0) + res.timings.get("fair_check", 0.0)
    return res, {
        "max": float(d.max()),
        "over90": int(np.sum(d > 90)),
        "le45": float(np.mean(d <= 45)),
        "fair": fair,
        "fallback": any("plain fold" in w for w in res.warnings),
        "zone": res.solver.get("fair_zone"),
        "closed": ok,
        "inter": inter,
        "time": t,
        "target": bool(d.max() <= 90 and np.mean(d <= 45) >= 0.999 and ok and inter == 0),
    }


def line(name, m):
    return (f"  {name:9s} max {m['max']:5.1f} deg, {m['over90']:3d} edges > 90, {100 * m['le45']:.3f}% <= 45, "
            f"closed/oriented/chi2 {m['closed']}, intersecting pairs {m['inter']}, {m['time']:.2f} s "
            f"(fairing and its check {m['fair']:.2f} s{', ' + m['zone'] + ' zone' if m['zone'] else ''})"
            f"{' FELL BACK' if m['fallback'] else ''}")


def picture(mesh: Mesh, path: Path, size: int = 480) -> None:
    """A three-quarter view (turned 55 degrees about x, 25 about y) of an assembled mesh."""
    from sketchforge.geometry.raster import render_top, write_png

    V = (mesh.V - mesh.V.mean(axis=0)) @ _view().T
    write_png(path, render_top([Mesh(V, mesh.F)], np.array([0.5, 0.6, 0.62]), size))


def closeup(mesh: Mesh, centre: np.ndarray, path: Path, half: float = 0.3, size: int = 480,
            isophotes: int = 6) -> None:
    """The same three-quarter view, framed on ``centre`` (3,) with ``half`` the window's half
    width, shaded with isophote lines (as ``sketchforge render`` draws them): a fold shows as
    a crease where the lines break, a blend as lines that run on smoothly."""
    from sketchforge.geometry.raster import render_top, write_png

    R = _view()
    V = (mesh.V - mesh.V.mean(axis=0)) @ R.T
    c = (centre - mesh.V.mean(axis=0)) @ R.T
    inside = np.all(np.abs(V[:, :2] - c[:2]) <= half, axis=1)
    F = mesh.F[inside[mesh.F].all(axis=1)]
    used, F = np.unique(F, return_inverse=True)  # the renderer frames every vertex it is given
    write_png(path, render_top([Mesh(V[used], F.reshape(-1, 3))], np.array([0.5, 0.6, 0.62]), size, isophotes=isophotes, margin=0.0))


def _view() -> np.ndarray:
    """(3, 3) the three-quarter view's rotation: 55 degrees about x, then 25 about y."""
    a, b = np.radians(-55.0), np.radians(25.0)
    Rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    Ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    return Ry @ Rx


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--first", type=int, default=0, help="first seed (30: the held-out seeds 30-59)")
    ap.add_argument("--pictures", type=Path, default=None)
    args = ap.parse_args()
    for name in ("creature", "toucan", "separate"):
        layers, meshes, closed = meshes_from_journal(ROOT / "examples" / f"{name}.json")
        print(f"{name} ({sum(m.n_vertices for m in meshes)} layer vertices)")
        for label, params in SETTINGS.items():
            res, m = measure(meshes, closed, params)
            print(line(label, m))
            if args.pictures is not None:
                args.pictures.mkdir(parents=True, exist_ok=True)
                picture(res.mesh, args.pictures / f"junction-{name}-{label}.png")
                if name == "creature":  # the front arm's junction, where the fold was largest
                    arm = meshes[[layer.id for layer in layers].index("arm_front")]
                    j = arm.V[arm.junction]
                    near = np.linalg.norm(res.mesh.V[:, :2] - j[:, :2].mean(axis=0), axis=1) < 0.06
                    c = res.mesh.V[near][np.argmax(res.mesh.V[near, 2])]  # on the front, not the back
                    closeup(res.mesh, c, args.pictures / f"junction-arm-{label}.png")
    rates = {label: [] for label in SETTINGS}
    for seed in range(args.first, args.first + args.seeds):
        try:
            _, meshes, closed = meshes_from_journal(random_creature(seed))
        except ValueError as e:  # a seed the generator refuses (43: no head fits)
            print(e)
            continue
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
              f"not closed/oriented/chi2: {sum(not m['closed'] for m in ms)}; "
              f"fell back to the plain sleeve: {sum(m['fallback'] for m in ms)}; "
              f"faired in the wide zone: {sum(m['zone'] == 'wide' for m in ms)}; "
              f"time median {np.median([m['time'] for m in ms]):.2f} s")


if __name__ == "__main__":
    main()
