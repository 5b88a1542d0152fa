"""The isophote sculpt gesture (thesis figure 4.3): click to pick an isophote, then redraw it.

This is the one implementation of the gesture's logic; the Qt front end
(``sketchforge/qt/sculpt.py``) drives it and only adds drawing, threads and status text.
No Qt here: positions are document coordinates (x right, y up).

API (what a front end calls)
----------------------------
``pick_at(point) -> bool``
    Pick on the front-most visible layer under ``point``: the isovalue c there (0 in shadow),
    the component of the isophote E = c nearest to the point and the band around it, computed
    exactly as the ``sculpt_isophote`` command will (same cached layer data, same reflectance
    model). Fills :attr:`overlay` and returns True; a pick off every shape, or with no
    isophote, sets :attr:`message`, clears the pick and returns False.
``set_band(radius) -> bool``
    The band radius (drawing units); recomputes the band overlay. A radius that is not a
    positive number, or beyond the drawing's range (1e9, what the command accepts), keeps the
    old one, sets :attr:`message` and returns False.
``set_options(options)``
    Extra command fields: ``"model"`` (a registered reflectance model, e.g. ``"oren_nayar"``;
    absent is Lambertian), ``"solver"`` (a registered sculpt solver, e.g. ``"strips"``;
    absent is the default) and ``"params"`` (that solver's parameters). The pick uses the model
    too, so a current pick is recomputed. Raises SculptError for an unknown key, model or
    solver, ParameterError for parameters the solver refuses.
``command_for(stroke) -> SculptIsophote``
    The ``sculpt_isophote`` command for the current pick, band and options and a redrawn
    ``stroke`` (k, 2), *not* pushed: a front end may run ``cmd.prepare(doc)`` on a worker
    thread and push it later. Raises SculptError without a pick.
``command_dict(stroke) -> dict``
    Its journal entry.
``preview_job(stroke, mesh=None) -> callable``
    A zero-argument function computing the edit the stroke would make (a ``SculptResult``,
    not applied), with the layer, light, pick, band and model captured now: a front end runs
    it on a worker thread while the stroke is still being drawn and shows ``result.mesh``.
    ``mesh``: the surface the edit will start from when it is not the layer's current one
    (a front end that replaces its last attempt passes the surface before that attempt).
``press / move / release``
    The headless gesture. press-release without moving picks (as ``pick_at``); after a pick,
    press-move-release redraws: ``release`` builds the command, pushes it synchronously,
    returns it and the tool goes back to picking. A drag without a pick only sets
    :attr:`message`. ``end_stroke(pos)`` ends a drag without pushing (front ends that push
    on their own).

State
-----
``pick`` (2,) or None, ``layer_id``, ``isovalue``, ``isophote`` (k, 2), ``band`` (radius),
``options``, ``message`` (the last problem, "" if none) and ``overlay``: plain data for
drawing — ``"isophote"`` (k, 2) float64, ``"band"`` list of (m, 2) rings (exteriors and
holes), ``"isovalue"`` float, ``"layer"`` the picked layer id, ``"stroke"`` (k, 2) while a
stroke is drawn.
"""

from __future__ import annotations

import numpy as np

from sketchforge.errors import SculptError, SketchforgeError
from sketchforge.tools.base import Tool

from .command import SculptIsophote

COMMAND_NAME = SculptIsophote.name
#: Keys :meth:`SculptIsophoteTool.set_options` accepts (extra fields of the command dict).
OPTION_KEYS = ("model", "solver", "params")
NOT_ON_A_SHAPE = "the pick is not on a visible shape: click on a shape to choose an isophote"
PICK_FIRST = "pick an isophote first (click on the shape), then redraw it"


def _rings(geom) -> list[np.ndarray]:
    """Exterior and interior rings of a shapely (Multi)Polygon as (m, 2) float64 arrays."""
    if geom is None or geom.is_empty:
        return []
    out: list[np.ndarray] = []
    for g in getattr(geom, "geoms", [geom]):
        if g.geom_type == "Polygon":
            out.append(np.asarray(g.exterior.coords, dtype=np.float64)[:, :2])
            out.extend(np.asarray(r.coords, dtype=np.float64)[:, :2] for r in g.interiors)
        elif hasattr(g, "geoms"):
            out.extend(_rings(g))
    return out


