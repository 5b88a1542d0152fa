"""The smaller defects of issue 38, each through the real entry point: ``info | head -1``
printed a BrokenPipeError traceback, an export over a setuid file kept the bit, ``replay
--check`` without a snapshot exited 0 silently (read as a pass), and some messages doubled
("the light direction must be numbers: the light direction must not be the zero vector",
".glb, .glb")."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys

import pytest
from attack_helpers import SMALL_DOC, assert_one_line_error, run_cli, write_doc


def test_info_into_a_closed_pipe_prints_no_traceback(tmp_path):
    """More output than a pipe holds (256 layers with long names, ~260 KB), read by ``head -1``:
    the writer finds the pipe closed mid-way, every time."""
    doc = {"format": "sketchforge", "version": 1,
           "journal": [{"command": "add_layer", "id": f"l{i}", "name": "n" * 1000} for i in range(256)]}
    path = write_doc(tmp_path / "many.json", doc)
    for _ in range(3):
        res = subprocess.run(["sh", "-c", f'"{sys.executable}" -m sketchforge info "{path}" 2>"{tmp_path}/err" | head -1'],
                             capture_output=True, text=True, timeout=120)
        assert res.stdout.startswith(str(path)) and res.stdout.count("\n") == 1
        err = (tmp_path / "err").read_text()
        assert err == "", err


@pytest.mark.parametrize("mode", [0o4755, 0o2644, 0o6775, 0o1644])
def test_an_export_or_save_over_a_setuid_file_drops_the_special_bits(tmp_path, mode):
    """The new contents are not the program the bit was given to: setuid, setgid and sticky
    go, the permission bits stay (as a write to the file clears setuid)."""
    doc = write_doc(tmp_path / "doc.json", SMALL_DOC)
    for out, argv in ((tmp_path / "out.obj", ["--export"]), (tmp_path / "saved.json", ["--save"])):
        out.write_text("old")
        os.chmod(out, mode)
        assert stat.S_IMODE(os.stat(out).st_mode) == mode  # the bits were really set
        res = run_cli("replay", doc, *argv, out)
        assert res.rc == 0, res.err
        assert stat.S_IMODE(os.stat(out).st_mode) == mode & 0o777


def test_replay_check_without_a_snapshot_says_there_is_nothing_to_compare(tmp_path, monkeypatch):
    path = write_doc(tmp_path / "journal-only.json", SMALL_DOC)
    from sketchforge.document import fileformat as ff

    replays = []
    real = ff.replay_journal
    monkeypatch.setattr(ff, "replay_journal", lambda *a, **k: replays.append(1) or real(*a, **k))
    line = assert_one_line_error(run_cli("replay", path, "--check"), "has no snapshot: nothing to compare")
    assert str(path) in line and replays == []  # said before any work
    # with a snapshot, the check still runs and passes
    saved = tmp_path / "saved.json"
    assert run_cli("replay", path, "--save", saved).rc == 0
    res = run_cli("replay", saved, "--check")
    assert res.rc == 0 and "replay matches the snapshot" in res.err


def test_a_zero_light_says_it_once(tmp_path):
    data = json.loads(json.dumps(SMALL_DOC))
    data["journal"].append({"command": "set_light", "direction": [0.0, 0.0, 0.0]})
    line = assert_one_line_error(run_cli("info", write_doc(tmp_path / "d.json", data)), "zero vector")
    assert line.count("light direction") == 1 and "must be numbers" not in line


def test_the_known_export_formats_are_listed_once_each(tmp_path):
    line = assert_one_line_error(run_cli("replay", write_doc(tmp_path / "d.json", SMALL_DOC), "--export", tmp_path / "x.fbx"),
                                 "known formats are")
    known = line.split("known formats are ", 1)[1].split(", ")
    assert ".glb" in known and len(known) == len(set(known)), known
