"""Figures for docs/reliability.md (issue 38): time and peak memory of ``sketchforge info`` on
documents under the 512 MiB size cap that make a JSON parser build many objects (the memory
bombs), and on large legitimate documents near the cap.

Run: .venv/bin/python benchmarks/bench_parse_bounds.py [--quick] [--ceiling-mb 3500]
(``BENCH_SKETCHFORGE_FROM=/path/to/other/checkout`` times that checkout's core instead: the
figures before a change.) Prints figures only. The files are generated in a temporary folder and removed. Each run is a
fresh subprocess; its peak resident memory (VmHWM) is sampled every 20 ms, and a run that
passes the ceiling is killed (a 500 MB document of ``{},`` would otherwise take ~10 GB of a
shared machine): it is reported as "> ceiling".
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _write_repeated(path: Path, head: bytes, unit: bytes, last: bytes, tail: bytes, size: int) -> None:
    """``head + unit * k + last + tail`` of about ``size`` bytes, written in 8 MB blocks."""
    k = max(0, (size - len(head) - len(last) - len(tail)) // len(unit))
    block = unit * max(1, (8 << 20) // len(unit))
    per = (8 << 20) // len(unit)
    with open(path, "wb") as fh:
        fh.write(head)
        while k > 0:
            n = min(k, per)
            fh.write(block if n == per else unit * n)
            k -= n
        fh.write(last + tail)


def bomb_lists(path: Path, size: int) -> None:
    _write_repeated(path, b"[", b"[],", b"[]", b"]", size)


def bomb_dicts(path: Path, size: int) -> None:
    _write_repeated(path, b"[", b"{},", b"{}", b"]", size)


def bomb_journal_dicts(path: Path, size: int) -> None:
    """A document whose journal holds the bomb (the parser builds it before any field is read)."""
    _write_repeated(path, b'{"format":"sketchforge","version":1,"journal":[', b'{"a":0},', b'{"a":0}', b"]}", size)


def _pad_between(path: Path, head: bytes, tail: bytes, size: int) -> None:
    """Write ``head``, then ``x`` up to ``size`` bytes in all (8 MB at a time), then ``tail``."""
    with open(path, "wb") as fh:
        fh.write(head)
        left = size - len(head) - len(tail)
        block = b"x" * (8 << 20)
        while left > 0:
            fh.write(block[: min(left, len(block))])
            left -= len(block)
        fh.write(tail)


def wide_string(path: Path, size: int) -> None:
    """A name of ASCII with one emoji at its end: Python stores the whole text, and the parsed
    string, 4 bytes a character."""
    head = b'{"format":"sketchforge","version":1,"name":"'
    tail = "\U0001F600".encode() + b'"}'
    _pad_between(path, head, tail, size)


def worst_accepted(path: Path, size: int) -> None:
    """The costliest document the item limit lets through at ``size`` bytes: just under
    MAX_JSON_ITEMS of the dearest item per byte (``{"a":0}``, ~70 bytes of memory each) in
    the journal, the rest of the bytes one long string (a layer name)."""
    here = Path(__file__).resolve().parent.parent
    sys.path.insert(0, str(here))
    from sketchforge.document import fileformat as ff

    k = (ff.MAX_JSON_ITEMS - 100) // 3
    head = b'{"format":"sketchforge","version":1,"journal":[' + b'{"a":0},' * (k - 1) + b'{"a":0}],"name":"'
    tail = b'"}'
    _pad_between(path, head, tail, size)


def big_snapshot(path: Path, size: int) -> None:
    """A legitimate document near ``size`` bytes: one layer whose snapshot mesh is large (base64).
    The mesh is a flat strip of triangles; ``info`` decodes and validates it."""
    here = Path(__file__).resolve().parent.parent
    sys.path.insert(0, str(here))
    from sketchforge.document import fileformat as ff

    # bytes per vertex in base64: V 24 + ~2 faces * 24 -> ~96 base64 characters
    n = max(4, min(ff.MAX_SNAPSHOT_ELEMENTS // 2, size // 100))
    m = n // 2
    xs = np.arange(m, dtype=np.float64) * 1e-3
    V = np.zeros((2 * m, 3))
    V[:m, 0], V[m:, 0], V[m:, 1] = xs, xs, 1e-3
    i = np.arange(m - 1)
    F = np.concatenate([np.stack([i, i + 1, m + i], 1), np.stack([i + 1, m + i + 1, m + i], 1)]).astype(np.int64)
    boundary = np.concatenate([np.arange(m), np.arange(2 * m - 1, m - 1, -1)]).astype(np.int64)
    mesh = {k: ff.encode_array(a) for k, a in (("V", V), ("F", F), ("boundary", boundary), ("junction", np.zeros(0, np.int64)))}
    doc = {"format": "sketchforge", "version": 1, "journal": [],
           "snapshot": {"layers": [{"id": "a", "name": "a", "closed": True, "points": None, "mesh": mesh}]}}
    path.write_text(json.dumps(doc))


def big_stroke_journal(path: Path, size: int) -> None:
    """A legitimate journal of long strokes (set_contour entries of 20 000 points each, with
    their layers) of about ``size`` bytes: what a person drawing with a tablet for hours makes."""
    rng = np.random.default_rng(38)
    entries = []
    total = 0
    i = 0
    while total < size:
        t = np.linspace(0, 2 * np.pi, 20_000, endpoint=False)
        r = 1 + 0.05 * rng.random()
        pts = np.round(np.stack([r * np.cos(t), r * np.sin(t)], 1), 6).tolist()
        e = [{"command": "add_layer", "id": f"l{i}", "name": f"l{i}"}, {"command": "set_contour", "layer": f"l{i}", "points": pts}]
        total += len(json.dumps(e))
        entries += e
        i += 1
    path.write_text(json.dumps({"format": "sketchforge", "version": 1, "journal": entries}))


CHILD = r"""
import os, sys, time, io, contextlib
if os.environ.get("BENCH_SKETCHFORGE_FROM"):  # another checkout's core (the figures before a change)
    sys.meta_path = [f for f in sys.meta_path if getattr(f, "__module__", "") != "__editable___sketchforge_0_1_0_finder"]
    sys.path.insert(0, os.environ["BENCH_SKETCHFORGE_FROM"])
