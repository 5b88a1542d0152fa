"""Commands that move a layer's stroke, holes, mesh and edits together: transform (move,
scale, rotate), translate, mirror (with its twin rule) and duplicate (with an offset); and
the affine helpers they share."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from sketchforge.document.commands.assembly import host_of
from sketchforge.document.commands.base import Command, ReplaceLayerCommand, parse_field, parse_vector
from sketchforge.document.commands.contours import inflate_layer
from sketchforge.document.layer import Layer
from sketchforge.errors import (
    DocumentFormatError,
    EditNotMovableError,
    ParameterError,
    PluginError,
    SketchforgeError,
    quote,
)

#: Mirror axes: the host's vertical symmetry axis (the layer an attached part's junction lies
#: on), or the part's own.
MIRROR_AXES = ("host", "own")


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
    def from_dict(cls, d: dict) -> MirrorLayer:
        axis = d.get("axis", "own")  # files from before the option mirrored about the part's own axis
        if not (axis in MIRROR_AXES or (isinstance(axis, (int, float)) and not isinstance(axis, bool))):
            raise DocumentFormatError(f"command {cls.name!r}: 'axis' must be 'host', 'own' or a number")
        return cls(layer=parse_field(d, "layer", str, cls.name), axis=float(axis) if not isinstance(axis, str) else axis,
                   of=parse_field(d, "of", str, cls.name, None), find_twin=False)


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
        d: dict = {"command": self.name, "layer": self.layer, "id": self.new_id, "name": self.new_name}
        if self.index is not None:
            d["index"] = self.index
        if self.offset is not None:
            d["offset"] = [float(v) for v in np.asarray(self.offset, dtype=np.float64).reshape(-1)]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> DuplicateLayer:
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
    def from_dict(cls, d: dict) -> TransformLayer:
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
    def from_dict(cls, d: dict) -> TranslateLayer:
        offset = parse_vector(d, "offset", cls.name)
        if len(offset) != 2:
            raise DocumentFormatError(f"command {cls.name!r}: 'offset' must be 2 numbers")
        return cls(layer=parse_field(d, "layer", str, cls.name), offset=offset)
