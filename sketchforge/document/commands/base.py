"""The base of every command (:class:`Command`, :class:`ReplaceLayerCommand`,
:class:`MacroCommand`), gesture ids, and the checked parsing of journal fields that every
command's ``from_dict`` uses."""

from __future__ import annotations

import itertools
import math
import numbers
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from sketchforge.document.layer import Layer
from sketchforge.errors import DocumentFormatError, EditNotMovableError

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

    def merge(self, other: Command) -> bool:
        """Absorb ``other`` (already done) into self; return True when merged."""
        return False

    def try_merge(self, other: Command) -> bool:
        if self.merge_id is None or self.merge_id != other.merge_id or type(self) is not type(other):
            return False
        return self.merge(other)

    def to_dict(self) -> dict:
        raise NotImplementedError

    @classmethod
    def from_dict(cls, d: dict) -> Command:
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


def parse_params(d: dict, cmd: str, key: str = "params") -> dict:
    """A journal entry's solver parameters: an object of JSON values (the solver checks the
    keys and values when the command runs, and when a document with a snapshot is opened)."""
    from sketchforge.solver_kinds import json_value

    params = parse_field(d, key, dict, cmd, {})
    if not json_value(params):
        raise DocumentFormatError(f"command {cmd!r}: {key!r} must hold numbers, strings, true/false or lists of them")
    return dict(params)


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
    def from_dict(cls, d: dict, registry=None, depth: int = 1) -> MacroCommand:
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
