"""``sketchforge dataset``: samples for learning shape from shading, made on the batch engine.

Each sample (:mod:`.samples`: a shape and random edits from the plugins' dataset generators,
e.g. a random creature or a drawn shape with holes, random isophote
edits, a random light and a random installed reflectance model) is rendered from +z by the
project's renderer (:func:`sketchforge.geometry.gbuffer.front_surface`: the assembled model's
per-pixel normals, as ``sketchforge render`` shades them) and written as
``OUT/sample-NNNNNN.npz`` with its document ``OUT/sample-NNNNNN.json`` beside it (its journal,
without a snapshot: 12-17 kB instead of 0.4-0.6 MB, and replaying it recomputes the very
meshes); then ``OUT/manifest.json`` lists them all. Sample i's bytes depend only on the seed, i,
the size and the installed software (which the manifest records).

The ``.npz`` arrays (S = ``--size``):

``shading`` (S, S) float32
    max(0, R(n, l)) of the sample's model at each pixel inside the mask, 0 outside.
``normal`` (S, S, 3) float32
    Unit surface normal (x right, y up, z towards the viewer); 0 outside the mask.
``depth`` (S, S) float32
    Height of the visible surface towards the viewer, in pixels (so its finite differences
    match the normals: d depth / d column = -n_x / n_z, d depth / d row = n_y / n_z); 0 outside.
``mask`` (S, S) bool
    Pixels whose centre lies on the model.
``light`` (3,) float64
    Unit direction towards the light, z >= 0.
``model`` str
    The reflectance model's name.
``kind`` str
    The shape generator's name: ``"creature"``, ``"holes"`` (the built-ins) or a plugin's.
``scale`` float64, ``origin`` (2,) float64
    Pixels per document unit, and the document point (x, y) at the image's top-left corner:
    pixel (row r, column c) has its centre at x = origin[0] + (c + 0.5) / scale,
    y = origin[1] - (r + 0.5) / scale.
"""

from __future__ import annotations

import io
import json
import time
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from sketchforge.atomic import write_bytes_atomic
from sketchforge.batch.batch import MANIFEST_FORMAT
from sketchforge.batch.jobs import JobResult, check_software, one_line
from sketchforge.errors import ExportError, SketchforgeError

MANIFEST_NAME = "manifest.json"
#: Image margin, as ``sketchforge render``'s: the fraction of the image left empty per side.
MARGIN = 0.05
#: Every member of an .npz gets this time stamp (zip has no "none"), so bytes depend on data only.
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)


