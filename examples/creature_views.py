"""Creatures drawn as people draw them (issue 34): write ``examples/drawn.json`` (a quadruped of
the seeded Monster-Mash-style corpus, ``sketchforge_assemble.drawn``, seed 0: far legs drawn
behind and overlapping the near ones, twin ears whose bases touch, head, snout and tail as open
strokes) and pictures of assembled creatures from three views (front, side, three-quarter), drawn
by the project's own renderer (per-pixel normals, no OpenGL).

    .venv/bin/python examples/creature_views.py [--pictures docs/screenshots]

Deterministic: the same files every run.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

#: The three views: (about x, about y) in degrees, applied to the model centred on its middle.
VIEWS = {"front": (0.0, 0.0), "side": (0.0, 90.0), "three-quarter": (-20.0, 40.0)}


def _rotation(ax: float, ay: float) -> np.ndarray:
    a, b = np.radians(ax), np.radians(ay)
    Rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    Ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    return Ry @ Rx


def views(mesh, size: int = 420, light=(0.45, 0.55, 0.7)) -> np.ndarray:
    """(size, 3·size, 3) uint8: ``mesh`` (an assembled model) from the front, the side and in
    three-quarter view, side by side."""
    import dataclasses

    from sketchforge.geometry.mesh import AssembledMesh, Mesh
    from sketchforge.geometry.raster import render_top

    c = mesh.V.mean(axis=0)
    shots = []
    for ax, ay in VIEWS.values():
        V = (mesh.V - c) @ _rotation(ax, ay).T
        # turned, the model keeps its rim pairs (normals shared across each part's rim)
        turned = dataclasses.replace(mesh, V=V) if isinstance(mesh, AssembledMesh) else Mesh(V, mesh.F)
        shots.append(render_top([turned], np.array(light), size))
    return np.concatenate(shots, axis=1)


def three_views(mesh, path: Path, size: int = 420) -> None:
    """Write :func:`views` of ``mesh`` to the PNG ``path``."""
    from sketchforge.geometry.raster import write_png

    write_png(path, views(mesh, size))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pictures", type=Path, default=None, help="also write the README's pictures here")
    args = ap.parse_args(argv)
    from sketchforge.document import fileformat as ff
    from sketchforge.plugins import default_host
    from sketchforge_assemble.drawn import drawn_creature

    host = default_host()
    data = drawn_creature(0)
    doc = ff.document_from_dict(data, "drawn creature", host=host, use_snapshot=False)
    ff.save(doc, HERE / "drawn.json")
    print(f"wrote {HERE / 'drawn.json'}")
    if args.pictures:
        args.pictures.mkdir(parents=True, exist_ok=True)
        for seed in (0, 1, 2):
            d = ff.document_from_dict(drawn_creature(seed), f"drawn creature {seed}", host=host,
                                   use_snapshot=False)
            out = args.pictures / f"drawn-creature-{seed}.png"
            three_views(d.export_mesh(), out)
            print(f"wrote {out}")


if __name__ == "__main__":
    main()
