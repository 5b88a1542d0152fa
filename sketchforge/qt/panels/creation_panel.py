"""CREATION controls: the inflater and its parameters (of the selected part, and for the next
new part), whether the part is closed (a free part) or open (attached by its closing
segment), and how the drawing region shades (a display shader or a reflectance model,
isophote lines, layer tints and outlines).

The inflater's parameters are a form generated from what it declares
(:class:`~sketchforge.qt.param_form.SolverForm`): the built-in ``poisson`` and any plugin's
alike, none of them writes Qt for it. Choosing another inflater switches the selected part to
it (one undo step, from its defaults) and new parts are inflated by it.

A new stroke decides open or closed by itself (its ends meet: closed); the box shows the
selected part's kind and flips it (:attr:`closed_toggled`), it never carries over to the next
stroke."""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QGroupBox, QLabel, QSpinBox

from sketchforge.errors import SketchforgeError
from sketchforge.qt.param_form import SolverForm


class CreationPanel(QGroupBox):
    #: {key: value} for the current layer
    params_edited = Signal(dict)
    #: the inflater chosen (its name): for the selected part and the next new ones
    inflater_changed = Signal(str)
    shader_changed = Signal(str)
    isolines_changed = Signal(int)
    #: the person ticked or unticked "closed" for the selected part
    closed_toggled = Signal(bool)
    #: subtle per-layer tints on / off
    tint_changed = Signal(bool)
    #: thin lines along the layers' visible outlines on / off
    outlines_changed = Signal(bool)

    def __init__(self, host=None, parent=None) -> None:
        super().__init__("Creation", parent)
        self.host = host
        form = QFormLayout(self)
        self.layer_label = QLabel("no layer: draw to create one")
        form.addRow(self.layer_label)
        self.inflater = QComboBox()
        self.inflater.setToolTip("The inflater of the selected part, and of the next new part (plugins can add inflaters)")
        form.addRow("Inflater", self.inflater)
        self.params = SolverForm(host, "inflate")
        self.params.edited.connect(lambda d: self._updating or self.params_edited.emit(dict(d)))
        form.addRow(self.params)
        #: The inflater new parts get (None: the host's default).
        self.new_part_inflater: str | None = None
        self._fill_inflaters()
        self.inflater.currentIndexChanged.connect(lambda _: self._inflater_chosen())
        self.closed = QCheckBox("closed outline (free part)")
        self.closed.setToolTip(
            "The selected part's kind; click to flip it. A new stroke is closed when its ends "
            "meet; open, its closing segment attaches to the part it lies on"
        )
        self.closed.setEnabled(False)
        self.closed.clicked.connect(lambda on: self._updating or self.closed_toggled.emit(bool(on)))
        form.addRow(self.closed)
        self.shader = QComboBox()
        self.shader.currentIndexChanged.connect(lambda i: self.shader_changed.emit(self.shader.itemData(i) or ""))
        form.addRow("Shading", self.shader)
        self.isolines = QSpinBox()
        self.isolines.setRange(0, 20)
        self.isolines.setToolTip("Number of isophote lines drawn over the shading")
        self.isolines.valueChanged.connect(self.isolines_changed.emit)
        form.addRow("Isophote lines", self.isolines)
        self.tint = QCheckBox("tint layers")
        self.tint.setChecked(True)
        self.tint.setToolTip("A slightly different hue per layer, to tell touching layers apart")
        self.tint.toggled.connect(self.tint_changed.emit)
        self.outlines = QCheckBox("outline layers")
        self.outlines.setChecked(True)
        self.outlines.setToolTip("A thin line along each layer's visible outline")
        self.outlines.toggled.connect(self.outlines_changed.emit)
        form.addRow(self.tint)
        form.addRow(self.outlines)
        self._updating = False

    @property
    def spins(self) -> dict:
        """The inflater form's spin boxes by parameter (a number shown as one)."""
        return {k: w for k, w in self.params.widgets.items() if isinstance(w, (QDoubleSpinBox, QSpinBox))}

    def _fill_inflaters(self) -> None:
        try:
            solvers = dict(self.host.solvers("inflate")) if self.host is not None else {}
            default = self.host.default_solver_name("inflate") if self.host is not None else None
        except SketchforgeError:
            solvers, default = {}, None
        self._default_inflater = default
        for name, solver in sorted(solvers.items(), key=lambda item: (item[0] != default, item[0])):
            self.inflater.addItem(name, name)
            self.inflater.setItemData(self.inflater.count() - 1, getattr(solver, "description", "") or name,
                                      Qt.ItemDataRole.ToolTipRole)
        if self.inflater.count():
            self.params.set_solver(self.inflater.itemData(0))

    def _inflater_chosen(self) -> None:
        name = self.inflater.currentData()
        if self._updating or not name:
            return
        self.new_part_inflater = None if name == self._default_inflater else name
        self.params.set_solver(name)
        self.inflater_changed.emit(name)

    def set_shaders(self, names, current: str, labels: dict | None = None) -> None:
        """The display shadings: ``names`` (keys), shown as ``labels[name]`` where given."""
        labels = labels or {}
        self.shader.blockSignals(True)
        self.shader.clear()
        for name in names:
            self.shader.addItem(labels.get(name, name), name)
        i = self.shader.findData(current)
        self.shader.setCurrentIndex(max(i, 0))
        self.shader.blockSignals(False)

    def show_layer(self, layer, pending: dict | None = None) -> None:
        """Mirror the current layer's parameters (None: no layer selected); ``pending`` are
        values edited during a solve and not applied yet (shown, not reverted)."""
        self._updating = True
        try:
            self.closed.setEnabled(layer is not None and layer.points is not None)
            if layer is None:
                self.layer_label.setText("no layer: draw to create one")
                self.closed.setChecked(False)
                self._show_inflater(self.new_part_inflater or self._default_inflater, {})
                self.params.setEnabled(False)
                return
            self.params.setEnabled(True)
            closed = bool(layer.closed) or (layer.mesh is not None and len(layer.mesh.junction) == 0)
            kind = "no contour yet: draw it" if layer.points is None else (
                f"{'closed' if closed else 'open'}, {len(layer.edits)} sculpt edits"
            )
            self.layer_label.setText(f"<b>{layer.name}</b> ({kind})")
            # Closed as the assembly sees it: marked closed, or a stroke whose ends met.
            self.closed.setChecked(closed if layer.points is not None else False)
            self._show_inflater(layer.solver or self._default_inflater, {**dict(layer.params), **(pending or {})})
        finally:
            self._updating = False

    def _show_inflater(self, name: str | None, values: dict) -> None:
        """The combo on ``name`` and its form with ``values`` (signals blocked by the caller's
        ``_updating``). A layer's inflater that is not installed shows as such, without a form."""
        i = self.inflater.findData(name)
        if i < 0 and name:
            self.inflater.addItem(f"{name} (not installed)", name)
            i = self.inflater.count() - 1
        if i >= 0:
            self.inflater.setCurrentIndex(i)
        self.params.set_solver(name)
        self.params.set_values(values)
