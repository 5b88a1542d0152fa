"""Draw a layer's contour: one stroke per layer, open or closed, in front or at a given depth."""

from __future__ import annotations

import numpy as np

from sketchforge.document.commands import AddLayer, Command, SetContour
from sketchforge.tools.base import Tool


class DrawContourTool(Tool):
    """Press-move-release draws a stroke. On release the stroke becomes the contour of
    ``target_layer`` (redraw) or of a new layer on top (a macro: add layer + set contour, one
    undo step). A failed inflation (self-intersecting stroke...) leaves the document as it was
    and re-raises the error for the front end to show.

    A front end that inflates on a worker thread uses :meth:`commands_for` and runs the
    commands itself; ``release`` runs them synchronously (scripts, tests)."""

    name = "draw"
    label = "Draw contour"

    def __init__(self, doc, target_layer: str | None = None, closed: bool = False, index: int | None = None,
                 keep_edits: bool = False) -> None:
        super().__init__(doc)
        self.target_layer = target_layer
        self.closed = closed
        #: where a new layer goes in the back-to-front list (None: in front of all)
        self.index = index
        #: a redraw re-applies the layer's sculpt edits (SetContour.keep_edits)
        self.keep_edits = keep_edits
        self._points: list[np.ndarray] = []

    def press(self, pos) -> None:
        self._points = [self.as_point(pos)]
        self.overlay = {"stroke": np.array(self._points)}

    def move(self, pos) -> None:
        if self._points:
            self._points.append(self.as_point(pos))
            self.overlay = {"stroke": np.array(self._points)}

    def commands_for(self, points) -> tuple[list[Command], Command]:
        """(commands to push first, the inflating command) for a finished stroke: nothing and
        a SetContour for a redraw; an AddLayer (with its id fixed now) and a SetContour for a
        new layer, meant to be one macro "Draw layer"."""
        pts = np.asarray(points, dtype=np.float64)
        if self.target_layer is not None:
            return [], SetContour(layer=self.target_layer, points=pts, closed=self.closed, keep_edits=self.keep_edits)
        add = AddLayer(id=self.doc.new_layer_id(), index=self.index)
        return [add], SetContour(layer=add.id, points=pts, closed=self.closed)

    def release(self, pos):
        if not self._points:
            return None
        self._points.append(self.as_point(pos))
        pts = np.array(self._points)
        self._points = []
        self.overlay = {}
        before, main = self.commands_for(pts)
        if not before:
            return self.doc.push(main)
        stack = self.doc.undo_stack
        stack.begin_macro("Draw layer")
        try:
            for cmd in before:
                self.doc.push(cmd)
            self.doc.push(main)
        except Exception:
            stack.abort_macro()
            raise
        return stack.end_macro()
