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
``add_pick_at(point) -> bool``
    Shift+click: pick another isophote of the same layer while one is picked (each keeps the
    band radius it had; :meth:`set_band` then acts on the newest). Refused (False, with
    :attr:`message`) off that layer, on an isophote picked already, beyond
    ``joint.MAX_ISOPHOTES``, or when the chosen solver redraws one isophote per edit.
    Without a pick it is :meth:`pick_at`.
``command_for(stroke)`` with several isophotes picked
    The stroke is the new course of the picked isophote nearest to it (among those whose band
    it enters); it replaces any stroke drawn for that one before. Returns the
    ``sculpt_isophotes`` command once every picked isophote has a stroke, else None (the
    stroke is kept and :attr:`message` says what is left to draw).
``command_for_drawn()``
    The command for the strokes drawn so far (Enter, or the panel's Apply): the isophotes
    without one are left out (one stroke: a plain ``sculpt_isophote``). Raises SculptError
    when no stroke is drawn.
``press / move / release``
    The headless gesture. press-release without moving picks (as ``pick_at``); after a pick,
    press-move-release redraws: ``release`` builds the command, pushes it synchronously,
    returns it and the tool goes back to picking. A drag without a pick only sets
    :attr:`message`. ``end_stroke(pos)`` ends a drag without pushing (front ends that push
    on their own).

State
-----
``pick`` (2,) or None, ``layer_id``, ``isovalue``, ``isophote`` (k, 2), ``band`` (radius):
the newest pick; ``picks`` every picked isophote (:class:`PickedIsophote`, oldest first);
``options``, ``message`` (the last problem, "" if none) and ``overlay``: plain data for
drawing — ``"isophote"`` (k, 2) float64 (the newest pick's), ``"band"`` list of (m, 2) rings
(exteriors and holes, every pick's band), ``"isovalue"`` float, ``"layer"`` the picked layer
id, ``"stroke"`` (k, 2) while a stroke is drawn; with several picks also ``"isophotes"`` (the
earlier picks' isophotes) and ``"strokes"`` (the strokes kept for them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sketchforge.plugin_api import SculptError, SketchforgeError, Tool

from .command import SculptIsophote, SculptIsophotes

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


#: A Shift+click this close (in isovalue) to a picked isophote, and within its band, picks it
#: again: said, not added.
SAME_PICK = 0.02


@dataclass
class PickedIsophote:
    """One picked isophote of a gesture: the pick (2,), its isovalue, the isophote (k, 2) and
    its shapely line, the band radius and region, and the stroke drawn for it (None yet)."""

    pick: np.ndarray
    isovalue: float
    isophote: np.ndarray
    iso_geom: object
    band: float
    band_geom: object
    stroke: np.ndarray | None = None


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
        self._band_geom = None  # its band (shapely)
        self._ld = None  # the picked layer's LayerData
        self._stroke_for_pick: np.ndarray | None = None  # the stroke kept for the newest pick
        self._earlier: list[PickedIsophote] = []  # Shift+clicked before the newest pick
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
            # The isophote through a pick depends on the model: picked again, every one of them
            # with its band (strokes drawn for them are dropped). A solver that redraws one
            # isophote per edit keeps the first; the message says why.
            kept = [(p.pick.copy(), p.band) for p in self.picks]
            self.band = kept[0][1]
            if self.pick_at(kept[0][0]):
                for point, band in kept[1:]:
                    if not self.add_pick_at(point, band):
                        break

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
        self._iso_geom = self._band_geom = self._ld = None
        self._stroke_for_pick = None
        self._earlier = []
        self._stroke = []
        self.overlay = {}

    @property
    def picks(self) -> list[PickedIsophote]:
        """Every picked isophote, oldest first (empty without a pick)."""
        if self.pick is None:
            return []
        newest = PickedIsophote(self.pick, self.isovalue, self.isophote, self._iso_geom, self.band, self._band_geom,
                                self._stroke_for_pick)
        return [*self._earlier, newest]

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
            self._set_newest(p, lay.id, float(c), iso, ld)
            return True
        self._clear_pick()
        self.message = NOT_ON_A_SHAPE
        return False

    def _set_newest(self, p: np.ndarray, layer_id: str, c: float, iso, ld) -> None:
        self.pick, self.layer_id, self.isovalue = p, layer_id, c
        self._iso_geom, self._ld = iso, ld
        self._stroke_for_pick = None
        self.isophote = np.asarray(iso.coords, dtype=np.float64)[:, :2]
        self.overlay = {"isophote": self.isophote, "band": [], "isovalue": self.isovalue, "layer": layer_id}
        self.message = ""
        self._update_band()

    def add_pick_at(self, point, band: float | None = None) -> bool:
        """Shift+click: another isophote of the picked layer (see the module docstring), with
        the band radius ``band`` (None: the current one)."""
        from .isophote import picked_isophote
        from .joint import MAX_ISOPHOTES, one_at_a_time

        if self.pick is None:
            return self.pick_at(point)
        try:
            p = self.as_point(point)
        except ValueError:
            p = np.full(2, np.nan)
        refusal = None
        solver = self._solver()
        if not getattr(solver, "several_isophotes", False):
            refusal = one_at_a_time(solver.name, len(self.picks) + 1)
        elif len(self.picks) >= MAX_ISOPHOTES:
            refusal = f"one edit redraws at most {MAX_ISOPHOTES} isophotes: apply these first (Enter)"
        elif not np.isfinite(p).all() or self._ld.locator.locate(p.reshape(1, 2))[0][0] < 0:
            name = self.doc.layer(self.layer_id).name if self.layer_id in self.doc.layer_ids() else self.layer_id
            refusal = f"the isophotes of one edit lie on one part: Shift+click on {name!r}, or click to start again elsewhere"
        if refusal is None:
            try:
                c, iso = picked_isophote(self._ld, p)
            except SculptError as exc:
                refusal = str(exc)
        if refusal is None:
            import shapely

            for k, other in enumerate(self.picks, start=1):
                if abs(other.isovalue - c) < SAME_PICK and other.iso_geom.distance(shapely.Point(p)) < other.band:
                    refusal = (f"that is isophote {k} (n·l = {other.isovalue:.3f}), picked already: draw its new "
                               "course, or Shift+click another")
                    break
        if refusal is not None:
            self.message = refusal
            return False
        self._earlier = self.picks
        if band is not None:
            self.band = float(band)
        self._set_newest(p, self.layer_id, float(c), iso, self._ld)
        return True

    def _solver(self):
        from .command import _solver

        return _solver(self.doc, self.options.get("solver"))[0]

    # --- band ---------------------------------------------------------------------------------
    def set_band(self, radius) -> bool:
        from sketchforge.plugin_api import band_radius

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
        self._band_geom = geom
        self.overlay["band"] = _rings(geom) + [r for e in self._earlier for r in _rings(e.band_geom)]
        self._update_multi_overlay()
        return True

    def _update_multi_overlay(self) -> None:
        if self._earlier:
            self.overlay["isophotes"] = [e.isophote for e in self._earlier]
            self.overlay["strokes"] = [e.stroke for e in self.picks if e.stroke is not None]
        else:
            self.overlay.pop("isophotes", None)
            self.overlay.pop("strokes", None)

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

    def command_for(self, stroke):
        """The command for the current pick and ``stroke``, built but not pushed. With several
        isophotes picked: the stroke is kept for the nearest one, and the joint command comes
        once each has a stroke (None before; see the module docstring)."""
        if not self._earlier:
            return SculptIsophote.from_dict(self.command_dict(stroke))
        if self.pick is None or self.layer_id not in self.doc.layer_ids():
            raise SculptError(PICK_FIRST)
        k = self._take_stroke(np.asarray(stroke, dtype=np.float64).reshape(-1, 2))
        picks = self.picks
        waiting = [i for i, e in enumerate(picks, start=1) if e.stroke is None]
        if not waiting:
            self.message = ""
            return self.command_for_drawn()
        self.message = (f"stroke kept for isophote {k} (n·l = {picks[k - 1].isovalue:.3f}); draw isophote "
                        f"{', '.join(map(str, waiting))} too, or press Enter to apply the {len(picks) - len(waiting)} drawn")
        return None

    def _nearest_pick(self, stroke: np.ndarray) -> int:
        """Index (0-based) of the picked isophote a stroke redraws: the nearest (mean distance
        from the stroke's points) among those whose band it enters, or among all if none."""
        import shapely

        pts = shapely.points(stroke)
        picks = self.picks
        enter = [i for i, e in enumerate(picks) if e.band_geom is not None and e.band_geom.intersects(shapely.LineString(stroke))]
        pool = enter or list(range(len(picks)))
        return min(pool, key=lambda i: (float(shapely.distance(pts, picks[i].iso_geom).mean()), i))

    def _take_stroke(self, stroke: np.ndarray) -> int:
        """Keep ``stroke`` for its picked isophote; returns that isophote's number (from 1)."""
        if len(stroke) < 2:
            raise SculptError("a stroke needs at least two points")
        i = self._nearest_pick(stroke)
        if i == len(self._earlier):
            self._stroke_for_pick = stroke
        else:
            self._earlier[i].stroke = stroke
        self._update_multi_overlay()
        return i + 1

    def _edit_entries(self, tentative: tuple | None = None) -> list[dict]:
        out = []
        for i, e in enumerate(self.picks):
            stroke = tentative[1] if tentative is not None and tentative[0] == i else e.stroke
            if stroke is not None:
                out.append({"pick": [float(v) for v in e.pick], "band": float(e.band),
                            "stroke": np.asarray(stroke, dtype=np.float64).reshape(-1, 2).tolist()})
        return out

    def command_for_drawn(self):
        """The command for the strokes drawn so far (see the module docstring)."""
        if self.pick is None or self.layer_id not in self.doc.layer_ids():
            raise SculptError(PICK_FIRST)
        edits = self._edit_entries()
        if not edits:
            raise SculptError("no stroke drawn yet: draw the new course of a picked isophote")
        if len(edits) == 1:
            return SculptIsophote.from_dict({"command": COMMAND_NAME, "layer": self.layer_id, **edits[0], **self.options})
        return SculptIsophotes.from_dict({"command": SculptIsophotes.name, "layer": self.layer_id, "edits": edits,
                                          **self.options})

    def preview_job(self, stroke, mesh=None):
        """A pure function computing the edit ``stroke`` would make (see the module
        docstring). Raises SculptError without a pick."""
        if self.pick is None or self.layer_id not in self.doc.layer_ids():
            raise SculptError(PICK_FIRST)
        from .command import _solver
        from .pipeline import sculpt

        mesh = self.doc.layer(self.layer_id).mesh if mesh is None else mesh
        light = np.array(self.doc.light.direction, dtype=np.float64)
        pick, band, model = self.pick.copy(), float(self.band), self.model()
        solver, provider = _solver(self.doc, self.options.get("solver"))
        params = dict(self.options.get("params") or {})
        points = np.array(stroke, dtype=np.float64).reshape(-1, 2)
        if self._earlier:  # several picked: the joint edit with this stroke in its place
            from .joint import sculpt_many

            edits = [(e["pick"], e["band"], e["stroke"])
                     for e in self._edit_entries((self._nearest_pick(points), points))]
            return lambda: sculpt_many(mesh, light, edits, model, solver=solver, params=params, provider=provider)
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
        cmd = self.command_for(stroke)
        if cmd is None:  # several picked, some still without a stroke: kept
            self.overlay.pop("stroke", None)
            return None
        cmd = self.doc.push(cmd)
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
