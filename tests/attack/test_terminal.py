"""Names are printed escaped: an id with escape sequences or line breaks cannot fake output
lines, and a lone surrogate cannot crash printing (once a UnicodeEncodeError)."""

from __future__ import annotations

import subprocess
import sys

from attack_helpers import run_cli, write_doc

EVIL_ID = "a\x1b[2J\x1b[31m\nsketchforge: 0 layers\r\u202e\x07"
SURROGATE_ID = "b\ud800c"


def _doc(saved_doc, lid, name="Name\x1b]0;title\x07"):
    saved_doc["snapshot"]["layers"][0]["id"] = lid
    saved_doc["snapshot"]["layers"][0]["name"] = name
    return saved_doc


def test_control_characters_are_escaped(tmp_path, saved_doc):
    res = run_cli("info", write_doc(tmp_path / "doc.json", _doc(saved_doc, EVIL_ID)))
    assert res.rc == 0, res.err
    lines = res.out.splitlines()
    assert len(lines) == 2  # the header and one line for the one layer
    assert not any(ch in res.out for ch in "\x1b\r\x07\u202e")
    assert "a\\x1b[2J\\x1b[31m\\x0asketchforge: 0 layers\\x0d\\u202e\\x07" in lines[1]
    assert "'Name\\x1b]0;title\\x07'" in lines[1]


def test_lone_surrogate_prints_through_a_real_stdout(tmp_path, saved_doc):
    path = write_doc(tmp_path / "doc.json", _doc(saved_doc, SURROGATE_ID))
    res = subprocess.run([sys.executable, "-m", "sketchforge", "info", str(path)], capture_output=True, timeout=120)
    assert res.returncode == 0, res.stderr.decode(errors="replace")[-2000:]
    assert "b\\ud800c" in res.stdout.decode("utf-8")


def test_error_messages_are_one_line_whatever_the_path(tmp_path):
    res = run_cli("info", tmp_path / "no\nsuch\x1b[2Jfile.json")
    assert res.rc == 2 and res.err.count("\n") == 1 and "\x1b" not in res.err
    assert "no\\x0asuch\\x1b[2Jfile.json: no such file" in res.err
