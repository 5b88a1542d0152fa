"""Outputs: never over an input, never over a read-only file, modes kept, short temp names,
stale temps of a killed save removed, a folder that refuses new files is one line."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import time

import pytest
from attack_helpers import assert_one_line_error, refuse_new_files, run_cli, write_doc


@pytest.fixture
def doc_path(tmp_path, saved_doc):
    return write_doc(tmp_path / "doc.json", saved_doc)


@pytest.mark.parametrize(
    "argv",
    [
        ("replay", "{doc}", "--export", "{doc}"),
        ("replay", "{doc}", "--save", "{doc}"),
        ("replay", "{doc}", "--save", "{alias}"),
        ("render", "{doc}", "--png", "{doc}"),
        ("{doc}", "--screenshot", "{doc}"),
    ],
    ids=["replay-export", "replay-save", "replay-save-via-symlink", "render-png", "app-screenshot"],
)
def test_output_never_replaces_the_input(tmp_path, doc_path, argv):
    alias = tmp_path / "alias.json"
    alias.symlink_to(doc_path)
    before = doc_path.read_bytes()
    res = run_cli(*[a.format(doc=doc_path, alias=alias) for a in argv])
    assert_one_line_error(res, "it is the input document")
    assert doc_path.read_bytes() == before


def test_read_only_file_is_refused_even_for_root(tmp_path, doc_path):
    out = tmp_path / "model.obj"
    out.write_text("keep me")
    out.chmod(0o444)
    assert_one_line_error(run_cli("replay", doc_path, "--export", out), "the file is read-only")
    assert out.read_text() == "keep me" and stat.S_IMODE(out.stat().st_mode) == 0o444


@pytest.mark.parametrize("mode", [0o644, 0o664, 0o600, 0o640])
def test_existing_file_keeps_its_mode(tmp_path, doc_path, mode):
    out = tmp_path / "saved.json"
    out.write_text("{}")
    out.chmod(mode)
    assert run_cli("replay", doc_path, "--save", out).rc == 0
    assert stat.S_IMODE(out.stat().st_mode) == mode and out.stat().st_size > 1000


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_new_file_gets_the_umask(tmp_path, doc_path, umask, mask):
    umask(mask)
    for out, argv in (
        (tmp_path / "m.obj", ("replay", doc_path, "--export", tmp_path / "m.obj")),
        (tmp_path / "s.json", ("replay", doc_path, "--save", tmp_path / "s.json")),
        (tmp_path / "r.png", ("render", doc_path, "--png", tmp_path / "r.png", "--size", "64")),
    ):
        assert run_cli(*argv).rc == 0
        assert stat.S_IMODE(out.stat().st_mode) == 0o666 & ~mask


def test_longest_legal_name(tmp_path, doc_path):
    out = tmp_path / ("x" * 250 + ".obj")  # 254 bytes: legal; the old temp name was not
    res = run_cli("replay", doc_path, "--export", out)
    assert res.rc == 0, res.err
    assert out.stat().st_size > 100
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["doc.json", out.name])
    multibyte = tmp_path / ("é" * 125 + ".obj")  # 254 bytes in UTF-8
    assert run_cli("replay", doc_path, "--export", multibyte).rc == 0


def test_folder_that_refuses_new_files(tmp_path, doc_path, monkeypatch):
    """EACCES from creating the temp file (the check is simulated: root may write anywhere)."""
    refuse_new_files(monkeypatch)
    for argv in (("replay", doc_path, "--export", tmp_path / "m.obj"), ("render", doc_path, "--png", tmp_path / "r.png")):
        assert_one_line_error(run_cli(*argv), "does not allow new files")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["doc.json"]


def test_stale_temps_of_a_crashed_save_are_removed_at_the_next_save(tmp_path, doc_path):
    from sketchforge.atomic import temp_prefix

    out = tmp_path / "model.obj"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True).stdout.strip()
    stale = tmp_path / f"{temp_prefix(out)}{dead}.deadbeef.tmp"
    live = tmp_path / f"{temp_prefix(out)}{os.getppid()}.cafef00d.tmp"  # a running writer's
    legacy_old = tmp_path / f".{out.name}.abcd1234.tmp"
    legacy_new = tmp_path / f".{out.name}.wxyz5678.tmp"
    other = tmp_path / f"{temp_prefix(tmp_path / 'other.obj')}{dead}.deadbeef.tmp"
    for p in (stale, live, legacy_old, legacy_new, other):
        p.write_bytes(b"x" * 1000)
    old = time.time() - 3600
    os.utime(legacy_old, (old, old))
    assert run_cli("replay", doc_path, "--export", out).rc == 0
    left = {p.name for p in tmp_path.iterdir()}
    assert stale.name not in left and legacy_old.name not in left
    assert {live.name, legacy_new.name, other.name, out.name} <= left


def test_killed_saves_leave_nothing_after_the_next_save(tmp_path):
    """Kill a process in the middle of saving a large document, repeatedly; one more save of
    the same file leaves exactly that file."""
    target = tmp_path / "big.json"
    script = (
        "import sys, os\n"
        "from sketchforge.atomic import write_bytes_atomic\n"
        "data = b'x' * (16 << 20)\n"
        "print('ready', flush=True)\n"
        "while True:\n"
        "    write_bytes_atomic(sys.argv[1], data)\n"
    )
    kills = stale = 0
    for delay in (0.05, 0.15, 0.3):
        p = subprocess.Popen([sys.executable, "-c", script, str(target)], stdout=subprocess.PIPE)
        assert p.stdout.readline().strip() == b"ready"
        time.sleep(delay)
        p.send_signal(signal.SIGKILL)
        p.wait(30)
        kills += 1
        stale = max(stale, len(list(tmp_path.glob(".*.tmp"))))
    from sketchforge.atomic import write_bytes_atomic

    assert stale >= 1  # the kills did land mid-save (the writer is in a write or fsync nearly always)
    write_bytes_atomic(target, b"final")
    assert [p.name for p in tmp_path.iterdir()] == ["big.json"] and target.read_bytes() == b"final"
