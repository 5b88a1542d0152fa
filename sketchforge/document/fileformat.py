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
import re
import stat
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from sketchforge.atomic import write_bytes_atomic
from sketchforge.document import provenance
from sketchforge.document.document import Document
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


# --- files ----------------------------------------------------------------------------------


#: Nesting of JSON arrays and objects: a real document needs about 40 (macros of macros).
MAX_JSON_DEPTH = 100
#: JSON items (values and object keys) one file may hold. The byte cap alone does not bound
#: memory: each item costs the parser 40-80 bytes however short its text, so 60 MB of
#: ``[],`` grew past 3 GB (issue 38). With this many, the worst kind of item and a file at the
#: byte cap, opening stays under 2 GB; a real document needs far fewer (examples/creature.json,
#: whose meshes are base64 strings: 1 600; 100 strokes of 20 000 points: 6 million).
MAX_JSON_ITEMS = 8_000_000
#: Item boundaries outside strings: every value or key but the top-level one follows one of
#: these, so their count (plus one) bounds the items a parse builds.
_ITEM_MARKS = (b",", b":", b"[", b"{")
#: A string (skipped whole, escapes included; an unterminated one runs to the end), or a run
#: of item marks.
_SCAN = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*(?:"|\Z)|[,:\[{]+', re.DOTALL)
#: Digits of a JSON integer: no field of a document needs more (coordinates above 1e308
#: cannot even be a float).
MAX_INT_DIGITS = 308


def _parse_int(text: str) -> int:
    digits = len(text.lstrip("-"))
    if digits > MAX_INT_DIGITS:
        raise DocumentFormatError(f"an integer of {digits} digits is too large (at most {MAX_INT_DIGITS} digits)")
    return int(text)


def _parse_constant(name: str):
    raise DocumentFormatError(f"{name} is not a number a document may contain (numbers must be finite)")


def _check_depth(data: Any, limit: int = MAX_JSON_DEPTH) -> None:
    # Iterative, one level at a time: a recursive walk would hit the very recursion limit this
    # check is for, and a stack of (value, depth) pairs cost 70 bytes per container.
    level, depth = [data], 1
    while level:
        nested = []
        for v in level:
            if isinstance(v, dict):
                nested.extend(x for x in v.values() if isinstance(x, (dict, list)))
            elif isinstance(v, list):
                nested.extend(x for x in v if isinstance(x, (dict, list)))
        if nested and depth >= limit:
            raise LimitError(f"JSON nested more than {limit} levels deep")
        level, depth = nested, depth + 1


#: Python stores a whole string 1, 2 or 4 bytes a character, by its widest one: a UTF-8 lead
#: byte C4-EF or a ``\\uXXXX`` escape above 00FF makes 2, F0 and up or an escaped surrogate
#: makes 4. One emoji in 500 MB of ASCII made the text 2 GB, and the string parsed from it
#: 2 GB more (issue 38). (An escaped backslash before "u" is counted too: an overestimate.)
_ESCAPE_4 = re.compile(rb"\\u[dD][89abAB]")
_ESCAPE_2 = re.compile(rb"\\u(?:0[1-9a-fA-F]|[1-9a-fA-F][0-9a-fA-F])")
_BLOCK = 1 << 24


def text_memory(raw: bytes) -> int:
    """An upper bound of the bytes Python needs for the text of ``raw`` (UTF-8), and so for
    all the strings parsed from it: its characters times the widest one's storage size (1, 2
    or 4 bytes). Scans in 16 MB blocks with numpy and two regexes with a literal prefix: about
    a second for 512 MB."""
    width = 1
    view = np.frombuffer(raw, dtype=np.uint8)
    if not raw.isascii():
        top = max(int(view[i : i + _BLOCK].max()) for i in range(0, len(view), _BLOCK))
        width = 4 if top >= 0xF0 else 2 if top >= 0xC4 else 1
    if width < 4 and _ESCAPE_4.search(raw):
        width = 4
    elif width < 2 and _ESCAPE_2.search(raw):
        width = 2
    if width == 1:
        return len(raw)
    follow = sum(int(np.count_nonzero((view[i : i + _BLOCK] & 0xC0) == 0x80)) for i in range(0, len(view), _BLOCK))
    return width * (len(raw) - follow)


def count_json_items(raw: bytes, limit: int | None = None) -> int:
    """How many items (values and object keys) parsing ``raw`` can build: one plus the commas,
    colons, ``[`` and ``{`` outside strings; counting stops once it passes ``limit``.

    First a bound from ``bytes.count`` (a fraction of a second for 512 MB); only when that
    passes ``limit`` (a bomb, or marks inside strings) are strings skipped, item by item, until
    the count passes ``limit``, so the scan costs at most about ``limit`` steps. Two strings
    with no mark between them cannot be JSON: the scan stops there, since the parser fails at
    or before that point, having built no more than what was counted. Never builds an item.

    Parameters
    ----------
    raw : bytes
        The file's UTF-8 text (multi-byte characters never contain an ASCII byte).
    limit : int or None
        Default :data:`MAX_JSON_ITEMS`.

    Returns
    -------
    int
        The count, exact up to ``limit + 1`` when the quick bound passed ``limit``.
    """
    limit = MAX_JSON_ITEMS if limit is None else limit
    bound = 1 + sum(raw.count(m) for m in _ITEM_MARKS)
    return bound if bound <= limit else scan_items(raw, limit)


def scan_items(raw: bytes, limit: int) -> int:
    """:func:`count_json_items`' exact count, strings skipped; it stops once past ``limit``."""
    count, strings = 1, 0
    for m in _SCAN.finditer(raw):
        if raw[m.start()] == 0x22:  # '"'
            strings += 1
            if strings > count:
                break  # not JSON from here on (see above)
        else:
            count += m.end() - m.start()
            if count > limit:
                break
    return count


def read_regular_file(path, limit: int | None = None, info: dict | None = None) -> bytearray:
    """The bytes of ``path`` (a bytearray), a regular file of at most ``limit`` bytes. A FIFO, a
    device (``/dev/zero``), a socket or a directory is refused before reading (opening a FIFO does not
    block: O_NONBLOCK), and at most ``limit + 1`` bytes are ever read, so a file that grows
    while being read cannot exhaust memory. With ``info`` (a dict), ``info["stat"]`` is the
    file's ``fstat`` as it was opened. Raises DocumentFormatError or LimitError."""
    path = Path(path)
    limit = MAX_FILE_BYTES if limit is None else limit
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise DocumentFormatError(f"cannot open {path}: no such file") from None
    except PermissionError:
        raise DocumentFormatError(f"cannot open {path}: permission denied") from None
    except IsADirectoryError:
        raise DocumentFormatError(f"cannot open {path}: it is a directory") from None
    except OSError as exc:
        raise DocumentFormatError(f"cannot open {path}: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        if info is not None:
            info["stat"] = st
        if stat.S_ISDIR(st.st_mode):
            raise DocumentFormatError(f"cannot open {path}: it is a directory")
        if not stat.S_ISREG(st.st_mode):
            raise DocumentFormatError(f"cannot open {path}: not a regular file (a pipe, device or socket)")
        if st.st_size > limit:
            raise LimitError(f"cannot open {path}: {st.st_size} bytes is over the limit of {limit}")
        # One buffer of the announced size (and a byte more, to notice growth), filled in
        # place: a list of chunks joined at the end held the file twice.
        buf, total = bytearray(min(st.st_size, limit) + 1), 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 22, limit + 1 - total))
            if not chunk:
                break
            if total + len(chunk) > len(buf):  # the file grew while being read
                buf.extend(bytes(total + len(chunk) - len(buf)))  # still at most limit + 1
            buf[total : total + len(chunk)] = chunk
            total += len(chunk)
        if total > limit:
            raise LimitError(f"cannot open {path}: more than {limit} bytes, the limit")
        del buf[total:]
        return buf
    except OSError as exc:
        raise DocumentFormatError(f"cannot open {path}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


def read_json(path, info: dict | None = None) -> Any:
    """The JSON value of the document file ``path``, through every bound (size, items, text
    memory, nesting). With ``info`` (a dict): ``info["stat"]``, the file's fstat, and
    ``info["sha256"]``, the digest of the very bytes parsed (the app tells later whether the
    file changed on disk since, :func:`changed_on_disk`)."""
    path = Path(path)
    raw = read_regular_file(path, info=info)
    if info is not None:
        info["sha256"] = hashlib.sha256(raw).hexdigest()
    box = [raw]
    del raw  # _parse holds the only reference, and drops it before the parse
    return _parse(box, path)


def parse_json(raw: bytes, path) -> Any:
    """A document file's bytes as JSON, with the checks and one-line errors of :func:`read_json`
    (``path`` names the file in them): for bytes read elsewhere (a batch worker on another
    machine gets the document's bytes, not its path)."""
    return _parse([raw], path)


def _parse(box: list, path) -> Any:
    """The JSON of the bytes ``box[0]`` (taken out of the list, so that they can be freed
    before the parse builds its objects), through every bound."""
    raw = box.pop()
    if len(raw) > MAX_FILE_BYTES:
        raise LimitError(f"cannot open {path}: {len(raw)} bytes is over the limit of {MAX_FILE_BYTES}")
    items = count_json_items(raw)
    if items > MAX_JSON_ITEMS:
        raise LimitError(
            f"cannot open {path}: it holds more than {MAX_JSON_ITEMS:,} JSON items (values and keys); the limit is "
            f"{MAX_JSON_ITEMS:,}"
        )
    need = text_memory(raw)
    if need > MAX_FILE_BYTES:
        raise LimitError(
            f"cannot open {path}: its text would take {need / 2**20:,.1f} MiB in memory (characters outside Latin-1, "
            f"even as \\u escapes, take 2 or 4 bytes each); the limit is {MAX_FILE_BYTES / 2**20:g} MiB"
        )
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DocumentFormatError(f"cannot open {path}: not UTF-8 text (byte {exc.start})") from None
    del raw  # the parse needs the text only: never both copies and the parsed items at once
    try:
        data = json.loads(text, parse_int=_parse_int, parse_constant=_parse_constant)
    except json.JSONDecodeError as exc:
        raise DocumentFormatError(f"cannot open {path}: invalid JSON at line {exc.lineno}, column {exc.colno} ({exc.msg})") from None
    except RecursionError:
        raise DocumentFormatError(f"cannot open {path}: JSON nested too deeply") from None
    except SketchforgeError as exc:
        raise DocumentFormatError(f"cannot open {path}: {exc}") from None
    try:
        _check_depth(data)
    except LimitError as exc:
        raise LimitError(f"cannot open {path}: {exc}") from None
    return data


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
