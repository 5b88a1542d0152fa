"""Commands: every change of a Document is one of these, pushed on its UndoStack.

A command receives the document as an argument (it never captures an app), so a journal of
command dicts replays headlessly. Contract for ``do``: either the change happens completely,
or the document is left untouched and a :class:`~sketchforge.errors.SketchforgeError` is
raised. Expensive results (an inflated mesh) are computed on the first ``do`` and kept, so
redo is instant and bit-identical.

Plugins add commands through the ``sketchforge_commands`` hook; a command that edits a
layer's mesh after inflation (a sculpt edit) also implements :meth:`Command.reapply` so that
changing the inflation parameters can re-apply it.
"""

from __future__ import annotations

import itertools
import math
import numbers
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from sketchforge.document.layer import Layer, Light
from sketchforge.geometry.inflate_params import check_inflate_params
from sketchforge.errors import (
    DocumentFormatError,
    EditsDoNotApplyError,
    ParameterError,
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


def inflate_layer(doc, layer: Layer) -> Layer:
    """``layer`` with a mesh freshly inflated from its points and parameters, and its sculpt
    edits re-applied in order. Raises before anything changes."""
    if layer.points is None:
        return layer.evolve(mesh=None, edits=())
    mesh = doc.host.inflate(layer.points, layer.closed, dict(layer.params), holes=[np.asarray(h) for h in layer.holes])
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
    """Change inflation parameters; the mesh is rebuilt and the layer's sculpt edits are
    re-applied in order (if one no longer applies, the whole change is refused with its
    message and nothing changes)."""

    name: ClassVar[str] = "set_inflate_params"
    params: dict = field(default_factory=dict)

    def text(self) -> str:
        return "Set inflation parameters"

    def compute(self, doc, old: Layer) -> Layer:
        merged = check_inflate_params({**dict(old.params), **self.params})
        return inflate_layer(doc, old.evolve(params=merged))

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer, "params": dict(self.params)}

    @classmethod
    def from_dict(cls, d: dict) -> "SetInflateParams":
        params = parse_field(d, "params", dict, cls.name)
        check_inflate_params(params)
        return cls(layer=parse_field(d, "layer", str, cls.name), params=dict(params))


#: Mirror axes: the host's vertical symmetry axis (the layer an attached part's junction lies
#: on), or the part's own.
MIRROR_AXES = ("host", "own")


