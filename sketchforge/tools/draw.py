"""Draw a layer's contour: one stroke per layer, open or closed."""

from __future__ import annotations

import numpy as np

from sketchforge.document.commands import AddLayer, SetContour
from sketchforge.tools.base import Tool


class DrawContourTool(Tool):
    """Press-move-release draws a stroke. On release the stroke becomes the contour of
    ``target_layer`` (redraw) or of a new layer on top (a macro: add layer + set contour, one
    undo step). A failed inflation (self-intersecting stroke...) leaves the document as it was
    and re-raises the error for the front end to show."""

    name = "draw"
    label = "Draw contour"

    def __init__(self, doc, target_layer: str | None = None, closed: bool = False) -> None:
        super().__init__(doc)
        self.target_layer = target_layer
        self.closed = closed
        self._points: list[np.ndarray] = []

    def press(self, pos) -> None:
        self._points = [self.as_point(pos)]
        self.overlay = {"stroke": np.array(self._points)}

    def move(self, pos) -> None:
        if self._points:
            self._points.append(self.as_point(pos))
            self.overlay = {"stroke": np.array(self._points)}

    def release(self, pos):
        if not self._points:
            return None
        self._points.append(self.as_point(pos))
        pts = np.array(self._points)
        self._points = []
        self.overlay = {}
        stack = self.doc.undo_stack
        if self.target_layer is not None:
            return self.doc.push(SetContour(layer=self.target_layer, points=pts, closed=self.closed))
        stack.begin_macro("Draw layer")
        try:
            add = self.doc.push(AddLayer())
            self.doc.push(SetContour(layer=add.id, points=pts, closed=self.closed))
        except Exception:
            stack.abort_macro()
            raise
        return stack.end_macro()
