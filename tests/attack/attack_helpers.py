"""The attack corpus of issue 14: every input class that once produced a traceback, a hang, a
clobbered file or lost work, run through the real CLI entry point (in-process unless the case
needs a real terminal, a signal or a second process). Each case asserts what the user sees:
exit status 2 and exactly one ``sketchforge: error: ...`` line, or the correct result."""

from __future__ import annotations

import io
import json
import os
import resource
import sys
import time
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))

#: The issue's bounds on any single bad input.
MAX_SECONDS = 60.0
MAX_RSS_GROWTH = 2 << 30


@dataclass
class Result:
    rc: int
    out: str
    err: str
    seconds: float


def run_cli(*argv) -> Result:
    """``sketchforge ARGV`` in this process: exit status, stdout, stderr, seconds. Any exception
    escaping ``main`` (a traceback for the user) fails the test by propagating."""
    from sketchforge.cli import main

    out, err = io.StringIO(), io.StringIO()
    t = time.perf_counter()
    with redirect_stdout(out), redirect_stderr(err):
        try:
            rc = main([str(a) for a in argv])
        except SystemExit as exc:  # argparse's own usage errors
            rc = exc.code
    return Result(rc, out.getvalue(), err.getvalue(), time.perf_counter() - t)


def assert_one_line_error(res: Result, *fragments: str) -> str:
    """Exit 2, one stderr line that starts with the program's prefix and contains every
    fragment, nothing on stdout, within the time bound."""
    assert res.rc == 2, (res.rc, res.err[-2000:])
    lines = res.err.splitlines()
    assert len(lines) == 1, res.err[-2000:]
    assert lines[0].startswith("sketchforge: error: "), lines[0]
    for f in fragments:
        assert f in lines[0], (f, lines[0])
    assert res.out == ""
    assert res.seconds < MAX_SECONDS
    return lines[0]


def peak_rss_bytes() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


SQUARE = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]

#: A small real document: one square layer, coarse enough to inflate in well under a second.
SMALL_DOC = {
    "format": "sketchforge",
    "version": 1,
    "light": [1.0, 0.0, 0.0],
    "journal": [
        {"command": "add_layer", "id": "a", "name": "A"},
        {"command": "set_contour", "layer": "a", "points": SQUARE, "closed": True},
        {"command": "set_inflate_params", "layer": "a", "params": {"resolution": 0.1}},
    ],
}


def write_doc(path: Path, data) -> Path:
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    return path




def refuse_new_files(monkeypatch) -> None:
    """Make creating any file fail with EACCES in sketchforge.atomic (simulated: tests run as
    root, who may write anywhere)."""
    import sketchforge.atomic as atomic

    real_open = os.open

    def refuse(path, flags, *a, **k):
        if flags & os.O_CREAT:
            raise PermissionError(13, "Permission denied", str(path))
        return real_open(path, flags, *a, **k)

    monkeypatch.setattr(atomic.os, "open", refuse)
