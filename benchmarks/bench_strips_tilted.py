"""Both sculpt solvers under a light above the drawing plane (issue 35, point 3, for ``strips``):
the sculpt called directly with 3D lights at 0, 30, 60 and 90 degrees of elevation (azimuth
45 degrees) on a seeded corpus.

Run: ``.venv/bin/python benchmarks/bench_strips_tilted.py [layers_per_shape] [edits_per_layer] [seed]``
(default 2, 3, 36: 24 edits per elevation). Prints per elevation and solver: applied edits,
how many land (after <= max(2, 0.3 x before) edge lengths), how many ended farther (target 0),
the largest height change per edit (median, max; the host bounds it at 60% of the peak) and
how many edits the host scaled down, and the CPU time per edit.
"""

from __future__ import annotations

import os
import sys

import numpy as np


def main(layers: int = 2, edits: int = 3, seed: int = 36) -> None:
    from sketchforge_isophote_tool.corpus import SHAPES, corpus_layers, draw_edits, run_edit
    from sketchforge_strips.solver import STRIPS

    print(f"load {os.getloadavg()[0]:.1f}")
    for elevation in (0, 30, 60, 90):
        e = np.radians(elevation)
        light = np.array([np.cos(e) / np.sqrt(2.0), np.cos(e) / np.sqrt(2.0), np.sin(e)])
        outs: dict = {"gauss_newton": [], "strips": []}
        for shape, _, mesh, rng in corpus_layers(SHAPES, per_shape=layers, seed=seed):
            for ed in draw_edits(shape, mesh, rng, light, edits):
                outs["gauss_newton"].append(run_edit(mesh, light, ed, None))
                outs["strips"].append(run_edit(mesh, light, ed, STRIPS))
        for name, o in outs.items():
            ok = [x for x in o if x.status == "ok"]
            mdz = np.array([x.max_dz for x in ok]) if ok else np.array([np.nan])
            print(f"{elevation:3d} deg {name:13s} applied {len(ok):3d}/{len(o)}  lands {sum(x.lands for x in o):3d}  "
                  f"worse {sum(x.after > x.before for x in ok)}  crashes {sum(x.status == 'crash' for x in o)}  "
                  f"largest change median {np.median(mdz):.0%} max {mdz.max():.0%}  scaled down {sum(x.bounded > 0 for x in ok)}  "
                  f"CPU {1e3 * np.nanmean([x.cpu for x in o]):.0f} ms/edit", flush=True)


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:]))
