"""Figures for docs/reliability.md (issue 14): the costliest renders the raster cap lets
through, the attack inputs' time and memory, and the full 10,000-direction exact-replay loop.

Run: .venv/bin/python benchmarks/bench_reliability.py [--quick]
Prints figures only. Each render runs in a fresh subprocess so its peak memory (ru_maxrss) is
its own.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "creature.json"

CHILD = r"""
import resource, sys, time, io, contextlib
from sketchforge.cli import main
t = time.perf_counter()
err = io.StringIO()
with contextlib.redirect_stderr(err):
    rc = main(sys.argv[1:])
dt = time.perf_counter() - t
print(rc, f"{dt:.2f}", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024, err.getvalue().strip().splitlines()[-1][:110])
"""


def child(*argv):
    out = subprocess.run([sys.executable, "-c", CHILD, *map(str, argv)], capture_output=True, text=True, timeout=600)
    return out.stdout.strip() or out.stderr.strip()[-300:]


def overlapping_doc(path: Path, n: int) -> None:
    sys.path.insert(0, str(ROOT / "tests" / "attack"))
    from test_render_limits import _overlapping_triangles_doc

    path.write_text(json.dumps(_overlapping_triangles_doc(n)))


def exact_replay(n: int) -> tuple[int, float]:
    import numpy as np

    from sketchforge.document.commands import SetLight

    rng = np.random.default_rng(14)
    ang = rng.uniform(-math.pi, math.pi, n)
    r = 10.0 ** rng.uniform(-3, 3, n)
    bad = 0
    t = time.perf_counter()
    for a, b in zip(r * np.cos(ang), r * np.sin(ang)):
        cmd = SetLight.from_dict({"command": "set_light", "direction": [float(a), float(b), 0.0]})
        again = SetLight.from_dict(json.loads(json.dumps(cmd.to_dict())))
        bad += again._new != cmd._new
    return bad, time.perf_counter() - t


def save_load_replay_check(n: int) -> tuple[int, float]:
    """n directions, each through the whole path: a document with the light set, saved by the
    library, then ``replay --check`` in process."""
    import io
    from contextlib import redirect_stderr

    import numpy as np

    from sketchforge.cli import main
    from sketchforge.document import commands as C
    from sketchforge.document import fileformat as ff
    from sketchforge.document.document import Document
    from sketchforge.plugins.testing import FanInflater, make_test_host

    host = make_test_host(FanInflater())
    rng = np.random.default_rng(1414)
    bad = 0
    t = time.perf_counter()
    with tempfile.TemporaryDirectory() as d:
        for _ in range(n):
            doc = Document(host=host)
            a = rng.uniform(-math.pi, math.pi)
            doc.push(C.SetLight(direction=[math.cos(a) * 3.7, math.sin(a) * 3.7, 0.0]))
            p = Path(d) / "d.json"
            ff.save(doc, p)
            with redirect_stderr(io.StringIO()):
                bad += main(["replay", str(p), "--check"]) != 0
    return bad, time.perf_counter() - t


def main() -> None:
    quick = "--quick" in sys.argv
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        saved = d / "creature.json"
        subprocess.run([sys.executable, "-m", "sketchforge", "replay", EXAMPLE, "--save", saved], check=True, capture_output=True)
        print("render of examples/creature.json (rc, seconds, peak RSS MB, last line):")
        for size in ([512, 2048] if quick else [512, 1024, 2048, 3000, 3500, 4096, 8192]):
            print(f"  --size {size}: {child('render', saved, '--png', d / 'o.png', '--size', size)}")
        print("2000 overlapping snapshot triangles:")
        overlapping_doc(d / "over.json", 2000)
        print(f"  render: {child('render', d / 'over.json', '--png', d / 'o.png')}")
        print(f"  info /dev/zero: {child('info', '/dev/zero')}")
    n = 10_000
    bad, dt = exact_replay(n)
    print(f"exact replay, parse -> journal -> JSON -> parse: {n} directions, {bad} differ, {dt:.2f} s")
    m = 200 if quick else 10_000
    bad, dt = save_load_replay_check(m)
    print(f"save -> load -> replay --check: {m} directions, {bad} failures, {dt:.1f} s")


if __name__ == "__main__":
    main()
