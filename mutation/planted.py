"""Planted bugs: how many realistic one-line bugs the tests of a module catch (issue 39).

mutmut (``mutation/run.py``) plants every mutation it can think of, most of them in code no
person would get wrong. This script plants the bugs people do write, one at a time, in a
seeded sample per module, and runs the tests that cover that module:

- ``sign``: ``a + b`` <-> ``a - b``, a unary minus dropped;
- ``compare``: ``<`` <-> ``<=``, ``>`` <-> ``>=``, ``==`` <-> ``!=``, ``in`` <-> ``not in``;
- ``off-by-one``: an integer literal one more or one less;
- ``dropped check``: the condition of an ``if`` that raises, returns or skips set to False;
- ``dropped call``: a statement that only calls something (a check, an update) removed;
- ``boolean``: ``and`` <-> ``or``, a ``not`` dropped, ``return True`` <-> ``return False``;
- ``swapped args``: the first two positional arguments of a call swapped.

Message texts (f-strings), docstrings and log calls are never touched. The sample is drawn
once from the code of one checkout (``--draw``) and kept in ``mutation/planted/sample.json``;
every later run (``--root`` any checkout: main before the tests, this branch after) plants the
same bugs by their text, so "before" and "after" measure the same bugs. A bug whose line is no
longer in the code is reported as not applicable.

Usage::

    python mutation/planted.py --draw --root /tmp/main-export --per-module 24
    python mutation/planted.py --root /tmp/main-export --label before
    python mutation/planted.py --root . --label after
    python mutation/planted.py --table before after

Each run copies the checkout's packages and tests to ``build/planted/<label>/`` (the copies come
first on PYTHONPATH, ahead of the editable installs), checks that the tests pass unchanged, then
runs them once per planted bug with ``-x``; a bug is caught when they fail (or pass their
timeout). Results go to ``mutation/planted/<label>.json``.
"""

from __future__ import annotations

import argparse
import ast
import fnmatch
import json
import os
import random
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "planted"

#: The packages a workspace holds (folder in the checkout -> import name).
PACKAGES = {
    "sketchforge": "sketchforge",
    "plugins/inflate/sketchforge_inflate": "sketchforge_inflate",
    "plugins/isophote_tool/sketchforge_isophote_tool": "sketchforge_isophote_tool",
    "plugins/assemble/sketchforge_assemble": "sketchforge_assemble",
    "plugins/animate/sketchforge_animate": "sketchforge_animate",
    "plugins/strips/sketchforge_strips": "sketchforge_strips",
}
COPIED = ["tests", "examples", "docs", "README.md", "Makefile", "pyproject.toml"]

# The modules of issue 39's table (the attachment row is left to issue 34, which rewrites it):
# the files planted in (``only``: just these functions and classes), and the tests that cover
# them. A test file missing from a checkout (one written later) is left out of its runs.
# (quick files first: ``-x`` stops at the first failure)
PLUGIN_TESTS = ["tests/test_plugin_contracts.py", "tests/test_solver_registries.py", "tests/test_plugins.py",
                "tests/test_plugin_platform.py", "tests/test_plugin_data_validation.py"]
