"""The pre-solve flush (``Autosaver.begin_solve``) on examples/creature.json.

Run: .venv/bin/python benchmarks/bench_autosave.py
Prints figures only (no assertions): medians of REPEAT runs of ``begin_solve`` when the document
changed since its last autosave (the whole document is written and fsynced, then the record)
and when it did not (only the small pending record). docs/reliability.md quotes them.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import sketchforge_inflate.plugin as inflate
from sketchforge.document import commands as C
from sketchforge.document import fileformat as ff
from sketchforge.document.autosave import Autosaver
from sketchforge.plugins.testing import make_test_host

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "creature.json"
REPEAT = 9


def timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main() -> None:
    doc = ff.load(EXAMPLE, host=make_test_host(inflate))
    layer = doc.layer_ids()[0]
    cmd = C.SetContour(layer=layer, points=[[0, 0], [1, 0], [0, 1]])
    full, small = [], []
    with tempfile.TemporaryDirectory() as tmp:
        saver = Autosaver(doc, interval_s=3600, folder=Path(tmp))
        for i in range(REPEAT):
            doc.execute({"command": "rename_layer", "layer": layer, "name": f"changed {i}"})
            tokens = []
            full.append(timed(lambda: tokens.append(saver.begin_solve(cmd))))  # changed: everything  # noqa: B023 - called in this iteration
            saver.end_solve(tokens.pop())
            small.append(timed(lambda: tokens.append(saver.begin_solve(cmd))))  # unchanged: the record  # noqa: B023 - called in this iteration
            record = saver.pending_path.stat().st_size
            saver.end_solve(tokens.pop())
        size = saver.path.stat().st_size
    print(
        f"pre-solve flush of {EXAMPLE.name} ({len(doc.layers)} layers, autosave {size} bytes, record {record} bytes): "
        f"whole document {1e3 * statistics.median(full):.1f} ms, pending record only "
        f"{1e3 * statistics.median(small):.1f} ms (medians of {REPEAT})"
    )


if __name__ == "__main__":
    main()
