"""``sketchforge batch``: every document under some paths replayed and exported on a real Dask
cluster (a local one, and a scheduler and worker started here on loopback), each output the
bytes ``replay DOC --export`` writes, a broken document one line that never stops the rest."""

from __future__ import annotations

import io
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from sketchforge import cli
from sketchforge.batch.batch import Entry, plan, prepare_output_dir, run_batch
from sketchforge.batch.engine import Engine, WorkerDied
from sketchforge.batch.progress import ProgressBar

ROOT = Path(__file__).resolve().parent.parent
#: Documents that replay (the example with holes, one of free parts, two seeded random creatures)
GOOD = ["holes.json", "separate.json", "creature-3.json", "creature-8.json", "sub/holes.json"]
#: Documents that do not, and the words of their one line.
BAD = {
    "bad-json.json": "invalid JSON",
    "figure-eight.json": "journal entry 1 (set_contour)",
    "unknown-command.json": "unknown command 'grow_wings'",
}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    """A folder of documents: good ones (one, of the same name, in a subfolder), broken ones, an
    old batch report and a text file (neither is a document)."""
    from sketchforge_assemble.testing import random_creature

    root = tmp_path_factory.mktemp("corpus")
    (root / "sub").mkdir()
    for name in ("holes.json", "separate.json"):
        shutil.copy(ROOT / "examples" / name, root / name)
    shutil.copy(ROOT / "examples" / "holes.json", root / "sub" / "holes.json")
    for seed in (3, 8):
        (root / f"creature-{seed}.json").write_text(json.dumps(random_creature(seed, resolution=0.05)))
    (root / "bad-json.json").write_text('{"format": "sketchforge", "journal": [')
    eight = {"format": "sketchforge", "version": 1, "journal": [
        {"command": "add_layer", "id": "body"},
        {"command": "set_contour", "layer": "body", "points": [[0, 0], [1, 1], [1, 0], [0, 1]]}]}
    (root / "figure-eight.json").write_text(json.dumps(eight))
    (root / "unknown-command.json").write_text(json.dumps({"format": "sketchforge", "version": 1,
                                                           "journal": [{"command": "grow_wings"}]}))
    (root / "batch-report.json").write_text(json.dumps({"format": "sketchforge-batch-report", "results": []}))
    (root / "notes.txt").write_text("not a document")
    return root


@pytest.fixture(scope="module")
def references(corpus, tmp_path_factory):
    """What ``sketchforge replay DOC --export`` writes for each good document, as obj."""
    out = tmp_path_factory.mktemp("refs")
    refs = {}
    for name in GOOD:
        target = out / (name.replace("/", "_") + ".obj")
        assert cli.main(["replay", str(corpus / name), "--export", str(target)]) == 0
        refs[name] = target.read_bytes()
    return refs


def _output(out: Path, name: str, fmt: str) -> Path:
    return out / (name[: -len(".json")] + "." + fmt)


def _failure_lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if line.startswith("sketchforge: failed:")]


def test_a_folder_on_the_default_local_cluster_gives_the_replay_bytes_and_one_line_per_failure(corpus, references, tmp_path, capsys):
    out = tmp_path / "out"
    rc = cli.main(["batch", str(corpus), "--export-dir", str(out), "--format", "obj", "--workers", "2"])
    err = capsys.readouterr().err
    assert rc == 2  # some failed
    for name in GOOD:
        assert _output(out, name, "obj").read_bytes() == references[name], name
    lines = _failure_lines(err)
    assert len(lines) == len(BAD)
    for name, words in BAD.items():
        assert sum(name in line and words in line for line in lines) == 1, (name, lines)
        assert not _output(out, name, "obj").exists()
    assert "Traceback" not in err and "exported 5 of 8 documents" in err
    # nothing else: Dask's own warnings and log lines stay out of the user's terminal
    assert all(line.startswith(("sketchforge: failed:", "exported ")) for line in err.splitlines()), err
    report = json.loads((out / "batch-report.json").read_text())
    assert report["documents"] == 8 and report["ok"] == 5 and report["failed"] == 3
    assert "local Dask cluster of 2 workers" in report["cluster"]
    by_doc = {Path(r["document"]).relative_to(corpus).as_posix(): r for r in report["results"]}
    assert sorted(by_doc) == sorted(GOOD + list(BAD))  # neither the old report nor the text file
    for name in GOOD:
        r = by_doc[name]
        assert r["ok"] and r["error"] is None and r["output"] == str(_output(out, name, "obj"))
        assert 0 < r["cpu_seconds"] and 0 < r["seconds"] < 120
        assert int(r["worker"].rsplit(":", 1)[1]) != os.getpid()  # a worker process ran it
    for name, words in BAD.items():
        assert not by_doc[name]["ok"] and words in by_doc[name]["error"] and by_doc[name]["output"] is None


