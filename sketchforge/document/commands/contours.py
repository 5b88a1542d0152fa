"""Commands on a layer's contour and its inflation: draw or redraw the stroke (with its
holes), change the inflater or its parameters; and the inflation of a layer with its sculpt
edits re-applied, which every command that changes a stroke uses."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from sketchforge.cache import array_key
from sketchforge.document.commands.base import ReplaceLayerCommand, parse_field, parse_params, parse_points
from sketchforge.document.layer import Layer
from sketchforge.errors import EditsDoNotApplyError, SketchforgeError, SolverError


def layer_inflater(doc, layer: Layer):
    """The inflater of ``layer`` (its ``solver``, or the default for a layer that names none)
    and the layer's complete parameters for it (checked by the inflater).

    Raises
    ------
    UnknownSolverError, ParameterError, SketchforgeError
    """
    host = doc.host
    try:
        inflater = host.solver("inflate", layer.solver)
    except SketchforgeError:
        if layer.solver is None and not host.solvers("inflate"):
            raise SketchforgeError("no inflate plugin is installed, so a contour cannot become a mesh") from None
        raise
    return inflater, host.solver_params("inflate", inflater, layer.params)


def inflate_layer(doc, layer: Layer) -> Layer:
    """``layer`` with a mesh freshly inflated from its points by its inflater, with that
    inflater's name and complete parameters recorded, and its sculpt edits re-applied in
    order. Raises before anything changes."""
    inflater, params = layer_inflater(doc, layer)
    layer = layer.evolve(solver=inflater.name, params=params)
    if layer.points is None:
        return layer.evolve(mesh=None, edits=())
    return reapply_edits(doc, layer.evolve(mesh=inflated(doc, layer, inflater, params), edits=()), layer.edits)


def inflated(doc, layer: Layer, inflater=None, params=None):
    """``layer``'s surface as its inflater makes it from its points, before any sculpt edit
    (a Mesh; None for a layer without points). Kept in ``doc.inflations`` by its inputs
    (points, holes, closed, the inflater and its complete parameters), so the inflation a
    sculpt edit bounds its creases against (issue 36) is the one :func:`inflate_layer` made,
    bit for bit, in this session or on a replay. ``inflater`` and ``params``: the layer's, from
    :func:`layer_inflater` (found when not given).

    Raises
    ------
    SketchforgeError
        No inflater, refused parameters, or an inflation that fails or is not finite.
    """
    if layer.points is None:
        return None
    if inflater is None:
        inflater, params = layer_inflater(doc, layer)
    holes = [np.asarray(h, dtype=np.float64) for h in layer.holes]
    key = (array_key(np.asarray(layer.points, dtype=np.float64), *holes), bool(layer.closed), inflater.name, id(inflater),
           json.dumps(params, sort_keys=True, default=repr))
    cache = getattr(doc, "inflations", None)
    got = None if cache is None else cache.get(key)
    if got is not None and got[0] is inflater:
        return got[1]
    mesh = doc.host.inflate(layer.points, layer.closed, params, holes=holes, solver=inflater.name)
    if mesh is None:
        raise SketchforgeError("no inflate plugin is installed, so a contour cannot become a mesh")
    if not np.all(np.isfinite(mesh.V)):
        raise SolverError(f"inflating layer {layer.id!r} produced non-finite heights; nothing was changed")
    if cache is not None:
        cache.put(key, (inflater, mesh))
    return mesh


def reapply_edits(doc, layer: Layer, edits) -> Layer:
    """``layer`` (freshly inflated, no edits) with the sculpt ``edits`` re-applied in order."""
    out = layer
    for entry in edits:
        cls = doc.host.command_class(entry.get("command", ""))
        out = cls.reapply(doc, out, entry)
    return out


@dataclass
class SetContour(ReplaceLayerCommand):
    """Set (or redraw) a layer's stroke. By default redrawing drops the layer's sculpt edits
    (they were drawn on the old shape; the app asks first). With ``keep_edits`` the edits are
    re-applied to the new surface in order; if one no longer applies, nothing changes and
    :class:`~sketchforge.errors.EditsDoNotApplyError` says which (the app then asks whether
    to redraw without them).

    ``holes`` are the part's inner rings (any orientation), replacing the ones it had: the
    surface keeps height 0 on each. A hole that crosses the outline or another hole, lies
    outside, or is too small for the resolution is refused with a message naming it (1-based)
    and nothing changes. Cutting a hole into a drawn part is this command with the same
    points, the old holes plus the new one and ``keep_edits``."""

    name: ClassVar[str] = "set_contour"
    points: Any = None  # (n,2) float64
    closed: bool = False
    keep_edits: bool = False
    holes: Any = ()  # sequence of (n_i,2) float64

    def __post_init__(self) -> None:
        self.points = np.array(self.points, dtype=np.float64)
        self.points.setflags(write=False)
        self.holes = Layer(id="", name="", holes=self.holes).holes  # checked, read-only copies

    def text(self) -> str:
        return "Draw contour"

    def compute(self, doc, old: Layer) -> Layer:
        base = inflate_layer(doc, old.evolve(points=self.points, closed=bool(self.closed), edits=(), holes=self.holes))
        if not (self.keep_edits and old.edits):
            return base
        try:
            return reapply_edits(doc, base, old.edits)
        except SketchforgeError as exc:
            raise EditsDoNotApplyError(
                f"the {len(old.edits)} sculpt edit(s) of layer {old.id!r} do not apply to the new outline ({exc})"
            ) from None

    def to_dict(self) -> dict:
        d = {"command": self.name, "layer": self.layer, "points": self.points.tolist()}
        if self.closed:
            d["closed"] = True
        if self.keep_edits:
            d["keep_edits"] = True
        if self.holes:
            d["holes"] = [h.tolist() for h in self.holes]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> SetContour:
        raw = parse_field(d, "holes", list, cls.name, [])
        holes = [parse_points({"hole": h}, cls.name, key="hole") for h in raw]
        return cls(
            layer=parse_field(d, "layer", str, cls.name),
            points=parse_points(d, cls.name),
            closed=parse_field(d, "closed", bool, cls.name, False),
            keep_edits=parse_field(d, "keep_edits", bool, cls.name, False),
            holes=holes,
        )


@dataclass
class SetInflateParams(ReplaceLayerCommand):
    """Change a layer's inflater or its parameters; the mesh is rebuilt and the layer's sculpt
    edits are re-applied in order (if one no longer applies, the whole change is refused with
    its message and nothing changes).

    ``solver`` names the inflater (None: keep the layer's). Choosing another inflater starts
    from its defaults (the old inflater's parameters mean nothing to it); otherwise ``params``
    are merged into the layer's. The inflater checks them: an unknown key or a bad value is a
    one-line ParameterError naming the inflater and the key."""

    name: ClassVar[str] = "set_inflate_params"
    solver_kind: ClassVar[str | None] = "inflate"
    params: dict = field(default_factory=dict)
    solver: str | None = None

    def text(self) -> str:
        return "Set inflater" if self.solver is not None and not self.params else "Set inflation parameters"

    def compute(self, doc, old: Layer) -> Layer:
        switch = self.solver is not None and self.solver != old.solver
        base = {} if switch else dict(old.params)
        solver = self.solver if self.solver is not None else old.solver
        return inflate_layer(doc, old.evolve(solver=solver, params={**base, **self.params}))

    def to_dict(self) -> dict:
        d = {"command": self.name, "layer": self.layer, "params": dict(self.params)}
        if self.solver is not None:
            d["solver"] = self.solver
        return d

    @classmethod
    def from_dict(cls, d: dict) -> SetInflateParams:
        params = parse_params(d, cls.name)
        return cls(layer=parse_field(d, "layer", str, cls.name), params=params,
                   solver=parse_field(d, "solver", str, cls.name, None))
