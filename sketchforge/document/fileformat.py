"""The sketchforge document file: JSON, saved atomically.

``{"format": "sketchforge", "version": 2, "light": [x, y, z], "journal": [...],
"snapshot": {...}}``

- ``version``: 2 since lights may leave the drawing plane (z > 0). A version 1 file keeps
  meaning what it meant: its lights lay in the plane, a z component was dropped, so reading it
  drops z from its ``light`` fields and its ``set_light`` entries (:func:`upgrade_v1`).
- ``light``: the light at the start of the journal.
- ``journal``: command dicts, each with a ``"command"`` name, in order; each acts with the light
  current at its place (``set_light`` entries change it).
- ``providers`` (optional, written since plugins record provenance): which plugin and version
  provided each command, reflectance model and solver the document uses
  (:mod:`sketchforge.document.provenance`); read to name missing plugins and solvers.
- ``snapshot`` (optional): the state after the journal: ``light`` and every layer (id, name,
  visible, closed, points, ``solver`` (its inflater) and its params, edits, mesh), the
  document's ``assembly`` ({"solver", "params"}, absent for the default) and, when a plugin
  keeps document-level data (an animation), ``plugin_data``: {key: JSON value}. Mesh arrays are stored as base64 of their
  little-endian bytes, so a reopened file is bit-identical to the saved one.

Opening uses the snapshot (a file reopens exactly as saved even after the solvers change);
without one, the journal is replayed. :func:`replay` recomputes from the journal and
:func:`compare` reports where the two differ.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import os
from types import MappingProxyType
from typing import Any

import numpy as np

from sketchforge.atomic import write_bytes_atomic
from sketchforge.document import provenance
from sketchforge.document.document import Document
from sketchforge.document.jsonfile import (  # noqa: F401 - re-exported: read through this module
    MAX_FILE_BYTES,
    MAX_INT_DIGITS,
    MAX_JSON_DEPTH,
    MAX_JSON_ITEMS,
    count_json_items,
    parse_json,
    read_json,
    read_regular_file,
    scan_items,
    text_memory,
)
from sketchforge.document.layer import Layer, Light
from sketchforge.errors import DocumentFormatError, ExportError, LimitError, SketchforgeError, quote
from sketchforge.geometry.mesh import Mesh
from sketchforge.solver_kinds import SOLVER_KINDS, SolverChoice

FORMAT_NAME = "sketchforge"
FORMAT_VERSION = 2
#: Before this version a light lay in the drawing plane: its z component was dropped.
FIRST_VERSION_WITH_3D_LIGHTS = 2
#: Journals longer than this are refused (each entry may run a solver).
MAX_JOURNAL_ENTRIES = 100_000


# --- arrays ---------------------------------------------------------------------------------


def encode_array(a: np.ndarray) -> dict:
    a = np.ascontiguousarray(a)
    dtype = {"f": "float64", "i": "int64"}[a.dtype.kind]
    return {
        "dtype": dtype,
        "shape": list(a.shape),
        "data": base64.b64encode(a.astype("<" + dtype[0] + "8").tobytes()).decode("ascii"),
    }


#: Per mesh field: (dtype, trailing dimensions). Snapshots are checked as strictly as the
#: journal: a float64 F would otherwise be reinterpreted as integers, a 100-dimensional or
#: [0, 1e20] shape would reach numpy.
_MESH_FIELDS = {"V": ("float64", (3,)), "F": ("int64", (3,)), "boundary": ("int64", ()), "junction": ("int64", ())}
#: Vertices or triangles of one snapshot mesh: generous above what inflation makes (200 000).
MAX_SNAPSHOT_ELEMENTS = 2_000_000


def decode_array(d: Any, where: str, dtype: str | None = None, trailing: tuple | None = None) -> np.ndarray:
    """A stored array. With ``dtype`` and ``trailing``, the stored dtype must be ``dtype`` and
    the shape ``(k, *trailing)`` with k <= MAX_SNAPSHOT_ELEMENTS."""
    if not isinstance(d, dict) or not {"dtype", "shape", "data"} <= set(d):
        raise DocumentFormatError(f"{where}: expected an array object with dtype, shape and data")
    dt = {"float64": "<f8", "int64": "<i8"}.get(d["dtype"]) if isinstance(d["dtype"], str) else None
    shape = d["shape"]
    if dt is None:
        raise DocumentFormatError(f"{where}: unsupported dtype {_short(d['dtype'])}")
    if dtype is not None and d["dtype"] != dtype:
        raise DocumentFormatError(f"{where}: dtype must be {dtype}, got {d['dtype']}")
    if (
        not isinstance(shape, list)
        or len(shape) > 8
        or not all(isinstance(s, int) and not isinstance(s, bool) and 0 <= s <= MAX_SNAPSHOT_ELEMENTS for s in shape)
    ):
        raise DocumentFormatError(f"{where}: bad shape {_short(shape)}")
    if trailing is not None and (len(shape) != 1 + len(trailing) or tuple(shape[1:]) != tuple(trailing)):
        want = ", ".join(["k"] + [str(t) for t in trailing])
        raise DocumentFormatError(f"{where}: shape must be [{want}], got {_short(shape)}")
    if not isinstance(d["data"], str):
        raise DocumentFormatError(f"{where}: data must be a base64 string")
    count = math.prod(shape)
    if len(d["data"]) != 4 * ((count * 8 + 2) // 3):
        raise DocumentFormatError(f"{where}: data has {len(d['data'])} base64 characters, shape {shape} needs {4 * ((count * 8 + 2) // 3)}")
    try:
        raw = base64.b64decode(d["data"], validate=True)
    except (ValueError, TypeError):
        raise DocumentFormatError(f"{where}: data is not valid base64") from None
    if len(raw) != count * 8:
        raise DocumentFormatError(f"{where}: data has {len(raw)} bytes, shape {shape} needs {count * 8}")
    return np.frombuffer(raw, dtype=dt).astype(np.float64 if dt == "<f8" else np.int64).reshape(shape)


def _short(v: Any, n: int = 60) -> str:
    text = repr(v)
    return text if len(text) <= n else text[: n - 3] + "..."


def encode_mesh(m: Mesh) -> dict:
    out = {k: encode_array(getattr(m, k)) for k in ("V", "F", "boundary", "junction")}
    if m.holes:
        out["holes"] = [encode_array(h) for h in m.holes]
    return out


def decode_mesh(d: Any, where: str) -> Mesh:
    """A snapshot mesh, validated: dtypes and shapes, finite coordinates within the drawing
    range, indices in range, no triangle of zero area in the drawing plane (the sculpt builds
    cotangent operators there), boundary and junction without repeats."""
    from sketchforge.geometry import guard

    if not isinstance(d, dict):
        raise DocumentFormatError(f"{where}: a mesh must be an object")
    arrays = {k: decode_array(d.get(k), f"{where}.{k}", *_MESH_FIELDS[k]) for k in _MESH_FIELDS}
    try:
        guard.mesh(arrays["V"], arrays["F"], f"{where}", planar=True)
    except SketchforgeError as exc:
        raise DocumentFormatError(str(exc)) from None
    n = len(arrays["V"])
    for k in ("boundary", "junction"):
        idx = arrays[k]
        if idx.size and (idx.min() < 0 or idx.max() >= n):
            raise DocumentFormatError(f"{where}.{k}: refers to a vertex outside 0..{n - 1}")
        if len(np.unique(idx)) != len(idx):
            raise DocumentFormatError(f"{where}.{k}: lists a vertex twice")
    holes = d.get("holes", [])
    if not isinstance(holes, list):
        raise DocumentFormatError(f"{where}.holes: must be a list of arrays")
    arrays["holes"] = tuple(decode_array(h, f"{where}.holes[{i}]", *_MESH_FIELDS["boundary"]) for i, h in enumerate(holes))
    for i, idx in enumerate(arrays["holes"]):
        if idx.size and (idx.min() < 0 or idx.max() >= n):
            raise DocumentFormatError(f"{where}.holes[{i}]: refers to a vertex outside 0..{n - 1}")
        if len(np.unique(idx)) != len(idx):
            raise DocumentFormatError(f"{where}.holes[{i}]: lists a vertex twice")
    try:
        return Mesh(**arrays)
    except ValueError as exc:
        raise DocumentFormatError(f"{where}: {exc}") from None


# --- document <-> dict ----------------------------------------------------------------------


def _light_list(light: Light) -> list[float]:
    return light.to_list()


def _layer_to_dict(layer: Layer) -> dict:
    return {
        "id": layer.id,
        "name": layer.name,
        "visible": layer.visible,
        "closed": layer.closed,
        "points": None if layer.points is None else layer.points.tolist(),
        **({"holes": [h.tolist() for h in layer.holes]} if layer.holes else {}),
        **({"solver": layer.solver} if layer.solver is not None else {}),
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
        if doc.assembly.to_dict():
            out["snapshot"]["assembly"] = doc.assembly.to_dict()
    out["providers"] = provenance.record(doc)
    return out


def _parse_light(v: Any, where: str, version: int = FORMAT_VERSION) -> Light:
    if not isinstance(v, list) or len(v) not in (2, 3) or not all(
        isinstance(x, (int, float)) and not isinstance(x, bool) for x in v
    ):
        raise DocumentFormatError(f"{where}: must be a list of 2 or 3 numbers")
    try:
        return Light.from_vector(v if version >= FIRST_VERSION_WITH_3D_LIGHTS else v[:2])
    except SketchforgeError as exc:
        raise DocumentFormatError(f"{where}: {exc}") from None


def check_solver_entry(host, entry: dict) -> None:
    """A journal entry (or stored edit) of a solver command that names its solver: that solver
    must be installed and accept the entry's ``params`` (its own check, one line naming the
    solver and the key). Entries that name none are checked when they run (the layer's solver
    decides). Raises SketchforgeError."""
    cls = host.commands._classes.get(entry.get("command")) if isinstance(entry.get("command"), str) else None
    kind = getattr(cls, "solver_kind", None)
    if kind is None or not isinstance(entry.get("solver"), str):
        return
    solver = host.solver(kind, entry["solver"])
    params = entry.get("params", {})
    host.solver_params(kind, solver, params if isinstance(params, dict) else {})


def _check_edits(edits: list, where: str, registry, host=None) -> None:
    """Each stored sculpt edit must be a journal entry of an edit command (one that can be
    re-applied) that parses, with an optional ``light`` of 3 finite numbers, and parameters its
    solver accepts: a garbage edit would otherwise be accepted and fail at the next parameter
    change."""
    from sketchforge.document.commands import Command

    for i, e in enumerate(edits):
        at = f"{where}.edits[{i}]"
        try:
            cls = registry.get(e.get("command")) if isinstance(e.get("command"), str) else None
            if cls is None:
                raise DocumentFormatError("needs a string field 'command'")
            if getattr(cls.reapply, "__func__", None) is Command.reapply.__func__:
                raise DocumentFormatError(f"{cls.name!r} is not a sculpt edit")
            registry.from_dict(e)
            if host is not None:
                check_solver_entry(host, e)
        except SketchforgeError as exc:
            raise DocumentFormatError(f"{at}: {exc}") from None
        if "light" in e:
            lv = e["light"]
            # The light the edit used, as it used it (a 3-vector: in-plane edits since the
            # first version, z > 0 since lights may leave the plane).
            if not (
                isinstance(lv, list)
                and len(lv) == 3
                and all(isinstance(x, float) and math.isfinite(x) for x in lv)
                and (math.hypot(lv[0], lv[1]) > 0.5 or (lv[2] >= 0.0 and math.hypot(*lv) > 0.5))
            ):
                raise DocumentFormatError(f"{at}.light: must be a unit direction of 3 finite numbers")


def _layer_from_dict(d: Any, where: str, registry=None, host=None) -> Layer:
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
        except (TypeError, ValueError, OverflowError):
            raise DocumentFormatError(f"{where}.points: must be [x, y] pairs of finite numbers") from None
        if pts.ndim != 2 or pts.shape[1] != 2 or not np.isfinite(pts).all():
            raise DocumentFormatError(f"{where}.points: must be [x, y] pairs of finite numbers")
    holes = d.get("holes", [])
    try:
        holes = [np.array(h, dtype=np.float64) for h in holes] if isinstance(holes, list) else None
    except (TypeError, ValueError, OverflowError):
        holes = None
    if holes is None or any(h.ndim != 2 or h.shape[1] != 2 or not np.isfinite(h).all() for h in holes):
        raise DocumentFormatError(f"{where}.holes: must be a list of rings of [x, y] pairs of finite numbers")
    params = d.get("params", {})
    edits = d.get("edits", [])
    if not isinstance(params, dict) or not isinstance(edits, list) or not all(isinstance(e, dict) for e in edits):
        raise DocumentFormatError(f"{where}: params must be an object and edits a list of objects")
    solver = d.get("solver")
    if solver is not None and not isinstance(solver, str):
        raise DocumentFormatError(f"{where}.solver: must be the name of an inflater (a string)")
    if solver is None and d.get("mesh") is not None:
        # Written before inflaters had names: only the built-in existed.
        solver = SOLVER_KINDS["inflate"].default
    if host is not None and (solver is not None or params):
        try:
            inflater = host.solver("inflate", solver)
            params = host.solver_params("inflate", inflater, params)
        except SketchforgeError as exc:
            raise DocumentFormatError(f"{where}.params: {exc}") from None
    visible, closed = d.get("visible", True), d.get("closed", False)
    if not isinstance(visible, bool) or not isinstance(closed, bool):
        raise DocumentFormatError(f"{where}: visible and closed must be true or false")
    if registry is not None:
        _check_edits(edits, where, registry, host)
    mesh = d.get("mesh")
    mesh = None if mesh is None else decode_mesh(mesh, f"{where}.mesh")
    return Layer(id=lid, name=name, visible=visible, points=pts, closed=closed, params=params, mesh=mesh, edits=tuple(edits),
                 holes=tuple(holes), solver=solver)


def _flatten_set_light(entry: Any, depth: int = 0) -> Any:
    """A version 1 journal entry as it was read then: a ``set_light`` direction's z dropped
    (also inside macros). Anything malformed is left for the command's own check."""
    if not isinstance(entry, dict) or depth > MAX_JSON_DEPTH:
        return entry
    d = entry.get("direction")
    # z = 0 means the same in both versions: such entries (all the app ever wrote) stay as written.
    if entry.get("command") == "set_light" and isinstance(d, list) and len(d) == 3 and d[2] != 0:
        return {**entry, "direction": d[:2]}
    if entry.get("command") == "macro" and isinstance(entry.get("children"), list):
        return {**entry, "children": [_flatten_set_light(c, depth + 1) for c in entry["children"]]}
    return entry


