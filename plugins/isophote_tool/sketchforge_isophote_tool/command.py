"""The ``sculpt_isophote`` command: one isophote edit as a journal entry.

``{"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3,
"stroke": [[0.1, -0.3], ...]}``, optional ``"model"`` (a registered reflectance model name,
default "lambertian"), ``"solver"`` (a registered sculpt solver, default the built-in
"gauss_newton") and ``"params"`` (that solver's parameters, which it checks: an unknown key is
refused, naming the solver and the key). It acts with the document's current light; it keeps
the replaced layer so undo is instant and exact, and the new one so redo is too. The edit
recorded in the layer (re-applied after a parameter change) names the solver that made it and
the light it used.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from sketchforge.plugin_api import (
    MAX_COORDINATE,
    DocumentFormatError,
    Layer,
    NothingToDoError,
    ReplaceLayerCommand,
    SculptError,
    SketchforgeError,
    inflated,
    parse_field,
    parse_params,
    parse_points,
    parse_vector,
    transform_points,
)


def _model(doc, name: str):
    models = getattr(getattr(doc, "host", None), "reflectance_models", None) or {}
    if name in models:
        return models[name]
    if name == "lambertian":
        from sketchforge.plugin_api import LAMBERTIAN  # imports jax: only when used

        return LAMBERTIAN
    raise SculptError(f"no reflectance model named {name!r} is installed")


def _solver(doc, name: str | None):
    """The sculpt solver ``name`` (None: the default) of the document's host; a host that
    predates the registries (a bare test host) gets the built-in."""
    host = getattr(doc, "host", None)
    if host is None or not hasattr(host, "solver"):
        from .gauss_newton import GAUSS_NEWTON

        if name not in (None, GAUSS_NEWTON.name):
            raise SculptError(f"no sculpt solver named {name!r} is installed")
        return GAUSS_NEWTON, None
    solver = host.solver("sculpt", name)
    return solver, host.provider_of(solver)


def turn_light(light, L: np.ndarray):
    """An edit's light after its layer's linear map ``L`` (2, 2): the in-plane part turned,
    its length kept (a scale or a shear must not change a direction's length), z kept. An
    in-plane light is renormalised exactly as before lights could tilt; an overhead one
    (no in-plane part) stays as it is. Anything that is not a list of numbers is returned as
    it is (the file check refuses it)."""
    if not (isinstance(light, list) and len(light) >= 2):
        return light
    xy = np.asarray(light[:2], dtype=np.float64)
    v = L @ xy
    if len(light) < 3 or light[2] == 0.0:
        v = v / max(float(np.hypot(v[0], v[1])), 1e-300)
    else:
        length = float(np.hypot(xy[0], xy[1]))
        if length == 0.0:
            return list(light)
        v = v * (length / max(float(np.hypot(v[0], v[1])), 1e-300))
    return [float(v[0]), float(v[1]), *light[2:]]


def _transform_drawn(entry: dict, A: np.ndarray, scale: float, moved_only: bool) -> dict:
    """``pick`` and ``stroke`` of one isophote edit mapped by the affine ``A`` (2, 3), ``band``
    scaled by ``scale`` (not for a pure move: kept bit for bit)."""
    e = dict(entry)
    if isinstance(e.get("pick"), list) and len(e["pick"]) >= 2:
        q = transform_points(A, np.asarray(e["pick"][:2], dtype=np.float64))[0]
        e["pick"] = [float(q[0]), float(q[1]), *e["pick"][2:]]
    if isinstance(e.get("stroke"), list):
        e["stroke"] = transform_points(A, e["stroke"]).tolist()
    if not moved_only and isinstance(e.get("band"), (int, float)) and not isinstance(e.get("band"), bool):
        e["band"] = float(e["band"]) * scale
    return e


def _fresh(doc, layer: Layer):
    """The layer as inflated, before any edit (the reference of the crease bounds an edit is
    asked to keep, :mod:`.creases`), or None where it cannot be had (a host without an inflater,
    a bare test host): the edit then keeps the fixed bound. Refused parameters or a failing
    inflater are the next re-inflation's business, not this edit's."""
    if getattr(getattr(doc, "host", None), "inflate", None) is None:
        return None
    try:
        return inflated(doc, layer)
    except SketchforgeError:
        return None


def _apply(doc, layer: Layer, pick, band, stroke, model_name: str, light=None, solver_name=None, params=None):
    from .pipeline import sculpt  # imports jax: only when an edit actually runs

    if layer.mesh is None:
        raise SculptError(f"layer {layer.id!r} has no surface to sculpt yet (draw its contour first)")
    solver, provider = _solver(doc, solver_name)
    direction = doc.light.direction if light is None else np.asarray(light, dtype=np.float64)
    return sculpt(layer.mesh, direction, pick, band, stroke, _model(doc, model_name), solver=solver,
                  params=params, provider=provider, reference=_fresh(doc, layer))


def _with_solver_fields(d: dict, cmd) -> dict:
    """``d`` with the optional journal fields both sculpt commands share (``model`` when not
    Lambertian, ``solver``, ``params``): written only when set, so older files stay as they were."""
    if cmd.model != "lambertian":
        d["model"] = cmd.model
    if cmd.solver is not None:
        d["solver"] = cmd.solver
    if cmd.params:
        d["params"] = dict(cmd.params)
    return d


def _solver_fields(d: dict, name: str) -> dict:
    """The optional fields of :func:`_with_solver_fields` read back from a journal entry."""
    return {"model": parse_field(d, "model", str, name, "lambertian"),
            "solver": parse_field(d, "solver", str, name, None),
            "params": parse_params(d, name)}


@dataclass
class SculptIsophote(ReplaceLayerCommand):
    """Redraw the isophote through ``pick`` as ``stroke`` (thesis 4.3-4.6)."""

    name: ClassVar[str] = "sculpt_isophote"
    solver_kind: ClassVar[str | None] = "sculpt"
    pick: list = field(default_factory=list)
    band: float = 0.3
    stroke: list = field(default_factory=list)
    model: str = "lambertian"
    #: The sculpt solver (None: the default) and its parameters.
    solver: str | None = None
    params: dict = field(default_factory=dict)
    #: The last SculptResult (edit zone, fidelity, timings) for display; not saved.
    result: Any = field(default=None, repr=False, compare=False)

    def text(self) -> str:
        return "Sculpt isophote"

    def compute(self, doc, old: Layer) -> Layer:
        # Read once: the light the edit solves with is the one it records.
        light = [float(v) for v in doc.light.direction]
        self.result = _apply(doc, old, self.pick, self.band, self.stroke, self.model, light, self.solver, self.params)
        # The layer remembers the light this edit used and the solver that made it, so
        # re-applying it after a parameter change gives the same edit even if the light has
        # moved since or another solver has become the default.
        entry = {**self.to_dict(), "light": light, "solver": self.result.solver}
        return old.evolve(mesh=self.result.mesh, edits=tuple(old.edits) + (entry,))

    def to_dict(self) -> dict:
        d = {
            "command": self.name,
            "layer": self.layer,
            "pick": [float(v) for v in np.asarray(self.pick, float).reshape(-1)],
            "band": float(self.band),
            "stroke": np.asarray(self.stroke, float).reshape(-1, 2).tolist(),
        }
        return _with_solver_fields(d, self)

    @classmethod
    def from_dict(cls, d: dict) -> SculptIsophote:
        pick = parse_vector(d, "pick", cls.name)
        if len(pick) != 2:
            raise DocumentFormatError(f"command {cls.name!r}: 'pick' must be 2 numbers [x, y]")
        band = parse_field(d, "band", float, cls.name)
        if band > MAX_COORDINATE:  # band_radius() refuses it too; a file says so at load
            raise DocumentFormatError(f"command {cls.name!r}: 'band' is {band:.3g}; it must be at most "
                                      f"{MAX_COORDINATE:.0e} drawing units")
        return cls(
            layer=parse_field(d, "layer", str, cls.name),
            pick=pick,
            band=band,
            stroke=parse_points(d, cls.name, "stroke").tolist(),
            **_solver_fields(d, cls.name),
        )

    @classmethod
    def transform_edit(cls, entry: dict, matrix, scale: float) -> dict:
        """The edit after its layer was mapped by ``matrix`` (2, 3): where it was drawn
        (``pick``, ``stroke``) follows the part; the band radius scales with the part's size
        (``scale``); the light the edit was shaped by turns with it. A pure move adds the
        offset only (the band and light stay as they are, bit for bit)."""
        A = np.asarray(matrix, dtype=np.float64)
        L = A[:, :2]
        moved_only = bool(np.array_equal(L, np.eye(2)))
        e = _transform_drawn(entry, A, scale, moved_only)
        if not moved_only and "light" in e:
            e["light"] = turn_light(e["light"], L)
        return e

    @classmethod
    def reapply(cls, doc, layer: Layer, entry: dict) -> Layer:
        """Re-apply a saved edit to a re-inflated layer, with the light it was made with. An
        edit that no longer applies refuses the whole parameter change, saying which edit and
        why (silently dropping an edit would lose the user's work)."""
        cmd = cls.from_dict(entry)
        try:
            res = _apply(doc, layer, cmd.pick, cmd.band, cmd.stroke, cmd.model, entry.get("light"), cmd.solver, cmd.params)
        except (NothingToDoError, SculptError) as exc:
            n = len(layer.edits) + 1
            raise SculptError(
                f"sculpt edit {n} of layer {layer.id!r} no longer applies to the rebuilt surface ({exc}); "
                "the change was not made — undo that edit first to change these parameters"
            ) from None
        return layer.evolve(mesh=res.mesh, edits=tuple(layer.edits) + (dict(entry),))


def _apply_many(doc, layer: Layer, edits: list, model_name: str, light=None, solver_name=None, params=None):
    from .joint import sculpt_many  # imports jax: only when an edit actually runs

    if layer.mesh is None:
        raise SculptError(f"layer {layer.id!r} has no surface to sculpt yet (draw its contour first)")
    solver, provider = _solver(doc, solver_name)
    direction = doc.light.direction if light is None else np.asarray(light, dtype=np.float64)
    return sculpt_many(layer.mesh, direction, [(e["pick"], e["band"], e["stroke"]) for e in edits],
                       _model(doc, model_name), solver=solver, params=params, provider=provider,
                       reference=_fresh(doc, layer))


def _parse_edit(d, i: int, cmd: str) -> dict:
    """One entry of ``edits``: {"pick": [x, y], "band": b, "stroke": [[x, y], ...]}."""
    try:
        if not isinstance(d, dict):
            raise DocumentFormatError(f"command {cmd!r}: each edit must be an object with pick, band and stroke")
        unknown = sorted(set(d) - {"pick", "band", "stroke"})
        if unknown:
            raise DocumentFormatError(f"command {cmd!r}: unknown field {unknown[0]!r} (an edit has pick, band and stroke)")
        pick = parse_vector(d, "pick", cmd)
        if len(pick) != 2:
            raise DocumentFormatError(f"command {cmd!r}: 'pick' must be 2 numbers [x, y]")
        band = parse_field(d, "band", float, cmd)
        if band > MAX_COORDINATE:
            raise DocumentFormatError(f"command {cmd!r}: 'band' is {band:.3g}; it must be at most {MAX_COORDINATE:.0e} drawing units")
        return {"pick": pick, "band": band, "stroke": parse_points(d, cmd, "stroke").tolist()}
    except DocumentFormatError as exc:
        raise DocumentFormatError(f"{exc} (edits[{i}])") from None


@dataclass
class SculptIsophotes(ReplaceLayerCommand):
    """Redraw several isophotes of one layer in one edit, solved jointly (beyond the thesis:
    see :mod:`.joint`): ``{"command": "sculpt_isophotes", "layer": ..., "edits": [{"pick":
    [x, y], "band": b, "stroke": [[x, y], ...]}, ...]}`` with the optional ``model``,
    ``solver`` and ``params`` of ``sculpt_isophote``. One command, one undo step; the layer
    keeps it (with the light it used and the solver that made it) to re-apply it after a
    parameter change, and it follows its layer when that is moved."""

    name: ClassVar[str] = "sculpt_isophotes"
    solver_kind: ClassVar[str | None] = "sculpt"
    edits: list = field(default_factory=list)
    model: str = "lambertian"
    solver: str | None = None
    params: dict = field(default_factory=dict)
    #: The last JointSculptResult, for display; not saved.
    result: Any = field(default=None, repr=False, compare=False)

    def text(self) -> str:
        return f"Sculpt {len(self.edits)} isophotes" if len(self.edits) != 1 else "Sculpt isophote"

    def compute(self, doc, old: Layer) -> Layer:
        light = [float(v) for v in doc.light.direction]  # read once: the light used is the one recorded
        self.result = _apply_many(doc, old, self.edits, self.model, light, self.solver, self.params)
        entry = {**self.to_dict(), "light": light, "solver": self.result.solver}
        return old.evolve(mesh=self.result.mesh, edits=tuple(old.edits) + (entry,))

    def to_dict(self) -> dict:
        d = {
            "command": self.name,
            "layer": self.layer,
            "edits": [
                {
                    "pick": [float(v) for v in np.asarray(e["pick"], float).reshape(-1)],
                    "band": float(e["band"]),
                    "stroke": np.asarray(e["stroke"], float).reshape(-1, 2).tolist(),
                }
                for e in self.edits
            ],
        }
        return _with_solver_fields(d, self)

    @classmethod
    def from_dict(cls, d: dict) -> SculptIsophotes:
        raw = parse_field(d, "edits", list, cls.name)
        if not raw:
            raise DocumentFormatError(f"command {cls.name!r}: 'edits' must list at least one edit")
        from .joint import MAX_ISOPHOTES

        if len(raw) > MAX_ISOPHOTES:
            raise DocumentFormatError(f"command {cls.name!r}: 'edits' lists {len(raw)} edits; one edit redraws at most "
                                      f"{MAX_ISOPHOTES} isophotes")
        return cls(
            layer=parse_field(d, "layer", str, cls.name),
            edits=[_parse_edit(e, i, cls.name) for i, e in enumerate(raw)],
            **_solver_fields(d, cls.name),
        )

    @classmethod
    def transform_edit(cls, entry: dict, matrix, scale: float) -> dict:
        """As :meth:`SculptIsophote.transform_edit`, for every isophote of the edit."""
        A = np.asarray(matrix, dtype=np.float64)
        L = A[:, :2]
        moved_only = bool(np.array_equal(L, np.eye(2)))
        e = dict(entry)
        if isinstance(e.get("edits"), list):
            e["edits"] = [_transform_drawn(x, A, scale, moved_only) if isinstance(x, dict) else x for x in e["edits"]]
        if not moved_only and "light" in e:
            e["light"] = turn_light(e["light"], L)
        return e

    @classmethod
    def reapply(cls, doc, layer: Layer, entry: dict) -> Layer:
        """Re-apply a saved joint edit to a re-inflated layer, with the light it was made with;
        one that no longer applies refuses the parameter change, saying which edit and why."""
        cmd = cls.from_dict(entry)
        try:
            res = _apply_many(doc, layer, cmd.edits, cmd.model, entry.get("light"), cmd.solver, cmd.params)
        except (NothingToDoError, SculptError) as exc:
            n = len(layer.edits) + 1
            raise SculptError(
                f"sculpt edit {n} of layer {layer.id!r} no longer applies to the rebuilt surface ({exc}); "
                "the change was not made — undo that edit first to change these parameters"
            ) from None
        return layer.evolve(mesh=res.mesh, edits=tuple(layer.edits) + (dict(entry),))