from sketchforge.cli import main
t = time.perf_counter()
err = io.StringIO()
with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
    rc = main(["info", sys.argv[1]])
print(rc, f"{time.perf_counter() - t:.1f}", (err.getvalue().strip().splitlines() or [""])[-1][:150])
"""


def _hwm_mb(pid: int) -> float:
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def run_info(path: Path, ceiling_mb: float, timeout_s: float = 600) -> tuple[str, float, float]:
    """(the child's last line or why it was stopped, wall seconds, peak MB)."""
    t = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-c", CHILD, str(path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    peak = 0.0
    why = None
    while p.poll() is None:
        peak = max(peak, _hwm_mb(p.pid))
        if peak > ceiling_mb:
            why = f"killed at the {ceiling_mb:.0f} MB ceiling"
        elif time.perf_counter() - t > timeout_s:
            why = f"killed after {timeout_s:.0f} s"
        if why:
            p.send_signal(signal.SIGKILL)
            p.wait()
            break
        time.sleep(0.02)
    dt = time.perf_counter() - t
    out, err = p.communicate()
    if why:
        return why, dt, peak
    return (out.strip() or err.strip()[-200:]), dt, peak


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="only the files of at most 60 MB")
    ap.add_argument("--ceiling-mb", type=float, default=3500.0)
    args = ap.parse_args()
    mb = 1 << 20
    cases = [
        ("[[],[],...] 10 MB", bomb_lists, 10 * mb),
        ("[[],[],...] 60 MB", bomb_lists, 60 * mb),
        ("[{},{},...] 500 MB", bomb_dicts, 500 * mb),
        ('journal of {"a":0} 200 MB', bomb_journal_dicts, 200 * mb),
        ("one emoji in a 128 MB name", wide_string, 128 * mb),
        ("one emoji in a 500 MB name", wide_string, 500 * mb),
        ("worst accepted: 8M items + a 490 MB string", worst_accepted, 512 * mb - 1),
        ("snapshot mesh 1M vertices (legitimate)", big_snapshot, 100 * mb),
        ("journal of 20k-point strokes, 40 MB (legitimate)", big_stroke_journal, 40 * mb),
    ]
    if args.quick:
        cases = [(n, f, s) for n, f, s in cases if s <= 60 * mb]
    print(f"load: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f} (1/5/15 min)")
    print(f"{'document':52s} {'size':>8s} {'wall s':>7s} {'peak MB':>8s}  result")
    with tempfile.TemporaryDirectory() as tmp:
        for name, make, size in cases:
            path = Path(tmp) / "doc.json"
            make(path, size)
            real = path.stat().st_size
            line, dt, peak = run_info(path, args.ceiling_mb)
            print(f"{name:52s} {real / mb:7.1f}M {dt:7.1f} {peak:8.0f}  {line}", flush=True)
            path.unlink()


if __name__ == "__main__":
    main()