def upgrade_v1(journal: list) -> list:
    """The journal of a version 1 file in today's terms: every light lay in the drawing plane
    then (``Light`` dropped z), so a ``set_light`` entry with z != 0 keeps only [x, y], which
    gives the very light it gave, bit for bit. Stored sculpt edits' ``light`` was always used as the 3-vector
    it is and needs nothing."""
    return [_flatten_set_light(e) for e in journal]


def validate_header(data: Any, source: str) -> tuple[Light, list]:
    if not isinstance(data, dict):
        raise DocumentFormatError(f"{source}: not a sketchforge document (the top level is not an object)")
    if data.get("format") != FORMAT_NAME:
        raise DocumentFormatError(f"{source}: not a sketchforge document (field 'format' is {quote(data.get('format'))})")
    version = data.get("version")
    if not isinstance(version, int) or isinstance(version, bool):
        raise DocumentFormatError(f"{source}: field 'version' must be an integer")
    if version > FORMAT_VERSION:
        raise DocumentFormatError(
            f"{source}: written by a newer sketchforge (format version {version}); this one reads version {FORMAT_VERSION}"
        )
    if version < 1:
        raise DocumentFormatError(f"{source}: field 'version' must be >= 1")
    light = _parse_light(data.get("light", [1.0, 0.0, 0.0]), f"{source}: field 'light'", version)
    journal = data.get("journal", [])
    if not isinstance(journal, list):
        raise DocumentFormatError(f"{source}: field 'journal' must be a list")
    if len(journal) > MAX_JOURNAL_ENTRIES:
        raise LimitError(f"{source}: the journal has {len(journal)} entries; the limit is {MAX_JOURNAL_ENTRIES}")
    if version < FIRST_VERSION_WITH_3D_LIGHTS:
        journal = upgrade_v1(journal)
    return light, journal


