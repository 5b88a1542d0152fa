"""Commands: every change of a Document is one of these, pushed on its UndoStack.

A command receives the document as an argument (it never captures an app), so a journal of
command dicts replays headlessly. Contract for ``do``: either the change happens completely,
or the document is left untouched and a :class:`~sketchforge.errors.SketchforgeError` is
raised. Expensive results (an inflated mesh) are computed on the first ``do`` and kept, so
redo is instant and bit-identical.

Plugins add commands through the ``sketchforge_commands`` hook; a command that edits a
layer's mesh after inflation (a sculpt edit) also implements :meth:`Command.reapply` so that
changing the inflation parameters can re-apply it, and :meth:`Command.transform_edit` so that
its edit follows the layer when the layer is moved, scaled or rotated. The core never reads
an edit's fields: only the edit's own command knows what they mean.
"""

from __future__ import annotations

import itertools
import math
import numbers
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np

from sketchforge.document.layer import Layer, Light
from sketchforge.errors import (
    DocumentFormatError,
    EditNotMovableError,
    EditsDoNotApplyError,
    ParameterError,
    PluginError,
    SketchforgeError,
    SolverError,
    quote,
)

_gesture_ids = itertools.count(1)


def new_gesture_id() -> int:
    """A fresh id for an interactive gesture whose commands merge into one undo step."""
    return next(_gesture_ids)


class Command:
    """Base class. Subclasses set ``name`` (the journal's ``"command"`` field) and implement
    ``do``, ``undo``, ``to_dict`` and ``from_dict``."""

    name: ClassVar[str] = ""
    #: Commands with the same non-None ``merge_id`` may merge (see :meth:`merge`).
    merge_id: ClassVar[str | None] = None
    #: A command that runs a named solver ("inflate", "sculpt", "assemble"; see
    #: :mod:`sketchforge.plugins.solvers`): its journal entry may name it (``"solver"``) and
    #: pass its parameters (``"params"``), which the solver checks; provenance records it.
    solver_kind: ClassVar[str | None] = None

    def text(self) -> str:
        """Human-readable name for menus ("Undo Set light")."""
        return self.name.replace("_", " ").capitalize()

    def prepare(self, doc) -> None:
        """Do the expensive part (a solve) without changing the document, so a front end can
        run it on a worker thread and then ``push`` the command on the GUI thread, where
        ``do`` only swaps the result in. The default does nothing. Must not mutate ``doc``;
        ``do`` recomputes if the document changed in between."""

    def do(self, doc) -> None:  # also redo
        raise NotImplementedError

    def undo(self, doc) -> None:
        raise NotImplementedError

    def merge(self, other: "Command") -> bool:
        """Absorb ``other`` (already done) into self; return True when merged."""
        return False

    def try_merge(self, other: "Command") -> bool:
        if self.merge_id is None or self.merge_id != other.merge_id or type(self) is not type(other):
            return False
        return self.merge(other)

    def to_dict(self) -> dict:
        raise NotImplementedError

    @classmethod
    def from_dict(cls, d: dict) -> "Command":
        raise NotImplementedError

    @classmethod
    def reapply(cls, doc, layer: Layer, entry: dict) -> Layer:
        """For edit commands: return ``layer`` with the edit ``entry`` applied to its mesh."""
        raise NotImplementedError(f"command {cls.name!r} cannot be re-applied")

    @classmethod
    def transform_edit(cls, entry: dict, matrix: np.ndarray, scale: float) -> dict:
        """For edit commands: the edit ``entry`` (its dict in ``Layer.edits``) as it must read
        after its layer was mapped by the affine ``matrix`` (2, 3) float64 [[a, b, tx],
        [c, d, ty]] (x' = a x + b y + tx; det > 0), so that re-applying it later (after a
        parameter change) edits the moved surface where the edit now lies. ``scale`` is
        sqrt(det), the part's linear size factor: the layer's heights were multiplied by it
        (1.0 for a rotation or a move). Return a new dict (same ``"command"``); positions go
        through :func:`transform_points` (a pure move adds the offset only, bit for bit).

        ``transform_layer``, ``translate_layer`` and ``duplicate_layer`` with an offset call it
        for every edit of the layer. The default refuses the transform
        (:class:`~sketchforge.errors.EditNotMovableError`, naming the layer and this command):
        leaving the edit's positions where they were drawn would re-apply it off the moved
        part at the next parameter change. Raise a SketchforgeError to refuse a transform the
        edit cannot follow."""
        raise EditNotMovableError("its plugin does not say how to move its edits (Command.transform_edit)")


# --- parsing helpers (journal entries are user-writable, so every field is checked) ---------


def parse_field(d: dict, key: str, kind: type | tuple, cmd: str, default: Any = ...):
    if key not in d:
        if default is ...:
            raise DocumentFormatError(f"command {cmd!r} needs the field {key!r}")
        return default
    v = d[key]
    if kind is float and isinstance(v, int) and not isinstance(v, bool):
        v = _to_float(v, cmd, key)
    if not isinstance(v, kind) or (kind is int and isinstance(v, bool)):
        raise DocumentFormatError(f"command {cmd!r}: field {key!r} has the wrong type ({type(v).__name__})")
    if kind is float and not math.isfinite(v):
        raise DocumentFormatError(f"command {cmd!r}: field {key!r} must be a finite number, got {v}")
    if kind is int and abs(v) > MAX_INDEX:
        raise DocumentFormatError(f"command {cmd!r}: field {key!r} is out of range ({_digits(v)})")
    return v


#: Integers in a journal are indices: anything beyond this is no index of a real document.
MAX_INDEX = 10**9


def _digits(v: int) -> str:
    """An integer for an error line: itself up to 20 digits, else its length (str() of an
    integer over 4300 digits raises, so beyond 1000 digits the length is not counted)."""
    if abs(v) >= 10**1000:
        return "an integer of over 1000 digits"
    n = len(str(abs(v)))
    return f"{v}" if n <= 20 else f"an integer of {n} digits"


def _to_float(v, cmd: str, key: str) -> float:
    try:
        return float(v)
    except OverflowError:
        raise DocumentFormatError(f"command {cmd!r}: field {key!r} is too large for a number ({_digits(v)})") from None