def npz_bytes(arrays: dict[str, np.ndarray]) -> bytes:
    """An ``.npz`` (what ``np.savez_compressed`` writes, members in name order) whose bytes
    depend only on the arrays: no time stamps."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(arrays):
            member = io.BytesIO()
            np.lib.format.write_array(member, np.asarray(arrays[name]), allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, member.getvalue())
    return buf.getvalue()


def render_sample(mesh, light: np.ndarray, model, size: int) -> dict[str, np.ndarray]:
    """The maps of one model seen from +z (see the module docstring).

    Parameters
    ----------
    mesh : Mesh
        The assembled model.
    light : (3,) float64
    model : ReflectanceModel
    size : int
    """
    from sketchforge.geometry.gbuffer import View, front_surface, reflectance_image
    from sketchforge.geometry.raster import check_raster_cost
    from sketchforge.geometry.reflectance import evaluate

    view = View.framing([mesh], size, size, MARGIN)
    check_raster_cost([mesh], view)
    maps = front_surface([mesh], view)
    # Every pixel is evaluated (a JAX model then compiles once per image size, not per sample).
    shading = reflectance_image(maps, light, lambda normals, towards: evaluate(model, normals, towards))
    return {
        "shading": shading.astype(np.float32),
        "normal": maps.normal,
        "depth": (maps.height * view.scale).astype(np.float32),
        "mask": maps.mask,
        "light": np.asarray(light, dtype=np.float64),
        "scale": np.array(view.scale, dtype=np.float64),
        "origin": np.array([view.x0, view.y1], dtype=np.float64),
    }


def sample_names(index: int, count: int) -> tuple[str, str]:
    """(npz name, document name) of sample ``index`` of ``count``."""
    stem = f"sample-{index:0{max(6, len(str(count - 1)))}d}"
    return f"{stem}.npz", f"{stem}.json"


def dataset_sample(seed: int, index: int, count: int, size: int, expected: tuple) -> JobResult:
    """The job: make sample ``index`` (:func:`.samples.make_sample`), render it, and return the
    ``.npz`` bytes (``data``), its document's bytes (``extra``) and its manifest entry
    (``record``)."""
    from sketchforge.batch.jobs import tune_malloc
    from sketchforge.batch.samples import make_sample
    from sketchforge.document import fileformat as ff

    tune_malloc()
    t0, c0 = time.perf_counter(), time.process_time()
    npz_name, doc_name = sample_names(index, count)
    try:
        check_software(expected)
        s = make_sample(seed, index)
        mesh = s.doc.export_mesh()
        arrays = render_sample(mesh, s.light, s.doc.host.reflectance_models[s.model], size)
        arrays["model"] = np.array(s.model)
        arrays["kind"] = np.array(s.kind)
        record = {
            "index": index,
            "npz": npz_name,
            "document": doc_name,
            "kind": s.kind,
            "model": s.model,
            "light": [float(v) for v in s.light],
            "layers": len(s.doc.layers),
            "holes": s.holes,
            "edits": s.edits,
            "vertices": int(mesh.n_vertices),
            "mask_pixels": int(arrays["mask"].sum()),
            "attempt": s.attempt,
        }
        data, doc_bytes = npz_bytes(arrays), ff.dumps(s.doc, snapshot=False)
    except Exception as exc:  # noqa: BLE001 - the sample's one line
        return JobResult(False, b"", one_line(exc, f"sample {index}"), time.perf_counter() - t0, time.process_time() - c0)
    return JobResult(True, data, npz_name, time.perf_counter() - t0, time.process_time() - c0, doc_bytes, record)


def prepare_dataset_dir(out_dir: Path) -> None:
    """Make ``out_dir``; refuse one that holds anything (a dataset never mixes with other files,
    and never overwrites any)."""
    if out_dir.exists():
        if not out_dir.is_dir():
            raise ExportError(f"cannot write into {out_dir}: it is a file, not a folder")
        if any(out_dir.iterdir()):
            raise ExportError(f"{out_dir} is not empty: write the dataset into a new or empty folder")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ExportError(f"cannot make the folder {out_dir}: {exc.strerror or exc}") from None


def manifest_bytes(seed: int, count: int, size: int, records: list[dict], failed: list[dict], software: tuple, models: list[str],
                   generators: dict | None = None) -> bytes:
    """The manifest: what made the dataset (``generators``: {"shape": [names], "edit": [names]},
    the dataset generators the samples were drawn from), and one entry per sample in index
    order."""
    body: dict[str, Any] = {
        "format": MANIFEST_FORMAT,
        "version": 1,
        "seed": seed,
        "count": count,
        "size": size,
        "models": models,
        "generators": generators or {},
        "lights": "hemisphere facing the viewer (z >= 0)",
        "software": {name: version for name, version in software},
        "arrays": {
            "shading": "(S, S) float32: max(0, R(n, l)) inside the mask, 0 outside",
            "normal": "(S, S, 3) float32: unit normal, x right, y up, z towards the viewer",
            "depth": "(S, S) float32: height towards the viewer in pixels",
            "mask": "(S, S) bool",
            "light": "(3,) float64: unit direction towards the light",
            "model": "str: the reflectance model",
            "kind": "str: the shape generator (creature, holes, or a plugin's)",
            "scale": "float64: pixels per document unit",
            "origin": "(2,) float64: document (x, y) at the top-left corner",
        },
        "samples": sorted(records, key=lambda r: r["index"]),
        "failed": sorted(failed, key=lambda r: r["index"]),
    }
    return (json.dumps(body, indent=1) + "\n").encode("utf-8")


def run_dataset(out_dir: Path, count: int, size: int, seed: int, engine, progress) -> tuple[int, int, float]:
    """Make ``count`` samples into ``out_dir`` (:func:`prepare_dataset_dir`) on ``engine``;
    returns (written, failed, seconds). The manifest is written last, so a folder with one is
    complete."""
    from sketchforge.batch.jobs import software
    from sketchforge.plugins.manager import default_host

    bar = progress(count) if callable(progress) else progress
    expected = software()
    from sketchforge.batch.samples import generators as installed_generators

    models = sorted(default_host().reflectance_models)
    shapes, edits = installed_generators(default_host())
    generators = {"shape": [g.name for g in shapes], "edit": [g.name for g in edits]}
    records: list[dict] = []
    failed: list[dict] = []
    t0 = time.perf_counter()

    def jobs() -> Iterator[tuple[int, tuple]]:
        for i in range(count):
            yield i, (seed, i, count, size, expected)

    try:
        for i, r in engine.run(dataset_sample, jobs()):
            message = f"sample {i}: {r}" if isinstance(r, BaseException) else (None if r.ok else r.summary)
            if message is None:
                npz_name, doc_name = sample_names(i, count)
                try:
                    write_bytes_atomic(out_dir / doc_name, r.extra)
                    write_bytes_atomic(out_dir / npz_name, r.data)
                except SketchforgeError as exc:
                    message = f"sample {i}: {exc}"
                else:
                    records.append(r.record)
                    bar.advance(True)
                    continue
            failed.append({"index": i, "error": message})
            from sketchforge.errors import printable

            bar.advance(False)
            bar.line(f"sketchforge: failed: {printable(message)}")
    finally:
        bar.close()
    write_bytes_atomic(out_dir / MANIFEST_NAME, manifest_bytes(seed, count, size, records, failed, expected, models,
                                                                 generators))
    return len(records), len(failed), time.perf_counter() - t0