def document_from_dict(data: Any, source: str = "document", host=None, use_snapshot: bool = True) -> Document:
    """Validate and build a document on ``host`` (its plugin host: required). Uses the snapshot
    when there is one, else replays."""
    if host is None:
        raise TypeError("document_from_dict needs the plugin host: document_from_dict(data, source, host=host)")
    light, journal = validate_header(data, source)
    provenance.check_available(data, host, source)  # every missing plugin, in one message
    snap = data.get("snapshot") if use_snapshot else None
    if snap is None:
        return replay_journal(light, journal, source, host)
    if not isinstance(snap, dict) or not isinstance(snap.get("layers"), list):
        raise DocumentFormatError(f"{source}: field 'snapshot' must be an object with a 'layers' list")
    from sketchforge.document.document import MAX_LAYERS

    if len(snap["layers"]) > MAX_LAYERS:
        raise LimitError(f"{source}: the snapshot has {len(snap['layers']):,} layers; a document holds at most {MAX_LAYERS}")
    # Parse the journal too, so a bad entry is reported now rather than at the next save.
    doc = Document(host=host, light=light)
    for i, entry in enumerate(journal):
        try:
            doc.host.commands.from_dict(entry)
            for e in provenance._entries([entry]):
                check_solver_entry(doc.host, e)
        except SketchforgeError as exc:
            raise DocumentFormatError(f"{source}: journal entry {i}: {exc}") from None
    layers = [_layer_from_dict(l, f"{source}: snapshot.layers[{i}]", doc.host.commands, doc.host)
              for i, l in enumerate(snap["layers"])]
    ids = [l.id for l in layers]
    if len(set(ids)) != len(ids):
        raise DocumentFormatError(f"{source}: snapshot.layers has duplicate ids")
    cur_light = _parse_light(snap.get("light", data.get("light", [1.0, 0.0, 0.0])), f"{source}: snapshot.light",
                             data["version"])
    plugin_data = snap.get("plugin_data", {})
    if not isinstance(plugin_data, dict) or not all(isinstance(k, str) for k in plugin_data):
        raise DocumentFormatError(f"{source}: snapshot.plugin_data must be an object")
    doc.host.validate_plugin_data(plugin_data, f"{source}: snapshot")  # the limits the plugins' commands keep
    assembly = _assembly_from_dict(snap.get("assembly"), f"{source}: snapshot.assembly", doc.host)
    doc.restore_state(layers, cur_light, light, journal, plugin_data, assembly)
    return doc


