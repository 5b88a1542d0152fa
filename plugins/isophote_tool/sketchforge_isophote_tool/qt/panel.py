"""The isophote tool's SCULPTURE controls: the reflectance model the height solve inverts, the
sculpt solver and its parameters (a form the app generates from what the solver declares,
``panel_api.SolverForm``), the band radius (slider and field; the mouse wheel in the drawing too), the live
preview, what to show of the last edit (characteristics, edit region) and, with several
isophotes picked (Shift+click), a button that applies the strokes drawn so far.

The panel drives the app's sculpt controller (``app.sculpt``) and shows its state; the model
and solver become the tool's options (:meth:`SculptIsophoteTool.set_options`), always set
together, so the next ``sculpt_isophote`` command carries ``"model"``, ``"solver"`` and the
parameters changed from the solver's defaults, ``"params"`` (each absent for the default). It is enabled while the isophote
tool is the chosen tool.
"""

from __future__ import annotations

import math

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QPushButton, QSlider, QWidget

from sketchforge.plugin_api import SketchforgeError
from sketchforge.qt.panel_api import MAX_RADIUS, MIN_RADIUS, SolverForm

from ..tool import SculptIsophoteTool

_STEPS = 1000
LAMBERTIAN = "lambertian"


def from_slider(v: int) -> float:
    """Slider position -> band radius; logarithmic, for fine control of small bands."""
    return MIN_RADIUS * (MAX_RADIUS / MIN_RADIUS) ** (v / _STEPS)


def to_slider(r: float) -> int:
    return round(_STEPS * math.log(r / MIN_RADIUS) / math.log(MAX_RADIUS / MIN_RADIUS))