def parse_points(d: dict, cmd: str, key: str = "points") -> np.ndarray:
    raw = parse_field(d, key, list, cmd)
    if not all(
        isinstance(p, (list, tuple)) and len(p) == 2
        and all(isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_)) for x in p)
        for p in raw
    ):
        raise DocumentFormatError(f"command {cmd!r}: {key!r} must be a list of [x, y] number pairs")
    try:
        arr = np.array(raw, dtype=np.float64).reshape(-1, 2)
    except (TypeError, ValueError, OverflowError):
        raise DocumentFormatError(f"command {cmd!r}: {key!r} must be a list of [x, y] pairs of numbers within float range") from None
    return arr


def parse_vector(d: dict, key: str, cmd: str) -> list[float]:
    raw = parse_field(d, key, list, cmd)
    if len(raw) not in (2, 3) or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in raw):
        raise DocumentFormatError(f"command {cmd!r}: {key!r} must be 2 or 3 numbers")
    out = [_to_float(x, cmd, key) for x in raw]
    if not all(math.isfinite(x) for x in out):
        raise DocumentFormatError(f"command {cmd!r}: {key!r} must be finite numbers")
    return out


def layer_inflater(doc, layer: Layer):
    """The inflater of ``layer`` (its ``solver``, or the default for a layer that names none)
    and the layer's complete parameters for it (checked by the inflater).

    Raises
    ------
    UnknownSolverError, ParameterError, SketchforgeError
    """
    host = doc.host
    try:
        inflater = host.solver("inflate", layer.solver)
    except SketchforgeError:
        if layer.solver is None and not host.solvers("inflate"):
            raise SketchforgeError("no inflate plugin is installed, so a contour cannot become a mesh") from None
        raise
    return inflater, host.solver_params("inflate", inflater, layer.params)


def inflate_layer(doc, layer: Layer) -> Layer:
    """``layer`` with a mesh freshly inflated from its points by its inflater, with that
    inflater's name and complete parameters recorded, and its sculpt edits re-applied in
    order. Raises before anything changes."""
    inflater, params = layer_inflater(doc, layer)
    layer = layer.evolve(solver=inflater.name, params=params)
    if layer.points is None:
        return layer.evolve(mesh=None, edits=())
    mesh = doc.host.inflate(layer.points, layer.closed, params, holes=[np.asarray(h) for h in layer.holes],
                            solver=inflater.name)
    if mesh is None:
        raise SketchforgeError("no inflate plugin is installed, so a contour cannot become a mesh")
    if not np.all(np.isfinite(mesh.V)):
        raise SolverError(f"inflating layer {layer.id!r} produced non-finite heights; nothing was changed")
    return reapply_edits(doc, layer.evolve(mesh=mesh, edits=()), layer.edits)


def reapply_edits(doc, layer: Layer, edits) -> Layer:
    """``layer`` (freshly inflated, no edits) with the sculpt ``edits`` re-applied in order."""
    out = layer
    for entry in edits:
        cls = doc.host.command_class(entry.get("command", ""))
        out = cls.reapply(doc, out, entry)
    return out


# --- layer commands ---------------------------------------------------------------------------


@dataclass
class AddLayer(Command):
    name: ClassVar[str] = "add_layer"
    id: str | None = None
    layer_name: str | None = None
    index: int | None = None  # None: on top (in front)
    _layer: Layer | None = field(default=None, repr=False)

    def text(self) -> str:
        return "Add layer"

    def do(self, doc) -> None:
        if self.id is None:
            self.id = doc.new_layer_id()
        if self.id in doc.layer_ids():
            raise ParameterError(f"a layer with id {quote(self.id)} already exists")
        from sketchforge.document.document import check_layer_count

        check_layer_count(doc)
        if self.layer_name is None:
            self.layer_name = self.id.replace("_", " ").capitalize()
        n = len(doc.layers)
        idx = n if self.index is None else self.index
        if not 0 <= idx <= n:
            raise ParameterError(f"layer index {idx} is outside 0..{n}")
        if self._layer is None:  # the same value on redo, so later commands' caches stay valid
            self._layer = Layer(id=self.id, name=self.layer_name)
        doc._insert_layer(idx, self._layer)

    def undo(self, doc) -> None:
        doc._remove_layer(doc.index_of(self.id))

    def to_dict(self) -> dict:
        d = {"command": self.name, "id": self.id, "name": self.layer_name}
        if self.index is not None:
            d["index"] = self.index
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "AddLayer":
        return cls(
            id=parse_field(d, "id", str, cls.name, None),
            layer_name=parse_field(d, "name", str, cls.name, None),
            index=parse_field(d, "index", int, cls.name, None),
        )


@dataclass
class RemoveLayer(Command):
    name: ClassVar[str] = "remove_layer"
    layer: str
    _removed: Layer | None = field(default=None, repr=False)
    _index: int = field(default=-1, repr=False)

    def text(self) -> str:
        return "Remove layer"

    def do(self, doc) -> None:
        self._index = doc.index_of(self.layer)
        self._removed = doc._remove_layer(self._index)

    def undo(self, doc) -> None:
        doc._insert_layer(self._index, self._removed)

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer}

    @classmethod
    def from_dict(cls, d: dict) -> "RemoveLayer":
        return cls(layer=parse_field(d, "layer", str, cls.name))


@dataclass
class ReplaceLayerCommand(Command):
    """Shared machinery: compute a new Layer value once, swap it in, swap the old one back."""

    layer: str
    _old: Layer | None = field(default=None, repr=False)
    _new: Layer | None = field(default=None, repr=False)

    @property
    def replaced(self) -> Layer | None:
        """The layer value this command replaces (None before its first ``do``): what an
        attempt that replaces this one would start from."""
        return self._old

    def compute(self, doc, old: Layer) -> Layer:
        raise NotImplementedError

    def prepare(self, doc) -> None:
        old = doc.layer(self.layer)
        if self._new is None or old is not self._old:  # first time, or the layer changed since
            self._new = self.compute(doc, old)  # may raise: nothing has changed yet
            self._old = old

    def do(self, doc) -> None:
        self.prepare(doc)  # computes only on the first do or if the layer changed; may raise
        doc._replace_layer(self._new)

    def undo(self, doc) -> None:
        doc._replace_layer(self._old)