MODULES: dict[str, dict] = {
    "solver registries": {"files": ["sketchforge/plugins/solvers.py"], "tests": PLUGIN_TESTS},
    "plugin manager": {"files": ["sketchforge/plugins/manager.py", "sketchforge/plugins/plugin_data.py"],
                       "tests": PLUGIN_TESTS},
    "contracts": {"files": ["sketchforge/plugins/contracts.py"], "tests": PLUGIN_TESTS},
    "provenance": {"files": ["sketchforge/document/provenance.py"],
                   "tests": ["tests/test_provenance.py", "tests/test_solver_registries.py",
                             "tests/test_plugin_platform.py"]},
    "transform/mirror commands": {
        "files": ["sketchforge/document/commands/transforms.py"],
        "only": ["_translated", "check_affine", "transform_points", "_transformed", "transformed_edits",
                 "compose_affine", "scale_about", "rotate_about", "TransformLayer", "TranslateLayer",
                 "MirrorLayer", "mirror_axis_x", "twin_source", "DuplicateLayer"],
        "tests": ["tests/test_transform_contracts.py", "tests/test_undo_memory.py", "tests/test_transform.py",
                  "tests/test_transform_edits.py", "tests/test_mirror_twin.py", "tests/test_command_roundtrip.py"]},
    "offload": {"files": ["sketchforge/offload.py"],
                "tests": ["tests/test_offload.py",
                          "tests/qt/test_qt_issue30.py::test_the_app_inflates_in_a_child_process_with_the_same_result",
                          "tests/qt/test_qt_issue30.py::test_a_host_with_another_inflater_inflates_here"]},
    "strips": {"files": ["plugins/strips/sketchforge_strips/*.py"],
               "tests": ["tests/test_strips_parts.py", "tests/test_strips_solver.py", "tests/test_strips_corpus.py"]},
    "animate state": {"files": ["plugins/animate/sketchforge_animate/state.py"],
                      "tests": ["tests/test_animate_oracle.py", "tests/test_animate.py",
                                "tests/test_plugin_data_validation.py"]},
}

#: Files split after the samples were drawn: a bug drawn in the old file is planted, by its text,
#: in the file its function moved to, at the same occurrence of that text there unless
#: MOVED_OCCURRENCE says otherwise (counted when commands.py was split: the add_layer check
#: with the same text stayed behind in layers.py). A checkout from before the split still has
#: the old file and plants there.
MOVED = {"sketchforge/document/commands.py": "sketchforge/document/commands/transforms.py"}
MOVED_OCCURRENCE = {"transform/mirror commands#10": 0}

_FLIP_CMP = {ast.Lt: ast.LtE, ast.LtE: ast.Lt, ast.Gt: ast.GtE, ast.GtE: ast.Gt, ast.Eq: ast.NotEq,
             ast.NotEq: ast.Eq, ast.In: ast.NotIn, ast.NotIn: ast.In, ast.Is: ast.IsNot, ast.IsNot: ast.Is}


# --- finding candidate bugs -------------------------------------------------------------------


def _line_starts(src: bytes) -> list[int]:
    starts = [0]
    for i, b in enumerate(src):
        if b == 0x0A:
            starts.append(i + 1)
    return starts


