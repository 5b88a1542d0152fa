"""Draw a layer's contour: one stroke per layer, open or closed, in front or at a given depth;
and :func:`plan_stroke`, where a finished stroke goes (new part in front or behind, redraw of
a stretch or of the whole outline), decided from the document alone."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sketchforge.document.commands import AddLayer, Command, SetContour, SetInflateParams
from sketchforge.errors import ContourError, SketchforgeError
from sketchforge.geometry import guard
from sketchforge.geometry.inflate_params import DEFAULT_INFLATE_PARAMS
from sketchforge.geometry.parts import chord_touches, overlapped, splice_outline, stroke_closes
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
                 keep_edits: bool = False, holes=(), inflater: str | None = None) -> None:
        super().__init__(doc)
        self.target_layer = target_layer
        self.closed = closed
        #: where a new layer goes in the back-to-front list (None: in front of all)
        self.index = index
        #: a redraw re-applies the layer's sculpt edits (SetContour.keep_edits)
        self.keep_edits = keep_edits
        #: the target layer's holes after the stroke (a redraw keeps those that still fit; a
        #: cut adds one), each (n_i, 2) float64
        self.holes = tuple(holes)
        #: the inflater a new layer gets (None: the default; a redraw keeps the layer's own)
        self.inflater = inflater
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
        a SetContour for a redraw; an AddLayer (with its id fixed now), the choice of
        ``inflater`` if one is set (on the layer, before it has an outline: nothing to
        inflate yet) and a SetContour for a new layer, meant to be one macro "Draw layer"."""
        pts = np.asarray(points, dtype=np.float64)
        if self.target_layer is not None:
            return [], SetContour(layer=self.target_layer, points=pts, closed=self.closed, keep_edits=self.keep_edits,
                                  holes=self.holes)
        add = AddLayer(id=self.doc.new_layer_id(), index=self.index)
        before: list[Command] = [add]
        if self.inflater is not None:
            before.append(SetInflateParams(layer=add.id, solver=self.inflater))
        return before, SetContour(layer=add.id, points=pts, closed=self.closed)

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


# --- where a finished stroke goes (Monster Mash's rules), decided on the document alone ------


@dataclass(frozen=True)
class StrokePlan:
    """What a finished draw stroke does; :func:`plan_stroke` makes it, the front end runs it
    with :class:`DrawContourTool` (``target``, ``closed``, ``index``)."""

    #: the layer whose contour it sets (a redraw, or an empty layer); None: a new layer
    target: str | None
    #: (n, 2) float64, the contour: the stroke, or the outline with a stretch redrawn
    points: np.ndarray
    closed: bool
    #: where a new layer goes in the back-to-front list (None: in front of all)
    index: int | None = None
    #: "whole" or "stretch" for a redraw of an existing part, "hole" for a hole cut into it,
    #: None otherwise
    redraw: str | None = None
    #: the target's holes after the stroke, each (n_i, 2) float64 (a redraw keeps those still
    #: inside the new outline, a cut adds the stroke)
    holes: tuple = ()
    #: what the person should be told besides the result (drawn behind whom, made free)
    notes: tuple[str, ...] = ()
    #: why nothing is done (the rest is then meaningless)
    refusal: str | None = None


def layer_outlines(doc) -> list:
    """Each layer's outline, back to front, as it is drawn: the mesh boundary (m, 2) float64,
    else the stroke, None for an empty or hidden layer."""
    out: list[np.ndarray | None] = []
    for layer in doc.layers:
        if not layer.visible:
            out.append(None)
        elif layer.mesh is not None and len(layer.mesh.boundary):
            out.append(np.asarray(layer.mesh.V)[layer.mesh.boundary, :2])
        else:
            out.append(layer.points)
    return out


def is_free(layer) -> bool:
    """Closed as the assembly sees it: marked closed, or its mesh has no junction."""
    return bool(layer.closed) or (layer.mesh is not None and len(layer.mesh.junction) == 0)