@dataclass
class RenameLayer(ReplaceLayerCommand):
    name: ClassVar[str] = "rename_layer"
    new_name: str = ""

    def text(self) -> str:
        return "Rename layer"

    def compute(self, doc, old: Layer) -> Layer:
        if not self.new_name.strip():
            raise ParameterError("a layer name must not be empty")
        return old.evolve(name=self.new_name)

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer, "name": self.new_name}

    @classmethod
    def from_dict(cls, d: dict) -> "RenameLayer":
        return cls(layer=parse_field(d, "layer", str, cls.name), new_name=parse_field(d, "name", str, cls.name))


@dataclass
class SetLayerVisible(ReplaceLayerCommand):
    name: ClassVar[str] = "set_layer_visible"
    visible: bool = True

    def text(self) -> str:
        return "Show layer" if self.visible else "Hide layer"

    def compute(self, doc, old: Layer) -> Layer:
        return old.evolve(visible=bool(self.visible))

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer, "visible": bool(self.visible)}

    @classmethod
    def from_dict(cls, d: dict) -> "SetLayerVisible":
        return cls(layer=parse_field(d, "layer", str, cls.name), visible=parse_field(d, "visible", bool, cls.name))


@dataclass
class SetContour(ReplaceLayerCommand):
    """Set (or redraw) a layer's stroke. By default redrawing drops the layer's sculpt edits
    (they were drawn on the old shape; the app asks first). With ``keep_edits`` the edits are
    re-applied to the new surface in order; if one no longer applies, nothing changes and
    :class:`~sketchforge.errors.EditsDoNotApplyError` says which (the app then asks whether
    to redraw without them).

    ``holes`` are the part's inner rings (any orientation), replacing the ones it had: the
    surface keeps height 0 on each. A hole that crosses the outline or another hole, lies
    outside, or is too small for the resolution is refused with a message naming it (1-based)
    and nothing changes. Cutting a hole into a drawn part is this command with the same
    points, the old holes plus the new one and ``keep_edits``."""

    name: ClassVar[str] = "set_contour"
    points: Any = None  # (n,2) float64
    closed: bool = False
    keep_edits: bool = False
    holes: Any = ()  # sequence of (n_i,2) float64

    def __post_init__(self) -> None:
        self.points = np.array(self.points, dtype=np.float64)
        self.points.setflags(write=False)
        self.holes = Layer(id="", name="", holes=self.holes).holes  # checked, read-only copies

    def text(self) -> str:
        return "Draw contour"

    def compute(self, doc, old: Layer) -> Layer:
        base = inflate_layer(doc, old.evolve(points=self.points, closed=bool(self.closed), edits=(), holes=self.holes))
        if not (self.keep_edits and old.edits):
            return base
        try:
            return reapply_edits(doc, base, old.edits)
        except SketchforgeError as exc:
            raise EditsDoNotApplyError(
                f"the {len(old.edits)} sculpt edit(s) of layer {old.id!r} do not apply to the new outline ({exc})"
            ) from None

    def to_dict(self) -> dict:
        d = {"command": self.name, "layer": self.layer, "points": self.points.tolist()}
        if self.closed:
            d["closed"] = True
        if self.keep_edits:
            d["keep_edits"] = True
        if self.holes:
            d["holes"] = [h.tolist() for h in self.holes]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "SetContour":
        raw = parse_field(d, "holes", list, cls.name, [])
        holes = [parse_points({"hole": h}, cls.name, key="hole") for h in raw]
        return cls(
            layer=parse_field(d, "layer", str, cls.name),
            points=parse_points(d, cls.name),
            closed=parse_field(d, "closed", bool, cls.name, False),
            keep_edits=parse_field(d, "keep_edits", bool, cls.name, False),
            holes=holes,
        )


@dataclass
class SetInflateParams(ReplaceLayerCommand):
    """Change a layer's inflater or its parameters; the mesh is rebuilt and the layer's sculpt
    edits are re-applied in order (if one no longer applies, the whole change is refused with
    its message and nothing changes).

    ``solver`` names the inflater (None: keep the layer's). Choosing another inflater starts
    from its defaults (the old inflater's parameters mean nothing to it); otherwise ``params``
    are merged into the layer's. The inflater checks them: an unknown key or a bad value is a
    one-line ParameterError naming the inflater and the key."""

    name: ClassVar[str] = "set_inflate_params"
    solver_kind: ClassVar[str | None] = "inflate"
    params: dict = field(default_factory=dict)
    solver: str | None = None

    def text(self) -> str:
        return "Set inflater" if self.solver is not None and not self.params else "Set inflation parameters"

    def compute(self, doc, old: Layer) -> Layer:
        switch = self.solver is not None and self.solver != old.solver
        base = {} if switch else dict(old.params)
        solver = self.solver if self.solver is not None else old.solver
        return inflate_layer(doc, old.evolve(solver=solver, params={**base, **self.params}))

    def to_dict(self) -> dict:
        d = {"command": self.name, "layer": self.layer, "params": dict(self.params)}
        if self.solver is not None:
            d["solver"] = self.solver
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "SetInflateParams":
        params = parse_params(d, cls.name)
        return cls(layer=parse_field(d, "layer", str, cls.name), params=params,
                   solver=parse_field(d, "solver", str, cls.name, None))


def parse_params(d: dict, cmd: str, key: str = "params") -> dict:
    """A journal entry's solver parameters: an object of JSON values (the solver checks the
    keys and values when the command runs, and when a document with a snapshot is opened)."""
    from sketchforge.solver_kinds import json_value

    params = parse_field(d, key, dict, cmd, {})
    if not json_value(params):
        raise DocumentFormatError(f"command {cmd!r}: {key!r} must hold numbers, strings, true/false or lists of them")
    return dict(params)