class SculptIsophoteTool(Tool):
    name = "sculpt_isophote"
    label = "Redraw isophote"

    @staticmethod
    def warm_up() -> None:
        """Compile the reflectance evaluation every edit calls (the app runs this in the
        background at start, so the first stroke does not wait ~0.3 s for JAX)."""
        from .warmup import warm_up

        warm_up()

    def __init__(self, doc, layer: str | None = None, band: float = 0.3, options: dict | None = None) -> None:
        super().__init__(doc)
        #: Restrict picks to this layer id (None: the front-most visible layer under the point).
        self.layer = layer
        self.band = float(band)
        self.options: dict = {}
        self.message = ""
        self.pick: np.ndarray | None = None
        self.layer_id: str | None = None
        self.isovalue: float | None = None
        self.isophote: np.ndarray | None = None
        self._iso_geom = None  # shapely LineString of the picked isophote
        self._ld = None  # the picked layer's LayerData
        self._stroke: list[np.ndarray] = []
        self._pressed = False
        if options:
            self.set_options(options)

    # --- model --------------------------------------------------------------------------------
    def model(self):
        """The solver-side reflectance model the command will use."""
        from .command import _model

        return _model(self.doc, self.options.get("model", "lambertian"))

    def set_options(self, options: dict) -> None:
        options = dict(options or {})
        unknown = set(options) - set(OPTION_KEYS)
        if unknown:
            raise SculptError(f"unknown sculpt tool options {sorted(unknown)}; known: {list(OPTION_KEYS)}")
        if options.get("model") == "lambertian":
            options.pop("model")
        if options.get("solver") is None:
            options.pop("solver", None)
        if not options.get("params"):
            options.pop("params", None)
        old = self.options
        self.options = options
        try:
            self.model()  # an unknown model name raises here, not at the first stroke
            self._check_solver()  # and an unknown solver or a parameter it refuses
        except SketchforgeError:
            self.options = old
            raise
        if self.pick is not None and options != old:
            self.pick_at(self.pick)  # the isophote through the pick depends on the model

    def _check_solver(self) -> None:
        from .command import _solver
        from .pipeline import solver_params

        if "solver" not in self.options and "params" not in self.options:
            return
        solver, _ = _solver(self.doc, self.options.get("solver"))
        solver_params(solver, self.options.get("params"))

    # --- pick ---------------------------------------------------------------------------------
    def _candidates(self):
        if self.layer is not None:
            ids = self.doc.layer_ids()
            return [self.doc.layer(self.layer)] if self.layer in ids else []
        return [lay for lay in reversed(self.doc.layers) if lay.visible]  # front-most first

    def _clear_pick(self) -> None:
        self.pick = self.layer_id = self.isovalue = self.isophote = None
        self._iso_geom = self._ld = None
        self._stroke = []
        self.overlay = {}

    def pick_at(self, point) -> bool:
        import shapely

        from .isophote import picked_isophote
        from .layerdata import layer_data, outline_polygon

        try:
            p = self.as_point(point)
        except ValueError:
            p = np.full(2, np.nan)
        if not np.isfinite(p).all():
            self._clear_pick()
            self.message = f"the pick must be one finite point [x, y], got {np.ravel(point).tolist()}"
            return False
        model = self.model()
        for lay in self._candidates():
            mesh = lay.mesh
            if mesh is None or mesh.n_faces == 0:
                continue
            if not outline_polygon(mesh).covers(shapely.Point(p)):
                continue
            ld = layer_data(mesh, self.doc.light.direction, model)
            if ld.locator.locate(p.reshape(1, 2))[0][0] < 0:
                continue  # not on this layer after all
            try:
                c, iso = picked_isophote(ld, p)
            except SculptError as exc:
                self._clear_pick()
                self.message = str(exc)
                return False
            self._clear_pick()
            self.pick, self.layer_id, self.isovalue = p, lay.id, float(c)
            self._iso_geom, self._ld = iso, ld
            self.isophote = np.asarray(iso.coords, dtype=np.float64)[:, :2]
            self.overlay = {"isophote": self.isophote, "band": [], "isovalue": self.isovalue, "layer": lay.id}
            self.message = ""
            self._update_band()
            return True
        self._clear_pick()
        self.message = NOT_ON_A_SHAPE
        return False

    # --- band ---------------------------------------------------------------------------------
    def set_band(self, radius) -> bool:
        from sketchforge.geometry.band import band_radius

        try:  # the pipeline's own check: a radius it would refuse at the stroke is refused now
            r = band_radius(radius)
        except SculptError as exc:
            self.message = str(exc)
            return False
        old = self.band
        self.band = r
        if not self._update_band():
            self.band = old
            self._update_band()
            return False
        return True

    def _update_band(self) -> bool:
        from .isophote import band_around

        if self._iso_geom is None:
            return True
        try:
            geom = band_around(self._ld, self._iso_geom, self.band)
        except SketchforgeError as exc:
            self.message = str(exc)
            return False
        self.overlay["band"] = _rings(geom)
        return True

    # --- command ------------------------------------------------------------------------------
    def command_dict(self, stroke) -> dict:
        """The journal entry of an edit: what replay needs (the light is the document's)."""
        if self.pick is None or self.layer_id not in self.doc.layer_ids():
            raise SculptError(PICK_FIRST)
        d = {
            "command": COMMAND_NAME,
            "layer": self.layer_id,
            "pick": [float(v) for v in self.pick],
            "band": float(self.band),
            "stroke": np.asarray(stroke, dtype=np.float64).reshape(-1, 2).tolist(),
        }
        d.update(self.options)
        return d

    def command_for(self, stroke) -> SculptIsophote:
        """The command for the current pick and ``stroke``, built but not pushed."""
        return SculptIsophote.from_dict(self.command_dict(stroke))

    def preview_job(self, stroke, mesh=None):
        """A pure function computing the edit ``stroke`` would make (see the module
        docstring). Raises SculptError without a pick."""
        if self.pick is None or self.layer_id not in self.doc.layer_ids():
            raise SculptError(PICK_FIRST)
        from .pipeline import sculpt

        from .command import _solver

        mesh = self.doc.layer(self.layer_id).mesh if mesh is None else mesh
        light = np.array(self.doc.light.direction, dtype=np.float64)
        pick, band, model = self.pick.copy(), float(self.band), self.model()
        solver, provider = _solver(self.doc, self.options.get("solver"))
        params = dict(self.options.get("params") or {})
        points = np.array(stroke, dtype=np.float64).reshape(-1, 2)
        return lambda: sculpt(mesh, light, pick, band, points, model, solver=solver, params=params, provider=provider)

    # --- headless gesture ---------------------------------------------------------------------
    def _add(self, p: np.ndarray) -> None:
        if not self._stroke or not np.array_equal(p, self._stroke[-1]):  # a release repeats the last move
            self._stroke.append(p)

    def press(self, pos) -> None:
        self._pressed = True
        self._stroke = [self.as_point(pos)]
        self.overlay["stroke"] = np.array(self._stroke)

    def move(self, pos) -> None:
        if self._pressed and self._stroke:
            self._add(self.as_point(pos))
            self.overlay["stroke"] = np.array(self._stroke)

    def end_stroke(self, pos) -> np.ndarray:
        """End a press-move-release and return its points (k, 2) without pushing anything;
        ``overlay["stroke"]`` keeps them for display."""
        if self._stroke:
            self._add(self.as_point(pos))
        stroke = np.array(self._stroke) if self._stroke else np.zeros((0, 2))
        self._stroke, self._pressed = [], False
        if len(stroke):
            self.overlay["stroke"] = stroke
        return stroke

    def release(self, pos):
        p = self.as_point(pos)
        stroke = self.end_stroke(p)
        if len(stroke) < 2:  # a click: (re-)pick
            self.overlay.pop("stroke", None)
            self.pick_at(p)
            return None
        if self.pick is None:
            self.overlay.pop("stroke", None)
            self.message = PICK_FIRST
            return None
        cmd = self.doc.push(self.command_for(stroke))
        self._clear_pick()  # the surface changed: back to picking
        self.message = ""
        return cmd

    def cancel(self) -> None:
        """Drop the stroke in progress (the pick stays)."""
        self._stroke, self._pressed = [], False
        self.overlay.pop("stroke", None)

    def reset(self) -> None:
        """Forget the pick and any stroke."""
        self._pressed = False
        self._clear_pick()
        self.message = ""
