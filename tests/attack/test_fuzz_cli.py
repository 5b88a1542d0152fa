"""Hypothesis over the CLI's argument space and the JSON loader, through the real entry point.

Every run must end with exit status 0, or 2 and exactly one ``sketchforge: error:`` line; no
exception escapes; the input document is never modified. Bounded in CI (``CI=true``: a few
examples per property), longer locally (``SKETCHFORGE_FUZZ_EXAMPLES`` overrides both)."""

from __future__ import annotations

import copy
import json
import os

from attack_helpers import SMALL_DOC, run_cli
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")
EXAMPLES = int(os.environ.get("SKETCHFORGE_FUZZ_EXAMPLES", 12 if IN_CI else 150))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck), derandomize=IN_CI)

BIG_NUMBERS = st.sampled_from(["1" + "0" * 400, "7" * 5000, "1e308", "-1e308", "1e-300", "NaN", "Infinity", "-0"])
json_scalars = st.none() | st.booleans() | st.integers(-10**30, 10**30) | st.floats(allow_nan=False) | st.text(max_size=10)
json_values = st.recursive(
    json_scalars, lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=6), c, max_size=4), max_leaves=12
)


#: What a successful step may print before a later step fails (each its own single line).
PROGRESS = ("replay matches the snapshot", "wrote ", "replayed ")


def _assert_clean(res):
    assert res.rc in (0, 2), (res.rc, res.err[-3000:])
    assert "Traceback" not in res.err
    if res.rc == 2:
        lines = res.err.splitlines()
        assert lines and lines[-1].startswith("sketchforge: error: "), res.err[-3000:]
        assert all(l.startswith(PROGRESS) for l in lines[:-1]), res.err[-3000:]


@st.composite
def cli_args(draw, doc, folder):
    """An argv over every subcommand and option, with outputs that may be the input, a
    missing folder, a directory, a 250-character name, odd suffixes and control characters."""
    names = st.sampled_from(
        [str(doc), str(folder), str(folder / "missing" / "x.obj"), str(folder / ("n" * 250 + ".obj")),
         str(folder / "out.obj"), str(folder / "out.stl"), str(folder / "out.glb"), str(folder / "out.fbx"),
         str(folder / "out.png"), str(folder / "out.json"), str(folder / "a\nb\x1b.ply"), "/dev/null", ""]
    ) | st.text(min_size=1, max_size=12).map(lambda t: str(folder / t.replace("/", "_").replace("\0", "_")))
    cmd = draw(st.sampled_from(["replay", "info", "render", "app"]))
    src = draw(st.sampled_from([str(doc), str(doc), str(folder / "nope.json"), str(folder), "/dev/zero"]))
    if cmd == "app":  # only the paths that never start a GUI: refusals before Qt starts
        return [src, "--screenshot", str(doc)]
    argv = [cmd, src]
    if cmd == "replay":
        if draw(st.booleans()):
            argv += ["--export", draw(names)]
        if draw(st.booleans()):
            argv += ["--layer", draw(st.sampled_from(["a", "zz", "\x1b[2J", ""]))]
        if draw(st.booleans()):
            argv += ["--check"]
        if draw(st.booleans()):
            argv += ["--save", draw(names)]
    elif cmd == "render":
        argv += ["--png", draw(names)]
        if draw(st.booleans()):
            argv += ["--size", str(draw(st.integers(-100, 300) | st.sampled_from([8193, 10**6, -10**12])))]
        if draw(st.booleans()):
            argv += ["--isophotes", str(draw(st.integers(-10, 300) | st.sampled_from([10**9])))]
        if draw(st.booleans()):
            argv += ["--cel"]
    if draw(st.integers(0, 9)) == 0:
        argv += [draw(st.sampled_from(["--bogus", "-v", "--size=abc"]))]
    return argv


@FUZZ
@given(data=st.data())
def test_cli_argument_space(tmp_path_factory, saved_doc_dict, data):
    folder = tmp_path_factory.mktemp("fuzzcli")
    doc = folder / "doc.json"
    doc.write_text(json.dumps(saved_doc_dict))
    before = doc.read_bytes()
    argv = data.draw(cli_args(doc, folder))
    res = run_cli(*argv)
    if res.rc == 2 and res.err.startswith("usage:"):  # argparse's own usage error: exit 2 too
        assert "error:" in res.err
    else:
        _assert_clean(res)
    assert doc.read_bytes() == before


def _paths(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _paths(v, prefix + (i,))


@FUZZ
@given(data=st.data())
def test_json_loader(tmp_path_factory, saved_doc_dict, data):
    """Mutated documents (values replaced by random JSON, huge or non-finite number literals,
    deleted keys, duplicated list items, macros nested at random): ``info``, ``replay`` and
    ``render`` each end cleanly."""
    base = copy.deepcopy(data.draw(st.sampled_from([saved_doc_dict, SMALL_DOC])))
    literal = None
    for _ in range(data.draw(st.integers(1, 3))):
        paths = [p for p in _paths(base) if p]
        path = data.draw(st.sampled_from(paths))
        parent = base
        for k in path[:-1]:
            parent = parent[k]
        action = data.draw(st.sampled_from(["replace", "delete", "dup", "number", "nest"]))
        if action == "replace":
            parent[path[-1]] = data.draw(json_values)
        elif action == "delete":
            del parent[path[-1]]
        elif action == "dup" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[path[-1]]))
        elif action == "number" and literal is None:
            parent[path[-1]] = "@@NUMBER@@"
            literal = data.draw(BIG_NUMBERS)
        elif action == "nest":
            m = {"command": "add_layer", "id": "n"}
            for _ in range(data.draw(st.integers(1, 40))):
                m = {"command": "macro", "children": [m]}
            parent[path[-1]] = m
    text = json.dumps(base)
    if literal is not None:
        text = text.replace('"@@NUMBER@@"', literal)
    folder = tmp_path_factory.mktemp("fuzzjson")
    doc = folder / "doc.json"
    doc.write_text(text)
    # ``replay`` alone too: without a snapshot ``--check`` stops before replaying (nothing to compare)
    for argv in (("info", doc), ("replay", doc), ("replay", doc, "--check"), ("render", doc, "--png", folder / "o.png", "--size", "64")):
        _assert_clean(run_cli(*argv))
    assert doc.read_text() == text
