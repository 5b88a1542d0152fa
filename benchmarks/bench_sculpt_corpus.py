"""The isophote edit on a randomized corpus nobody here drew (issue 16, point 7).

Run: ``.venv/bin/python benchmarks/bench_sculpt_corpus.py [layers_per_shape] [edits_per_layer]``
(default 10 and 8: 320 edits on 40 layers). Shapes and edits: see
``sketchforge_isophote_tool.corpus`` (random blobs, stars, thin limbs 0.2–0.3 wide, letter
shapes; strokes = the isophote shifted or bumped by 1–5 edge lengths, with a small loop, or
partly outside the band). Fixed seeds: the same corpus on every run.

Each shape kind runs in its own child process, so a native crash (a segfault in a solver)
is counted instead of ending the benchmark. Prints:

- crashes (must be 0), refusals by reason, success rate;
- fidelity: the mean distance from the stroke to the new isophote, in edge lengths (median,
  p95) and against the distance before (after/before, median); edits that land (after ≤
  max(2, 0.3·before) edge lengths), over valid edits (the stroke has a part inside the band
  and outside the rim margin) and over all;
- edits that ended farther from the stroke than they started (must be 0);
- null drift: a stroke drawn on the isophote itself, on every fresh layer, and after 10 edits;
- the largest height change of each edit (fraction of the peak): median, p95, max;
- warm time per edit, p50 / p95, and the layers' vertex counts.
"""

from __future__ import annotations

import multiprocessing as mp
import sys
import time
from collections import Counter

import numpy as np

SEED = 2026


def _shape_worker(shape: str, layers: int, edits: int, queue) -> None:
    from sketchforge_isophote_tool.corpus import corpus_layers, run_edits
    from sketchforge_isophote_tool.testing import LIGHT

    for _, i, mesh, rng in corpus_layers((shape,), per_shape=layers, seed=SEED):
        outcomes = run_edits(shape, mesh, rng, LIGHT, edits)
        queue.put(("edits", shape, i, outcomes, _null_drift(mesh, rng, LIGHT), _accumulated_drift(shape, mesh, rng, LIGHT) if i < 3 else None))
    queue.put(("done", shape, None, None, None, None))


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


def _null_drift(mesh, rng, light):
    """Largest height change (fraction of the peak) of a stroke drawn on the isophote; 0 when
    the edit reports there is nothing to change."""
    from sketchforge.errors import SketchforgeError
    from sketchforge_isophote_tool.pipeline import sculpt

    drawn = _null_stroke(mesh, rng, light)
    if drawn is None:
        return None
    pick, band, stroke = drawn
    try:
        r = sculpt(mesh, light, pick, band, stroke)
    except SketchforgeError:
        return 0.0
    return float(np.abs(r.mesh.V[:, 2] - mesh.V[:, 2]).max() / mesh.V[:, 2].max())


def _accumulated_drift(shape, mesh, rng, light):
    """Null drift after 10 accepted random edits on the same layer."""
    from sketchforge.errors import SketchforgeError
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.corpus import random_edit
    from sketchforge_isophote_tool.layerdata import layer_data
    from sketchforge_isophote_tool.pipeline import sculpt

    done = tries = 0
    while done < 10 and tries < 60:
        tries += 1
        e = random_edit(shape, layer_data(mesh, light, LAMBERTIAN), rng, kind="shift")
        if e is None:
            continue
        try:
            mesh = sculpt(mesh, light, e.pick, e.band, e.stroke).mesh
            done += 1
        except SketchforgeError:
            continue
    return _null_drift(mesh, rng, light) if done == 10 else None