@dataclass
class SetAssembly(Command):
    """Choose the document's assembler and its parameters (``set_assembly``): ``solver`` (None:
    the default, the built-in ``"depth_qp"``) and its ``params``, checked by the assembler
    (an unknown key or a bad value is refused, naming the assembler and the key). Naming
    another assembler starts from its defaults; otherwise ``params`` are merged into the
    current ones. The assembled model is rebuilt when next shown."""

    name: ClassVar[str] = "set_assembly"
    solver_kind: ClassVar[str | None] = "assemble"
    solver: str | None = None
    params: dict = field(default_factory=dict)
    _old: Any = field(default=None, repr=False)
    _new: Any = field(default=None, repr=False)

    def text(self) -> str:
        return "Set assembly"

    def do(self, doc) -> None:
        from sketchforge.solver_kinds import SolverChoice

        old = doc.assembly
        switch = self.solver is not None and self.solver != old.solver
        solver = self.solver if self.solver is not None else old.solver
        assembler = doc.host.solver("assemble", solver)  # raises for an unknown or ambiguous name
        params = {} if switch else dict(old.params)
        params.update(self.params)
        doc.host.solver_params("assemble", assembler, params)  # checked now: a bad key is refused here
        self._old, self._new = old, SolverChoice(solver, MappingProxyType(params))
        doc._set_assembly(self._new)

    def undo(self, doc) -> None:
        doc._set_assembly(self._old)

    def to_dict(self) -> dict:
        d: dict = {"command": self.name}
        if self.solver is not None:
            d["solver"] = self.solver
        d["params"] = dict(self.params)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "SetAssembly":
        return cls(solver=parse_field(d, "solver", str, cls.name, None), params=parse_params(d, cls.name))


#: Mirror axes: the host's vertical symmetry axis (the layer an attached part's junction lies
#: on), or the part's own.
MIRROR_AXES = ("host", "own")


def _attachments(doc, which=None) -> dict:
    """{layer id: JunctionHost or None} for the layers ``which`` (None: every layer) by the one
    rule the assembly uses too (:func:`sketchforge.geometry.attachment.plan_attachments`, on
    the layers the assembly takes: the visible ones with a mesh; parts glued to one face of a
    host kept apart as the assembly keeps them); None for a part without a junction. The
    layers' regions and edge lengths are built once for all of them (the app checks every
    part before an assembly and after a redraw)."""
    from sketchforge.geometry.attachment import find_host, median_edge_length, plan_attachments

    layers = doc.layers
    wanted = [l for l in layers if which is None or l.id in which]
    out: dict = {l.id: None for l in wanted}
    if not any(not l.closed and l.mesh is not None and len(l.mesh.junction) >= 2 for l in wanted):
        return out
    taken = [l.visible and l.mesh is not None for l in layers]
    regions = [_region(l) if t else None for l, t in zip(layers, taken)]
    h = [median_edge_length(l.mesh.V[:, :2], l.mesh.F) if l.mesh is not None else 0.0 for l in layers]
    ends = [l.mesh.V[l.mesh.junction[[0, -1]], :2] if t and len(l.mesh.junction) >= 2 and not l.closed else None
            for l, t in zip(layers, taken)]
    names = [quote(l.name or l.id) for l in layers]
    # every glued part the assembly takes counts for the separation on a face, asked about
    # or not; a hidden part is not assembled (it gets its host alone: to mirror about it)
    junctions = [l.mesh.V[l.mesh.junction, :2] if t and not l.closed and len(l.mesh.junction) >= 2 else None
                 for l, t in zip(layers, taken)]
    plans = plan_attachments(junctions, regions, h, names, ends)
    for k, l in enumerate(layers):
        if l.id not in out:
            continue
        if plans[k] is not None:
            out[l.id] = plans[k]
        elif not taken[k] and l.mesh is not None and not l.closed and len(l.mesh.junction) >= 2:
            out[l.id] = find_host(l.mesh.V[l.mesh.junction, :2], k, regions, h, names, h[k], ends)
    return out


def _attachment(doc, layer: Layer):
    return _attachments(doc, {layer.id})[layer.id]


def host_of(doc, layer: Layer) -> Layer | None:
    """The layer an attached part hangs on, by the assembly's own rule (:func:`attachment`):
    the nearest visible layer behind it that its junction lies over, or failing that the
    nearest in front (a leg drawn behind the body hangs on the body's back face), looking past
    a twin glued by the same junction (a copy duplicated in place, about to be mirrored). A
    junction that runs partly off that layer still names it (the assembly will refuse it, and
    :func:`attachment` says why); None for a free part or a junction over empty space."""
    found = _attachment(doc, layer)
    return None if found is None or found.near is None else doc.layers[found.near]


def _region(layer: Layer):
    """The layer's region in the drawing plane (holes cut out), or None if it has none."""
    from sketchforge.geometry import guard

    mesh = layer.mesh
    if layer.points is None or mesh is None or not len(mesh.boundary):
        return None
    try:
        region = guard.polygon(mesh.V[mesh.boundary, :2], f"the outline of layer {quote(layer.id)}")
        for hole in mesh.holes:
            region = region.difference(guard.polygon(mesh.V[hole, :2], "a hole"))
    except SketchforgeError:
        return None
    return region


def attachment(doc, layer: Layer) -> tuple[Layer | None, str | None]:
    """Where the assembly glues ``layer`` — the one rule of
    :func:`sketchforge.geometry.attachment.plan_attachments`, which the assemble plugin applies
    too: (host, None) for a part glued to a layer (the one that holds the longest stretch of
    its junction; see :func:`attachment_note` for a part glued by a stretch only); (None,
    problem) when no stretch long enough lies inside one layer, clear of the layers between
    and of the junctions glued to that face, the problem a sentence saying the part is
    assembled free and why; (None, None) for a free part (closed, or a junction over empty
    space).

    Cheap (shapely on the outlines), so the app can say at once why an assembly will fail and
    check, after a redraw, whether the parts glued to a layer still are (for many layers at
    once: :func:`attachments`)."""
    return attachments(doc, {layer.id})[layer.id]


def attachment_note(doc, layer: Layer) -> str | None:
    """What to tell the person about how ``layer`` is glued although it is (only the stretch
    of its junction inside its host is glued, it spans two layers and goes to the one holding
    most of it, or it touches another part's junction on one face), or None."""
    found = _attachments(doc, {layer.id})[layer.id]
    return None if found is None else found.note


def attachments(doc, which=None) -> dict:
    """{layer id: (host, problem)} as :func:`attachment` says it, for the layers ``which``
    (ids; None: every layer), with the layers' outlines built once."""
    out = {}
    for lid, found in _attachments(doc, which).items():
        out[lid] = (None, None) if found is None else (
            (doc.layers[found.host] if found.host is not None else None), found.problem)
    return out


