"""Throughput of ``sketchforge batch``: documents per second on 1, 2 and all cores of a local
Dask cluster and through a dask.distributed cluster (``dask scheduler`` + ``dask worker``
started here on loopback), against one process replaying the same documents warm, and what one
cold ``sketchforge replay`` costs.

Run: .venv/bin/python benchmarks/bench_batch.py [DOCUMENTS] [SEED]
(default 24 random creatures from seed 0, at the default resolution; obj exports.)

Prints figures only. Per-document costs: wall time per document of a run (its documents
divided by its wall time, times its workers) and CPU time of a warm job (median over the jobs,
measured in the worker). The issue's target: a warm engine's per-document cost within 1.3x of
the in-process one.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from sketchforge.batch.batch import Entry, plan, prepare_output_dir, run_batch
from sketchforge.batch.engine import Engine, local_cores
from sketchforge.batch.jobs import replay_export, software
from sketchforge.batch.progress import ProgressBar


def corpus(folder: Path, n: int, seed: int) -> list[Path]:
    """``n`` random creature documents (journals, as scripts write them)."""
    from sketchforge_assemble.testing import random_creature

    docs: list[Path] = []
    s = seed * 1000
    while len(docs) < n:
        try:
            body = random_creature(s)
        except ValueError:  # a seed whose head cannot be placed
            s += 1
            continue
        path = folder / f"creature-{s:05d}.json"
        path.write_text(json.dumps(body))
        docs.append(path)
        s += 1
    return docs


def cold_replays(docs: list[Path], out: Path) -> tuple[float, float]:
    """Median CPU and wall seconds of one ``sketchforge replay DOC --export`` process each."""
    cpu, wall = [], []
    for doc in docs:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "sketchforge", "replay", str(doc), "--export", str(out / "cold.obj")],
                       check=True, capture_output=True)
        wall.append(time.perf_counter() - t)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(cpu), statistics.median(wall)


def in_process(docs: list[Path], out: Path) -> tuple[float, float]:
    """Median CPU and wall seconds per document of warm replays in this process (the first
    document, which imports and compiles, is replayed once before)."""
    expected = software()
    replay_export(str(docs[0]), docs[0].read_bytes(), str(out / "warm.obj"), "obj", 0, expected)
    cpu, t0 = [], time.perf_counter()
    for doc in docs:
        r = replay_export(str(doc), doc.read_bytes(), str(out / f"{doc.stem}.obj"), "obj", 0, expected)
        assert r.ok, r.summary
        cpu.append(r.cpu_seconds)
    return statistics.median(cpu), (time.perf_counter() - t0) / len(docs)


def through(engine: Engine, docs: list[Path], out: Path, workers: int) -> tuple[float, float, float, float, int]:
    """(start-up seconds, documents per second, median job CPU seconds, this process's CPU
    seconds per document, workers) of a batch. This process reads and writes the files and,
    for the local cluster, runs its scheduler."""
    t = time.perf_counter()
    engine.start()
    engine.wait_for_workers(workers, timeout=120)
    startup = time.perf_counter() - t
    try:
        entries = plan(docs, out, "obj")
        prepare_output_dir(out)
        c0 = time.process_time()
        result = run_batch(entries, out, "obj", 0, engine, ProgressBar(len(docs), stream=open(os.devnull, "w")))
        client = (time.process_time() - c0) / len(docs)
        assert result.failed == 0, [e.error for e in result.entries if not e.ok]
        first: dict[str | None, Entry] = {}  # each worker's first job compiles: not in the CPU median
        for e in result.entries:
            first.setdefault(e.worker, e)
        warm = [e.cpu_seconds for e in result.entries if first[e.worker] is not e and e.cpu_seconds is not None]
        return startup, len(docs) / result.seconds, statistics.median(warm), client, engine.workers
    finally:
        engine.close()


def loopback_cluster(workers: int, folder: Path) -> tuple[str, list[subprocess.Popen]]:
    dask = str(Path(sys.executable).parent / "dask")
    info = folder / "scheduler.json"
    procs = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                               "--scheduler-file", str(info)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              start_new_session=True)]
    while not info.exists() or not info.read_text().strip():
        time.sleep(0.2)
    address = json.loads(info.read_text())["address"]
    procs.append(subprocess.Popen([dask, "worker", address, "--nworkers", str(workers), "--nthreads", "1",
                                   "--no-dashboard", "--host", "127.0.0.1"], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL, start_new_session=True))
    return address, procs


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 24
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    cores = local_cores()
    print(f"load before: {os.getloadavg()[0]:.2f} (1 min) on {cores} cores")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "docs").mkdir()
        docs = corpus(root / "docs", n, seed)
        cold_cpu, cold_wall = cold_replays(docs[:3], root)
        print(f"one `sketchforge replay DOC --export` process (cold): {cold_cpu:.2f} s CPU, {cold_wall:.2f} s wall (median of 3)")
        warm_cpu, warm_wall = in_process(docs, root)
        print(f"in one process, warm: {warm_cpu:.3f} s CPU, {warm_wall:.3f} s wall per document "
              f"({1 / warm_wall:.2f} documents/s), {n} random creatures")
        rows = []
        for k in sorted({1, 2, cores}):
            startup, rate, cpu, client, w = through(Engine(workers=k), docs, root / f"local-{k}", k)
            rows.append((f"local cluster, {w} worker{'s' if w > 1 else ''}", startup, rate, cpu, client, w))
        address, procs = loopback_cluster(cores, root)
        try:
            startup, rate, cpu, client, w = through(Engine(scheduler=address, timeout=120), docs, root / "remote", cores)
            rows.append((f"dask scheduler + {w} dask workers (loopback)", startup, rate, cpu, client, w))
        finally:
            for p in procs[::-1]:
                os.killpg(p.pid, signal.SIGTERM)
            for p in procs:
                p.wait(timeout=30)
        print(f"{'engine':<42} {'start-up':>8} {'docs/s':>7} {'wall/doc x workers':>18} {'job CPU':>8} "
              f"{'client CPU/doc':>14}   per document against one warm process")
        for name, startup, rate, cpu, client, w in rows:
            per_doc = w / rate
            print(f"{name:<42} {startup:7.1f}s {rate:7.2f} {per_doc:17.3f}s {cpu:7.3f}s {client:13.3f}s   "
                  f"wall {per_doc / warm_wall:.2f}x, CPU {(cpu + client) / warm_cpu:.2f}x (job alone {cpu / warm_cpu:.2f}x)")
        best = max(r[2] for r in rows)
        print(f"10,000 documents: {10_000 * warm_cpu / 3600:.1f} CPU-hours warm "
              f"(against {10_000 * cold_cpu / 3600:.1f} as one replay process each); "
              f"{10_000 / best / 60:.0f} min wall at the best rate here ({best:.2f} documents/s)")
    print(f"load after: {os.getloadavg()[0]:.2f} (1 min)")


if __name__ == "__main__":
    main()
