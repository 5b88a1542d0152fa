"""The animation's commands: each replaces the document's animation value, undo puts the old
one back. Journal entries::

    {"command": "add_pin", "id": "pin1", "at": [x, y, z]}
    {"command": "move_pin", "pin": "pin1", "to": [x, y, z]}          (one undo step per drag)
    {"command": "remove_pin", "pin": "pin1"}
    {"command": "hold_pin", "pin": "pin1"}           (drop its motion: pinned in place)
    {"command": "record_motion", "pin": "pin1", "start": 0, "samples": [[x, y, z], ...]}
    {"command": "copy_motion", "source": "pin1", "pin": "pin2"}
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from sketchforge.plugin_api import Command, DocumentFormatError, ParameterError, parse_field

from .state import KEY, MAX_LOOP_FRAMES, Animation, Pin, _triples, _vec, check_range, fit_recording


def _parse_vec(d: dict, key: str, cmd: str) -> tuple:
    raw = parse_field(d, key, list, cmd)
    try:
        return _vec(raw, f"command {cmd!r}: {key!r}")
    except ParameterError as exc:
        raise DocumentFormatError(str(exc)) from None


@dataclass
class AnimationCommand(Command):
    """Shared machinery: compute the new animation once, swap it in, swap the old one back."""

    _old: Any = field(default=None, repr=False)
    _new: Any = field(default=None, repr=False)
    _computed: bool = field(default=False, repr=False)

    def compute(self, doc, anim: Animation) -> Animation:
        raise NotImplementedError

    def prepare(self, doc) -> None:
        old = doc.plugin_data(KEY)
        if not self._computed or old is not self._old:
            new = self.compute(doc, Animation.from_json(old))  # may raise: nothing changed yet
            for pin in new.pins:  # never a value that the file could not hold (see state._vec)
                check_range(np.array([pin.rest, pin.target]), f"{self.text()} on pin {pin.id!r}")
                if pin.motion is not None:
                    check_range(pin.motion, f"{self.text()} on pin {pin.id!r}")
            self._old, self._new, self._computed = old, new.to_json(), True

    def do(self, doc) -> None:
        self.prepare(doc)
        doc._set_plugin_data(KEY, self._new)

    def undo(self, doc) -> None:
        doc._set_plugin_data(KEY, self._old)


@dataclass
class AddPin(AnimationCommand):
    name: ClassVar[str] = "add_pin"
    id: str | None = None
    at: tuple = (0.0, 0.0, 0.0)

    def text(self) -> str:
        return "Add pin"

    def compute(self, doc, anim):
        from .pose import attach_pins

        at = _vec(self.at, "a pin's position")
        if self.id is None:
            self.id = anim.new_pin_id()
        if self.id in {p.id for p in anim.pins}:
            raise ParameterError(f"a pin with id {self.id!r} already exists")
        mesh = doc.export_mesh()  # raises a clear error when there is no model to pin
        rests = np.array([p.rest for p in anim.pins] + [at]).reshape(-1, 3)
        attach_pins(mesh.V, rests, [p.id for p in anim.pins] + [self.id])  # refuses a second pin on a vertex
        return anim.with_pin(Pin(self.id, at, at))

    def to_dict(self) -> dict:
        return {"command": self.name, "id": self.id, "at": [float(v) for v in self.at]}

    @classmethod
    def from_dict(cls, d: dict) -> AddPin:
        return cls(id=parse_field(d, "id", str, cls.name, None), at=_parse_vec(d, "at", cls.name))


@dataclass
class MovePin(AnimationCommand):
    """Move a pin's target (the pose). A pin with a motion moves its whole trajectory by the
    same offset. Moves of one drag (same ``gesture``) merge into one undo step."""

    name: ClassVar[str] = "move_pin"
    merge_id: ClassVar[str | None] = "move_pin"
    pin: str = ""
    to: tuple = (0.0, 0.0, 0.0)
    gesture: int | None = None

    def text(self) -> str:
        return "Move pin"

    def compute(self, doc, anim):
        p = anim.pin(self.pin)
        to = np.array(_vec(self.to, "a pin's new position"))
        motion = p.motion
        if motion is not None:
            motion = motion + (to - np.array(p.target))
            motion.setflags(write=False)
        return anim.with_pin(replace(p, target=tuple(float(v) for v in to), motion=motion))

    def merge(self, other) -> bool:
        if self.gesture is None or other.gesture != self.gesture or other.pin != self.pin:
            return False
        self.to, self._new = other.to, other._new
        return True

    def to_dict(self) -> dict:
        return {"command": self.name, "pin": self.pin, "to": [float(v) for v in self.to]}

    @classmethod
    def from_dict(cls, d: dict) -> MovePin:
        return cls(pin=parse_field(d, "pin", str, cls.name), to=_parse_vec(d, "to", cls.name))


@dataclass
class RemovePin(AnimationCommand):
    name: ClassVar[str] = "remove_pin"
    pin: str = ""

    def text(self) -> str:
        return "Remove pin"

    def compute(self, doc, anim):
        return anim.without_pin(self.pin)

    def to_dict(self) -> dict:
        return {"command": self.name, "pin": self.pin}

    @classmethod
    def from_dict(cls, d: dict) -> RemovePin:
        return cls(pin=parse_field(d, "pin", str, cls.name))


@dataclass
class HoldPin(AnimationCommand):
    """Pin in place: drop the pin's motion; it holds its vertex at its current target."""

    name: ClassVar[str] = "hold_pin"
    pin: str = ""

    def text(self) -> str:
        return "Pin in place"

    def compute(self, doc, anim):
        p = anim.pin(self.pin)
        if p.motion is None:
            raise ParameterError(f"pin {self.pin!r} has no motion: it is already held in place")
        return anim.with_pin(replace(p, motion=None))._loop_checked()

    def to_dict(self) -> dict:
        return {"command": self.name, "pin": self.pin}

    @classmethod
    def from_dict(cls, d: dict) -> HoldPin:
        return cls(pin=parse_field(d, "pin", str, cls.name))


