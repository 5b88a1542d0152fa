"""Run mypy on sketchforge/ and plugins/ (pyproject's [tool.mypy]) and hold every module to its
error count in mypy-baseline.json: the count may only go down.

    python tools/check_types.py            # check (make lint runs this; CI too)
    python tools/check_types.py --update   # rewrite the baseline from this run

Fails (exit 1) when a module has more errors than its baseline, or a module that is not in the
baseline has any; prints mypy's lines for those modules. A module whose count dropped passes,
with a hint to lower the baseline (``--update``), so that the gain is kept.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASELINE = ROOT / "mypy-baseline.json"
ERROR = re.compile(r"^(?P<path>[^:\s]+\.py):\d+(?::\d+)?: error: ")


def run_mypy() -> tuple[list[str], int]:
    """mypy's output lines (configuration from pyproject.toml) and its exit status."""
    proc = subprocess.run([sys.executable, "-m", "mypy", "--no-error-summary", "--no-pretty"], cwd=ROOT,
                          capture_output=True, text=True)
    return (proc.stdout + proc.stderr).splitlines(), proc.returncode


def count_errors(lines: list[str]) -> Counter:
    """{module path: number of errors} of mypy's output lines."""
    return Counter(m["path"] for m in map(ERROR.match, lines) if m)


def compare(counts: Counter, baseline: dict[str, int]) -> tuple[list[str], list[str]]:
    """(worse, better): lines for the modules over their baseline (or absent from it with
    errors), and for those under it."""
    worse = [f"{path}: {n} errors (baseline {baseline.get(path, 0)})"
             for path, n in sorted(counts.items()) if n > baseline.get(path, 0)]
    better = [f"{path}: {counts.get(path, 0)} errors (baseline {n})"
              for path, n in sorted(baseline.items()) if counts.get(path, 0) < n]
    return worse, better


def main(argv: list[str]) -> int:
    lines, status = run_mypy()
    counts = count_errors(lines)
    if status not in (0, 1) or (status == 1 and not counts):
        print("\n".join(lines))
        print(f"check_types: mypy itself failed (exit {status})")
        return 2
    if "--update" in argv:
        BASELINE.write_text(json.dumps(dict(sorted(counts.items())), indent=1) + "\n")
        print(f"check_types: baseline written: {sum(counts.values())} errors in {len(counts)} modules")
        return 0
    baseline = json.loads(BASELINE.read_text()) if BASELINE.exists() else {}
    worse, better = compare(counts, baseline)
    if worse:
        bad = {w.split(":")[0] for w in worse}
        print("\n".join(line for line in lines if (m := ERROR.match(line)) and m["path"] in bad))
        print("check_types: more mypy errors than mypy-baseline.json allows:\n  " + "\n  ".join(worse))
        print("fix them (the baseline only goes down)")
        return 1
    if better:
        print("check_types: fewer errors than the baseline, lower it with "
              "`.venv/bin/python tools/check_types.py --update`:\n  " + "\n  ".join(better))
    print(f"check_types: {sum(counts.values())} mypy errors in {len(counts)} modules, none over the baseline")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
