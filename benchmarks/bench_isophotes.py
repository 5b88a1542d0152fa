"""Isophote wobble: drawn lines and marching-triangles isophotes against an exact surface.

Run: .venv/bin/python benchmarks/bench_isophotes.py [view_pixels]   (default 900)

Surfaces: the exact inflation of an ellipse 3 x 2 (outlines of 120 and 2000 points) and of a
unit disk, meshed like the inflate plugin at resolutions 0.03 (the default) and 0.015, heights
set to the exact z = sqrt(u) (see ``sketchforge.geometry.isophote_error``). Vertex normal
fields compared:

- area: area-weighted vertex normals (what the display drew before);
- display: the display's own (``heightfield.layer_normals``: (−∇w, 2z), w = z²), also the
  field the sculpt solver fits;
- exact: the exact normals at the vertices (the best any per-vertex field can draw).

Per case and light (in the plane, and raised 36°): the exact distance of the drawn lines'
centre pixels to the exact levels, px (median / p95 / max); the lines' pieces beyond the
exact count, summed over the 8 levels (a broken, ragged line near the rim adds pieces); and for
marching-triangles isophotes at n·l = 0.3, 0.6, 0.89 (the picked isophote) the exact distance
of their points in edge lengths (p95 / max, worst level) and pieces beyond one per level.
Prints figures only.
"""

from __future__ import annotations

import sys
import time

import numpy as np

LIGHTS = {
    "in-plane": np.array([np.cos(0.5), np.sin(0.5), 0.0]),
    "raised": np.array([0.7 * np.cos(0.5), 0.7 * np.sin(0.5), np.sqrt(1 - 0.49)]),
}
CASES = [  # (label, a, b, outline points, resolution)
    ("ellipse 120 pts, res 0.03", 1.5, 1.0, 120, 0.03),
    ("ellipse 2000 pts, res 0.03", 1.5, 1.0, 2000, 0.03),
    ("ellipse 2000 pts, res 0.015", 1.5, 1.0, 2000, 0.015),
    ("disk 400 pts, res 0.03", 1.0, 1.0, 400, 0.03),
]
LEVELS = (0.3, 0.6, 0.89)


def main(size: int = 900) -> None:
    from sketchforge.geometry import gbuffer as gb
    from sketchforge.geometry.heightfield import layer_normals
    from sketchforge.geometry.isophote_error import InflatedEllipse, line_wobble, polyline_wobble
    from sketchforge.geometry.normals import vertex_normals

    print(f"view {size}x{size} px, 8 lines (width 1.2 px: a perfect line's centre pixels lie within 0.6 px)")
    for label, a, b, n, res in CASES:
        s = InflatedEllipse(a, b)
        m = s.mesh(n, res)
        view = gb.View.framing([m], size, size, 0.05)
        t = time.perf_counter()
        fields = {"area": vertex_normals(m.V, m.F), "display": layer_normals(m), "exact": s.normal(m.V[:, :2])}
        print(f"{label}: {m.n_vertices} vertices, {view.scale:.0f} px per unit")
        for lname, l in LIGHTS.items():
            for fname, N in fields.items():
                w = line_wobble(s, m, view, l, 8, normals=N)
                poly = [polyline_wobble(s, m, N @ l, c, l) for c in LEVELS]
                print(f"  {lname:8s} {fname:7s} lines px median {w.median:5.2f} p95 {w.p95:5.2f} max {w.max:6.2f} "
                      f"extra pieces {w.extra_pieces:3d} | isophotes (h) p95 {max(p[0] for p in poly):5.3f} "
                      f"max {max(p[1] for p in poly):5.3f} extra pieces {sum(p[2] - 1 for p in poly)}")
        print(f"  ({time.perf_counter() - t:.1f} s)")


if __name__ == "__main__":
    main(*(int(x) for x in sys.argv[1:]))