@dataclass
class RecordMotion(AnimationCommand):
    """A pin's trajectory recorded while dragging, one sample per frame (24 fps) from loop
    frame ``start``. The first recording defines the loop; later ones run in sync with it."""

    name: ClassVar[str] = "record_motion"
    pin: str = ""
    start: int = 0
    samples: Any = None  # (k,3) float64

    def __post_init__(self) -> None:
        self.samples = np.array(self.samples if self.samples is not None else np.zeros((0, 3)), dtype=np.float64).reshape(-1, 3)
        self.samples.setflags(write=False)

    def text(self) -> str:
        return "Record motion"

    def compute(self, doc, anim):
        p = anim.pin(self.pin)
        check_range(self.samples, "a recorded motion")
        if self.start < 0:
            raise ParameterError(f"a recording's start frame must be 0 or more, got {self.start}")
        # re-recording the only moving pin redefines the loop
        others = any(q.motion is not None for q in anim.pins if q.id != p.id)
        loop = anim.loop if others else 0
        traj, loop = fit_recording(self.samples, self.start, loop)
        traj.setflags(write=False)
        pins = anim.with_pin(replace(p, motion=traj, target=tuple(float(v) for v in traj[0])))
        return replace(pins, loop=loop)

    def to_dict(self) -> dict:
        return {"command": self.name, "pin": self.pin, "start": int(self.start), "samples": self.samples.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> RecordMotion:
        raw = parse_field(d, "samples", list, cls.name)
        if len(raw) > 4 * MAX_LOOP_FRAMES:
            raise DocumentFormatError(f"command {cls.name!r}: at most {4 * MAX_LOOP_FRAMES} samples")
        try:
            samples = _triples(raw, f"command {cls.name!r}: 'samples'")
        except ParameterError as exc:
            raise DocumentFormatError(str(exc)) from None
        return cls(pin=parse_field(d, "pin", str, cls.name), start=parse_field(d, "start", int, cls.name, 0), samples=samples)


@dataclass
class CopyMotion(AnimationCommand):
    """Paste ``source``'s motion onto ``pin``, relative to each pin's own rest point (the
    copy moves the same way, from where it is)."""

    name: ClassVar[str] = "copy_motion"
    source: str = ""
    pin: str = ""

    def text(self) -> str:
        return "Paste motion"

    def compute(self, doc, anim):
        src, dst = anim.pin(self.source), anim.pin(self.pin)
        if src.motion is None:
            raise ParameterError(f"pin {self.source!r} has no motion to copy")
        if src.id == dst.id:
            raise ParameterError("copy a motion to another pin")
        motion = src.motion + (np.array(dst.rest) - np.array(src.rest))
        motion.setflags(write=False)
        return anim.with_pin(replace(dst, motion=motion, target=tuple(float(v) for v in motion[0])))

    def to_dict(self) -> dict:
        return {"command": self.name, "source": self.source, "pin": self.pin}

    @classmethod
    def from_dict(cls, d: dict) -> CopyMotion:
        return cls(source=parse_field(d, "source", str, cls.name), pin=parse_field(d, "pin", str, cls.name))


ANIMATION_COMMANDS = (AddPin, MovePin, RemovePin, HoldPin, RecordMotion, CopyMotion)