def twin_source(doc, layer: Layer) -> Layer | None:
    """The attached part ``layer`` is an unchanged copy of, moved aside (Ctrl+D: the same
    stroke and holes shifted by one offset, the same kind and parameters); None if there is
    none, or the copy lies in place (then :func:`host_of` looks past it already).

    Mirroring such a copy about its host's axis is meant to give the original's twin (a
    right leg from a left leg): its mirror image at the mirrored place, not the mirror of
    wherever the copy was put aside. The nearest such layer behind ``layer`` wins, then the
    nearest in front."""
    P = None if layer.points is None else np.asarray(layer.points)
    if P is None or not len(P):
        return None
    k = doc.index_of(layer.id)
    others = list(reversed(doc.layers[:k])) + list(doc.layers[k + 1 :])
    scale = max(1.0, float(np.abs(P).max()))
    for other in others:
        Q = None if other.points is None else np.asarray(other.points)
        if Q is None or Q.shape != P.shape or other.closed != layer.closed or len(other.holes) != len(layer.holes):
            continue
        if other.solver != layer.solver or dict(other.params) != dict(layer.params):
            continue
        d = P[0] - Q[0]
        tol = 1e-9 * (scale + float(np.abs(d).max()))
        if not np.abs(d).max() > tol:
            continue  # in place: not moved aside
        if np.abs(P - Q - d).max() > tol:
            continue
        if any(np.asarray(a).shape != np.asarray(b).shape or np.abs(np.asarray(a) - np.asarray(b) - d).max() > tol
               for a, b in zip(layer.holes, other.holes)):
            continue
        if host_of(doc, other) is not None:
            return other
    return None


def mirror_axis_x(doc, layer: Layer, axis) -> tuple[float, str]:
    """x of the vertical axis to mirror ``layer`` about, and which axis that is ("host",
    "own" or "x"). ``axis``: "host" (the host's bounding-box centre; a free part falls back
    to its own), "own" (the part's bounding-box centre) or a number (that x)."""
    if isinstance(axis, (int, float)) and not isinstance(axis, bool):
        x = float(axis)
        if not np.isfinite(x):
            raise ParameterError("a mirror axis must be a finite x")
        return x, "x"
    if axis not in MIRROR_AXES:
        raise ParameterError(f"a mirror axis is 'host', 'own' or a number, got {axis!r}")
    if axis == "host":
        host = host_of(doc, layer)
        if host is not None:
            hp = np.asarray(host.points)
            return 0.5 * (hp[:, 0].min() + hp[:, 0].max()), "host"
    pts = np.asarray(layer.points)
    return 0.5 * (pts[:, 0].min() + pts[:, 0].max()), "own"


@dataclass
class MirrorLayer(ReplaceLayerCommand):
    """Mirror a layer's stroke and holes left-right about a vertical axis (the mesh is
    re-inflated; sculpt edits are dropped as for a redraw).

    ``axis``: "host" (the default in the app) mirrors an attached part about its host's
    vertical symmetry axis, the bounding-box centre x of the layer its junction lies on, so a
    left leg becomes a right leg; a free part (no host) is mirrored about its own axis.
    "own": the part's own bounding-box centre (what a journal without ``axis`` means: files
    written before this option replay unchanged). A number: that x. The junction is
    mirrored with the part: the assembly re-attaches it to the layer it then lies over.
    Mirroring twice about the same axis gives the stroke back."""

    name: ClassVar[str] = "mirror_layer"
    axis: Any = "host"
    #: The layer whose mirror image this layer becomes (journal field ``of``): with
    #: ``axis="host"``, an unchanged copy moved aside becomes its original's twin (see
    #: :func:`twin_source`), found by the first ``do`` and journaled, so a replay does exactly
    #: that. A journal entry without it mirrors the layer itself, as files written before.
    of: str | None = None
    #: Look for the original of a copy moved aside (commands made by the app or a script);
    #: False for journal entries, which say with ``of`` what to mirror.
    find_twin: bool = field(default=True, repr=False)
    #: Which axis the last ``do`` used ("host", "own" or "x"), for the app's message.
    used_axis: str = field(default="", repr=False)

    def text(self) -> str:
        return "Mirror layer"

    def compute(self, doc, old: Layer) -> Layer:
        if old.points is None:
            raise ParameterError(f"layer {quote(old.id)} has no contour to mirror")
        if self.of is None and self.find_twin and self.axis == "host":
            twin = twin_source(doc, old)
            self.of = None if twin is None else twin.id
        src = old if self.of is None else doc.layer(self.of)
        if src.points is None:
            raise ParameterError(f"layer {quote(src.id)} has no contour to mirror")
        cx, self.used_axis = mirror_axis_x(doc, src, self.axis)
        pts = np.array(src.points)
        pts[:, 0] = 2.0 * cx - pts[:, 0]
        holes = []
        for h in src.holes:
            h = np.array(h)
            h[:, 0] = 2.0 * cx - h[:, 0]
            holes.append(h)
        return inflate_layer(doc, old.evolve(points=pts, holes=tuple(holes), closed=src.closed, edits=()))

    def to_dict(self) -> dict:
        d = {"command": self.name, "layer": self.layer}
        if self.axis != "own":
            d["axis"] = self.axis
        if self.of is not None:
            d["of"] = self.of
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "MirrorLayer":
        axis = d.get("axis", "own")  # files from before the option mirrored about the part's own axis
        if not (axis in MIRROR_AXES or (isinstance(axis, (int, float)) and not isinstance(axis, bool))):
            raise DocumentFormatError(f"command {cls.name!r}: 'axis' must be 'host', 'own' or a number")
        return cls(layer=parse_field(d, "layer", str, cls.name), axis=float(axis) if not isinstance(axis, str) else axis,
                   of=parse_field(d, "of", str, cls.name, None), find_twin=False)


@dataclass
class MoveLayer(Command):
    """Move a layer to ``index`` in the back-to-front list (0 = furthest back)."""

    name: ClassVar[str] = "move_layer"
    layer: str = ""
    index: int = 0
    _from: int = field(default=-1, repr=False)

    def text(self) -> str:
        return "Reorder layers"

    def do(self, doc) -> None:
        n = len(doc.layers)
        if not 0 <= self.index < n:
            raise ParameterError(f"layer index {self.index} is outside 0..{n - 1}")
        self._from = doc.index_of(self.layer)
        doc._move_layer(self._from, self.index)

    def undo(self, doc) -> None:
        doc._move_layer(self.index, self._from)

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer, "index": self.index}

    @classmethod
    def from_dict(cls, d: dict) -> "MoveLayer":
        return cls(layer=parse_field(d, "layer", str, cls.name), index=parse_field(d, "index", int, cls.name))


