"""The isophote edit on a randomized corpus nobody here drew, both sculpt solvers side by side
(issue 16, point 7; issue 29, point 3).

Run: ``.venv/bin/python benchmarks/bench_sculpt_corpus.py [layers_per_shape] [edits_per_layer] [seed]
[--parts solvers,elevations,pairs] [--pairs N]`` (default 10, 8 and 2026: 320 edits on 40 layers,
every part, 3 pairs per layer). Shapes and edits: see
``sketchforge_isophote_tool.corpus`` (random blobs, stars, thin limbs 0.2–0.3 wide, letter
shapes; strokes = the isophote shifted or bumped by 1–5 edge lengths, with a small loop, or
partly outside the band). Fixed seeds: the same corpus on every run, and the very same edits
for both solvers (``gauss_newton``, the built-in, and ``strips``, the thesis' method).

Each shape kind runs in its own child process, so a native crash (a segfault in a solver)
is counted instead of ending the benchmark. Prints, per solver:

- crashes (target 0), refusals by reason, applied edits;
- lands: the mean distance from the stroke to the new isophote ≤ max(2, 0.3 × before) edge
  lengths, over the valid edits (the stroke has a part inside the band and outside the rim
  margin) and over the applied ones (target for ``strips``: ≥ 90% of applied);
- fidelity after (edge lengths: median, p95), after/before;
- worse: edits that ended farther from the stroke than they started (target 0);
- null drift: a stroke drawn on the isophote itself, on every fresh layer and after 10 edits
  (largest height change / peak; target ≤ 1%);
- chains of 10 edits on the first three layers of each shape (issue 36): the largest dihedral
  angle across an interior edge (both ends ≥ 3 edge lengths from the outline) and the largest
  shading jump across such an edge, against the fresh layer's (target ≤ 2.5×); new folded
  triangles near the rim (the surface falling toward the inside; target 0); the null drift
  after the chain (target ≤ 1%);
- locality: the share of the layer's vertices that moved and the distance from the stroke of
  the farthest one that did (edge lengths);
- the largest height change per edit (the host scales an edit down to 60% of the peak), time
  per edit (p50 / p95), and the mean time per edit in a fresh process, compilation included:
  each shape kind runs in a new process, so its first edits pay JAX's tracing (and its
  compilation, unless the persistent compilation cache holds it); target for ``strips``: at most
  3× ``gauss_newton``.

Beyond the thesis (issue 35), with ``gauss_newton``:

- ``elevations``: the same kind of corpus under a light raised 30, 60 and 80 degrees above the
  drawing plane (azimuth 45°; the edits are drawn on that light's isophotes); the same figures
  per elevation (target: >= 90% of the valid edits land, none worse);
- ``pairs``: pairs of edits of two different isophotes near each other (their bands overlap;
  ``corpus.random_pair``), in the plane and at 60°, made jointly (``sculpt_isophotes``) and
  one after the other (the same two edits, the second on the first's result): the share of
  valid pairs where both isophotes land, where one ends farther from its stroke than it
  started, each stroke's distance after (median, p95), the fallbacks the joint edit took and
  its refusals (targets: both land >= 80%, none worse, better than one after the other).
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import re
import time
from collections import Counter

import numpy as np

SEED = 2026
SOLVERS = ("gauss_newton", "strips")
#: Elevations of the raised lights (degrees above the drawing plane) and their azimuth.
ELEVATIONS = (30.0, 60.0, 80.0)
AZIMUTH = 45.0
#: Lights of the pairs: in the plane (the thesis') and raised.
PAIR_ELEVATIONS = (0.0, 60.0)
PARTS = ("solvers", "elevations", "pairs")


def _solver(name):
    if name == "strips":
        from sketchforge_strips.solver import STRIPS

        return STRIPS
    from sketchforge_isophote_tool.gauss_newton import GAUSS_NEWTON

    return GAUSS_NEWTON


def _shape_worker(shape: str, layers: int, edits: int, seed: int, queue) -> None:
    from sketchforge_isophote_tool.corpus import corpus_layers, draw_edits, run_edit
    from sketchforge_isophote_tool.testing import LIGHT

    for _, i, mesh, rng in corpus_layers((shape,), per_shape=layers, seed=seed):
        drawn = draw_edits(shape, mesh, rng, LIGHT, edits)
        state = rng.bit_generator.state
        for name in SOLVERS:
            solver = _solver(name)
            outcomes = [run_edit(mesh, LIGHT, e, solver) for e in drawn]
            rng.bit_generator.state = state  # both solvers: the same null stroke and later edits
            null = _null_drift(mesh, rng, LIGHT, solver)
            acc = _accumulated_drift(shape, mesh, rng, LIGHT, solver) if i < 3 else None
            if acc is not None:
                acc.update(shape=shape, layer=i)
            queue.put(("edits", name, shape, outcomes, null, acc))
    queue.put(("done", None, shape, None, None, None))


def _light(elevation: float) -> np.ndarray:
    from sketchforge.document.layer import Light

    return Light.from_angle(AZIMUTH, elevation).direction


def _elevation_worker(shape: str, layers: int, edits: int, seed: int, queue) -> None:
    """The single-edit corpus under each raised light (gauss_newton)."""
    from sketchforge_isophote_tool.corpus import corpus_layers, draw_edits, run_edit

    for _, i, mesh, _rng in corpus_layers((shape,), per_shape=layers, seed=seed):
        for el in ELEVATIONS:
            light = _light(el)
            # One stream per light, seeded from the layer's: the same shapes, each light's own
            # isophotes.
            sub = np.random.default_rng([seed, int(el), i, len(shape)])
            outcomes = [run_edit(mesh, light, e) for e in draw_edits(shape, mesh, sub, light, edits)]
            queue.put(("edits", f"elevation {el:g}", shape, outcomes, _null_drift(mesh, sub, light, _solver("gauss_newton")), None))
    queue.put(("done", None, shape, None, None, None))


def _pairs_worker(shape: str, layers: int, pairs: int, seed: int, queue) -> None:
    """Pairs of edits, jointly and one after the other (gauss_newton)."""
    from sketchforge_isophote_tool.corpus import corpus_layers, draw_pairs, run_pair

    for _, i, mesh, _rng in corpus_layers((shape,), per_shape=layers, seed=seed):
        for el in PAIR_ELEVATIONS:
            light = _light(el)
            sub = np.random.default_rng([seed, int(el), i, len(shape), 2])
            got = [run_pair(mesh, light, pair) for pair in draw_pairs(shape, mesh, sub, light, pairs)]
            queue.put(("edits", f"pairs at {el:g}°", shape, got, None, None))
    queue.put(("done", None, shape, None, None, None))


def _null_stroke(mesh, rng, light):
    """A pick on a lit vertex well inside, and the isophote through it as the stroke."""
    import shapely
    import shapely.ops

    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.isophote import picked_isophote
    from sketchforge_isophote_tool.layerdata import layer_data

    ld = layer_data(mesh, light, LAMBERTIAN)
    inner = ld.planar.d_rim > 0.4 * ld.planar.d_rim.max()
    cand = np.nonzero(inner & (ld.E > 0.1) & (ld.E < 0.9))[0]
    if not len(cand):
        return None
    pick = ld.V2[int(rng.choice(cand))]
    _, iso = picked_isophote(ld, pick)
    s0 = iso.project(shapely.Point(pick))
    band = float(np.clip(ld.planar.d_rim.max() / 1.5, 3 * ld.h, 0.3))
    seg = shapely.ops.substring(iso, max(s0 - band, 0.0), min(s0 + band, iso.length))
    return pick, band, np.asarray(seg.coords)


def _null_drift(mesh, rng, light, solver):
    """Largest height change (fraction of the peak) of a stroke drawn on the isophote; 0 when
    the edit reports there is nothing to change."""
    from sketchforge.errors import SketchforgeError
    from sketchforge_isophote_tool.pipeline import sculpt

    drawn = _null_stroke(mesh, rng, light)
    if drawn is None:
        return None
    pick, band, stroke = drawn
    try:
        r = sculpt(mesh, light, pick, band, stroke, solver=solver)
    except SketchforgeError:
        return 0.0
    return float(np.abs(r.mesh.V[:, 2] - mesh.V[:, 2]).max() / mesh.V[:, 2].max())


def _crease(mesh, light) -> float:
    """The largest jump of shading across an interior edge: a seam an edit left shows here (the
    strip pipeline's null drift came from those: 1.27 after 6 edits against 0.12 fresh)."""
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.layerdata import layer_data

    ld = layer_data(mesh, light, LAMBERTIAN)
    F = mesh.F
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    inner = ~(ld.planar.is_contour[e[:, 0]] | ld.planar.is_contour[e[:, 1]])
    return float(np.abs(ld.E[e[inner, 0]] - ld.E[e[inner, 1]]).max())


def _accumulated_drift(shape, mesh, rng, light, solver):
    """A chain of 10 accepted random edits on one layer: the null drift after it, the chain
    measures (:func:`~sketchforge_isophote_tool.corpus.chain_measures`) and the largest height
    change of each edit (fraction of the peak); None if 10 edits were not accepted in 60 tries."""
    from sketchforge.errors import SketchforgeError
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.corpus import chain_measures, random_edit
    from sketchforge_isophote_tool.layerdata import layer_data
    from sketchforge_isophote_tool.pipeline import sculpt

    fresh = mesh
    done = tries = 0
    largest = []
    while done < 10 and tries < 60:
        tries += 1
        e = random_edit(shape, layer_data(mesh, light, LAMBERTIAN), rng, kind="shift")
        if e is None:
            continue
        try:
            new = sculpt(mesh, light, e.pick, e.band, e.stroke, solver=solver, reference=fresh).mesh
        except SketchforgeError:
            continue
        largest.append(float(np.abs(new.V[:, 2] - mesh.V[:, 2]).max() / mesh.V[:, 2].max()))
        mesh = new
        done += 1
    if done < 10:
        return None
    return {"null": _null_drift(mesh, rng, light, solver), **chain_measures(fresh, mesh, light), "largest": max(largest)}


def _pct(a, q):
    return float(np.percentile(a, q)) if len(a) else float("nan")


def report(name: str, outcomes, nulls, accum, crashed, first=()) -> None:
    from sketchforge_isophote_tool.corpus import SHAPES, refusal_reason

    n = len(outcomes)
    ok = [o for o in outcomes if o.status == "ok"]
    refused = [o for o in outcomes if o.status == "refused"]
    crashes = [o for o in outcomes if o.status == "crash"]
    invalid = {"stroke outside the band", "stroke in the rim margin"}
    valid = [o for o in outcomes if not (o.status == "refused" and refusal_reason(o.reason) in invalid)]
    landed = [o for o in outcomes if o.lands]
    worse = [o for o in ok if o.after > max(o.before, 0.25)]
    after = np.array([o.after for o in ok])
    ratio = np.array([o.after / o.before for o in ok if o.before > 0])
    times = np.array([o.seconds for o in outcomes if o.status != "crash"])
    print(f"\n== {name} ==")
    print(f"crashes: {len(crashes)}" + (f"  (processes died: {crashed})" if crashed else ""))
    print(f"refusals: {len(refused)}")
    for reason, k in Counter(refusal_reason(o.reason) for o in refused).most_common():
        print(f"  {k:4d}  {reason}")
    print(f"applied: {len(ok)}/{n} = {len(ok) / max(n, 1):.1%}")
    print(f"lands (after <= max(2h, 0.3 before)): {len(landed)}/{len(ok)} applied = {len(landed) / max(len(ok), 1):.1%}; "
          f"{len(landed)}/{len(valid)} valid = {len(landed) / max(len(valid), 1):.1%}")
    moved = [o for o in outcomes if o.moved]
    print(f"moved (lands, and the isophote beside the stroke too): {len(moved)}/{len(ok)} applied = {len(moved) / max(len(ok), 1):.1%}")
    if len(after):
        print(f"fidelity after (edge lengths): median {np.median(after):.2f}, p95 {_pct(after, 95):.2f}, max {after.max():.2f};"
              f" after/before median {np.median(ratio):.2f}, p95 {_pct(ratio, 95):.2f}")
    print(f"partial edits (the full change overshot): {sum(o.fraction < 1 for o in ok)}")
    print(f"worse than before: {len(worse)}")
    if ok:
        mdz = np.array([o.max_dz for o in ok])
        ch = np.array([o.changed for o in ok])
        reach = np.array([o.reach for o in ok])
        print(f"largest height change per edit (fraction of the peak): median {np.median(mdz):.1%}, "
              f"p95 {_pct(mdz, 95):.1%}, max {mdz.max():.1%}")
        print(f"locality: vertices moved {np.median(ch):.1%} of the layer median, p95 {_pct(ch, 95):.1%}; farthest moved "
              f"vertex from the stroke {np.median(reach):.1f}h median, p95 {_pct(reach, 95):.1f}h")
    for shape in SHAPES:
        s_all = [o for o in outcomes if o.shape == shape]
        s_ok = [o for o in s_all if o.status == "ok"]
        a = np.array([o.after for o in s_ok]) if s_ok else np.array([np.nan])
        print(f"  {shape:8s} applied {len(s_ok):3d}/{len(s_all)}  lands {sum(o.lands for o in s_all):3d}  "
              f"after median {np.nanmedian(a):.2f}h p95 {np.nanpercentile(a, 95):.2f}h")
    if nulls:
        nd = np.array(nulls)
        print(f"null drift, fresh layers (max |dz| / peak): median {np.median(nd):.3%}, p95 {_pct(nd, 95):.3%}, "
              f"max {nd.max():.3%} ({len(nd)} layers)")
    if accum:
        ad = np.array([a["null"] for a in accum])
        di = np.array([a["dihedral"] / a["dihedral_fresh"] for a in accum])
        ju = np.array([a["jump"] / a["jump_fresh"] for a in accum])
        folds = np.array([a["folds"] for a in accum])
        print(f"chains of 10 edits ({len(accum)} layers): null drift after, median {np.median(ad):.3%}, max {ad.max():.3%}")
        print(f"  largest dihedral angle across an interior edge, x fresh: median {np.median(di):.2f}x, max {di.max():.2f}x "
              f"(fresh median {np.median([a['dihedral_fresh'] for a in accum]):.1f} deg); over 2.5x: {(di > 2.5).sum()}")
        print(f"  largest shading jump across an interior edge, x fresh: median {np.median(ju):.2f}x, max {ju.max():.2f}x; "
              f"over 2.5x: {(ju > 2.5).sum()}")
        print(f"  new folded triangles near the rim: {int(folds.sum())} in {(folds > 0).sum()} of {len(folds)} chains; "
              f"largest height change of a chain's edit: max {max(a['largest'] for a in accum):.0%}")
        for a, d, j in zip(accum, di, ju):
            if d > 2.5 or j > 2.5 or a["folds"]:
                print(f"    over a target: {a['shape']} layer {a['layer']}: dihedral {d:.2f}x, shading jump {j:.2f}x, "
                      f"folds {a['folds']}")
    if ok:
        bounded = [o for o in ok if o.bounded > 0]
        print(f"edits scaled down to 60% of the peak: {len(bounded)}" + (
            f" (their full change: max {max(o.bounded for o in bounded):.0%})" if bounded else ""))
    if len(times):
        cpu = np.array([o.cpu for o in outcomes if o.status != "crash"])
        print(f"time per edit (wall): p50 {1e3 * np.median(times):.0f} ms, p95 {1e3 * _pct(times, 95):.0f} ms, "
              f"max {1e3 * times.max():.0f} ms; "
              f"CPU per edit, mean {1e3 * np.nanmean(cpu):.0f} ms (fresh processes, compilation included)")
    if first:
        print(f"first edit of each process (compiling): {', '.join(f'{1e3 * t:.0f}' for t in first)} ms")


def _run(worker, names, layers: int, per_layer: int, seed: int, missing_outcome):
    """Run ``worker(shape, layers, per_layer, seed, queue)`` for each shape kind in its own
    child process (it reports one batch of ``per_layer`` outcomes per layer and name); collect
    the outcomes by name, and the wall time of each process's first edit by name. A child that
    dies (a native crash) is counted: ``missing_outcome(shape, exitcode)`` stands for each of
    its edits that never reported."""
    from sketchforge_isophote_tool.corpus import SHAPES

    ctx = mp.get_context("fork")
    outcomes: dict = {s: [] for s in names}
    nulls: dict = {s: [] for s in names}
    accum: dict = {s: [] for s in names}
    first: dict = {s: [] for s in names}
    crashed = []
    for shape in SHAPES:
        q = ctx.Queue()
        p = ctx.Process(target=worker, args=(shape, layers, per_layer, seed, q))
        p.start()
        got = {s: 0 for s in names}
        finished = False
        while not finished:
            try:
                kind, name, _, outs, null, acc = q.get(timeout=5)
            except Exception:  # noqa: BLE001  (queue.Empty: is the child still alive?)
                if not p.is_alive():
                    break
                continue
            if kind == "done":
                finished = True
                continue
            if got[name] == 0 and outs:  # the first edit of the process (of a pair: the joint edit)
                first[name].append((outs[0][0] if isinstance(outs[0], tuple) else outs[0]).seconds)
            got[name] += 1
            outcomes[name].extend(outs)
            if null is not None:
                nulls[name].append(null)
            if acc is not None:
                accum[name].append(acc)
        p.join()
        if p.exitcode != 0:
            crashed.append((shape, p.exitcode))
            for name in names:
                outcomes[name].extend(missing_outcome(shape, p.exitcode) for _ in range((layers - got[name]) * per_layer))
    return outcomes, nulls, accum, crashed, first


def _crashed_edit(shape, code):
    from sketchforge_isophote_tool.corpus import Outcome

    return Outcome(shape, "?", np.nan, "crash", f"process died ({code})", *[np.nan] * 3, 0.0, 0)


def _crashed_pair(shape, code):
    from sketchforge_isophote_tool.corpus import PairOutcome

    nan2 = np.full(2, np.nan)
    out = PairOutcome(shape, "crash", f"process died ({code})", nan2, nan2, nan2, 0.0)
    return (out, out)


def report_elevations(outcomes: dict, nulls: dict, crashed) -> None:
    from sketchforge_isophote_tool.corpus import refusal_reason

    invalid = {"stroke outside the band", "stroke in the rim margin"}
    print("\n== gauss_newton under raised lights (azimuth 45°) ==")
    print("elevation | valid edits | land (of valid) | worse | crashes | after median / p95 (h) | refused unreachable | "
          "null drift max | time p50 / p95")
    for name, outs in outcomes.items():
        ok = [o for o in outs if o.status == "ok"]
        valid = [o for o in outs if not (o.status == "refused" and refusal_reason(o.reason) in invalid)]
        lands = sum(o.lands for o in outs)
        worse = sum(o.after > max(o.before, 0.25) for o in ok)
        after = np.array([o.after for o in ok])
        unreachable = sum(o.status == "refused" and refusal_reason(o.reason) == "no closer isophote reachable" for o in outs)
        times = np.array([o.seconds for o in outs if o.status != "crash"])
        nd = np.array(nulls.get(name, []) or [np.nan])
        print(f"{name:>15} | {len(valid):4d} | {lands:4d} = {lands / max(len(valid), 1):.1%} | {worse} | "
              f"{sum(o.status == 'crash' for o in outs)} | {np.median(after):.2f} / {_pct(after, 95):.2f} | {unreachable} | "
              f"{np.nanmax(nd):.3%} | {1e3 * np.median(times):.0f} / {1e3 * _pct(times, 95):.0f} ms")
    for name, outs in outcomes.items():
        report(f"gauss_newton, {name}", outs, nulls.get(name, []), [], crashed)


def report_pairs(outcomes: dict, crashed) -> None:
    from sketchforge_isophote_tool.corpus import refusal_reason

    print("\n== pairs of isophotes: jointly (sculpt_isophotes) against one after the other ==")
    if crashed:
        print(f"processes died: {crashed}")
    for name, got in outcomes.items():
        joint = [j for j, _ in got]
        seq = [s for _, s in got]
        # A pair is valid when each of its strokes is one a single edit takes (a part inside its
        # band, outside the rim margin); refusals for those reasons are the corpus', not the edit's.
        invalid = {"stroke outside the band", "stroke in the rim margin"}
        valid = [k for k, j in enumerate(joint)
                 if not (j.status == "refused" and refusal_reason(re.sub(r"^stroke \d+: ", "", j.reason)) in invalid)]
        print(f"\n-- {name}: {len(got)} pairs drawn, {len(valid)} valid --")
        for label, outs in (("joint", joint), ("one after the other", seq)):
            v = [outs[k] for k in valid]
            both = sum(o.both_land for o in v)
            worse = sum(o.worse for o in v)
            ok = [o for o in v if o.status == "ok"]
            a1 = np.array([o.after[0] for o in ok])
            a2 = np.array([o.after[1] for o in ok])
            t = np.array([o.seconds for o in v if o.status != "crash"])
            print(f"{label:>20}: both land {both}/{len(v)} = {both / max(len(v), 1):.1%}; one ends worse: {worse}; "
                  f"crashes {sum(o.status == 'crash' for o in v)}; refused {sum(o.status == 'refused' for o in v)}; "
                  f"stroke 1 after median {np.median(a1):.2f}h p95 {_pct(a1, 95):.2f}h, stroke 2 median {np.median(a2):.2f}h "
                  f"p95 {_pct(a2, 95):.2f}h; time p50 {1e3 * np.median(t):.0f} ms, p95 {1e3 * _pct(t, 95):.0f} ms (both edits)")
        v = [joint[k] for k in valid]
        fr = Counter(tuple(float(f) for f in o.fractions) for o in v if o.status == "ok")
        print(f"{'':>20}  joint fallbacks (share of each stroke's change kept): "
              + ", ".join(f"{k}: {n}" for k, n in sorted(fr.items(), reverse=True)))
        reasons = Counter(o.reason.split(":")[0][:60] for o in v if o.status == "refused")
        if reasons:
            print(f"{'':>20}  joint refusals: " + "; ".join(f"{n}x {r}" for r, n in reasons.most_common()))


def main(layers: int = 10, edits: int = 8, seed: int = SEED, parts=PARTS, pairs: int = 3) -> None:
    from sketchforge_isophote_tool.corpus import SHAPES

    t0 = time.perf_counter()
    c0 = time.process_time()
    if "solvers" in parts:
        outcomes, nulls, accum, crashed, first = _run(_shape_worker, SOLVERS, layers, edits, seed, _crashed_edit)
        verts = np.array([o.vertices for o in outcomes[SOLVERS[0]] if o.vertices])
        print(f"corpus: {len(SHAPES)} shape kinds x {layers} layers x {edits} edits = {len(outcomes[SOLVERS[0]])} edits per solver, "
              f"seed {seed} ({verts.min()}-{verts.max()} vertices, median {int(np.median(verts))}); {time.perf_counter() - t0:.0f} s")
        means = {}
        for name in SOLVERS:
            report(name, outcomes[name], nulls[name], accum[name], crashed, first[name])
            means[name] = float(np.nanmean([o.cpu for o in outcomes[name] if o.status != "crash"]))
        print(f"\nmean CPU time per edit in fresh processes, strips / gauss_newton: "
              f"{means['strips'] / means['gauss_newton']:.2f}x (target <= 3x); load {os.getloadavg()[0]:.1f}")
    if "elevations" in parts:
        names = [f"elevation {el:g}" for el in ELEVATIONS]
        outcomes, nulls, _, crashed, _ = _run(_elevation_worker, names, layers, edits, seed, _crashed_edit)
        report_elevations(outcomes, nulls, crashed)
    if "pairs" in parts:
        names = [f"pairs at {el:g}°" for el in PAIR_ELEVATIONS]
        outcomes, _, _, crashed, _ = _run(_pairs_worker, names, layers, pairs, seed, _crashed_pair)
        report_pairs(outcomes, crashed)
    print(f"\n{time.perf_counter() - t0:.0f} s wall, {time.process_time() - c0:.0f} s CPU in this process (children apart)")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("layers", type=int, nargs="?", default=10)
    ap.add_argument("edits", type=int, nargs="?", default=8)
    ap.add_argument("seed", type=int, nargs="?", default=SEED)
    ap.add_argument("--parts", default=",".join(PARTS), help="which parts to run: " + ", ".join(PARTS))
    ap.add_argument("--pairs", type=int, default=3, help="pairs of edits per layer and light")
    a = ap.parse_args()
    main(a.layers, a.edits, a.seed, tuple(a.parts.split(",")), a.pairs)
