"""The Tool protocol shared by built-in and plugin tools.

Positions are document coordinates (x right, y up) as (2,) float64 arrays; the front end
converts from its pixel space (Qt's y axis points down). A tool pushes commands on the
document itself and keeps whatever preview state a view needs in :attr:`overlay`.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np


class Tool:
    #: Unique registry name and menu label.
    name: ClassVar[str] = ""
    label: ClassVar[str] = ""
    #: Optional zero-argument callable doing slow one-time work ahead of the first gesture
    #: (compiling a solver); the app runs it on a background thread at start.
    warm_up: ClassVar = None

    def __init__(self, doc) -> None:
        self.doc = doc
        #: Plain data for drawing the gesture in progress (polylines as (k,2) arrays, ...).
        self.overlay: dict = {}

    def press(self, pos) -> None:
        pass

    def move(self, pos) -> None:
        pass

    def release(self, pos):
        """End the gesture; returns the command pushed, if any."""
        return None

    def cancel(self) -> None:
        self.overlay = {}

    @staticmethod
    def as_point(pos) -> np.ndarray:
        p = np.asarray(pos, dtype=np.float64).reshape(2)
        return p