def _assembly_from_dict(d: Any, where: str, host) -> SolverChoice:
    """The document's assembler choice from a snapshot (absent: the default)."""
    if d is None:
        return SolverChoice()
    if not isinstance(d, dict) or set(d) - {"solver", "params"}:
        raise DocumentFormatError(f"{where}: must be an object with 'solver' and 'params'")
    solver, params = d.get("solver"), d.get("params", {})
    if (solver is not None and not isinstance(solver, str)) or not isinstance(params, dict):
        raise DocumentFormatError(f"{where}: 'solver' must be a name and 'params' an object")
    try:
        host.solver_params("assemble", host.solver("assemble", solver), params)
    except SketchforgeError as exc:
        raise DocumentFormatError(f"{where}: {exc}") from None
    return SolverChoice(solver, MappingProxyType(dict(params)))


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
            name = name if isinstance(name, str) and len(name) <= 80 else quote(name)
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


# --- files (read through jsonfile's bounds) --------------------------------------------------


def load(path, host=None, use_snapshot: bool = True, info: dict | None = None) -> Document:
    """Open a document file (snapshot if present, else replay). ``info``: see :func:`read_json`."""
    return document_from_dict(read_json(path, info=info), str(path), host=host, use_snapshot=use_snapshot)


def dumps(doc: Document, snapshot: bool = True) -> bytes:
    return json.dumps(document_to_dict(doc, snapshot), separators=(",", ":")).encode("utf-8")


