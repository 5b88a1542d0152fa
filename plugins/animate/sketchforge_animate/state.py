"""The animation as a value: pins, their poses and recorded motions, the loop length.

Stored in the document as plain JSON under ``doc.plugin_data("animate")``::

    {"loop": 48, "pins": [{"id": "pin1", "rest": [x, y, z], "target": [x, y, z],
                           "motion": [[x, y, z], ...]}]}

- ``rest``: where the pin was put on the static model; it is re-attached to the nearest
  vertex of the assembled model whenever that is rebuilt.
- ``target``: where the pin holds that vertex when it has no motion (the pose).
- ``motion`` (optional): one position per frame of the loop (``loop`` frames at 24 fps).
- ``loop``: frames of the loop, set by the first recording; 0 while nothing is recorded.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field, replace

import numpy as np

from sketchforge.plugin_api import MAX_PARAMETER, DocumentFormatError, ParameterError, number, quote

KEY = "animate"
FPS = 24
#: Gaussian smoothing of a recorded trajectory, in frames (removes the hand's jitter).
SMOOTHING_FRAMES = 1.5
MAX_PINS = 64
MAX_LOOP_FRAMES = 24 * 60


def validate_json(value) -> None:
    """The ``sketchforge_plugin_data_validators`` check of a stored animation: raises
    DocumentFormatError where :meth:`Animation.from_json` would."""
    Animation.from_json(value)


#: A coordinate, by the core's rule for numeric parameters: a real number (not a bool, not a
#: string such as "1"), finite, within the drawing's range (issue 38: ``add_pin`` took "1" and
#: 1e308, and a snapshot target [[0], [0], [0]] was flattened into a point).
_COORDINATE = number("coordinate", -MAX_PARAMETER, MAX_PARAMETER)


def _vec(v, what: str) -> tuple[float, float, float]:
    """A point [x, y, z]: a list, tuple or (3,) array of 3 coordinates (see _COORDINATE)."""
    if isinstance(v, np.ndarray) and v.shape == (3,):
        v = v.tolist()
    if not isinstance(v, (list, tuple)) or len(v) != 3:
        raise ParameterError(f"{what} must be 3 numbers [x, y, z], got {quote(v, 60)}")
    try:
        return tuple(_COORDINATE(x) for x in v)
    except ParameterError:
        raise ParameterError(
            f"{what} must be 3 finite numbers [x, y, z] within ±{MAX_PARAMETER:g}, got {quote(v, 60)}"
        ) from None


def _triples(raw, what: str) -> np.ndarray:
    """(k, 3) float64 from a list of [x, y, z] (a journal's samples, a stored motion), each
    coordinate checked as in :func:`_vec`; one line naming ``what`` otherwise."""
    bad = ParameterError(f"{what} must be [x, y, z] triples of finite numbers within ±{MAX_PARAMETER:g}")
    if not isinstance(raw, (list, tuple)) or not all(isinstance(p, (list, tuple)) and len(p) == 3 for p in raw):
        raise bad
    if not all(isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_)) for p in raw for x in p):
        raise bad
    try:
        a = np.array(raw, dtype=np.float64).reshape(-1, 3)
    except (OverflowError, TypeError, ValueError):
        raise bad from None
    if not np.all(np.isfinite(a)) or (a.size and np.abs(a).max() > MAX_PARAMETER):
        raise bad
    return a


def check_range(a: np.ndarray, what: str) -> None:
    """Refuse positions a file could not hold: non-finite or beyond the drawing's range (a
    motion moved again and again by ``move_pin``)."""
    if not np.all(np.isfinite(a)) or (a.size and np.abs(a).max() > MAX_PARAMETER):
        raise ParameterError(f"{what} would leave the drawing's range (±{MAX_PARAMETER:g}); it was not changed")


@dataclass(frozen=True)
class Pin:
    id: str
    rest: tuple
    target: tuple
    motion: np.ndarray | None = field(default=None, compare=False)  # (loop, 3) float64, read-only

    def to_json(self) -> dict:
        d = {"id": self.id, "rest": list(self.rest), "target": list(self.target)}
        if self.motion is not None:
            d["motion"] = self.motion.tolist()
        return d


@dataclass(frozen=True)
class Animation:
    pins: tuple = ()
    loop: int = 0

    # --- JSON ---------------------------------------------------------------------------------
    def to_json(self) -> dict | None:
        """The document value (None when there is nothing: no pins)."""
        if not self.pins:
            return None
        return {"loop": int(self.loop), "pins": [p.to_json() for p in self.pins]}

    @classmethod
    def from_json(cls, d) -> Animation:
        """The animation of a stored value, checked with the limits the commands keep (at
        most MAX_PINS pins with distinct string ids, a loop of 0..MAX_LOOP_FRAMES frames, one
        finite [x, y, z] per loop frame in a motion, and a motion only with a loop). Raises
        DocumentFormatError in one line."""
        if d is None:
            return cls()
        try:
            if not isinstance(d, dict):
                raise ParameterError(f"it must be an object with 'loop' and 'pins', got {type(d).__name__}")
            loop = d.get("loop", 0)
            if not isinstance(loop, int) or isinstance(loop, bool) or not 0 <= loop <= MAX_LOOP_FRAMES:
                raise ParameterError(f"the loop length must be 0..{MAX_LOOP_FRAMES} frames, got {quote(loop, 40)}")
            raw = d["pins"]
            if not isinstance(raw, list):
                raise ParameterError(f"'pins' must be a list, got {type(raw).__name__}")
            if len(raw) > MAX_PINS:
                raise ParameterError(f"an animation has at most {MAX_PINS} pins, this one has {len(raw):,}")
            pins, seen = [], set()
            for p in raw:
                if not isinstance(p, dict):
                    raise ParameterError(f"a pin must be an object, got {type(p).__name__}")
                pid = p["id"]
                if not isinstance(pid, str) or not pid:
                    raise ParameterError(f"a pin's id must be a non-empty string, got {quote(pid, 40)}")
                if pid in seen:
                    raise ParameterError(f"two pins have the id {quote(pid)}")
                seen.add(pid)
                motion = p.get("motion")
                if motion is not None:
                    if loop < 2:
                        raise ParameterError(f"pin {quote(pid)} has a motion but the loop has {loop} frames")
                    if not isinstance(motion, list) or len(motion) != loop:
                        raise ParameterError(f"pin {quote(pid)}: its motion must have one [x, y, z] per loop frame ({loop})")
                    motion = _triples(motion, f"pin {quote(pid)}: its motion (one [x, y, z] per loop frame ({loop}))")
                    motion.setflags(write=False)
                pins.append(
                    Pin(
                        pid,
                        _vec(p["rest"], f"the rest of pin {quote(pid)}"),
                        _vec(p["target"], f"the target of pin {quote(pid)}"),
                        motion,
                    )
                )
        except KeyError as exc:
            raise DocumentFormatError(
                f"the animation data is malformed: a pin or the animation lacks the field {quote(exc.args[0], 40)}"
            ) from None
        except (TypeError, AttributeError, ValueError, ParameterError, OverflowError) as exc:
            raise DocumentFormatError(f"the animation data is malformed: {exc}") from None
        return cls(tuple(pins), loop)

    @classmethod
    def of(cls, doc) -> Animation:
        return cls.from_json(doc.plugin_data(KEY))

    # --- queries ------------------------------------------------------------------------------
    def pin(self, pin_id: str) -> Pin:
        for p in self.pins:
            if p.id == pin_id:
                return p
        known = ", ".join(p.id for p in self.pins) or "none"
        raise ParameterError(f"there is no pin {pin_id!r} (pins: {known})")

    def has_motion(self) -> bool:
        return self.loop >= 2 and any(p.motion is not None for p in self.pins)

    def new_pin_id(self) -> str:
        taken = {p.id for p in self.pins}
        i = 1
        while f"pin{i}" in taken:
            i += 1
        return f"pin{i}"

    def targets(self, frame: int) -> np.ndarray:
        """(k,3) float64: every pin's position at ``frame`` (wrapping around the loop)."""
        out = np.empty((len(self.pins), 3))
        for i, p in enumerate(self.pins):
            out[i] = p.motion[frame % self.loop] if p.motion is not None else p.target
        return out

    # --- edits (return new values) ------------------------------------------------------------
    def with_pin(self, pin: Pin) -> Animation:
        pins = [pin if p.id == pin.id else p for p in self.pins]
        if pin.id not in {p.id for p in self.pins}:
            if len(pins) >= MAX_PINS:
                raise ParameterError(f"an animation has at most {MAX_PINS} pins")
            pins.append(pin)
        return replace(self, pins=tuple(pins))

    def without_pin(self, pin_id: str) -> Animation:
        self.pin(pin_id)
        out = replace(self, pins=tuple(p for p in self.pins if p.id != pin_id))
        return out._loop_checked()

    def _loop_checked(self) -> Animation:
        # the loop is defined by the recordings: with none left, the next one starts afresh
        if not any(p.motion is not None for p in self.pins):
            return replace(self, loop=0)
        return self