@dataclass
class DuplicateLayer(Command):
    """Copy a layer (mesh and edits included), by default just in front of it. ``index``
    places the copy elsewhere in the back-to-front list (after the copy is inserted: 0 = at
    the very back); ``offset`` (dx, dy) moves the copy in the drawing plane: its stroke, its
    mesh and its edits (each by its command's ``transform_edit``) move together, so a later
    parameter change re-applies the edits where they now are."""

    name: ClassVar[str] = "duplicate_layer"
    layer: str = ""
    new_id: str | None = None
    new_name: str | None = None
    index: int | None = None
    offset: Any = None  # None or (dx, dy)
    _copy: Layer | None = field(default=None, repr=False)
    _src: Layer | None = field(default=None, repr=False)

    def text(self) -> str:
        return "Duplicate layer"

    def do(self, doc) -> None:
        src_index = doc.index_of(self.layer)
        src = doc.layers[src_index]
        n = len(doc.layers)
        idx = src_index + 1 if self.index is None else self.index
        if not 0 <= idx <= n:
            raise ParameterError(f"layer index {idx} is outside 0..{n}")
        if self.offset is not None:
            off = np.asarray(self.offset, dtype=np.float64).reshape(-1)
            if off.shape != (2,) or not np.all(np.isfinite(off)):
                raise ParameterError("a duplicate's offset must be two finite numbers")
        if self.new_id is None:
            self.new_id = doc.new_layer_id(src.id + "_copy")
        if self.new_id in doc.layer_ids():
            raise ParameterError(f"a layer with id {quote(self.new_id)} already exists")
        from sketchforge.document.document import check_layer_count

        check_layer_count(doc)
        if self.new_name is None:
            self.new_name = src.name + " copy"
        if self._copy is None or self._src is not src:
            # Moved before it is renamed, so a refusal names the layer the person sees.
            moved = src if self.offset is None else _translated(doc, src, off)
            copy = moved.evolve(id=self.new_id, name=self.new_name)
            self._copy, self._src = copy, src
        doc._insert_layer(idx, self._copy)

    def undo(self, doc) -> None:
        doc._remove_layer(doc.index_of(self.new_id))

    def to_dict(self) -> dict:
        d = {"command": self.name, "layer": self.layer, "id": self.new_id, "name": self.new_name}
        if self.index is not None:
            d["index"] = self.index
        if self.offset is not None:
            d["offset"] = [float(v) for v in np.asarray(self.offset, dtype=np.float64).reshape(-1)]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "DuplicateLayer":
        offset = parse_vector(d, "offset", cls.name) if "offset" in d else None
        if offset is not None and len(offset) != 2:
            raise DocumentFormatError(f"command {cls.name!r}: 'offset' must be 2 numbers")
        return cls(
            layer=parse_field(d, "layer", str, cls.name),
            new_id=parse_field(d, "id", str, cls.name, None),
            new_name=parse_field(d, "name", str, cls.name, None),
            index=parse_field(d, "index", int, cls.name, None),
            offset=offset,
        )


def _translated(doc, layer: Layer, off: np.ndarray) -> Layer:
    """``layer`` moved by ``off`` (2,) in the drawing plane: stroke, holes, mesh and edits."""
    return _transformed(doc, layer, np.array([[1.0, 0.0, off[0]], [0.0, 1.0, off[1]]]))


def check_affine(matrix) -> np.ndarray:
    """A layer transform as a (2, 3) float64 array [[a, b, tx], [c, d, ty]]: x' = a x + b y + tx,
    y' = c x + d y + ty. Raises ParameterError for a wrong shape, a non-finite entry, a linear
    part that collapses the part (|det| below 1e-6, or scaling by more than 1e4 in area) or
    one that mirrors it (det < 0: that is mirror_layer, which re-inflates)."""
    try:
        A = np.array(matrix, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError("a transform must be a 2x3 matrix of numbers [[a, b, tx], [c, d, ty]]") from None
    if A.shape != (2, 3):
        raise ParameterError(f"a transform must be a 2x3 matrix [[a, b, tx], [c, d, ty]], got shape {A.shape}")
    if not np.all(np.isfinite(A)):
        raise ParameterError("a transform must be finite numbers")
    det = float(A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0])
    if det < 0:
        raise ParameterError("this transform mirrors the part (negative determinant); use Mirror layer instead")
    if not 1e-6 <= det <= 1e4:
        raise ParameterError(f"this transform scales the part's area by {det:.3g}; the allowed range is 1e-6 to 1e4")
    return A


def transform_points(matrix, points) -> np.ndarray:
    """``points`` (k, 2) (or one point (2,)) under the affine ``matrix`` (2, 3), as (k, 2)
    float64. A pure move (linear part exactly the identity) adds the offset only, so moving
    and moving back restores the bits a ``translate_layer`` always gave."""
    A = np.asarray(matrix, dtype=np.float64)
    L, t = A[:, :2], A[:, 2]
    P = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    return P + t if np.array_equal(L, np.eye(2)) else P @ L.T + t


def _transformed(doc, layer: Layer, A: np.ndarray) -> Layer:
    """``layer`` under the affine map A (2, 3): its stroke, holes, mesh and its edits
    together. Heights scale by sqrt(det), the linear size of the part, so a scaled blob keeps
    its shape (a rotation or a move leaves them untouched). A pure move adds the offset only,
    bit for bit what ``translate_layer`` always did. Each edit is moved by its own command
    (:meth:`Command.transform_edit`): what its fields mean is its plugin's business."""
    L = A[:, :2]
    moved_only = bool(np.array_equal(L, np.eye(2)))
    s = float(np.sqrt(L[0, 0] * L[1, 1] - L[0, 1] * L[1, 0]))
    edits = transformed_edits(doc, layer, A, s)  # first: a refusal leaves nothing half-done

    def f(P) -> np.ndarray:
        return transform_points(A, P)

    changes: dict[str, Any] = {}
    if layer.points is not None:
        changes["points"] = f(layer.points)
    changes["holes"] = tuple(f(h) for h in layer.holes)
    if layer.mesh is not None:
        V = np.array(layer.mesh.V, dtype=np.float64)
        V[:, :2] = f(V[:, :2])
        if not moved_only:
            V[:, 2] *= s
        V.setflags(write=False)  # the step keeps these vertices, and shares everything else
        changes["mesh"] = replace(layer.mesh, V=V)
    changes["edits"] = edits
    return layer.evolve(**changes)


