"""The sketchforge document file: JSON, saved atomically.

``{"format": "sketchforge", "version": 1, "light": [x, y, 0], "journal": [...],
"snapshot": {...}}``

- ``light``: the light at the start of the journal.
- ``journal``: command dicts, each with a ``"command"`` name, in order; each acts with the light
  current at its place (``set_light`` entries change it).
- ``snapshot`` (optional): the state after the journal: ``light`` and every layer (id, name,
  visible, closed, points, params, edits, mesh) and, when a plugin keeps document-level data
  (an animation), ``plugin_data``: {key: JSON value}. Mesh arrays are stored as base64 of their
  little-endian bytes, so a reopened file is bit-identical to the saved one.

Opening uses the snapshot (a file reopens exactly as saved even after the solvers change);
without one, the journal is replayed. :func:`replay` recomputes from the journal and
:func:`compare` reports where the two differ.
"""

from __future__ import annotations

import base64
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from sketchforge.atomic import write_bytes_atomic
from sketchforge.document.document import Document
from sketchforge.document.layer import Layer, Light
from sketchforge.errors import DocumentFormatError, ExportError, LimitError, SketchforgeError
from sketchforge.geometry.inflate_params import check_inflate_params
from sketchforge.geometry.mesh import Mesh

FORMAT_NAME = "sketchforge"
FORMAT_VERSION = 1
#: Journals longer than this are refused (each entry may run a solver).
MAX_JOURNAL_ENTRIES = 100_000
#: Files larger than this are refused before parsing.
MAX_FILE_BYTES = 512 * 1024 * 1024


# --- arrays ---------------------------------------------------------------------------------


def encode_array(a: np.ndarray) -> dict:
    a = np.ascontiguousarray(a)
    dtype = {"f": "float64", "i": "int64"}[a.dtype.kind]
    return {
        "dtype": dtype,
        "shape": list(a.shape),
        "data": base64.b64encode(a.astype("<" + dtype[0] + "8").tobytes()).decode("ascii"),
    }


def decode_array(d: Any, where: str) -> np.ndarray:
    if not isinstance(d, dict) or not {"dtype", "shape", "data"} <= set(d):
        raise DocumentFormatError(f"{where}: expected an array object with dtype, shape and data")
    dt = {"float64": "<f8", "int64": "<i8"}.get(d["dtype"]) if isinstance(d["dtype"], str) else None
    shape = d["shape"]
    if dt is None:
        raise DocumentFormatError(f"{where}: unsupported dtype {d['dtype']!r}")
    if not isinstance(shape, list) or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in shape):
        raise DocumentFormatError(f"{where}: bad shape {shape!r}")
    if not isinstance(d["data"], str):
        raise DocumentFormatError(f"{where}: data must be a base64 string")
    try:
        raw = base64.b64decode(d["data"], validate=True)
    except (ValueError, TypeError):
        raise DocumentFormatError(f"{where}: data is not valid base64") from None
    count = math.prod(shape)
    if len(raw) != count * 8:
        raise DocumentFormatError(f"{where}: data has {len(raw)} bytes, shape {shape} needs {count * 8}")
    return np.frombuffer(raw, dtype=dt).astype(np.float64 if dt == "<f8" else np.int64).reshape(shape)


def encode_mesh(m: Mesh) -> dict:
    out = {k: encode_array(getattr(m, k)) for k in ("V", "F", "boundary", "junction")}
    if m.holes:
        out["holes"] = [encode_array(h) for h in m.holes]
    return out


def decode_mesh(d: Any, where: str) -> Mesh:
    if not isinstance(d, dict):
        raise DocumentFormatError(f"{where}: a mesh must be an object")
    arrays = {k: decode_array(d.get(k), f"{where}.{k}") for k in ("V", "F", "boundary", "junction")}
    if not np.all(np.isfinite(arrays["V"])):
        raise DocumentFormatError(f"{where}.V: has non-finite coordinates")
    holes = d.get("holes", [])
    if not isinstance(holes, list):
        raise DocumentFormatError(f"{where}.holes: must be a list of arrays")
    arrays["holes"] = tuple(decode_array(h, f"{where}.holes[{i}]") for i, h in enumerate(holes))
    try:
        return Mesh(**arrays)
    except ValueError as exc:
        raise DocumentFormatError(f"{where}: {exc}") from None


# --- document <-> dict ----------------------------------------------------------------------


def _light_list(light: Light) -> list[float]:
    return [light.x, light.y, 0.0]