def main(layers: int = 10, edits: int = 8) -> None:
    from sketchforge_isophote_tool.corpus import SHAPES, Outcome, refusal_reason

    t0 = time.perf_counter()
    ctx = mp.get_context("fork")
    outcomes: list[Outcome] = []
    nulls, accum, crashed_shapes = [], [], []
    for shape in SHAPES:
        q = ctx.Queue()
        p = ctx.Process(target=_shape_worker, args=(shape, layers, edits, q))
        p.start()
        got_layers, finished = 0, False
        while not finished:
            try:
                kind, _, _, outs, null, acc = q.get(timeout=5)
            except Exception:  # noqa: BLE001  (queue.Empty: is the child still alive?)
                if not p.is_alive():
                    break
                continue
            if kind == "done":
                finished = True
                continue
            got_layers += 1
            outcomes.extend(outs)
            if null is not None:
                nulls.append(null)
            if acc is not None:
                accum.append(acc)
        p.join()
        if p.exitcode != 0:
            crashed_shapes.append((shape, p.exitcode))
            missing = (layers - got_layers) * edits
            outcomes.extend(Outcome(shape, "?", np.nan, "crash", f"process died ({p.exitcode})", *[np.nan] * 3, 0.0, 0) for _ in range(missing))

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
    verts = np.array([o.vertices for o in outcomes if o.vertices])

    print(f"corpus: {len(SHAPES)} shape kinds x {layers} layers x {edits} edits = {n} edits, seed {SEED} "
          f"({verts.min()}-{verts.max()} vertices, median {int(np.median(verts))}); {time.perf_counter() - t0:.0f} s")
    print(f"crashes: {len(crashes)}" + (f"  (processes died: {crashed_shapes})" if crashed_shapes else ""))
    print(f"refusals: {len(refused)}")
    for reason, k in Counter(refusal_reason(o.reason) for o in refused).most_common():
        print(f"  {k:4d}  {reason}")
    print(f"success (applied): {len(ok)}/{n} = {len(ok) / n:.1%}")
    print(f"lands (after <= max(2h, 0.3 before)): {len(landed)}/{len(valid)} valid edits = {len(landed) / max(len(valid), 1):.1%};"
          f" {len(landed)}/{n} of all = {len(landed) / n:.1%}")
    moved = [o for o in outcomes if o.moved]
    print(f"moved (lands, and the isophote beside the stroke is within the same bound): {len(moved)}/{len(valid)} valid edits = {len(moved) / max(len(valid), 1):.1%}")
    print(f"fidelity after (edge lengths): median {np.median(after):.2f}, p95 {np.percentile(after, 95):.2f}, max {after.max():.2f};"
          f" after/before median {np.median(ratio):.2f}, p95 {np.percentile(ratio, 95):.2f}")
    print(f"partial edits (the full change overshot): {sum(o.fraction < 1 for o in ok)}")
    mdz = np.array([o.max_dz for o in ok])
    print(f"largest height change per edit (fraction of the peak): median {np.median(mdz):.1%}, p95 {np.percentile(mdz, 95):.1%}, max {mdz.max():.1%}")
    print(f"worse than before: {len(worse)}")
    print("by shape:")
    for shape in SHAPES:
        s_all = [o for o in outcomes if o.shape == shape]
        s_ok = [o for o in s_all if o.status == "ok"]
        a = np.array([o.after for o in s_ok]) if s_ok else np.array([np.nan])
        print(f"  {shape:8s} applied {len(s_ok):3d}/{len(s_all)}  lands {sum(o.lands for o in s_all):3d}  after median {np.nanmedian(a):.2f}h p95 {np.nanpercentile(a, 95):.2f}h")
    print("by stroke kind:")
    for kind in sorted({o.kind for o in outcomes}):
        k_all = [o for o in outcomes if o.kind == kind]
        print(f"  {kind:8s} applied {sum(o.status == 'ok' for o in k_all):3d}/{len(k_all)}  lands {sum(o.lands for o in k_all):3d}")
    if nulls:
        nd = np.array(nulls)
        print(f"null drift on fresh layers (max |dz| / peak): median {np.median(nd):.3%}, p95 {np.percentile(nd, 95):.3%}, max {nd.max():.3%} ({len(nd)} layers)")
    if accum:
        ad = np.array(accum)
        print(f"null drift after 10 edits: median {np.median(ad):.3%}, max {ad.max():.3%} ({len(ad)} layers)")
    print(f"time per edit: p50 {1e3 * np.median(times):.0f} ms, p95 {1e3 * np.percentile(times, 95):.0f} ms")


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:]))