def transformed_edits(doc, layer: Layer, A: np.ndarray, scale: float) -> tuple:
    """``layer.edits``, each moved by its command's :meth:`Command.transform_edit`.

    Raises
    ------
    EditNotMovableError
        An edit's command does not say how to move it, or refuses this transform (the
        message names the layer, the edit's command and its plugin).
    PluginError
        A ``transform_edit`` failed with a bug or returned something other than a dict for
        the same command.
        An edit of a command no installed plugin provides is refused the same way.
    """
    out = []
    for entry in layer.edits:
        name = entry.get("command", "")
        try:
            cls = doc.host.command_class(name)
        except SketchforgeError as exc:
            raise EditNotMovableError(f"layer {layer.id!r} cannot be moved: its edit {name!r} cannot follow it: {exc}") from None
        who = doc.host.provider_of(cls)
        try:
            moved = cls.transform_edit(dict(entry), np.array(A, dtype=np.float64), float(scale))
        except SketchforgeError as exc:
            raise EditNotMovableError(f"layer {layer.id!r} cannot be moved: its edit {name!r} (plugin {who!r}) "
                                      f"cannot follow it: {exc}") from None
        except Exception as exc:  # noqa: BLE001 - foreign code: named, not hidden
            raise PluginError(f"layer {layer.id!r} cannot be moved: transform_edit of command {name!r} (plugin {who!r}) "
                              f"failed: {type(exc).__name__}: {exc}") from exc
        if not isinstance(moved, dict) or moved.get("command") != name:
            raise PluginError(f"layer {layer.id!r} cannot be moved: transform_edit of command {name!r} (plugin {who!r}) "
                              f"must return the edit's dict with \"command\": {name!r}, got {type(moved).__name__}")
        out.append(moved)
    return tuple(out)


def compose_affine(*matrices) -> np.ndarray:
    """The (2, 3) affine doing ``matrices[0]`` first, then the next, ... (each (2, 3))."""
    out = np.eye(3)
    for m in matrices:
        M = np.vstack([np.asarray(m, dtype=np.float64), [0.0, 0.0, 1.0]])
        out = M @ out
    return out[:2]


def scale_about(center, sx: float, sy: float | None = None) -> np.ndarray:
    """(2, 3) affine scaling by (sx, sy) about ``center`` (2,)."""
    sy = sx if sy is None else sy
    c = np.asarray(center, dtype=np.float64).reshape(2)
    return np.array([[sx, 0.0, c[0] - sx * c[0]], [0.0, sy, c[1] - sy * c[1]]])


def rotate_about(center, radians: float) -> np.ndarray:
    """(2, 3) affine rotating counter-clockwise by ``radians`` about ``center`` (2,)."""
    c = np.asarray(center, dtype=np.float64).reshape(2)
    co, si = np.cos(radians), np.sin(radians)
    L = np.array([[co, -si], [si, co]])
    return np.column_stack([L, c - L @ c])


@dataclass
class TransformLayer(ReplaceLayerCommand):
    """Move, scale and rotate a layer in the drawing plane: ``matrix`` is a 2x3 affine
    [[a, b, tx], [c, d, ty]] (x' = a x + b y + tx, y' = c x + d y + ty) applied to its stroke,
    holes, mesh and edits together (each edit by its command's ``transform_edit``; a layer
    with an edit whose plugin does not say how to move it is refused), without re-inflation
    (heights scale by sqrt(det), so a scaled part keeps its shape). One command per gesture:
    a drag of the app's handles is one ``transform_layer`` with the matrix of the whole drag.

    Attached parts are re-attached, not pinned: the junction is part of the layer's own
    stroke, so it moves with the part, and the assembly glues it to whichever layer it then
    lies over (a junction moved off every layer makes the part free; one moved across two
    layers is reported by the assembly). Parts attached to a moved layer stay where they are.

    The inflation parameters are kept as they are (``resolution`` is in drawing units): a
    later parameter change re-inflates the transformed outline at that resolution."""

    name: ClassVar[str] = "transform_layer"
    matrix: Any = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))

    def __post_init__(self) -> None:
        self.matrix = check_affine(self.matrix).tolist()

    def text(self) -> str:
        L = np.asarray(self.matrix)[:, :2]
        if np.array_equal(L, np.eye(2)):
            return "Move layer"
        if np.allclose(L, L[0, 0] * np.eye(2)) and L[0, 0] > 0:
            return "Scale layer"
        # A rotation keeps lengths (L L^T = I) and orientation (det 1); det 1 alone would also
        # name a shear "Rotate layer", and a uniform negative scale is a half turn, not a scale.
        if np.allclose(L @ L.T, np.eye(2)) and np.linalg.det(L) > 0:
            return "Rotate layer"
        return "Transform layer"

    def compute(self, doc, old: Layer) -> Layer:
        return _transformed(doc, old, np.asarray(self.matrix, dtype=np.float64))

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer, "matrix": [list(map(float, r)) for r in self.matrix]}

    @classmethod
    def from_dict(cls, d: dict) -> "TransformLayer":
        raw = parse_field(d, "matrix", list, cls.name)
        if len(raw) != 2 or not all(isinstance(r, list) and len(r) == 3 for r in raw) or not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) for r in raw for x in r
        ):
            raise DocumentFormatError(f"command {cls.name!r}: 'matrix' must be [[a, b, tx], [c, d, ty]] numbers")
        return cls(layer=parse_field(d, "layer", str, cls.name), matrix=raw)


