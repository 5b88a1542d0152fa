"""Time one isophote edit on inflated ellipses of about 1k, 5k and 20k vertices, by step.

Run: ``.venv/bin/python benchmarks/bench_sculpt.py``. "first" is the first edit in the process
(includes JAX tracing/compilation of the sizes it needs); "warm" is the median of 3 further edits
with the per-layer cache cleared, so it includes the per-layer preparation ("layer": normals,
shading, grid fields) that every edit on a freshly changed mesh pays.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from sculpt_helpers import isophote_stroke  # noqa: E402
from sketchforge_isophote_tool import layerdata, sculpt  # noqa: E402
from sketchforge_isophote_tool.testing import LIGHT, inflated  # noqa: E402

SIZES = {"1k": 0.063, "5k": 0.03, "20k": 0.0145}
STEPS = ["layer", "isophote", "strips", "regions", "interpolation", "integration", "rbf", "total"]


def main(solver: str = "rk4") -> None:
    print(f"solver={solver}   times in ms")
    print(f"{'layer':>6} {'verts':>6} {'call':>6} " + " ".join(f"{s:>13}" for s in STEPS))
    for name, res in SIZES.items():
        mesh = inflated("ellipse", res)
        st, _, _ = isophote_stroke(mesh, [0.2, 0.1], 0.1)
        rows = []
        for k in range(4):
            layerdata._CACHE.clear()
            t = time.perf_counter()
            r = sculpt(mesh, LIGHT, [0.2, 0.1], 0.3, st, options={"solver": solver})
            r.timings["total"] = time.perf_counter() - t
            rows.append(r.timings)
        for label, T in [("first", rows[0]), ("warm", {s: float(np.median([x.get(s, 0) for x in rows[1:]])) for s in STEPS})]:
            print(f"{name:>6} {mesh.n_vertices:>6} {label:>6} " + " ".join(f"{1e3 * T.get(s, 0):13.1f}" for s in STEPS))
        print(f"{'':>6} {'':>6} {'':>6} strips: {len(r.regions.strips)} region, {len(r.strips)} characteristic; "
              f"changed vertices {int(r.changed.sum())}")


if __name__ == "__main__":
    main(*sys.argv[1:])