class _Finder(ast.NodeVisitor):
    """Every candidate bug of one file: (kind, start byte, end byte, replacement text)."""

    def __init__(self, src: bytes, only: list[str] | None) -> None:
        self.src = src
        self.starts = _line_starts(src)
        self.only = only
        self.found: list[tuple[str, int, int, str]] = []
        self._inside = only is None

    def span(self, node) -> tuple[int, int]:
        return (self.starts[node.lineno - 1] + node.col_offset, self.starts[node.end_lineno - 1] + node.end_col_offset)

    def text(self, node) -> str:
        a, b = self.span(node)
        return self.src[a:b].decode()

    def add(self, kind: str, node, new: str) -> None:
        a, b = self.span(node)
        if new != self.src[a:b].decode():
            self.found.append((kind, a, b, new))

    # scopes
    def _scoped(self, node) -> None:
        if self._inside or node.name not in (self.only or ()):
            self.generic_visit(node)
            return
        self._inside = True
        self.generic_visit(node)
        self._inside = False

    visit_FunctionDef = visit_AsyncFunctionDef = visit_ClassDef = _scoped

    # never inside message texts, docstrings or log calls
    def visit_JoinedStr(self, node) -> None:
        return

    def visit_Expr(self, node) -> None:
        if isinstance(node.value, ast.Constant):
            return  # a docstring
        if self._inside and isinstance(node.value, ast.Call) and not self._is_log(node.value):
            self.found.append(("dropped call", *self.span(node), "pass"))
        self.generic_visit(node)

    @staticmethod
    def _is_log(call) -> bool:
        f = call.func
        return isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) and f.value.id in ("log", "logging", "warnings")

    def visit_Call(self, node) -> None:
        if self._is_log(node):
            return
        if self._inside:
            pos = [a for a in node.args if not isinstance(a, ast.Starred)]
            if (len(pos) >= 2 and len(node.args) == len(pos) and self.text(pos[0]) != self.text(pos[1])
                    and not self._obvious_swap(node, pos)):
                a0, a1 = self.span(pos[0]), self.span(pos[1])
                s = self.src
                swapped = (s[a0[0]:a0[1]], s[a1[0]:a1[1]])
                start, end = self.span(node)
                new = s[start:a0[0]] + swapped[1] + s[a0[1]:a1[0]] + swapped[0] + s[a1[1]:end]
                self.found.append(("swapped args", start, end, new.decode()))
        self.generic_visit(node)

    @staticmethod
    def _obvious_swap(node, pos) -> bool:
        # Swaps nobody writes, or that fail on the first call whatever the input: the
        # arguments of builtins of different kinds (isinstance(int, v)), a text and a value.
        f = node.func
        if isinstance(f, ast.Name) and f.id in ("isinstance", "issubclass", "getattr", "setattr", "hasattr"):
            return True
        texts = [isinstance(a, ast.JoinedStr) or (isinstance(a, ast.Constant) and isinstance(a.value, str))
                 for a in pos[:2]]
        return texts[0] != texts[1]

    def visit_BinOp(self, node) -> None:
        if self._inside and isinstance(node.op, (ast.Add, ast.Sub)) and not self._string_op(node):
            self._replace_op(node, ast.Sub() if isinstance(node.op, ast.Add) else ast.Add(), "sign")
        self.generic_visit(node)

    def _string_op(self, node) -> bool:
        return any(isinstance(n, (ast.Constant, ast.JoinedStr)) and isinstance(getattr(n, "value", None), str)
                   or isinstance(n, ast.JoinedStr) for n in (node.left, node.right))

    def _replace_op(self, node, op, kind: str) -> None:
        # Only the operator changes: the text between the operands is rewritten, the rest kept.
        (_, a1), (b0, _) = self.span(node.left), self.span(node.right)
        start, end = self.span(node)
        middle = self.src[a1:b0].decode()
        sym = {ast.Add: "+", ast.Sub: "-"}
        old = sym[type(node.op)]
        if middle.count(old) != 1:
            return
        new = self.src[start:a1].decode() + middle.replace(old, sym[type(op)]) + self.src[b0:end].decode()
        self.found.append((kind, start, end, new))

    def visit_UnaryOp(self, node) -> None:
        if self._inside:
            if isinstance(node.op, ast.USub) and not isinstance(node.operand, ast.Constant):
                self.add("sign", node, self.text(node.operand))
            elif isinstance(node.op, ast.Not):
                atom = isinstance(node.operand, (ast.Name, ast.Call, ast.Attribute, ast.Subscript))
                self.add("boolean", node, self.text(node.operand) if atom else f"({self.text(node.operand)})")
        self.generic_visit(node)

    def visit_Compare(self, node) -> None:
        if self._inside and len(node.ops) == 1 and type(node.ops[0]) in _FLIP_CMP:
            (_, a1), (b0, _) = self.span(node.left), self.span(node.comparators[0])
            start, end = self.span(node)
            middle = self.src[a1:b0].decode()
            sym = {ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==", ast.NotEq: "!=",
                   ast.In: " in ", ast.NotIn: " not in ", ast.Is: " is ", ast.IsNot: " is not "}
            old, new_op = sym[type(node.ops[0])], sym[_FLIP_CMP[type(node.ops[0])]]
            if middle.count(old.strip()) == 1 or old.strip() in ("in", "is"):
                new_middle = middle.replace(old.strip(), new_op.strip(), 1) if old.strip() not in ("in", "is") else \
                    f" {new_op.strip()} "
                self.found.append(("compare", start, end, self.src[start:a1].decode() + new_middle + self.src[b0:end].decode()))
        self.generic_visit(node)

    def visit_Constant(self, node) -> None:
        if self._inside and type(node.value) is int:
            for d in (1, -1):
                if node.value + d >= 0:
                    self.add("off-by-one", node, str(node.value + d))

    def visit_BoolOp(self, node) -> None:
        if self._inside and len(node.values) == 2:
            (_, a1), (b0, _) = self.span(node.values[0]), self.span(node.values[1])
            start, end = self.span(node)
            middle = self.src[a1:b0].decode()
            old, new = ("and", "or") if isinstance(node.op, ast.And) else ("or", "and")
            if middle.split().count(old) == 1 and "(" not in middle:
                self.found.append(("boolean", start, end, self.src[start:a1].decode() + middle.replace(old, new)
                                   + self.src[b0:end].decode()))
        self.generic_visit(node)

    def visit_If(self, node) -> None:
        if self._inside and any(isinstance(s, (ast.Raise, ast.Return, ast.Continue, ast.Break)) for s in node.body):
            self.add("dropped check", node.test, "False")
        self.generic_visit(node)

    def visit_Return(self, node) -> None:
        if self._inside and isinstance(node.value, ast.Constant) and isinstance(node.value.value, bool):
            self.add("boolean", node.value, str(not node.value.value))
        self.generic_visit(node)

    def visit_AnnAssign(self, node) -> None:
        if node.value is not None:
            self.visit(node.value)  # not the annotation

    def visit_arguments(self, node) -> None:
        for d in (*node.defaults, *node.kw_defaults):
            if d is not None:
                self.visit(d)


