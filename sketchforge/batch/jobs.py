"""What a worker runs: one document replayed and exported, as bytes.

A job gets the document's bytes (not its path) and returns the output's bytes (not a file), so a
worker on another machine needs no shared folder: the process that asked reads the inputs and
writes the outputs. Each worker process keeps its plugin host, imports and compiled JAX
functions from one job to the next (:func:`sketchforge.plugins.manager.default_host` is built
once per process), so only a worker's first job pays for them.

A job never raises for a bad document: its one-line error comes back in the result, so the
other documents go on. Only a worker that dies (a native crash) loses its job, which the engine
then reports as such.
"""

from __future__ import annotations

import ctypes
import os
import platform
import socket
import time
from dataclasses import dataclass, field
from functools import cache
from importlib import metadata
from pathlib import Path

from sketchforge.errors import SketchforgeError, shorten

#: Distributions whose versions decide the bytes a replay writes (with the plugins').
LIBRARIES = ("sketchforge", "numpy", "scipy", "jax", "jaxlib", "libigl", "triangle", "shapely", "osqp")
#: The image format a batch can write besides the exporters' mesh formats.
PNG = "png"


def this_worker() -> str:
    """This process as a job's result names it: ``host:pid``."""
    return f"{socket.gethostname()}:{os.getpid()}"


@dataclass(frozen=True)
class JobResult:
    """What one job sends back.

    Attributes
    ----------
    ok : bool
    data : bytes
        The output file's bytes (empty when not ok).
    summary : str
        One line on the output ("15992 vertices, 31976 triangles"); the error when not ok.
    seconds : float
        Wall time the worker spent on the job.
    cpu_seconds : float
        CPU time of the worker process during the job.
    extra : bytes
        A second file's bytes where a job writes two (a dataset sample's document); else empty.
    record : dict
        What the job reports besides (a dataset sample's manifest entry); else empty.
    worker : str
        ``host:pid`` of the worker process that ran it.
    """

    ok: bool
    data: bytes
    summary: str
    seconds: float
    cpu_seconds: float
    extra: bytes = b""
    record: dict | None = None
    worker: str = field(default_factory=this_worker)


@cache
def tune_malloc() -> None:
    """Undo, in a Dask worker, the cost of its nanny's ``MALLOC_TRIM_THRESHOLD_=65536``.

    Setting that variable also stops glibc from raising its mmap threshold (128 KiB) as a
    process frees large blocks, so every array above it is mapped and unmapped afresh, page
    faults and all: a replay then costs about 1.5x its CPU time (measured on random creatures:
    0.54 s per document against 0.35 s in one process, and 0.36 s once the variable is unset).
    Where it is set, the thresholds go where glibc's own adjustment would take them: mmap at
    32 MiB (its ceiling on 64-bit machines) and trim at twice that."""
    if "MALLOC_TRIM_THRESHOLD_" not in os.environ:
        return
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, 32 << 20)  # M_MMAP_THRESHOLD
        libc.mallopt(-1, 64 << 20)  # M_TRIM_THRESHOLD
    except (OSError, AttributeError):  # not glibc: nothing to undo
        pass


@cache
def software() -> tuple[tuple[str, str], ...]:
    """(name, version) of everything whose version decides an output's bytes, in a fixed
    order: Python, the machine's architecture, :data:`LIBRARIES` and each loaded plugin."""
    from sketchforge.plugins.manager import CORE, default_host

    out = [("python", platform.python_version()), ("machine", platform.machine())]
    for lib in LIBRARIES:
        try:
            out.append((lib, metadata.version(lib)))
        except metadata.PackageNotFoundError:
            out.append((lib, "not installed"))
    host = default_host()
    for name in host.plugin_names():
        if name != CORE:
            out.append((f"plugin {name!r}", host.provider_version(name) or "registered by hand"))
    return tuple(out)


def software_difference(mine: tuple, theirs: tuple) -> str | None:
    """The first difference between two :func:`software` lists, in words ("plugin 'strips'
    0.2.0 here, not installed there"), or None when they are the same."""
    a, b = dict(mine), dict(theirs)
    for name in list(a) + [n for n in b if n not in a]:
        if a.get(name) != b.get(name):
            return f"{name} {a.get(name, 'not installed')} here, {b.get(name, 'not installed')} there"
    return None


def check_software(expected: tuple) -> None:
    """Refuse to run on a worker whose software differs from the client's (its outputs could
    differ in their bytes)."""
    diff = software_difference(expected, software())
    if diff is not None:
        raise SketchforgeError(
            f"this worker's software differs from the client's ({diff}): its output could differ; "
            "install the same versions on every worker"
        )


def one_line(exc: BaseException, source: str) -> str:
    """An error as one line that names the document."""
    if isinstance(exc, SketchforgeError):
        text = str(exc)
    else:  # a bug: say so, with what it was
        text = f"internal error: {type(exc).__name__}: {exc}"
    text = " ".join(text.split())
    if source not in text:
        text = f"{source}: {text}"
    return shorten(text, 1000)


def replay_document(raw: bytes, source: str):
    """Replay a document's journal as ``sketchforge replay`` does (every missing plugin named at
    once, then each entry in order) and return the Document."""
    from sketchforge.document import fileformat as ff
    from sketchforge.document.provenance import check_available
    from sketchforge.plugins.manager import default_host

    host = default_host()
    data = ff.parse_json(raw, source)
    light, journal = ff.validate_header(data, source)
    check_available(data, host, source)
    return ff.replay_journal(light, journal, source, host=host)


def render_png(doc, source: str, size: int) -> tuple[bytes, str]:
    """PNG bytes of the document's top view as ``sketchforge render DOC --size N`` draws it."""
    from sketchforge.geometry.raster import encode_png, render_top

    meshes = [layer.mesh for layer in doc.layers if layer.visible and layer.mesh is not None]
    if not meshes:
        raise SketchforgeError(f"{source}: no visible layer with a mesh to render")
    img = render_top(meshes, doc.light.direction, size=size)
    return encode_png(img), f"{img.shape[1]}x{img.shape[0]}"


def replay_export(source: str, raw: bytes, output: str, fmt: str, size: int, expected: tuple) -> JobResult:
    """Replay one document and export it: the bytes ``sketchforge replay DOC --export OUTPUT``
    writes (``fmt`` a mesh format), or with ``fmt`` "png" those of ``sketchforge render DOC
    --png OUTPUT --size SIZE`` on the replayed document.

    Parameters
    ----------
    source : str
        The document's path as the user named it (for messages).
    raw : bytes
        The document file's bytes.
    output : str
        The output's path as the client will write it (its suffix picks the exporter; messages
        name it); nothing is written here.
    fmt : str
    size : int
        PNG width and height in pixels.
    expected : tuple
        The client's :func:`software`.
    """
    tune_malloc()
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        check_software(expected)
        doc = replay_document(raw, source)
        if fmt == PNG:
            data, summary = render_png(doc, source, size)
        else:
            from sketchforge.plugins.export import export_bytes
            from sketchforge.plugins.manager import default_host

            data, summary = export_bytes(default_host(), Path(output), doc=doc)
    except Exception as exc:  # noqa: BLE001 - every failure is this document's one line
        return JobResult(False, b"", one_line(exc, source), time.perf_counter() - t0, time.process_time() - c0)
    return JobResult(True, data, summary, time.perf_counter() - t0, time.process_time() - c0)


def warm_up() -> str:
    """Build the worker's plugin host (imports every plugin) before its first job; returns
    the worker's ``host:pid``."""
    tune_malloc()
    software()
    return this_worker()
