"""The depth-order QP's solvers compared (issue 39, point 3): ``solve_depth`` as the assembly
runs it (the exact glue-only optimum where it satisfies every depth row, else OSQP with
polishing off, then the hand-written active set where a row is still violated), the same
without its first step (OSQP alone: what it did before), OSQP with polishing on, the
hand-written active set alone, and the maintained interior-point solvers Clarabel and PIQP
(where installed: ``pip install clarabel piqp``).

The QPs are the assembly's own, captured from ``solve_depth`` while the example creature, its
3-layer part and seeded random creatures are assembled (one QP per independent group of glued
layers). Each solver's answer is measured against a reference optimum (Clarabel at 1e-10, else
the active set) by
- ``viol``: the largest violation of a depth row (the assembly needs none: > 0 is a failure),
- ``glue``: the largest glue-row residual,
- ``dx/gap``: the largest distance from the reference optimum, in gaps (the clearance asked
  between faces), and ``dobj``: the objective above the reference's, relative to it;
and its CPU time (the least of three runs). Prints one line per QP and a summary; asserts
nothing.

    .venv/bin/python benchmarks/bench_depth_qp.py [--random 10]
"""

from __future__ import annotations

import json
import os
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parents[1]


def capture(docs) -> list[tuple]:
    """[(name, (P, q, Aeq, beq, Ain, bin_), pad)] of every depth QP the assembly of ``docs``
    solves."""
    from sketchforge_assemble import assemble_detailed, depth
    from sketchforge_assemble.testing import meshes_from_journal

    found = []
    real = depth.solve_depth

    def spy(P, q, Aeq, beq, Ain, bin_, method="osqp", pad=0.0, **kw):
        found.append((P.copy(), q.copy(), sp.csr_matrix(Aeq).copy(), np.array(beq), sp.csr_matrix(Ain).copy(),
                      np.array(bin_), float(pad)))
        return real(P, q, Aeq, beq, Ain, bin_, method=method, pad=pad, **kw)

    out = []
    depth.solve_depth = spy
    try:
        for name, doc in docs:
            found.clear()
            _, meshes, closed = meshes_from_journal(doc)
            assemble_detailed(meshes, closed)
            for k, (*qp, pad) in enumerate(found):
                out.append((f"{name}/{k}", tuple(qp), pad))
    finally:
        depth.solve_depth = real
    return out


@contextmanager
def osqp_polishing():
    import osqp

    real = osqp.OSQP.setup

    def setup(self, *args, **kw):
        kw["polishing"] = True
        return real(self, *args, **kw)

    osqp.OSQP.setup = setup
    try:
        yield
    finally:
        osqp.OSQP.setup = real


def solve_pipeline(qp, pad, polish=False, osqp_only=False):
    """``solve_depth`` as the assembly calls it; ``osqp_only``: without its exact glue-only
    first step (what it did before issue 39)."""
    from sketchforge_assemble import depth_qp
    from sketchforge_assemble.depth import solve_depth

    if osqp_only:
        real = depth_qp._equality_solution
        depth_qp._equality_solution = lambda *a: None
        try:
            return solve_pipeline(qp, pad, polish)
        finally:
            depth_qp._equality_solution = real
    if polish:
        with osqp_polishing():
            x, info = solve_depth(*qp, method="osqp", pad=pad)
    else:
        x, info = solve_depth(*qp, method="osqp", pad=pad)
    how = "exact glue-only optimum" if info.get("exact") else f"osqp it {info['osqp_iterations']}"
    return x, f"{how}, active-set steps {info['iterations']}"


def solve_active_set(qp, pad):
    from sketchforge_assemble.depth import solve_depth

    x, info = solve_depth(*qp, method="active_set", pad=pad)
    return x, f"steps {info['iterations']}"


def solve_clarabel(qp, pad, tol=1e-8, margin=0.0):
    import clarabel

    P, q, Aeq, beq, Ain, bin_ = qp
    A = sp.vstack([sp.csr_matrix(Aeq), -sp.csr_matrix(Ain)]).tocsc()
    b = np.r_[beq, -(bin_ + margin)]
    s = clarabel.DefaultSettings()
    s.verbose = False
    s.tol_gap_abs = s.tol_gap_rel = s.tol_feas = tol
    s.max_threads = 1
    solver = clarabel.DefaultSolver(sp.triu(P).tocsc(), np.asarray(q, float), A, b,
                                    [clarabel.ZeroConeT(len(beq)), clarabel.NonnegativeConeT(len(bin_))], s)
    sol = solver.solve()
    return np.asarray(sol.x), f"{sol.status}, {sol.iterations} it"