def _layer_to_dict(layer: Layer) -> dict:
    return {
        "id": layer.id,
        "name": layer.name,
        "visible": layer.visible,
        "closed": layer.closed,
        "points": None if layer.points is None else layer.points.tolist(),
        **({"holes": [h.tolist() for h in layer.holes]} if layer.holes else {}),
        "params": dict(layer.params),
        "edits": [dict(e) for e in layer.edits],
        "mesh": None if layer.mesh is None else encode_mesh(layer.mesh),
    }


def document_to_dict(doc: Document, snapshot: bool = True) -> dict:
    out: dict = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "light": _light_list(doc.initial_light),
        "journal": doc.journal(),
    }
    if snapshot:
        out["snapshot"] = {"light": _light_list(doc.light), "layers": [_layer_to_dict(l) for l in doc.layers]}
        keys = doc.plugin_data_keys
        if keys:
            out["snapshot"]["plugin_data"] = {k: doc.plugin_data(k) for k in keys}
    return out


def _parse_light(v: Any, where: str) -> Light:
    if not isinstance(v, list) or len(v) not in (2, 3) or not all(
        isinstance(x, (int, float)) and not isinstance(x, bool) for x in v
    ):
        raise DocumentFormatError(f"{where}: must be a list of 2 or 3 numbers")
    try:
        return Light.from_vector(v)
    except SketchforgeError as exc:
        raise DocumentFormatError(f"{where}: {exc}") from None


def _layer_from_dict(d: Any, where: str) -> Layer:
    if not isinstance(d, dict):
        raise DocumentFormatError(f"{where}: a layer must be an object")
    try:
        lid, name = d["id"], d["name"]
    except KeyError as exc:
        raise DocumentFormatError(f"{where}: missing field {exc.args[0]!r}") from None
    if not isinstance(lid, str) or not isinstance(name, str):
        raise DocumentFormatError(f"{where}: id and name must be strings")
    pts = d.get("points")
    if pts is not None:
        try:
            pts = np.array(pts, dtype=np.float64)
        except (TypeError, ValueError):
            raise DocumentFormatError(f"{where}.points: must be [x, y] pairs") from None
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise DocumentFormatError(f"{where}.points: must be [x, y] pairs")
    holes = d.get("holes", [])
    try:
        holes = [np.array(h, dtype=np.float64) for h in holes] if isinstance(holes, list) else None
    except (TypeError, ValueError):
        holes = None
    if holes is None or any(h.ndim != 2 or h.shape[1] != 2 for h in holes):
        raise DocumentFormatError(f"{where}.holes: must be a list of rings of [x, y] pairs")
    params = d.get("params", {})
    edits = d.get("edits", [])
    if not isinstance(params, dict) or not isinstance(edits, list) or not all(isinstance(e, dict) for e in edits):
        raise DocumentFormatError(f"{where}: params must be an object and edits a list of objects")
    try:
        params = check_inflate_params(params)
    except SketchforgeError as exc:
        raise DocumentFormatError(f"{where}.params: {exc}") from None
    visible, closed = d.get("visible", True), d.get("closed", False)
    if not isinstance(visible, bool) or not isinstance(closed, bool):
        raise DocumentFormatError(f"{where}: visible and closed must be true or false")
    mesh = d.get("mesh")
    mesh = None if mesh is None else decode_mesh(mesh, f"{where}.mesh")
    return Layer(id=lid, name=name, visible=visible, points=pts, closed=closed, params=params, mesh=mesh, edits=tuple(edits),
                 holes=tuple(holes))


def validate_header(data: Any, source: str) -> tuple[Light, list]:
    if not isinstance(data, dict):
        raise DocumentFormatError(f"{source}: not a sketchforge document (the top level is not an object)")
    if data.get("format") != FORMAT_NAME:
        raise DocumentFormatError(f"{source}: not a sketchforge document (field 'format' is {data.get('format')!r})")
    version = data.get("version")
    if not isinstance(version, int) or isinstance(version, bool):
        raise DocumentFormatError(f"{source}: field 'version' must be an integer")
    if version > FORMAT_VERSION:
        raise DocumentFormatError(
            f"{source}: written by a newer sketchforge (format version {version}); this one reads version {FORMAT_VERSION}"
        )
    if version < 1:
        raise DocumentFormatError(f"{source}: field 'version' must be >= 1")
    light = _parse_light(data.get("light", [1.0, 0.0, 0.0]), f"{source}: field 'light'")
    journal = data.get("journal", [])
    if not isinstance(journal, list):
        raise DocumentFormatError(f"{source}: field 'journal' must be a list")
    if len(journal) > MAX_JOURNAL_ENTRIES:
        raise LimitError(f"{source}: the journal has {len(journal)} entries; the limit is {MAX_JOURNAL_ENTRIES}")
    return light, journal


