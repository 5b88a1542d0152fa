"""The light command (``set_light``): one drag is one undo step."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from sketchforge.document.commands.base import Command, parse_vector
from sketchforge.document.layer import Light
from sketchforge.errors import DocumentFormatError, ParameterError


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

    def merge(self, other: Command) -> bool:
        if not isinstance(other, SetLight) or self.gesture is None or other.gesture != self.gesture:
            return False
        self._new = other._new
        self.direction = other.direction
        return True

    def to_dict(self) -> dict:
        return {"command": self.name, "direction": [float(v) for v in self.direction]}

    @classmethod
    def from_dict(cls, d: dict) -> SetLight:
        try:
            return cls(direction=parse_vector(d, "direction", cls.name))
        except ParameterError as exc:
            raise DocumentFormatError(f"command {cls.name!r}: 'direction': {exc}") from None
