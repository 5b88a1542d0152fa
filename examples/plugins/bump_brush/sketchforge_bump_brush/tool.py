"""The "Bump brush" tool: press on a shape, drag up to raise (down to sink), release.

A click adds a bump of :attr:`BumpTool.click_height`. The overlay shows the brush disc and
the drag. In the app the command pushed here is prepared on a worker thread and is one undo
step; headless (tests, scripts) ``release`` pushes it on the document directly.
"""

from __future__ import annotations

import numpy as np

from sketchforge.plugin_api import SculptError, Tool, layer_at
from sketchforge_bump_brush.brush import BumpBrush


class BumpTool(Tool):
    name = "bump_brush"
    label = "Bump brush"
    shortcut = "Shift+B"
    #: Brush radius (drawing units) and the height a click adds.
    radius = 0.3
    click_height = 0.1

    def __init__(self, doc) -> None:
        super().__init__(doc)
        self._start: np.ndarray | None = None
        self.message = ""

    def _disc(self, c: np.ndarray) -> np.ndarray:
        t = np.linspace(0.0, 2.0 * np.pi, 49)
        return np.c_[c[0] + self.radius * np.cos(t), c[1] + self.radius * np.sin(t)]

    def press(self, pos) -> None:
        self._start = self.as_point(pos)
        self.overlay = {"disc": self._disc(self._start)}

    def move(self, pos) -> None:
        if self._start is not None:
            self.overlay["drag"] = np.vstack([self._start, self.as_point(pos)])

    def release(self, pos):
        start, self._start = self._start, None
        self.overlay = {}
        if start is None:
            return None
        dy = float(self.as_point(pos)[1] - start[1])
        height = self.click_height if abs(dy) < 1e-9 else dy
        layer = layer_at(self.doc, start)
        if layer is None:
            raise SculptError("press on a shape to brush it")
        return self.doc.push(BumpBrush(layer=layer, center=start.tolist(), radius=self.radius, height=height))

    def cancel(self) -> None:
        self._start = None
        self.overlay = {}
