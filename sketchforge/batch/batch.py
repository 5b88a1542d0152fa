"""``sketchforge batch``: replay every document under some paths and export each one.

The client (this process) finds the documents, reads each just before it is sent, and writes
each output atomically as it comes back; the workers replay and export (:mod:`.jobs`). One
document's failure is one line (and one entry in the report); the others go on.

Outputs: ``OUT/<name>.<ext>`` for a document named on the command line; for one found in a
folder, its path below that folder (``FOLDER/a/b.json`` -> ``OUT/a/b.<ext>``), so documents of
the same name in different subfolders never overwrite each other. Two documents that would
still write the same output are refused before anything runs.
"""

from __future__ import annotations

import json
import os
import re
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sketchforge.atomic import check_target, write_bytes_atomic
from sketchforge.errors import ExportError, SketchforgeError

#: The report's file name in the output folder.
REPORT_NAME = "batch-report.json"
#: ``format`` of the files sketchforge writes beside documents that are not documents (a batch
#: report, a dataset manifest): a folder scan skips them.
REPORT_FORMAT = "sketchforge-batch-report"
MANIFEST_FORMAT = "sketchforge-dataset"
_NOT_A_DOCUMENT = re.compile(rb'^\s*\{\s*"format"\s*:\s*"(' + re.escape(REPORT_FORMAT.encode()) + b"|"
                             + re.escape(MANIFEST_FORMAT.encode()) + rb')"')
#: Bytes read to recognise a report or manifest.
_SNIFF_BYTES = 256


@dataclass
class Entry:
    """One document of a batch and what became of it."""

    document: Path
    output: Path
    ok: bool = False
    summary: str = ""
    error: str | None = "not run"
    seconds: float | None = None
    cpu_seconds: float | None = None
    worker: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "document": str(self.document),
            "output": str(self.output) if self.ok else None,
            "ok": self.ok,
            "error": None if self.ok else self.error,
            "summary": self.summary if self.ok else None,
            "seconds": None if self.seconds is None else round(self.seconds, 4),
            "cpu_seconds": None if self.cpu_seconds is None else round(self.cpu_seconds, 4),
            "worker": self.worker,
        }


@dataclass
class BatchResult:
    """A finished (or interrupted) batch."""

    entries: list[Entry]
    seconds: float
    cluster: str
    report: Path
    interrupted: bool = False

    @property
    def failed(self) -> int:
        return sum(1 for e in self.entries if not e.ok)