@pytest.mark.parametrize("fmt", ["ply", "stl", "glb", "png"])
def test_every_format_is_the_bytes_of_replay_export_or_render(fmt, corpus, dask_engine, tmp_path):
    docs = [corpus / "creature-8.json"]
    out = tmp_path / "out"
    entries = plan(docs, out, fmt)
    prepare_output_dir(out)
    size = 96 if fmt == "png" else 0
    result = run_batch(entries, out, fmt, size, dask_engine, ProgressBar(len(entries), stream=io.StringIO()))
    assert result.failed == 0
    for doc in docs:
        ref = tmp_path / f"ref-{doc.stem}.{fmt}"
        args = ["render", str(doc), "--png", str(ref), "--size", str(size)] if fmt == "png" else ["replay", str(doc), "--export", str(ref)]
        assert cli.main(args) == 0
        assert (out / f"{doc.stem}.{fmt}").read_bytes() == ref.read_bytes(), doc
    # one warm worker ran them all
    assert len({e.worker for e in result.entries}) == 1


@pytest.mark.parametrize(
    "args, words",
    [
        (["NOPE", "--format", "obj"], "no such file or folder"),
        (["EMPTY", "--format", "obj"], "no documents found under"),
        (["TWINS", "--format", "obj"], "would both be written to"),
        (["DOC", "--format", "fbx"], "cannot export to '.fbx'"),
        (["DOC", "--format", "obj", "--size", "64"], "--size is the PNG's size"),
        (["DOC", "--format", "png", "--size", "9000"], "--size must be between 16 and 8192"),
        (["DOC", "--format", "obj", "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"], "--workers sets the size"),
    ],
)
def test_bad_arguments_are_one_line_before_any_cluster_or_output(args, words, corpus, tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    for d in ("a", "b"):
        shutil.copy(corpus / "holes.json", tmp_path / d / "holes.json")
    names = {"NOPE": [str(tmp_path / "nope")], "EMPTY": [str(tmp_path / "empty")],
             "TWINS": [str(tmp_path / "a"), str(tmp_path / "b")], "DOC": [str(corpus / "holes.json")]}
    out = tmp_path / "out"
    t = time.perf_counter()
    rc = cli.main(["batch", *names[args[0]], "--export-dir", str(out), *args[1:]])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and words in err[0], err
    assert not out.exists() and time.perf_counter() - t < 10


def test_an_output_that_would_overwrite_its_document_is_refused(tmp_path, capsys):
    doc = tmp_path / "model.obj"  # a document under an odd name, exported beside itself
    shutil.copy(ROOT / "examples" / "holes.json", doc)
    assert cli.main(["batch", str(doc), "--export-dir", str(tmp_path), "--format", "obj"]) == 2
    assert "it is an input document" in capsys.readouterr().err
    assert doc.read_bytes() == (ROOT / "examples" / "holes.json").read_bytes()


def test_the_progress_bar_draws_in_place_on_a_terminal_and_failures_scroll_above_it():
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    term = Terminal()
    bar = ProgressBar(4, "documents", stream=term)
    bar.advance(True)
    bar.advance(False)
    bar.line("sketchforge: failed: b.json: broken")
    assert "2/4 documents, 1 failed" in term.getvalue().rsplit("broken\n", 1)[1]  # the bar redrawn, counted
    bar.advance(True)
    bar.advance(True)
    bar.close()
    text = term.getvalue()
    assert text.count("\r[") >= 2 and "4/4 documents, 1 failed" in text
    # the failure is a whole line of its own: the bar was wiped before it and redrawn after
    assert "\r\x1b[Ksketchforge: failed: b.json: broken\n\r[" in text
    assert text.endswith("\r\x1b[K")  # no bar left behind the summary line
    half = ProgressBar(2, stream=io.StringIO())
    half.done = 1
    line = half.text(60)
    inside = line[1 : line.index("]")]
    assert len(line) <= 60 and inside.count("#") == len(inside) // 2 and set(inside) == {"#", "."}
    plain = io.StringIO()  # not a terminal: no bar, only the lines
    bar = ProgressBar(2, stream=plain)
    bar.advance(True)
    bar.line("sketchforge: failed: x")
    bar.advance(False)
    bar.close()
    assert plain.getvalue() == "sketchforge: failed: x\n"


def _crash(x: int) -> int:
    if x == 1:
        os._exit(3)  # what a native crash does to the worker
    return x * 10


def test_a_job_whose_worker_dies_is_reported_and_the_others_finish(dask_engine):
    results = dict(dask_engine.run(_crash, [(i, (i,)) for i in range(4)]))
    assert {i: results[i] for i in (0, 2, 3)} == {0: 0, 2: 20, 3: 30}
    assert isinstance(results[1], WorkerDied) and "died" in str(results[1])
    # the nanny restarted the worker: the engine goes on
    assert dict(dask_engine.run(_crash, [(5, (5,))])) == {5: 50}


def test_an_unreachable_scheduler_is_one_line():
    with pytest.raises(Exception, match="cannot reach the Dask scheduler at 'tcp://127.0.0.1:1'"):
        Engine("tcp://127.0.0.1:1", timeout=1).start()


@pytest.fixture
def loopback_cluster(tmp_path):
    """``dask scheduler`` and ``dask worker`` started here on 127.0.0.1, as a user would."""
    dask = Path(sys.executable).parent / "dask"
    info = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                               "--scheduler-file", str(info)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              start_new_session=True)]
    try:
        deadline = time.monotonic() + 60
        while not info.exists() or not info.read_text().strip():
            assert time.monotonic() < deadline, "the scheduler did not start"
            time.sleep(0.2)
        address = json.loads(info.read_text())["address"]
        procs.append(subprocess.Popen([str(dask), "worker", address, "--nthreads", "1", "--nworkers", "1", "--no-dashboard",
                                       "--host", "127.0.0.1"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      start_new_session=True))
        yield address
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def test_an_existing_cluster_given_by_its_scheduler_writes_the_same_bytes(loopback_cluster, corpus, references, tmp_path, capsys):
    assert loopback_cluster.startswith("tcp://127.0.0.1:")
    out = tmp_path / "out"
    docs = [str(corpus / name) for name in ("holes.json", "creature-3.json", "figure-eight.json")]
    rc = cli.main(["batch", *docs, "--export-dir", str(out), "--format", "obj", "--scheduler", loopback_cluster])
    err = capsys.readouterr().err
    assert rc == 2 and len(_failure_lines(err)) == 1 and "figure-eight.json" in _failure_lines(err)[0]
    assert (out / "holes.obj").read_bytes() == references["holes.json"]
    assert (out / "creature-3.obj").read_bytes() == references["creature-3.json"]
    report = json.loads((out / "batch-report.json").read_text())
    assert report["cluster"] == f"the Dask cluster at {loopback_cluster} (1 worker)"
    workers = {r["worker"] for r in report["results"] if r["ok"]}
    assert len(workers) == 1 and int(workers.pop().rsplit(":", 1)[1]) != os.getpid()


def test_an_interrupted_batch_still_writes_its_report(corpus, dask_engine, tmp_path):
    class Interrupting(ProgressBar):
        def advance(self, ok):
            super().advance(ok)
            raise KeyboardInterrupt

    docs = [corpus / "holes.json", corpus / "separate.json", corpus / "creature-3.json"]
    out = tmp_path / "out"
    entries = plan(docs, out, "obj")
    prepare_output_dir(out)
    with pytest.raises(KeyboardInterrupt):
        run_batch(entries, out, "obj", 0, dask_engine, Interrupting(3, stream=io.StringIO()))
    report = json.loads((out / "batch-report.json").read_text())
    assert report["interrupted"] and report["ok"] == 1 and report["documents"] == 3
    assert sum(r["error"] == "not run: the batch was interrupted" for r in report["results"]) == 2
    done = [r for r in report["results"] if r["ok"]]
    assert Path(done[0]["output"]).is_file()
    assert not Entry(tmp_path / "a.json", tmp_path / "a.obj").to_dict()["ok"]