def candidates(root: Path, module: str) -> list[dict]:
    """Every candidate bug of ``module`` in the checkout ``root``, in file order."""
    spec = MODULES[module]
    out = []
    for pattern in spec["files"]:
        for path in sorted(root.glob(pattern)):
            rel = path.relative_to(root).as_posix()
            src = path.read_bytes()
            finder = _Finder(src, spec.get("only"))
            finder.visit(ast.parse(src))
            starts = finder.starts
            for kind, a, b, new in finder.found:
                # the whole lines the bug touches, as text: how a later checkout finds it again
                first = max(i for i, s in enumerate(starts) if s <= a)
                last = max(i for i, s in enumerate(starts) if s <= max(a, b - 1))
                lo, hi = starts[first], (starts[last + 1] if last + 1 < len(starts) else len(src))
                old_lines = src[lo:hi].decode()
                new_lines = (src[lo:a] + new.encode() + src[b:hi]).decode()
                try:
                    ast.parse((src[:lo] + new_lines.encode() + src[hi:]).decode())
                except SyntaxError:
                    continue
                occurrence = src[:lo].decode().count(old_lines)
                out.append({"module": module, "file": rel, "line": first + 1, "kind": kind, "old": old_lines,
                            "new": new_lines, "occurrence": occurrence})
    return out


def draw(root: Path, per_module: int, seed: int, modules: list[str] | None = None,
         exclude: list[str] = ()) -> list[dict]:
    """A seeded sample of ``per_module`` bugs in each module (``modules``: only these), never
    one of the samples named in ``exclude`` (the same text planted at the same place)."""
    rng = random.Random(seed)
    def key(m):  # the indentation may have changed since
        return m["file"], m["old"].strip(), m["new"].strip(), m["occurrence"]

    seen = {key(m) for name in exclude for m in json.loads((OUT / f"{name}.json").read_text())}
    sample = []
    for module in MODULES:
        if modules and module not in modules:
            continue
        pool = [m for m in candidates(root, module) if key(m) not in seen]
        picked = rng.sample(pool, min(per_module, len(pool)))
        picked.sort(key=lambda m: (m["file"], m["line"]))
        for i, m in enumerate(picked):
            m["id"] = f"{module}#{i + 1}"
        sample += picked
        print(f"{module}: {len(picked)} of {len(pool)} candidates")
    return sample