def document_from_dict(data: Any, source: str = "document", host=None, use_snapshot: bool = True) -> Document:
    """Validate and build a document. Uses the snapshot when there is one, else replays."""
    light, journal = validate_header(data, source)
    snap = data.get("snapshot") if use_snapshot else None
    if snap is None:
        return replay_journal(light, journal, source, host)
    if not isinstance(snap, dict) or not isinstance(snap.get("layers"), list):
        raise DocumentFormatError(f"{source}: field 'snapshot' must be an object with a 'layers' list")
    # Parse the journal too, so a bad entry is reported now rather than at the next save.
    doc = Document(host=host, light=light)
    for i, entry in enumerate(journal):
        try:
            doc.host.commands.from_dict(entry)
        except SketchforgeError as exc:
            raise DocumentFormatError(f"{source}: journal entry {i}: {exc}") from None
    layers = [_layer_from_dict(l, f"{source}: snapshot.layers[{i}]") for i, l in enumerate(snap["layers"])]
    ids = [l.id for l in layers]
    if len(set(ids)) != len(ids):
        raise DocumentFormatError(f"{source}: snapshot.layers has duplicate ids")
    cur_light = _parse_light(snap.get("light", data.get("light", [1.0, 0.0, 0.0])), f"{source}: snapshot.light")
    plugin_data = snap.get("plugin_data", {})
    if not isinstance(plugin_data, dict) or not all(isinstance(k, str) for k in plugin_data):
        raise DocumentFormatError(f"{source}: snapshot.plugin_data must be an object")
    doc.restore_state(layers, cur_light, light, journal, plugin_data)
    return doc


def replay_journal(light: Light, journal: list, source: str = "journal", host=None, progress=None) -> Document:
    """Run every journal entry on a new document. Raises DocumentFormatError naming the entry
    (the command's own error, e.g. a ContourError, is its ``__cause__``)."""
    doc = Document(host=host, light=light)
    for i, entry in enumerate(journal):
        try:
            cmd = doc.host.commands.from_dict(entry)
            cmd.do(doc)
        except SketchforgeError as exc:
            name = entry.get("command") if isinstance(entry, dict) else None
            # One documented type for "this file is bad"; the specific error stays as __cause__.
            raise DocumentFormatError(f"{source}: journal entry {i} ({name}): {exc}") from exc
        if progress is not None:
            progress(i + 1, len(journal))
    # Commands ran outside the undo stack: the replayed state is the new base (and clean).
    doc.initial_light = light
    doc.base_journal = [dict(e) for e in journal]
    return doc


def compare(a: Document, b: Document) -> list[str]:
    """Differences between two documents' states (empty when bit-identical)."""
    return a.differences(b)


# --- files ----------------------------------------------------------------------------------


def read_json(path) -> Any:
    path = Path(path)
    try:
        if path.is_dir():
            raise DocumentFormatError(f"cannot open {path}: it is a directory")
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise LimitError(f"cannot open {path}: {size} bytes is over the limit of {MAX_FILE_BYTES}")
        raw = path.read_bytes()
    except FileNotFoundError:
        raise DocumentFormatError(f"cannot open {path}: no such file") from None
    except PermissionError:
        raise DocumentFormatError(f"cannot open {path}: permission denied") from None
    except IsADirectoryError:
        raise DocumentFormatError(f"cannot open {path}: it is a directory") from None
    except OSError as exc:
        raise DocumentFormatError(f"cannot open {path}: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DocumentFormatError(f"cannot open {path}: not UTF-8 text (byte {exc.start})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise DocumentFormatError(f"cannot open {path}: invalid JSON at line {exc.lineno}, column {exc.colno} ({exc.msg})") from None
    except RecursionError:
        raise DocumentFormatError(f"cannot open {path}: JSON nested too deeply") from None


def load(path, host=None, use_snapshot: bool = True) -> Document:
    """Open a document file (snapshot if present, else replay)."""
    return document_from_dict(read_json(path), str(path), host=host, use_snapshot=use_snapshot)


def dumps(doc: Document, snapshot: bool = True) -> bytes:
    return json.dumps(document_to_dict(doc, snapshot), separators=(",", ":")).encode("utf-8")


def save(doc: Document, path, mark_clean: bool = True) -> None:
    """Atomic save; marks the undo stack clean on success."""
    try:
        write_bytes_atomic(path, dumps(doc))
    except ExportError as exc:
        raise ExportError(str(exc).replace("cannot write", "cannot save")) from None
    if mark_clean:
        doc.undo_stack.set_clean()
