"""Memory bombs under the size cap (issue 38): documents whose bytes are few but whose parse
builds tens of millions of objects (60 MB of ``[],`` grew past 3 GB), or whose text Python
must store 4 bytes a character (one emoji in a long ASCII string). The size and nesting
limits did not bound them; the loader now counts the items a parse can build, and the memory
its text takes, before it builds anything."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from attack_helpers import assert_one_line_error, run_cli
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sketchforge.document import fileformat as ff
from sketchforge.document import jsonfile

#: The child prints its own peak resident memory after ``sketchforge info``: in a fresh process,
#: so the figure is the parse's, not this test session's.
CHILD = r"""
import resource, sys, io, contextlib
from sketchforge.cli import main
err = io.StringIO()
with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
    rc = main(["info", sys.argv[1]])
print(rc, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024)
print(err.getvalue().strip())
"""


def _info_in_child(path) -> tuple[int, int, str]:
    """(exit status, peak MB, stderr) of ``sketchforge info path`` in a fresh interpreter."""
    res = subprocess.run([sys.executable, "-c", CHILD, str(path)], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    first, _, err = res.stdout.partition("\n")
    rc, mb = map(int, first.split())
    return rc, mb, err.strip()


def _baseline_mb(tmp_path) -> int:
    small = tmp_path / "small.json"
    small.write_text("[]")
    return _info_in_child(small)[1]


@pytest.mark.parametrize("unit", [b"[],", b"{},"])
def test_a_bomb_of_empty_containers_is_refused_before_it_is_built(tmp_path, unit):
    """33 MB of ``[],`` (11 million lists) took 1.8 GB and 17 s to be refused as "not a
    sketchforge document"; now it is refused on its item count, within 150 MB of an empty
    document's footprint."""
    bomb = tmp_path / "bomb.json"
    n = 11_000_000
    bomb.write_bytes(b"[" + unit * n + unit[:2] + b"]")
    rc, mb, err = _info_in_child(bomb)
    base = _baseline_mb(tmp_path)
    assert mb - base < 150, (mb, base)  # the file's bytes (33 MB), nothing built
    assert rc == 2
    assert err.count("\n") == 0 and err.startswith("sketchforge: error: ")
    assert "JSON items (values and keys); the limit is 8,000,000" in err


def test_one_wide_character_cannot_quadruple_the_text(tmp_path, monkeypatch):
    """A string of ASCII with one emoji (or one escaped surrogate pair) is stored 4 bytes a
    character, the parsed copy too: 128 MB of it took 1.1 GB. The text's memory is bounded
    by the byte cap (shown here with a cap of 64 KiB)."""
    monkeypatch.setattr(jsonfile, "MAX_FILE_BYTES", 64 * 1024)  # where the file is read
    head = b'{"format":"sketchforge","version":1,"name":"'
    for wide in ("\U0001F600".encode(), b"\\ud83d\\ude00", "\u4e00".encode(), b"\\u4e00"):
        doc = tmp_path / "wide.json"
        doc.write_bytes(head + b"x" * 40_000 + wide + b'"}')
        line = assert_one_line_error(run_cli("info", doc), "its text would take", "the limit is 0.0625 MiB")
        assert "MiB in memory" in line
    # Latin-1 characters (é) keep one byte each: the same document opens.
    doc.write_bytes(head + b"x" * 40_000 + "é".encode() + b'"}')
    res = run_cli("info", doc)
    assert res.rc == 0, res.err


def test_items_inside_strings_do_not_count(tmp_path, monkeypatch):
    """A real document whose names are full of commas, colons and brackets opens: only marks
    outside strings count (escaped quotes included)."""
    monkeypatch.setattr(jsonfile, "MAX_JSON_ITEMS", 2_000)
    from attack_helpers import SMALL_DOC

    data = json.loads(json.dumps(SMALL_DOC))
    data["journal"][0]["name"] = 'a "quoted", [{name}]: ' * 400
    doc = tmp_path / "names.json"
    doc.write_text(json.dumps(data))
    assert ff.scan_items(doc.read_bytes(), 10**9) < 100 < doc.read_bytes().count(b",")
    res = run_cli("info", doc)
    assert res.rc == 0, res.err
    # and just over the limit, outside strings, is refused
    data["journal"].append({"command": "set_light", "direction": [1.0, 0.0, 0.0]})
    data["pad"] = [[] for _ in range(2_000)]
    doc.write_text(json.dumps(data))
    assert_one_line_error(run_cli("info", doc), "more than 2,000 JSON items")


def _items(v) -> tuple[int, int]:
    """(values + keys, empty containers) of a parsed JSON value."""
    if isinstance(v, dict):
        inner = [_items(x) for x in v.values()]
        return 1 + len(v) + sum(a for a, _ in inner), (not v) + sum(b for _, b in inner)
    if isinstance(v, list):
        inner = [_items(x) for x in v]
        return 1 + sum(a for a, _ in inner), (not v) + sum(b for _, b in inner)
    return 1, 0


_text = st.text(st.characters(blacklist_categories=("Cs",)), max_size=12) | st.sampled_from(
    ['",:[{', "\\", '\\"', "a,b", "\U0001f600", "ā"]
)
_json = st.recursive(
    st.none() | st.booleans() | st.integers(-10**20, 10**20) | st.floats(allow_nan=False, allow_infinity=False) | _text,
    lambda kids: st.lists(kids, max_size=5) | st.dictionaries(_text, kids, max_size=5),
    max_leaves=40,
)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(value=_json, ascii_only=st.booleans(), indent=st.sampled_from([None, 1]))
def test_the_count_bounds_what_the_parser_builds(value, ascii_only, indent):
    """The quick count never counts fewer items than the parse builds, and the exact scan
    (the path a bomb takes) is the items plus one per empty container, whatever the strings
    hold; it stops just past its limit. The text's memory bound is never below what Python
    stores for the text or for any string parsed from it."""
    raw = json.dumps(value, ensure_ascii=ascii_only, indent=indent).encode("utf-8")
    items, empty = _items(json.loads(raw))
    assert ff.count_json_items(raw) >= items
    assert ff.scan_items(raw, 10**9) == items + empty
    limit = (items + empty) // 2
    assert ff.count_json_items(raw, limit) > limit or items + empty <= limit
    text = raw.decode("utf-8")
    strings = [text] + [s for s in _strings(json.loads(raw))]
    need = ff.text_memory(raw)
    for s in strings:
        width = 4 if any(ord(c) > 0xFFFF for c in s) else 2 if any(ord(c) > 0xFF for c in s) else 1
        assert need >= width * len(s)


def _strings(v):
    if isinstance(v, str):
        yield v
    elif isinstance(v, dict):
        for k, x in v.items():
            yield k
            yield from _strings(x)
    elif isinstance(v, list):
        for x in v:
            yield from _strings(x)