# --- running ----------------------------------------------------------------------------------


def workspace(root: Path, label: str) -> Path:
    ws = ROOT / "build" / "planted" / f"{SAMPLE}-{label}"
    if ws.exists():
        shutil.rmtree(ws)
    ws.mkdir(parents=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", ".pytest_cache")
    for src, name in PACKAGES.items():
        shutil.copytree(root / src, ws / "pkgs" / name, ignore=ignore)
    for name in COPIED:
        p = root / name
        if p.is_dir():
            shutil.copytree(p, ws / name, ignore=ignore)
        elif p.exists():
            shutil.copy2(p, ws / name)
    return ws


def package_path(ws: Path, rel: str) -> Path:
    for src, name in PACKAGES.items():
        if rel == src or rel.startswith(src + "/"):
            return ws / "pkgs" / name / rel[len(src) + 1:] if rel != src else ws / "pkgs" / name
    raise ValueError(rel)


def test_args(ws: Path, module: str) -> list[str]:
    args = []
    for t in MODULES[module]["tests"]:
        if (ws / t.split("::")[0]).exists():
            args.append(t)
    return args


def run_tests(ws: Path, tests: list[str], timeout: float) -> tuple[str, float]:
    env = dict(os.environ, PYTHONPATH=str(ws / "pkgs"), QT_QPA_PLATFORM="offscreen", OMP_NUM_THREADS="1",
               OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1", FUZZ_EXAMPLES="10", CI="true")
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", "-p", "no:xvfb", "-m", "not gl",
           "-o", "addopts=", *tests]
    t0 = time.monotonic()
    try:
        proc = subprocess.run(cmd, cwd=ws, env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", time.monotonic() - t0
    took = time.monotonic() - t0
    if proc.returncode == 0:
        return "passed", took
    if proc.returncode == 1:
        return "failed", took
    return f"error {proc.returncode}: {(proc.stdout + proc.stderr)[-300:]}", took


def plant(path: Path, m: dict) -> bool:
    text = path.read_text()
    n = text.count(m["old"])
    if n == 0:
        return False
    k = m["occurrence"] if n > m["occurrence"] else None
    if k is None:
        return False
    at = -1
    for _ in range(k + 1):
        at = text.index(m["old"], at + 1)
    path.write_text(text[:at] + m["new"] + text[at + len(m["old"]):])
    return True


SAMPLE = "sample"


def run(root: Path, label: str, modules: list[str] | None, ids: list[str] | None) -> dict:
    sample = json.loads((OUT / f"{SAMPLE}.json").read_text())
    ws = workspace(root, label)
    results_path = OUT / f"{label}.json"
    results = json.loads(results_path.read_text()) if results_path.exists() and (modules or ids) else {}
    stamp = time.time()
    for module in MODULES:
        if modules and module not in modules:
            continue
        tests = test_args(ws, module)
        status, base = run_tests(ws, tests, 1800)
        print(f"{module}: baseline {status} in {base:.0f} s ({' '.join(tests)})", flush=True)
        if status != "passed":
            raise SystemExit(f"the tests of {module} do not pass unchanged in {root}")
        for m in sample:
            if m["module"] != module or (ids and not any(fnmatch.fnmatch(m["id"], p) for p in ids)):
                continue
            if results.get(m["id"], {}).get("status") in ("caught", "missed", "not applicable"):
                continue  # measured by an earlier run of this label (one that was stopped)
            path = package_path(ws, m["file"])
            if not path.exists() and m["file"] in MOVED:
                path = package_path(ws, MOVED[m["file"]])
                m = {**m, "occurrence": MOVED_OCCURRENCE.get(m["id"], m["occurrence"])}
            original = path.read_text()
            mtime = path.stat().st_mtime
            if not plant(path, m):
                results[m["id"]] = {"status": "not applicable"}
                print(f"  {m['id']:32s} not applicable", flush=True)
                continue
            stamp += 10  # a new mtime: no stale bytecode of another bug is ever used
            os.utime(path, (stamp, stamp))
            try:
                status, took = run_tests(ws, tests, 3 * base + 60)
            finally:
                path.write_text(original)
                stamp += 10
                os.utime(path, (stamp, stamp))
            verdict = "caught" if status in ("failed", "timeout") else ("missed" if status == "passed" else status)
            results[m["id"]] = {"status": verdict, "seconds": round(took, 1)}
            print(f"  {m['id']:32s} {verdict:8s} {took:5.0f} s  {m['kind']}: {m['file']}:{m['line']}", flush=True)
            results_path.write_text(json.dumps(results, indent=1))
        del mtime
    results_path.write_text(json.dumps(results, indent=1))
    return results


def _results(spec: str) -> dict:
    """The results of a label, or of several merged ("before+before2": runs of one checkout
    split in parts; a later part wins)."""
    out: dict = {}
    for label in spec.split("+"):
        out.update(json.loads((OUT / f"{label}.json").read_text()))
    return out


def table(labels: list[str]) -> str:
    """Caught / planted per module for each label (``a+b`` merges runs), counting only the bugs
    every label measured (so each column is over the same bugs), then the bugs missed."""
    sample = json.loads((OUT / f"{SAMPLE}.json").read_text())
    runs = {label: _results(label) for label in labels}
    done = ("caught", "missed")
    both = [m for m in sample if all(runs[l].get(m["id"], {}).get("status") in done for l in labels)]
    lines = ["| module | " + " | ".join(labels) + " |", "|---|" + "---|" * len(labels)]
    totals = {label: [0, 0] for label in labels}
    for module in MODULES:
        ms = [m for m in both if m["module"] == module]
        row = [module]
        for label in labels:
            caught = sum(runs[label][m["id"]]["status"] == "caught" for m in ms)
            totals[label][0] += caught
            totals[label][1] += len(ms)
            row.append(f"{caught}/{len(ms)} ({100 * caught / len(ms):.0f}%)" if ms else "-")
        lines.append("| " + " | ".join(row) + " |")
    lines.append("| all | " + " | ".join(f"{c}/{n} ({100 * c / n:.0f}%)" if n else "-" for c, n in totals.values()) + " |")
    missed = [(label, m) for label in labels for m in both if runs[label][m["id"]]["status"] == "missed"]
    if missed:
        lines.append("")
        lines.append("missed:")
        for label, m in missed:
            lines.append(f"  [{label}] {m['id']} {m['kind']} {m['file']}:{m['line']}: {m['old'].strip()!r} -> {m['new'].strip()!r}")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", type=Path, default=ROOT, help="the checkout to plant in (default: this one)")
    ap.add_argument("--draw", action="store_true", help="draw the sample from --root and save it")
    ap.add_argument("--per-module", type=int, default=24)
    ap.add_argument("--seed", type=int, default=39)
    ap.add_argument("--label", help="run the sample on --root; results in mutation/planted/LABEL.json")
    ap.add_argument("--module", action="append", help="only this module (repeatable)")
    ap.add_argument("--only", nargs="*", help="only these bug ids (fnmatch patterns)")
    ap.add_argument("--table", nargs="*", help="print the table of these labels")
    ap.add_argument("--sample", default="sample", help="the sample's name: mutation/planted/NAME.json")
    ap.add_argument("--exclude", nargs="*", default=[], help="with --draw: never a bug of these samples")
    args = ap.parse_args(argv)
    global SAMPLE
    SAMPLE = args.sample
    OUT.mkdir(exist_ok=True)
    if args.draw:
        sample = draw(args.root.resolve(), args.per_module, args.seed, args.module, args.exclude)
        (OUT / f"{SAMPLE}.json").write_text(json.dumps(sample, indent=1))
    if args.label:
        run(args.root.resolve(), args.label, args.module, args.only)
    if args.table:
        print(table(args.table))
    return 0


if __name__ == "__main__":
    sys.exit(main())