class IsophoteSculptPanel(QWidget):
    def __init__(self, app, parent=None) -> None:
        super().__init__(parent)
        self.app = app
        form = QFormLayout(self)
        form.setContentsMargins(0, 0, 0, 0)
        self.model = QComboBox()
        self.model.setToolTip("Reflectance model the height solve inverts (plugins can add models)")
        form.addRow("Reflectance", self.model)
        self.solver = QComboBox()
        self.solver.setToolTip("Sculpt solver that turns the new shading into heights (plugins can add solvers)")
        form.addRow("Solver", self.solver)
        # The chosen solver's parameters: a form the app generates from what the solver
        # declares (no solver writes Qt for them); values changed from its defaults go to the
        # next edit's "params".
        self.params = SolverForm(app.host, "sculpt", collapsible=True)
        form.addRow(self.params)
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(0, _STEPS)
        self.spin = QDoubleSpinBox()
        self.spin.setRange(MIN_RADIUS, MAX_RADIUS)
        self.spin.setDecimals(3)
        self.spin.setSingleStep(0.01)
        self.spin.setKeyboardTracking(False)
        form.addRow("Band radius", self.slider)
        form.addRow("", self.spin)
        self.preview = QCheckBox("live preview")
        self.preview.setToolTip("Recompute the edit while the stroke is drawn (the surface shown is not applied until release)")
        self.strips = QCheckBox("show characteristics")
        self.strips.setToolTip(
            "The characteristic directions (thesis 3.1) through the stroke: along them a shading change becomes a height change"
        )
        self.regions = QCheckBox("show edit region")
        self.regions.setToolTip("Where the shading changed (the band near the stroke) and where heights may change (its ring)")
        form.addRow(self.preview)
        form.addRow(self.strips)
        form.addRow(self.regions)
        self.apply = QPushButton("Apply strokes (Enter)")
        self.apply.setToolTip("Several isophotes picked (Shift+click): apply the strokes drawn so far as one edit. "
                              "It is applied by itself once every picked isophote has a stroke.")
        form.addRow(self.apply)

        self._updating = False
        self._warmed: set = set()
        self._default_solver = self._fill_solvers()
        self._fill_models()
        c = app.sculpt
        self.slider.valueChanged.connect(lambda v: self._radius(from_slider(v)))
        self.spin.valueChanged.connect(self._radius)
        self.preview.toggled.connect(lambda on: self._updating or c.set_preview(on))
        self.strips.toggled.connect(lambda _: self._show_changed())
        self.regions.toggled.connect(lambda _: self._show_changed())
        self.apply.clicked.connect(lambda: c.apply_drawn())
        self.model.currentIndexChanged.connect(lambda _: self._choice_changed())
        self.solver.currentIndexChanged.connect(lambda _: self._solver_changed())
        self.params.edited.connect(lambda _: self._choice_changed())
        self.params.set_solver(self.solver.currentData())
        c.changed.connect(self.show_state)
        if self.options():  # no built-in solver and several installed: the first is chosen
            self._choice_changed()
        self.show_state()

    # --- choices -------------------------------------------------------------------------------
    def _fill_models(self) -> None:
        try:
            names = list(self.app.host.reflectance_models)
        except SketchforgeError:
            names = []
        self.model.addItems(names or [LAMBERTIAN])
        self.model.setCurrentText(LAMBERTIAN)

    def _fill_solvers(self) -> str | None:
        """Every installed sculpt solver (label, or name), the host's default first and
        chosen; returns the default's name (None when the host has none: the first is chosen
        and named in the options)."""
        host = self.app.host
        try:
            solvers = dict(host.solvers("sculpt"))
            default = host.default_solver_name("sculpt")
        except SketchforgeError:
            solvers, default = {}, None
        for name, solver in sorted(solvers.items(), key=lambda item: item[0] != default):
            self.solver.addItem(getattr(solver, "label", "") or name, name)
            self.solver.setItemData(self.solver.count() - 1, getattr(solver, "description", "") or name,
                                    Qt.ItemDataRole.ToolTipRole)
        i = self.solver.findData(default) if default is not None else 0
        self.solver.setCurrentIndex(max(i, 0) if self.solver.count() else -1)
        return default

    def options(self) -> dict:
        """The tool options the two combos choose: the model and the solver together, each
        left out when it is the default (so a default edit's journal entry stays as before)."""
        out: dict = {}
        model = self.model.currentText()
        if model and model != LAMBERTIAN:
            out["model"] = model
        solver = self.solver.currentData()
        if solver and solver != self._default_solver:
            out["solver"] = solver
        params = self.params.changed_from_defaults()
        if params:
            out["params"] = params
        return out

    def _solver_changed(self) -> None:
        """Another solver: its own parameters, from its defaults."""
        self.params.set_solver(self.solver.currentData())
        self.params.set_values({})
        self._choice_changed()

    def _choice_changed(self) -> None:
        if self._updating:
            return
        c = self.app.sculpt
        wanted = self.options()
        self._warm(self.solver.currentData())
        c.set_options(wanted)  # a refusal (an unknown model, say) goes to the status bar
        tool = c.tool if c.tool_name == SculptIsophoteTool.name else None
        if tool is not None and getattr(tool, "options", wanted) != wanted:
            self._show_options(tool.options)  # refused: show what the tool still uses

    def _warm(self, name) -> None:
        """A solver that compiles ahead (the strips' JAX functions: seconds on first use) does
        it in the background as soon as it is chosen, once."""
        if not name or name in self._warmed:
            return
        self._warmed.add(name)
        solver = dict(self.app.host.solvers("sculpt")).get(name)
        warm = getattr(solver, "warm_up", None)
        if callable(warm):
            label = getattr(solver, "label", "") or name
            self.app.background(warm, f"Preparing {label}", lambda _r: self.app.show_message(f"“{label}” is ready"))

    def _show_options(self, options: dict) -> None:
        self._updating = True
        try:
            self.model.setCurrentText(options.get("model", LAMBERTIAN))
            solver = options.get("solver", self._default_solver)
            i = self.solver.findData(solver)
            if i >= 0:
                self.solver.setCurrentIndex(i)
            self.params.set_solver(solver)
            self.params.set_values(options.get("params", {}))
        finally:
            self._updating = False

    # --- the controller ------------------------------------------------------------------------
    def _radius(self, r: float) -> None:
        if not self._updating:
            self.app.sculpt.set_radius(float(r))

    def _show_changed(self) -> None:
        if not self._updating:
            self.app.sculpt.set_show(self.strips.isChecked(), self.regions.isChecked())

    def show_state(self) -> None:
        """Show the controller's radius and switches; enabled while the isophote tool is the
        chosen tool (another tool, such as a brush, has no band, model or solver)."""
        c = self.app.sculpt
        self._updating = True
        try:
            self.slider.setValue(to_slider(c.radius))
            self.spin.setValue(c.radius)
            self.preview.setChecked(bool(c.live_preview))
            self.strips.setChecked(bool(c.show_strips))
            self.regions.setChecked(bool(c.show_regions))
            mine = c.tool is not None and c.tool_name == SculptIsophoteTool.name
            for w in (self.model, self.solver):
                w.setEnabled(mine and w.count() > 0)
            self.params.setEnabled(mine)
            self.slider.setEnabled(mine)
            self.spin.setEnabled(mine)
            picked, drawn = getattr(c, "pick_count", 0), getattr(c, "strokes_drawn", 0)
            self.apply.setVisible(mine and picked > 1)
            self.apply.setEnabled(mine and getattr(c, "strokes_to_apply", drawn) > 0)
            self.apply.setText(f"Apply {drawn} of {picked} strokes (Enter)" if picked > 1 else "Apply strokes (Enter)")
        finally:
            self._updating = False