def solve_piqp(qp, pad, margin=0.0):
    import piqp

    P, q, Aeq, beq, Ain, bin_ = qp
    solver = piqp.SparseSolver()
    solver.settings.verbose = False
    solver.settings.num_threads = 1 if hasattr(solver.settings, "num_threads") else None
    solver.setup(sp.csc_matrix(P), np.asarray(q, float), sp.csc_matrix(Aeq), np.asarray(beq, float),
                 -sp.csc_matrix(Ain), None, -(np.asarray(bin_, float) + margin))
    status = solver.solve()
    return np.asarray(solver.result.x), f"{status}, {solver.result.info.iter} it"


def measure(qp, pad, x, ref):
    P, q, Aeq, beq, Ain, bin_ = qp
    if x is None or not np.all(np.isfinite(x)):
        return None
    f = lambda v: 0.5 * v @ (P @ v) + q @ v  # noqa: E731
    viol = float(max(0.0, -np.min(Ain @ x - bin_))) if len(bin_) else 0.0
    glue = float(np.max(np.abs(Aeq @ x - beq))) if len(beq) else 0.0
    gap = 2.0 * pad if pad > 0 else 1.0
    return {"viol": viol, "glue": glue, "dx": float(np.max(np.abs(x - ref))) / gap,
            "dobj": (f(x) - f(ref)) / max(abs(f(ref)), 1e-300)}


def cpu(fn, repeats=3):
    best, out = float("inf"), None
    for _ in range(repeats):
        t = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t)
    return best, out


def main(n_random: int) -> None:
    from sketchforge_assemble.testing import random_creature

    creature = json.loads((ROOT / "examples" / "creature.json").read_text())
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_assemble", ROOT / "benchmarks" / "bench_assemble.py")
    ba = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ba)
    docs = [("creature", creature), ("3-layer", ba.three_layer_doc())]
    docs += [(f"random{seed}", random_creature(seed)) for seed in range(n_random)]
    qps = capture(docs)
    have = {}
    for mod in ("clarabel", "piqp"):
        try:
            __import__(mod)
            have[mod] = True
        except ImportError:
            have[mod] = False
    solvers = {
        "solve_depth (osqp)": lambda qp, pad: solve_pipeline(qp, pad),
        "osqp alone (before)": lambda qp, pad: solve_pipeline(qp, pad, osqp_only=True),
        "osqp polished": lambda qp, pad: solve_pipeline(qp, pad, polish=True, osqp_only=True),
        "active set alone": solve_active_set,
    }
    # The interior-point solvers meet their rows to their tolerance only: they are asked for a
    # clearance of 1e-6 gap (far below any distance a person sees) so that "satisfied" means >= 0.
    if have["clarabel"]:
        solvers["clarabel"] = lambda qp, pad: solve_clarabel(qp, pad, margin=2e-6 * pad)
    if have["piqp"]:
        solvers["piqp"] = lambda qp, pad: solve_piqp(qp, pad, margin=2e-6 * pad)
    print(f"load {os.getloadavg()[0]:.2f}; {len(qps)} QPs; solvers: {', '.join(solvers)}"
          + ("" if all(have.values()) else f" (not installed: {', '.join(k for k, v in have.items() if not v)})"))
    table = {name: [] for name in solvers}
    for qname, qp, pad in qps:
        P, q, Aeq, beq, Ain, bin_ = qp
        if have["clarabel"]:
            ref, _ = solve_clarabel(qp, pad, tol=1e-10)
        else:
            ref, _ = solve_active_set(qp, pad)
        print(f"{qname}: {P.shape[0]} unknowns, {len(beq)} glue rows, {len(bin_)} depth rows, gap {2 * pad:.3g}")
        for name, fn in solvers.items():
            try:
                t, (x, note) = cpu(lambda: fn(qp, pad))  # noqa: B023 - called in this iteration
                m = measure(qp, pad, x, ref)
            except Exception as exc:  # noqa: BLE001 - a solver that fails is a result too
                t, m, note = float("nan"), None, f"{type(exc).__name__}: {exc}"
            table[name].append((t, m))
            if m is None:
                print(f"  {name:24s} failed ({note})")
            else:
                print(f"  {name:24s} {1000 * t:8.1f} ms  viol {m['viol']:.1e}  glue {m['glue']:.1e}  "
                      f"dx/gap {m['dx']:.2e}  dobj {m['dobj']:+.1e}  ({note})")
    print("summary (CPU ms: median, max, total; answers with a violated depth row; worst dx/gap; worst dobj):")
    for name, rows in table.items():
        ts = [t for t, m in rows if m is not None]
        ms = [m for _, m in rows if m is not None]
        bad = sum(m["viol"] > 0 for m in ms) + (len(rows) - len(ms))
        print(f"  {name:24s} median {1000 * np.median(ts):7.1f}  max {1000 * max(ts):7.1f}  total {1000 * sum(ts):8.1f}  "
              f"violated/failed {bad:2d} of {len(rows)}  dx/gap {max(m['dx'] for m in ms):.2e}  "
              f"dobj {max(m['dobj'] for m in ms):+.1e}")


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--random", type=int, default=10, help="seeded random creatures (0: none)")
    main(ap.parse_args().random)
