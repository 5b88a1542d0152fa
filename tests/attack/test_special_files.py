"""Documents that are not regular files, or too large: refused before reading (once a FIFO
blocked forever and /dev/zero was read until MemoryError at 9 GB)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from attack_helpers import MAX_RSS_GROWTH, assert_one_line_error, peak_rss_bytes, run_cli


def test_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "doc.json"
    os.mkfifo(fifo)
    # A subprocess: a regression would block forever, and the timeout turns that into a failure.
    res = subprocess.run([sys.executable, "-m", "sketchforge", "info", str(fifo)], capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and res.stderr.count("\n") == 1
    assert "not a regular file" in res.stderr


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
def test_devices_are_refused_before_reading(device, tmp_path):
    if not os.path.exists(device):
        pytest.skip(f"no {device}")
    before = peak_rss_bytes()
    for cmd in ("info", "replay", "render"):
        argv = [cmd, device] + (["--png", tmp_path / "x.png"] if cmd == "render" else [])
        res = run_cli(*argv)
        assert_one_line_error(res, "not a regular file")
        # "before reading" is shown by the memory bound below; the time only catches a hang
        # (a fixed 1 s failed on a loaded 2-core machine: 4 s, nothing read).
        assert res.seconds < 30.0
    assert peak_rss_bytes() - before < MAX_RSS_GROWTH


def test_directory_is_refused(tmp_path):
    assert_one_line_error(run_cli("info", tmp_path), "it is a directory")


def test_size_cap_is_checked_before_reading(tmp_path, monkeypatch):
    from sketchforge.document import fileformat as ff
    from sketchforge.document import jsonfile

    big = tmp_path / "big.json"
    big.write_bytes(b" " * 5000)
    monkeypatch.setattr(jsonfile, "MAX_FILE_BYTES", 4096)  # where the file is read
    read = []
    real_read = os.read
    monkeypatch.setattr(ff.os, "read", lambda fd, n: read.append(n) or real_read(fd, n))
    assert_one_line_error(run_cli("info", big), "5000 bytes is over the limit of 4096")
    assert read == []  # refused on its size, nothing read


def test_a_file_growing_while_read_is_cut_at_the_cap(tmp_path, monkeypatch):
    """st_size can lie (a file being appended to, /proc files): never read past the cap."""
    from sketchforge.document import fileformat as ff

    p = tmp_path / "doc.json"
    p.write_bytes(b" " * 3000)
    real_fstat = os.fstat

    class Small:
        def __init__(self, st):
            self.st_mode, self.st_size = st.st_mode, 10

    monkeypatch.setattr(ff.os, "fstat", lambda fd: Small(real_fstat(fd)))
    with pytest.raises(ff.LimitError, match="more than 1000 bytes"):
        ff.read_regular_file(p, limit=1000)


def test_a_fifo_in_the_autosave_folder_does_not_block_the_start_up_scan(tmp_path):
    """The recovery scan at start reads every *.json of the autosave folder: a FIFO there is
    skipped at once (it blocked forever with a plain read)."""
    import time

    from sketchforge.document.autosave import find_recoverable

    folder = tmp_path / "auto"
    folder.mkdir()
    os.mkfifo(folder / "x.json")
    os.mkfifo(folder / "y.pending")
    t = time.perf_counter()
    assert find_recoverable(folder) == []
    assert time.perf_counter() - t < 10  # a hang guard: it returns, it does not wait for a writer
