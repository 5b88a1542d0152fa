"""The costliest parameters each solver accepts, on a layer of about 5k vertices (issue 38:
"accepted parameters keep an edit under 60 s on a 5k-vertex layer"; the strips solver's worst
accepted values ran 145 s before refusing).

Run: .venv/bin/python benchmarks/bench_param_extremes.py [gauss_newton] [strips] [assemble] [inflate]
Prints, per case, wall and CPU seconds (time.process_time, all threads) and the outcome. Every
parameter is set, alone, to each end of its accepted range (the bound from the solver's
``check_params``), then the combination of the dearest ends, with a short stroke and with one
along the whole isophote (the most strips). The first strips edit of the
process compiles (JAX): a warm-up edit with the defaults runs first, and is shown.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from sculpt_helpers import isophote_stroke  # noqa: E402

from sketchforge.errors import SketchforgeError  # noqa: E402
from sketchforge_isophote_tool import sculpt  # noqa: E402
from sketchforge_isophote_tool.testing import LIGHT, inflated  # noqa: E402

PICK = [0.2, 0.1]
#: ellipse 1 x 0.7 at this resolution: about 5 000 vertices
RESOLUTION = 0.03


def timed(fn):
    t, c = time.perf_counter(), time.process_time()
    try:
        out = fn()
        what = out if isinstance(out, str) else "ok"
    except SketchforgeError as exc:
        what = f"refused: {str(exc)[:110]}"
    return time.perf_counter() - t, time.process_time() - c, what


def report(label, row) -> None:
    wall, cpu, what = row
    print(f"  {label:52s} {wall:7.1f} {cpu:7.1f}  {what}", flush=True)


def sculpt_cases(name: str, checks: dict, dear: dict):
    """(label, params) for each bound of each numeric parameter, then ``dear`` together."""
    out = []
    for key, (lo, hi) in checks.items():
        for v in (lo, hi):
            out.append((f"{key}={v:g}", {key: v}))
    if dear:
        out.append(("all dearest: " + ", ".join(f"{k}={v}" for k, v in dear.items()), dict(dear)))
    return out


def bench_sculpt(solver_name: str) -> None:
    from sketchforge.plugins.manager import default_host

    host = default_host()
    solver = host.solver("sculpt", solver_name)
    mesh = inflated("ellipse", RESOLUTION)
    stroke = isophote_stroke(mesh, PICK, offset=0.1)[0]
    print(f"{solver_name}: ellipse of {mesh.n_vertices} vertices, one edit (band 0.3)")
    print(f"  {'parameters':52s} {'wall s':>7s} {'cpu s':>7s}  outcome")

    long_stroke = isophote_stroke(mesh, PICK, offset=0.1, half=1.0)[0]  # the whole isophote

    def edit(params, band=0.3, stroke=stroke):
        def run():
            r = sculpt(mesh, LIGHT, PICK, band, stroke, solver=solver, params=params)
            return f"applied x{r.fraction:g}, {r.before / r.h:.2f} -> {r.after / r.h:.2f} h"
        return run

    report("defaults (first edit of the process: compiles)", timed(edit({})))
    report("defaults", timed(edit({})))
    ranges = bounds(solver)
    dear = DEAREST.get(solver_name, {})
    for label, params in sculpt_cases(solver_name, ranges, dear):
        report(label, timed(edit(params)))
    length = float(np.linalg.norm(np.diff(long_stroke, axis=0), axis=1).sum())
    report(f"defaults, a stroke along the whole isophote ({length:.2f} long)", timed(edit({}, stroke=long_stroke)))
    for k in range(2):
        report(f"all dearest, the whole isophote ({'first' if k == 0 else 'again'})", timed(edit(dict(dear), stroke=long_stroke)))
    report("band 1e9 (the whole layer), defaults", timed(edit({}, band=1e9)))


#: The dearest accepted value of each parameter, found with the single-parameter rows.
DEAREST = {
    "gauss_newton": {"steps": 50, "ring": 1e9, "smoothness": 1e6, "stroke_weight": 1e6, "rim_margin": 0.0},
    "strips": {"integrator": "kvaerno5", "rtol": 1e-8, "atol": 1e-11, "strip_spacing": 1.0, "sample_spacing": 0.25,
               "rbf_neighbors": 64, "ring": 20.0},
}


#: The top of each numeric assembly option (sketchforge_assemble.assemble.MAX_PARAMS), timed.
ASSEMBLY_TOPS = {"fillet": 100.0, "margin": 100.0, "gap": 100.0, "reg": 1e6, "stiffness": 1e4}


#: Values probed for the ends of a range: 0, every power of ten, and the round values the
#: solvers use as bounds.
_PROBES = sorted({0.0, 1e308, *(10.0 ** k for k in range(-16, 13)),
                  0.25, 0.5, 2.0, 4.0, 8.0, 16.0, 20.0, 32.0, 50.0, 64.0, 100.0, 128.0, 256.0, 512.0})


def bounds(solver) -> dict:
    """{numeric key: (lowest, highest accepted)} probed through ``check_params`` with
    :data:`_PROBES` (integers for an integer parameter): the range the solver enforces."""
    out = {}
    base = solver.check_params({})
    for key, v in base.items():
        if isinstance(v, bool) or not (v is None or isinstance(v, (int, float))):
            continue
        whole = isinstance(v, int)

        def ok(c):
            try:
                solver.check_params({key: int(c) if whole else c})  # noqa: B023 - called in this iteration
                return True
            except SketchforgeError:
                return False

        probes = [c for c in _PROBES if not whole or (c == int(c) and c < 1e19)]
        good = [c for c in probes if ok(c)]
        if good:
            out[key] = (int(good[0]) if whole else good[0], int(good[-1]) if whole else good[-1])
    return out


def bench_assemble() -> None:
    """An assembly of a body (about 5k vertices) and two glued legs with each bound of each
    assembly parameter."""
    from sketchforge.document.document import Document
    from sketchforge.plugins.manager import default_host

    host = default_host()
    asm = host.solver("assemble", None)
    doc = Document(host=host)
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    body = np.column_stack([np.cos(t), 0.7 * np.sin(t)])
    doc.execute({"command": "add_layer", "id": "body", "name": "body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": body.tolist(), "closed": True})
    doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"resolution": RESOLUTION}})
    for k, x in enumerate((-0.4, 0.4)):
        s = np.linspace(0, np.pi, 60)
        leg = np.column_stack([x + 0.15 * np.cos(s), -0.5 - 0.5 * np.sin(s)])
        doc.execute({"command": "add_layer", "id": f"leg{k}", "name": f"leg{k}", "index": 0})
        doc.execute({"command": "set_contour", "layer": f"leg{k}", "points": leg.tolist(), "closed": False})
    layers = [l for l in doc.layers if l.mesh is not None]
    print(f"assemble: {', '.join(f'{l.name} {l.mesh.n_vertices}' for l in layers)} vertices")
    print(f"  {'parameters':52s} {'wall s':>7s} {'cpu s':>7s}  outcome")
    report("defaults", timed(lambda: f"{asm.assemble(layers, asm.check_params({})).n_vertices} vertices"))
    ranges = bounds(asm)
    cases = [(f"{k}={v:g}", {k: v}) for k, (lo, hi) in ranges.items() for v in (lo, hi)]
    lows = {k: lo for k, (lo, hi) in ranges.items() if k in ("margin", "gap", "reg", "stiffness")}
    cases += [("fillet=100, fair=50", {"fillet": 100.0, "fair": 50}),
              (", ".join(f"{k}={v:g}" for k, v in lows.items()), lows),
              ("every top at once, fair=50", dict(ASSEMBLY_TOPS, fair=50))]
    for label, params in cases:
        report(label, timed(lambda: f"{asm.assemble(layers, asm.check_params(params)).n_vertices} vertices"))  # noqa: B023 - called in this iteration


def main() -> None:
    which = sys.argv[1:] or ["gauss_newton", "strips", "assemble"]
    print(f"load: {' '.join(f'{x:.2f}' for x in os.getloadavg())} (1/5/15 min), {os.cpu_count()} cores")
    for w in which:
        if w == "assemble":
            bench_assemble()
        else:
            bench_sculpt(w)


if __name__ == "__main__":
    main()