def _is_sketchforge_output(path: Path) -> bool:
    """A batch report or dataset manifest (by its leading ``format`` field), not a document."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(_SNIFF_BYTES)
    except OSError:
        return False  # unreadable: the job reports why
    return _NOT_A_DOCUMENT.match(head) is not None


def find_documents(paths: list[Path]) -> list[tuple[Path, Path]]:
    """The documents under ``paths``: (file, output stem relative to the output folder).

    A file named on the command line is a document whatever its suffix; in a folder (walked
    recursively in name order, hidden folders and files skipped), every ``*.json`` file except
    sketchforge's own batch reports and dataset manifests. A document named twice counts once.
    """
    found: list[tuple[Path, Path]] = []
    seen: set[str] = set()

    def add(path: Path, stem: Path) -> None:
        key = os.path.realpath(path)
        if key not in seen:
            seen.add(key)
            found.append((path, stem))

    for p in paths:
        if p.is_dir():
            for folder, dirs, files in os.walk(p):
                dirs[:] = sorted(d for d in dirs if not d.startswith("."))
                for name in sorted(files):
                    f = Path(folder) / name
                    if name.startswith(".") or f.suffix.lower() != ".json" or _is_sketchforge_output(f):
                        continue
                    rel = f.relative_to(p)
                    add(f, rel.parent / rel.stem)
        elif p.exists() or p.is_symlink():
            add(p, Path(p.stem))
        else:
            raise SketchforgeError(f"no such file or folder: {p}")
    if not found:
        where = ", ".join(str(p) for p in paths)
        raise SketchforgeError(f"no documents found under {where} (a folder's documents are its *.json files)")
    return found


def plan(paths: list[Path], out_dir: Path, fmt: str) -> list[Entry]:
    """Every document and its output, refused (before any work) when two documents would
    write one output or an output would overwrite an input."""
    entries = [Entry(doc, out_dir / stem.parent / f"{stem.name}.{fmt}") for doc, stem in find_documents(paths)]
    by_output: dict[str, Entry] = {}
    for e in entries:
        key = os.path.normcase(os.path.abspath(e.output))
        if key in by_output:
            raise SketchforgeError(
                f"{by_output[key].document} and {e.document} would both be written to {e.output}; "
                "export them in separate runs (or rename one)"
            )
        by_output[key] = e
    inputs = {os.path.realpath(e.document) for e in entries}
    for e in entries:
        if os.path.realpath(e.output) in inputs:
            raise ExportError(f"cannot write {e.output}: it is an input document; choose another --export-dir")
    return entries


def prepare_output_dir(out_dir: Path) -> None:
    """Make the output folder (and its parents); refuse a path that is a file."""
    if out_dir.exists() and not out_dir.is_dir():
        raise ExportError(f"cannot write into {out_dir}: it is a file, not a folder")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ExportError(f"cannot make the folder {out_dir}: {exc.strerror or exc}") from None
    check_target(out_dir / REPORT_NAME)


def write_report(result: BatchResult, fmt: str, size: int | None) -> None:
    """``OUT/batch-report.json``: every document, ok or its one-line error, and its time."""
    entries = result.entries
    body = {
        "format": REPORT_FORMAT,
        "version": 1,
        "export_format": fmt,
        "size": size,
        "cluster": result.cluster,
        "documents": len(entries),
        "ok": sum(1 for e in entries if e.ok),
        "failed": result.failed,
        "interrupted": result.interrupted,
        "seconds": round(result.seconds, 3),
        "results": [e.to_dict() for e in entries],
    }
    write_bytes_atomic(result.report, (json.dumps(body, indent=1, ensure_ascii=False) + "\n").encode("utf-8"))


def run_batch(entries: list[Entry], out_dir: Path, fmt: str, size: int, engine, progress) -> BatchResult:
    """Replay and export the documents of ``entries`` (:func:`plan`) into ``out_dir``
    (:func:`prepare_output_dir`) on ``engine`` (a started
    :class:`~sketchforge.batch.engine.Engine`), reporting to ``progress`` (a
    :class:`~sketchforge.batch.progress.ProgressBar` made for the count, or a factory
    ``progress(total)``). Writes the report even when interrupted (Ctrl+C), then re-raises."""
    from sketchforge.batch.jobs import replay_export, software
    from sketchforge.document.fileformat import read_regular_file

    bar = progress(len(entries)) if callable(progress) else progress
    expected = software()
    t0 = time.perf_counter()

    def fail(e: Entry, message: str) -> None:
        e.ok, e.error = False, message
        bar.advance(False)
        bar.line(f"sketchforge: failed: {_printable(message)}")

    def jobs() -> Iterator[tuple[Entry, tuple]]:
        for e in entries:
            try:
                raw = read_regular_file(e.document)
            except SketchforgeError as exc:  # unreadable, gone since the scan, too large
                fail(e, str(exc))
                continue
            yield e, (str(e.document), raw, str(e.output), fmt, size, expected)

    result = BatchResult(entries, 0.0, engine.where, out_dir / REPORT_NAME)
    try:
        for e, r in engine.run(replay_export, jobs()):
            if isinstance(r, BaseException):  # its worker died
                fail(e, f"{e.document}: {r}")
                continue
            e.seconds, e.cpu_seconds, e.worker = r.seconds, r.cpu_seconds, r.worker
            if not r.ok:
                fail(e, r.summary)
                continue
            try:
                e.output.parent.mkdir(parents=True, exist_ok=True)
                write_bytes_atomic(e.output, r.data)
            except (ExportError, OSError) as exc:
                fail(e, f"{e.document}: {exc}")
                continue
            e.ok, e.error, e.summary = True, None, r.summary
            bar.advance(True)
    except KeyboardInterrupt:
        result.interrupted = True
        for e in entries:
            if not e.ok and e.error == "not run":
                e.error = "not run: the batch was interrupted"
        raise
    finally:
        bar.close()
        result.seconds = time.perf_counter() - t0
        try:
            write_report(result, fmt, size if fmt == "png" else None)
        except SketchforgeError as exc:
            if not result.interrupted:
                raise ExportError(f"the batch ran but its report could not be written: {exc}") from None
    return result


def _printable(text: str) -> str:
    from sketchforge.errors import printable

    return printable(text)