def host_of(doc, layer: Layer) -> Layer | None:
    """The layer an attached part hangs on: the nearest layer behind ``layer`` whose outline
    (holes cut out) contains the midpoint of its junction Γ_conn, or failing that the nearest
    such layer in front of it (a leg drawn behind the body hangs on the body's back face),
    looking past a sibling attached by the same junction (a copy duplicated in place, about to
    be mirrored); None for a free part (no junction) or a junction over empty space. The
    assembly decides attachment by the same sides in the same order (see :func:`attachment`
    for its whole rule), so this is the host it will be glued to."""
    mesh = layer.mesh
    if mesh is None or len(mesh.junction) < 2:
        return None
    import shapely

    from sketchforge.geometry import guard

    J = mesh.V[mesh.junction, :2]
    mid = J.mean(axis=0)
    ends = J[[0, -1]]
    tol = 1e-6 * max(1.0, float(np.ptp(mesh.V[:, :2], axis=0).max()))
    k = doc.index_of(layer.id)
    # Behind first (the part on the host's front face), then in front (on its back face).
    for below in list(reversed(doc.layers[:k])) + list(doc.layers[k + 1 :]):
        if below.points is None or below.mesh is None:
            continue
        bj = below.mesh.junction
        if len(bj) >= 2:
            other = below.mesh.V[bj[[0, -1]], :2]
            if min(np.abs(other - ends).max(), np.abs(other[::-1] - ends).max()) <= tol:
                continue  # a sibling glued at the same place (a copy in place): look past it
        try:
            region = guard.polygon(below.mesh.V[below.mesh.boundary, :2], f"the outline of layer {below.id!r}")
            for hole in below.mesh.holes:
                region = region.difference(guard.polygon(below.mesh.V[hole, :2], "a hole"))
        except SketchforgeError:
            continue
        if region.contains(shapely.Point(mid)):
            return below
    return None


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
    """Where the assembly glues ``layer`` (the rule of the assemble plugin's
    ``find_attachments``, on the document): (host, None) for a part whose junction lies inside
    the nearest layer behind it that it lies over, or else inside the nearest one in front;
    (None, problem) when the nearest layer it lies over does not hold all of it (the junction
    runs outside it, or spans two layers), the problem a sentence naming both; (None, None)
    for a free part (closed, or a junction over empty space).

    Cheap (shapely on the outlines), so the app can say at once why an assembly will fail and
    check, after a redraw, whether the parts glued to a layer still are."""
    import shapely

    mesh = layer.mesh
    if layer.closed or mesh is None or len(mesh.junction) < 2:
        return None, None
    J = mesh.V[mesh.junction, :2]
    line = shapely.LineString(J)
    if not line.length > 0:
        return None, None
    h = float(np.median(np.linalg.norm(np.diff(mesh.V[mesh.boundary, :2], axis=0), axis=1))) if len(mesh.boundary) > 1 else 0.0
    tol = 1e-6 * max(line.length, h)
    k = doc.index_of(layer.id)
    layers = doc.layers
    problem = None
    for order in (range(k - 1, -1, -1), range(k + 1, len(layers))):
        regions = [(layers[i], _region(layers[i])) for i in order if layers[i].visible]
        hits = [(l, r) for l, r in regions if r is not None and line.intersection(r).length > tol]
        if not hits:
            continue
        host, region = hits[0]
        hb = host.mesh.V[host.mesh.boundary, :2]
        hh = float(np.median(np.linalg.norm(np.diff(hb, axis=0), axis=1))) if len(hb) > 1 else 0.0
        if line.difference(region.buffer(-0.05 * hh)).length <= tol:
            return host, None
        if problem is None:
            name, other = quote(layer.name or layer.id), quote(host.name or host.id)
            if len(hits) > 1 and any(line.difference(region).intersection(r).length > tol for _, r in hits[1:]):
                problem = (f"the junction of layer {name} spans two layers ({other} and "
                           f"{quote(hits[1][0].name or hits[1][0].id)}); redraw its ends so that both lie inside one layer")
            else:
                problem = f"the junction of layer {name} runs outside layer {other}; redraw its ends so that both lie inside {other}"
    return None, problem


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
        if dict(other.params) != dict(layer.params):
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
    mesh and the positions its sculpt edits were drawn at (``pick``, ``stroke``) move
    together, so a later parameter change re-applies the edits where they now are."""

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
            copy = src.evolve(id=self.new_id, name=self.new_name)
            if self.offset is not None:
                copy = _translated(copy, off)
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


def _translated(layer: Layer, off: np.ndarray) -> Layer:
    """``layer`` moved by ``off`` (2,) in the drawing plane: stroke, holes, mesh and edit positions."""
    return _transformed(layer, np.array([[1.0, 0.0, off[0]], [0.0, 1.0, off[1]]]))


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


def _transformed(layer: Layer, A: np.ndarray) -> Layer:
    """``layer`` under the affine map A (2, 3): its stroke, holes, mesh and the positions its
    sculpt edits were drawn at (``pick``, ``stroke``; a ``band`` radius scales with the part)
    together. Heights scale by sqrt(det), the linear size of the part, so a scaled blob keeps
    its shape (a rotation or a move leaves them untouched). A pure move adds the offset only,
    bit for bit what ``translate_layer`` always did."""
    L, t = A[:, :2], A[:, 2]
    moved_only = bool(np.array_equal(L, np.eye(2)))
    s = float(np.sqrt(L[0, 0] * L[1, 1] - L[0, 1] * L[1, 0]))

    def f(P) -> np.ndarray:
        P = np.asarray(P, dtype=np.float64).reshape(-1, 2)
        return P + t if moved_only else P @ L.T + t

    changes: dict[str, Any] = {}
    if layer.points is not None:
        changes["points"] = f(layer.points)
    changes["holes"] = tuple(f(h) for h in layer.holes)
    if layer.mesh is not None:
        V = np.array(layer.mesh.V, dtype=np.float64)
        V[:, :2] = f(V[:, :2])
        if not moved_only:
            V[:, 2] *= s
        changes["mesh"] = replace(layer.mesh, V=V)
    edits = []
    for entry in layer.edits:
        e = dict(entry)
        if isinstance(e.get("pick"), list) and len(e["pick"]) >= 2:
            q = f(np.asarray(e["pick"][:2], dtype=np.float64))[0]
            e["pick"] = [float(q[0]), float(q[1]), *e["pick"][2:]]
        if isinstance(e.get("stroke"), list):
            e["stroke"] = f(e["stroke"]).tolist()
        if not moved_only and isinstance(e.get("band"), (int, float)) and not isinstance(e.get("band"), bool):
            e["band"] = float(e["band"]) * s
        light = e.get("light")
        if not moved_only and isinstance(light, list) and len(light) >= 2:
            # The edit was shaped by that light: it turns with the part (a direction, so
            # by the linear part, renormalised).
            v = L @ np.asarray(light[:2], dtype=np.float64)
            v = v / max(float(np.hypot(v[0], v[1])), 1e-300)
            e["light"] = [float(v[0]), float(v[1]), *light[2:]]
        edits.append(e)
    changes["edits"] = tuple(edits)
    return layer.evolve(**changes)


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
    holes, mesh and sculpt-edit positions together, without re-inflation (heights scale by
    sqrt(det), so a scaled part keeps its shape). One command per gesture: a drag of the app's
    handles is one ``transform_layer`` with the matrix of the whole drag.

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
        return _transformed(old, np.asarray(self.matrix, dtype=np.float64))

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
    """Move a layer in the drawing plane by ``offset`` (dx, dy): its stroke, mesh and sculpt
    edit positions together (no re-inflation: the same surface, moved). Kept so that files
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
        return _translated(old, np.asarray(self.offset, dtype=np.float64))

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
    """Set the light direction. Commands of one drag (same ``gesture``) merge into one undo
    step; the gesture id is not saved (the journal keeps the final direction)."""

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
    SetLight,
    MacroCommand,
)


class CommandRegistry:
    """Maps journal names to command classes (core + plugins)."""

    def __init__(self, classes) -> None:
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