@dataclass
class TranslateLayer(ReplaceLayerCommand):
    """Move a layer in the drawing plane by ``offset`` (dx, dy): its stroke, mesh and edits
    together (no re-inflation: the same surface, moved). Kept so that files
    written before ``transform_layer`` load; the app now writes ``transform_layer`` (a pure
    move there is bit for bit the same). Each nudge is its own step."""

    name: ClassVar[str] = "translate_layer"
    offset: Any = (0.0, 0.0)

    def __post_init__(self) -> None:
        off = np.asarray(self.offset, dtype=np.float64).reshape(-1)
        if off.shape != (2,) or not np.all(np.isfinite(off)):
            raise ParameterError("a move's offset must be two finite numbers")
        self.offset = [float(off[0]), float(off[1])]

    def text(self) -> str:
        return "Move layer"

    def compute(self, doc, old: Layer) -> Layer:
        return _translated(doc, old, np.asarray(self.offset, dtype=np.float64))

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer, "offset": list(self.offset)}

    @classmethod
    def from_dict(cls, d: dict) -> "TranslateLayer":
        offset = parse_vector(d, "offset", cls.name)
        if len(offset) != 2:
            raise DocumentFormatError(f"command {cls.name!r}: 'offset' must be 2 numbers")
        return cls(layer=parse_field(d, "layer", str, cls.name), offset=offset)


@dataclass
class SetLight(Command):
    """Set the light direction: [x, y] (in the drawing plane) or [x, y, z] with z >= 0 (the
    hemisphere facing the viewer; [0, 0, 1] straight overhead), normalised once and journaled
    as used. Commands of one drag (same ``gesture``) merge into one undo step; the gesture id
    is not saved (the journal keeps the final direction)."""

    name: ClassVar[str] = "set_light"
    merge_id: ClassVar[str | None] = "set_light"
    direction: Any = (1.0, 0.0, 0.0)
    gesture: int | None = None
    _old: Light | None = field(default=None, repr=False)
    _new: Light | None = field(default=None, repr=False)

    def text(self) -> str:
        return "Set light"

    def __post_init__(self) -> None:
        # Normalised once, here where the direction enters; the journal keeps the vector as
        # used, and Light keeps an already-unit vector bit for bit, so a replay is exact.
        self._new = Light.from_vector(self.direction)
        self.direction = [float(v) for v in self._new.direction]

    def do(self, doc) -> None:
        self._old = doc.light
        doc._set_light(self._new)

    def undo(self, doc) -> None:
        doc._set_light(self._old)

    def merge(self, other: "Command") -> bool:
        if self.gesture is None or other.gesture != self.gesture:
            return False
        self._new = other._new
        self.direction = other.direction
        return True

    def to_dict(self) -> dict:
        return {"command": self.name, "direction": [float(v) for v in self.direction]}

    @classmethod
    def from_dict(cls, d: dict) -> "SetLight":
        try:
            return cls(direction=parse_vector(d, "direction", cls.name))
        except ParameterError as exc:
            raise DocumentFormatError(f"command {cls.name!r}: 'direction': {exc}") from None


class MacroCommand(Command):
    """A group of commands that is done and undone as one step."""

    name: ClassVar[str] = "macro"

    def __init__(self, text: str = "", children: list | None = None) -> None:
        self.text_ = text
        self.children = list(children or [])

    def text(self) -> str:
        return self.text_ or "Group"

    def do(self, doc) -> None:
        done: list[Command] = []
        try:
            for c in self.children:
                c.do(doc)
                done.append(c)
        except Exception:
            for c in reversed(done):  # all or nothing
                c.undo(doc)
            raise

    def undo(self, doc) -> None:
        for c in reversed(self.children):
            c.undo(doc)

    def to_dict(self) -> dict:
        return {"command": self.name, "text": self.text_, "children": [c.to_dict() for c in self.children]}

    @classmethod
    def from_dict(cls, d: dict, registry=None, depth: int = 1) -> "MacroCommand":
        children = parse_field(d, "children", list, cls.name)
        if registry is None:
            raise DocumentFormatError("a macro needs a command registry to read its children")
        if depth > MAX_MACRO_DEPTH:
            raise DocumentFormatError(f"macros are nested more than {MAX_MACRO_DEPTH} deep")
        return cls(
            text=parse_field(d, "text", str, cls.name, ""),
            children=[registry.from_dict(c, depth=depth + 1) for c in children],
        )


#: Macros inside macros: the app makes two levels; deeper ones would reach Python's recursion
#: limit in do/undo/to_dict.
MAX_MACRO_DEPTH = 16


#: The document's own commands, registered by the built-in plugin.
CORE_COMMANDS: tuple[type[Command], ...] = (
    AddLayer,
    RemoveLayer,
    RenameLayer,
    SetLayerVisible,
    MoveLayer,
    DuplicateLayer,
    TranslateLayer,
    TransformLayer,
    MirrorLayer,
    SetContour,
    SetInflateParams,
    SetAssembly,
    SetLight,
    MacroCommand,
)


class CommandRegistry:
    """Maps journal names to command classes (core + plugins)."""

    def __init__(self, classes, ambiguous: dict | None = None) -> None:
        #: {name: [plugins]}: names two plugins registered (neither is used).
        self._ambiguous = dict(ambiguous or {})
        self._classes: dict[str, type[Command]] = {}
        for cls in classes:
            if not cls.name:
                raise ValueError(f"command class {cls.__name__} has no name")
            if cls.name in self._classes and self._classes[cls.name] is not cls:
                raise ValueError(f"two plugins provide the command {cls.name!r}")
            self._classes[cls.name] = cls

    def names(self) -> list[str]:
        return sorted(self._classes)

    def get(self, name: str) -> type[Command]:
        from sketchforge.errors import UnknownCommandError

        try:
            return self._classes[name]
        except KeyError:
            if name in self._ambiguous:
                both = " and ".join(repr(p) for p in self._ambiguous[name])
                raise PluginError(f"the command {quote(name)} is registered by both plugins {both}; uninstall one of them") from None
            known = ", ".join(self.names())
            raise UnknownCommandError(
                f"unknown command {quote(name)} (is the plugin that provides it installed? known: {known})"
            ) from None

    def from_dict(self, d, depth: int = 1) -> Command:
        if not isinstance(d, dict):
            raise DocumentFormatError(f"a journal entry must be an object, got {type(d).__name__}")
        name = d.get("command")
        if not isinstance(name, str):
            raise DocumentFormatError("a journal entry needs a string field 'command'")
        cls = self.get(name)
        if cls is MacroCommand:
            return MacroCommand.from_dict(d, registry=self, depth=depth)
        try:
            return cls.from_dict(d)
        except SketchforgeError:
            raise
        except (TypeError, ValueError, KeyError, OverflowError) as exc:
            raise DocumentFormatError(f"command {quote(name)}: {exc}") from None