def closes(points, params) -> bool | None:
    """:func:`~sketchforge.geometry.parts.stroke_closes` at ``params``' resolution; None for a
    stroke that cannot be an outline (the inflation then says why)."""
    try:
        return stroke_closes(points, float(params.get("resolution", DEFAULT_INFLATE_PARAMS["resolution"])))
    except ContourError:
        return None


def _region(P):
    """A shapely polygon of the ring P (n, 2), or None when it encloses no valid area."""
    try:
        return guard.polygon(P, "the stroke")
    except SketchforgeError:
        return None


def _holes_inside(layer, outline) -> tuple[tuple, int]:
    """(the layer's holes that lie inside the new ``outline`` (n, 2), how many were dropped)."""
    if not layer.holes:
        return (), 0
    region = _region(outline)
    kept = tuple(h for h in layer.holes if region is not None and (r := _region(h)) is not None and region.contains(r))
    return kept, len(layer.holes) - len(kept)


def _dropped_note(n: int) -> tuple[str, ...]:
    return (f"{n} hole{'s' * (n != 1)} outside the new outline {'were' if n != 1 else 'was'} dropped",) if n else ()


def plan_stroke(doc, points, kind: str = "front", selected: str | None = None, splice_tol: float = 0.0) -> StrokePlan:
    """Where a finished stroke goes.

    points : (n, 2) float64. kind : "front" (a new part in front of all), "behind" (a new part
    under the backmost part it overlaps, or at the very back), "redraw" (the selected part's
    whole outline) or "hole" (a closed stroke inside the selected part cuts a hole in it: its
    contour is set again with the same outline and one more hole, sculpt edits kept). A
    "front" stroke that starts and ends within ``splice_tol`` of the selected part's outline
    redraws that stretch; one with an empty layer selected fills it. A redraw keeps the holes
    that still lie inside the new outline. A new part is closed when its ends meet, and also
    when its open junction touches no part."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    layer = doc.layer(selected) if selected in doc.layer_ids() else None
    if kind == "hole":
        if layer is None or layer.points is None:
            return StrokePlan(None, pts, False, refusal="Alt + drag cuts a hole in the selected part: select a part first (click it)")
        outline = layer_outlines(doc)[doc.index_of(layer.id)]
        region, cut = _region(outline if outline is not None else layer.points), _region(pts)
        if cut is None:
            return StrokePlan(None, pts, False, refusal="the hole stroke encloses no area: draw a closed loop inside the part")
        if region is None or not region.contains(cut):
            return StrokePlan(None, pts, False, refusal=f"draw the hole inside “{layer.name}”, away from its outline")
        return StrokePlan(layer.id, np.asarray(layer.points), bool(layer.closed), redraw="hole", holes=layer.holes + (pts,))
    if kind == "redraw":
        if layer is None:
            return StrokePlan(None, pts, False, refusal="Ctrl + drag redraws the selected part's outline: select a part first (click it)")
        c = closes(pts, layer.params)
        holes, dropped = _holes_inside(layer, pts)
        return StrokePlan(layer.id, pts, layer.closed if c is None else c, redraw="whole", holes=holes,
                          notes=_dropped_note(dropped))
    if kind == "front" and layer is not None and layer.points is not None:
        spliced = splice_outline(layer.points, is_free(layer), pts, splice_tol)
        if spliced is not None:
            holes, dropped = _holes_inside(layer, spliced)
            return StrokePlan(layer.id, spliced, bool(layer.closed), redraw="stretch", holes=holes,
                              notes=_dropped_note(dropped))
    target = layer.id if kind == "front" and layer is not None and layer.points is None else None
    outlines = layer_outlines(doc)
    notes = []
    closed = closes(pts, DEFAULT_INFLATE_PARAMS if layer is None or target is None else layer.params)
    if closed is False and not chord_touches(pts, outlines):
        closed = True
        notes.append("its open ends touch no part, so it was made a closed free part")
    index = None
    if kind == "behind":
        hit = np.flatnonzero(overlapped(pts, outlines))
        index = int(hit[0]) if len(hit) else 0
        notes.insert(0, f"drawn behind “{doc.layers[index].name}”" if len(hit) else "drawn behind all parts (it overlaps none)")
    return StrokePlan(target, pts, bool(closed), index=index, notes=tuple(notes))