def smooth_loop(traj: np.ndarray, sigma: float = SMOOTHING_FRAMES) -> np.ndarray:
    """Circular Gaussian smoothing. traj (L,3) float64 -> (L,3) float64 (the loop wraps)."""
    L = len(traj)
    if L < 3 or sigma <= 0:
        return traj.copy()
    r = min(int(np.ceil(3 * sigma)), (L - 1) // 2)
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    out = np.zeros_like(traj)
    for off, wk in zip(range(-r, r + 1), k):
        out += wk * np.roll(traj, off, axis=0)
    return out


def fit_recording(samples: np.ndarray, start: int, loop: int) -> tuple[np.ndarray, int]:
    """Place a recording on the loop (Monster Mash: later recordings run in sync with the first).

    samples (k,3) float64, one per frame from frame ``start``; ``loop`` the current loop length
    (0: this is the first recording, which defines the loop and starts at frame 0).
    Returns (trajectory (L,3) float64 smoothed, L). A recording longer than the loop keeps its
    last pass; frames it did not reach are filled by a straight blend from its last sample
    back to its first, so the loop closes.
    """
    samples = np.asarray(samples, dtype=np.float64)
    k = len(samples)
    if k < 2:
        raise ParameterError("a recording needs at least 2 frames (hold the record key while dragging)")
    if loop == 0:
        if k > MAX_LOOP_FRAMES:
            raise ParameterError(f"a recording is at most {MAX_LOOP_FRAMES} frames ({MAX_LOOP_FRAMES // FPS} s)")
        return smooth_loop(samples), k
    frames = (start + np.arange(k)) % loop
    traj = np.empty((loop, 3))
    have = np.zeros(loop, dtype=bool)
    for f, s in zip(frames, samples):  # later samples overwrite: the last pass wins
        traj[f] = s
        have[f] = True
    if not have.all():
        # the gap runs from just after the last sample's frame to just before the first's
        first, last = frames[-min(k, loop)], frames[-1]
        gap = [(last + 1 + i) % loop for i in range(loop) if not have[(last + 1 + i) % loop]]
        n = len(gap)
        for i, f in enumerate(gap):
            t = (i + 1) / (n + 1)
            traj[f] = (1 - t) * traj[last] + t * traj[first]
    return smooth_loop(traj), loop
