"""The ``batch`` and ``dataset`` subcommands (their parsers and what they run).

Both run on :class:`~sketchforge.batch.engine.Engine`: a local Dask cluster by default,
``--scheduler tcp://HOST:PORT`` for an existing one. Bad arguments are refused in one line
before any cluster starts; each failed document or sample is one line; the exit status is 2
when any failed.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from sketchforge.errors import SketchforgeError, quote

#: Mesh formats named in the help (any installed exporter's suffix is accepted) and the image.
FORMATS = ("obj", "ply", "stl", "glb", "png")
MIN_SIZE, MAX_SIZE = 16, 8192
#: Samples a dataset run may ask for at once.
MAX_COUNT = 10_000_000


def add_parsers(sub: Any, whole_number: Callable[[str], int]) -> None:
    """Add ``batch`` and ``dataset`` to the CLI's subparsers."""
    b = sub.add_parser(
        "batch",
        help="replay every document under some paths and export each (on a Dask cluster)",
        description="Replay every document (a folder's *.json files, recursively) and export each to "
        "OUT/<name>.<format>, the bytes `replay DOC --export` writes (png: those of `render`).",
    )
    b.add_argument("paths", nargs="+", type=Path, metavar="PATH", help="documents, or folders of them")
    b.add_argument("--export-dir", required=True, type=Path, metavar="OUT", help="folder for the outputs and batch-report.json")
    b.add_argument("--format", required=True, metavar="FORMAT",
                   help="obj, ply, stl, glb (any exporter's suffix, e.g. gltf) or png")
    b.add_argument("--size", type=whole_number, default=None, help="png width and height in pixels (default 512)")
    _cluster_options(b, whole_number)
    b.set_defaults(func=cmd_batch)

    d = sub.add_parser(
        "dataset",
        help="write random samples for learning shape from shading (on a Dask cluster)",
        description="Write N random samples (a creature or a shape with holes, isophote edits, a light, "
        "a reflectance model): OUT/sample-NNNNNN.npz (shading, normal, depth, mask, light, model), "
        "its document beside it, and OUT/manifest.json. The same seed gives the same bytes.",
    )
    d.add_argument("out", type=Path, metavar="OUT", help="a new or empty folder")
    d.add_argument("--count", required=True, type=whole_number, help="number of samples")
    d.add_argument("--size", type=whole_number, default=128, help="image width and height in pixels (default 128)")
    d.add_argument("--seed", type=whole_number, default=0, help="random seed (default 0)")
    _cluster_options(d, whole_number)
    d.set_defaults(func=cmd_dataset)


def _cluster_options(p: argparse.ArgumentParser, whole_number: Callable[[str], int]) -> None:
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="run on this dask.distributed cluster (default: a local one)")
    p.add_argument("--workers", type=whole_number, default=None, help="worker processes of the local cluster (default: one per core)")


def _progress(noun: str) -> Callable[[int], Any]:
    from sketchforge.batch.progress import ProgressBar

    return lambda total: ProgressBar(total, noun)


def _check_size(size: int) -> None:
    if not MIN_SIZE <= size <= MAX_SIZE:
        raise SketchforgeError(f"--size must be between {MIN_SIZE} and {MAX_SIZE}, got {quote(size, 40)}")


def cmd_batch(args: argparse.Namespace) -> int:
    from sketchforge.batch.batch import plan, prepare_output_dir, run_batch
    from sketchforge.batch.engine import Engine
    from sketchforge.errors import printable
    from sketchforge.plugins.manager import default_host

    fmt = args.format.strip().lstrip(".").lower()
    if fmt == "png":
        size = 512 if args.size is None else args.size
        _check_size(size)
    else:
        if args.size is not None:
            raise SketchforgeError(f"--size is the PNG's size; it has no effect with --format {quote(fmt, 20)}")
        size = 0
        default_host().exporter_for(Path(f"x.{fmt}"))  # an unknown format, before any work
    engine = Engine(args.scheduler, args.workers)  # its arguments checked; nothing started
    entries = plan(list(args.paths), args.export_dir, fmt)
    prepare_output_dir(args.export_dir)
    with engine:
        result = run_batch(entries, args.export_dir, fmt, size, engine, _progress("documents"))
    n, failed = len(result.entries), result.failed
    print(f"exported {n - failed} of {n} documents to {printable(args.export_dir)} in {result.seconds:.1f} s on "
          f"{result.cluster}" + (f"; {failed} failed" if failed else "") + f" (report: {printable(result.report)})",
          file=sys.stderr)
    return 2 if failed else 0


def cmd_dataset(args: argparse.Namespace) -> int:
    from sketchforge.batch.dataset import MANIFEST_NAME, prepare_dataset_dir, run_dataset
    from sketchforge.batch.engine import Engine
    from sketchforge.errors import printable

    if not 1 <= args.count <= MAX_COUNT:
        raise SketchforgeError(f"--count must be between 1 and {MAX_COUNT:,}, got {quote(args.count, 40)}")
    _check_size(args.size)
    if args.seed < 0:
        raise SketchforgeError(f"--seed must be 0 or more, got {quote(args.seed, 40)}")
    engine = Engine(args.scheduler, args.workers)
    prepare_dataset_dir(args.out)
    with engine:
        where = engine.where
        written, failed, seconds = run_dataset(args.out, args.count, args.size, args.seed, engine, _progress("samples"))
    print(f"wrote {written} of {args.count} samples to {printable(args.out)} in {seconds:.1f} s on {where}"
          + (f"; {failed} failed" if failed else "") + f" (manifest: {printable(args.out / MANIFEST_NAME)})",
          file=sys.stderr)
    return 2 if failed else 0