def save(doc: Document, path, mark_clean: bool = True) -> tuple:
    """Atomic save; marks the undo stack clean on success. Returns the file's stamp (see
    :func:`stamp_of`): a window compares it with the file before its next save."""
    data = dumps(doc)
    try:
        written = write_bytes_atomic(path, data)
    except ExportError as exc:
        raise ExportError(str(exc).replace("cannot write", "cannot save")) from None
    if mark_clean:
        doc.undo_stack.set_clean()
    return stamp_of(written, hashlib.sha256(data).hexdigest())


def stamp_of(st: os.stat_result, sha256: str) -> tuple:
    """What a window remembers of its file once it opened or saved it: its identity and times
    (device, inode, size, modification time in ns, from the very descriptor that read or wrote
    it) and the SHA-256 of its contents. :func:`changed_on_disk` compares a later look."""
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, sha256)


def changed_on_disk(path, stamp: tuple | None) -> tuple[bool, tuple | None]:
    """Whether ``path`` holds other contents than when ``stamp`` was taken (another window or
    program saved it, or replaced it), and the stamp to keep. Same identity and times: not
    changed, nothing read. Otherwise the contents decide (a ``touch`` or a copy of the same
    bytes is no change). A file that is gone, or no stamp, is no change (a save loses nobody's
    work). Never raises."""
    if stamp is None:
        return False, None
    try:
        st = os.stat(path)
    except OSError:
        return False, stamp
    if (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns) == stamp[:4]:
        return False, stamp
    try:
        digest = hashlib.sha256(read_regular_file(path)).hexdigest()
    except SketchforgeError:
        return True, stamp  # unreadable now (too big, not a file): not what this window saved
    if digest == stamp[4]:
        return False, stamp_of(st, digest)
    return True, stamp
