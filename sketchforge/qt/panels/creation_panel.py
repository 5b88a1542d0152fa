"""CREATION controls: the current layer's inflation parameters, whether it is closed (a free
part) or open (attached by its closing segment), and how the drawing region shades (Lambertian
or cel, isophote lines, layer tints and outlines).

A new stroke decides open or closed by itself (its ends meet: closed); the box shows the
selected part's kind and flips it (:attr:`closed_toggled`), it never carries over to the next
stroke."""

from __future__ import annotations

from PySide6.QtCore import Signal
from PySide6.QtWidgets import QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QGroupBox, QLabel, QSpinBox

#: (key, label, minimum, maximum, step, decimals, tooltip)
PARAMS = (
    ("resolution", "Resolution", 0.002, 1.0, 0.005, 3, "Target triangle edge length, drawing units"),
    ("inflation", "Inflation", 0.0, 10.0, 0.1, 2, "Height scale of the inflated shape"),
    ("smoothing", "Smoothing", 0.0, 0.99, 0.05, 2, "Fairing weight α (0 = none)"),
)


class CreationPanel(QGroupBox):
    #: {key: value} for the current layer
    params_edited = Signal(dict)
    shader_changed = Signal(str)
    isolines_changed = Signal(int)
    #: the person ticked or unticked "closed" for the selected part
    closed_toggled = Signal(bool)
    #: subtle per-layer tints on / off
    tint_changed = Signal(bool)
    #: thin lines along the layers' visible outlines on / off
    outlines_changed = Signal(bool)

    def __init__(self, parent=None) -> None:
        super().__init__("Creation", parent)
        form = QFormLayout(self)
        self.layer_label = QLabel("no layer: draw to create one")
        form.addRow(self.layer_label)
        self.spins: dict[str, QDoubleSpinBox] = {}
        for key, label, lo, hi, step, dec, tip in PARAMS:
            s = QDoubleSpinBox()
            s.setRange(lo, hi)
            s.setSingleStep(step)
            s.setDecimals(dec)
            s.setKeyboardTracking(False)
            s.setToolTip(tip)
            s.valueChanged.connect(lambda v, k=key: self._edited(k, v))
            self.spins[key] = s
            form.addRow(label, s)
        self.closed = QCheckBox("closed outline (free part)")
        self.closed.setToolTip(
            "The selected part's kind; click to flip it. A new stroke is closed when its ends "
            "meet; open, its closing segment attaches to the part it lies on"
        )
        self.closed.setEnabled(False)
        self.closed.clicked.connect(lambda on: self._updating or self.closed_toggled.emit(bool(on)))
        form.addRow(self.closed)
        self.shader = QComboBox()
        self.shader.currentTextChanged.connect(self.shader_changed.emit)
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

    def set_shaders(self, names, current: str) -> None:
        self.shader.blockSignals(True)
        self.shader.clear()
        self.shader.addItems(list(names))
        self.shader.setCurrentText(current)
        self.shader.blockSignals(False)

    def show_layer(self, layer, pending: dict | None = None) -> None:
        """Mirror the current layer's parameters (None: no layer selected); ``pending`` are
        values edited during a solve and not applied yet (shown, not reverted)."""
        self._updating = True
        try:
            for s in self.spins.values():
                s.setEnabled(layer is not None)
            self.closed.setEnabled(layer is not None and layer.points is not None)
            if layer is None:
                self.layer_label.setText("no layer: draw to create one")
                self.closed.setChecked(False)
                return
            closed = bool(layer.closed) or (layer.mesh is not None and len(layer.mesh.junction) == 0)
            kind = "no contour yet: draw it" if layer.points is None else (
                f"{'closed' if closed else 'open'}, {len(layer.edits)} sculpt edits"
            )
            self.layer_label.setText(f"<b>{layer.name}</b> ({kind})")
            # Closed as the assembly sees it: marked closed, or a stroke whose ends met.
            self.closed.setChecked(closed if layer.points is not None else False)
            values = {**dict(layer.params), **(pending or {})}
            for key, s in self.spins.items():
                s.setValue(float(values.get(key, s.value())))
        finally:
            self._updating = False

    def _edited(self, key: str, value: float) -> None:
        if not self._updating:
            self.params_edited.emit({key: float(value)})
