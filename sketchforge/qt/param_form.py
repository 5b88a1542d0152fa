"""Parameter forms generated from what a solver declares: a plugin writes no Qt for its
parameters.

:class:`ParamForm` turns :class:`~sketchforge.plugins.param_forms.ParamField` values into
rows: a spin box for a number in a moderate range (its bounds, open bounds excluded, a step
and decimals from the default's size), a text field in scientific notation for a number
whose range spans decades or whose default is tiny (tolerances), a whole-number spin box, a
combo box of the options, a check box for a switch, an "auto" box beside a number that may be
None, a text field, and a read-only line for a list or an object. Each row's tooltip says
what the solver's ``help`` says, the range and the default. An edit is one ``edited({key:
value})`` when the widget commits it (Enter, focus out, a step, a click); values arrive in
the parameter's type (int for a whole number). The form keeps no state of its own: the window
shows the document's values with :meth:`set_values`, and the solver's own ``check_params``
refuses what it must (the range shown is what it declares).

:class:`SolverForm` is the form of one solver of a kind, built from the host
(``host.solver_fields``) and rebuilt when another solver is chosen.
"""

from __future__ import annotations

import json
import math

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QDoubleValidator
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QSpinBox,
    QToolButton,
    QWidget,
)

#: The largest magnitude a spin box offers where a range is open-ended (the drawing's range).
UNBOUNDED = 1e9
#: Widest integer range of a QSpinBox.
INT_LIMIT = 2**31 - 1


def _step(default, lo, hi) -> float:
    """A step one tenth of the default's order of magnitude (0.03 -> 0.001, 20 -> 1)."""
    for ref in (default, hi, lo, 1.0):
        if isinstance(ref, (int, float)) and not isinstance(ref, bool) and ref and math.isfinite(ref):
            return 10.0 ** math.floor(math.log10(abs(float(ref)))) / 10.0
    return 0.1


def scientific(field) -> bool:
    """Whether a number is better typed than stepped: a range over four decades above 0 (a
    tolerance), or a default below 0.001 that is not 0."""
    if field.lo is not None and field.hi is not None and field.lo > 0 and field.hi / field.lo >= 1e4:
        return True
    d = field.default
    return isinstance(d, float) and d != 0.0 and abs(d) < 1e-3


def _tooltip(field) -> str:
    parts = [field.help] if field.help else []
    rng = field.range_text()
    if field.kind == "choice":
        rng = "one of " + ", ".join(map(str, field.options))
    if rng:
        parts.append(f"range: {rng}")
    if field.optional:
        parts.append("auto: the solver decides")
    parts.append(f"default: {json.dumps(field.default)}")
    if not field.declared:
        parts.append("(the solver declares no range for it)")
    return "\n".join(parts)


class ParamForm(QWidget):
    """Rows for a list of fields; ``edited({key: value})`` when the person commits a value."""

    edited = Signal(dict)

    def __init__(self, fields, parent=None) -> None:
        super().__init__(parent)
        self.fields = {f.key: f for f in fields}
        self.widgets: dict = {}
        self.auto: dict[str, QCheckBox] = {}
        self._values: dict = {f.key: f.default for f in fields}
        self._updating = False
        self.layout_ = QFormLayout(self)
        self.layout_.setContentsMargins(0, 0, 0, 0)
        for f in fields:
            editor = self._editor(f)
            editor.setToolTip(_tooltip(f))
            self.widgets[f.key] = editor
            row = editor
            if f.optional:
                row = QWidget()
                h = QHBoxLayout(row)
                h.setContentsMargins(0, 0, 0, 0)
                box = QCheckBox("auto")
                box.setToolTip("Let the solver choose this value")
                box.toggled.connect(lambda on, k=f.key: self._auto_toggled(k, on))
                self.auto[f.key] = box
                h.addWidget(editor, 1)
                h.addWidget(box)
            label = QLabel(f.title)
            label.setToolTip(_tooltip(f))
            self.layout_.addRow(label, row)
        self.set_values(self._values)

    # --- widgets ------------------------------------------------------------------------------
    def _editor(self, f) -> QWidget:
        if f.kind == "choice":
            combo = QComboBox()
            combo.addItems([str(o) for o in f.options])
            combo.currentIndexChanged.connect(lambda i, k=f.key: self._commit(k, self.fields[k].options[i] if i >= 0 else None))
            return combo
        if f.kind == "flag":
            check = QCheckBox()
            check.clicked.connect(lambda on, k=f.key: self._commit(k, bool(on)))
            return check
        if f.kind == "integer":
            spin = QSpinBox()
            lo = -INT_LIMIT if f.lo is None else max(-INT_LIMIT, math.ceil(f.lo + (1 if f.lo_open and f.lo == int(f.lo) else 0)))
            hi = INT_LIMIT if f.hi is None else min(INT_LIMIT, math.floor(f.hi - (1 if f.hi_open and f.hi == int(f.hi) else 0)))
            spin.setRange(int(lo), int(hi))
            spin.setKeyboardTracking(False)
            spin.valueChanged.connect(lambda v, k=f.key: self._commit(k, int(v)))
            return spin
        if f.kind == "number" and scientific(f):
            line = QLineEdit()
            v = QDoubleValidator(line)
            v.setNotation(QDoubleValidator.Notation.ScientificNotation)
            line.setValidator(v)
            line.editingFinished.connect(lambda k=f.key, e=line: self._text_number(k, e))
            return line
        if f.kind == "number":
            dspin = QDoubleSpinBox()
            step = _step(f.default, f.lo, f.hi)
            decimals = min(12, max(2, -math.floor(math.log10(step)) if step < 1 else 2))
            eps = 10.0 ** -decimals
            lo = -UNBOUNDED if f.lo is None else f.lo + (eps if f.lo_open else 0.0)
            hi = UNBOUNDED if f.hi is None else f.hi - (eps if f.hi_open else 0.0)
            dspin.setDecimals(decimals)
            dspin.setRange(max(lo, -UNBOUNDED), min(hi, UNBOUNDED))
            dspin.setSingleStep(step)
            dspin.setKeyboardTracking(False)
            dspin.valueChanged.connect(lambda v, k=f.key: self._commit(k, float(v)))
            return dspin
        if f.kind == "text":
            edit = QLineEdit()
            edit.editingFinished.connect(lambda k=f.key, e=edit: self._commit(k, e.text()))
            return edit
        label = QLabel()  # a list or an object: shown, kept as it is
        label.setWordWrap(True)
        return label

    def _text_number(self, key: str, edit: QLineEdit) -> None:
        try:
            value = float(edit.text().replace(",", "."))
        except ValueError:
            self._show(key, self._values.get(key))
            return
        self._commit(key, value)

    def _auto_toggled(self, key: str, on: bool) -> None:
        self.widgets[key].setEnabled(not on)
        if self._updating:
            return
        if on:
            self._commit(key, None)
        else:
            f = self.fields[key]
            w = self.widgets[key]
            value = w.value() if hasattr(w, "value") else (f.lo if f.lo is not None else 0.0)
            self._commit(key, int(value) if f.kind == "integer" else float(value))

    def _commit(self, key: str, value) -> None:
        old = self._values.get(key)
        if self._updating or (value == old and type(value) is type(old)):
            return
        self._values[key] = value
        self.edited.emit({key: value})

    # --- state --------------------------------------------------------------------------------
    def _show(self, key: str, value) -> None:
        f, w = self.fields[key], self.widgets[key]
        if key in self.auto:
            self.auto[key].setChecked(value is None)
            w.setEnabled(value is not None)
        if value is None:
            return
        if f.kind == "choice":
            w.setCurrentIndex(f.options.index(value) if value in f.options else -1)
        elif f.kind == "flag":
            w.setChecked(bool(value))
        elif isinstance(w, (QSpinBox, QDoubleSpinBox)):
            w.setValue(value)
        elif isinstance(w, QLineEdit):
            w.setText(f"{value:g}" if isinstance(value, float) else str(value))
        else:
            w.setText(json.dumps(value))

    def set_values(self, values: dict) -> None:
        """Show ``values`` (keys not given keep their default); emits nothing."""
        self._updating = True
        try:
            for key in self.fields:
                value = values.get(key, self.fields[key].default)
                self._values[key] = value
                self._show(key, value)
        finally:
            self._updating = False

    def values(self) -> dict:
        """{key: value} as shown."""
        return dict(self._values)

    def changed_from_defaults(self) -> dict:
        """The values that differ from the solver's defaults (what a journal entry needs)."""
        return {k: v for k, v in self._values.items() if v != self.fields[k].default}

    def setEnabled(self, on: bool) -> None:  # noqa: N802 - Qt's name
        super().setEnabled(on)
        if on:  # an "auto" number stays greyed out
            for key, box in self.auto.items():
                self.widgets[key].setEnabled(not box.isChecked())


class SolverForm(QWidget):
    """The parameter form of the chosen solver of one kind ("inflate", "sculpt", "assemble").

    ``set_solver(name)`` rebuilds it from ``host.solver_fields(kind, name)`` (a solver whose
    description fails shows that one line instead); ``edited({key: value})`` as
    :class:`ParamForm`. With ``collapsible`` the rows fold under a "Parameters" button (closed
    at first), which counts the values changed from the defaults: where a panel has little
    room (the Sculpture box)."""

    edited = Signal(dict)

    def __init__(self, host, kind: str, parent=None, collapsible: bool = False) -> None:
        super().__init__(parent)
        self.host, self.kind = host, kind
        self.solver_name: str | None = None
        self.form: ParamForm | None = None
        self.note = QLabel()
        self.note.setWordWrap(True)
        self.note.setVisible(False)
        self.box = QFormLayout(self)
        self.box.setContentsMargins(0, 0, 0, 0)
        self.toggle: QToolButton | None = None
        if collapsible:
            self.toggle = QToolButton()
            self.toggle.setCheckable(True)
            self.toggle.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
            self.toggle.setAutoRaise(True)
            self.toggle.toggled.connect(self._fold)
            self.box.addRow(self.toggle)
        self.box.addRow(self.note)
        self.edited.connect(lambda _: self._label())

    def set_solver(self, name: str | None) -> None:
        if name == self.solver_name and self.form is not None:
            return
        from sketchforge.errors import SketchforgeError

        if self.form is not None:
            self.box.removeRow(self.form)
            self.form = None
        self.solver_name = name
        try:
            fields = self.host.solver_fields(self.kind, name)
        except SketchforgeError as exc:
            self.note.setText(str(exc))
            self.note.setVisible(True)
            return
        self.note.setVisible(not fields and (self.toggle is None or self.toggle.isChecked()))
        self.note.setText("no parameters")
        self.form = ParamForm(fields)
        self.form.edited.connect(self.edited.emit)
        self.box.addRow(self.form)
        if self.toggle is not None:
            self.form.setVisible(self.toggle.isChecked())
            self._label()

    def _fold(self, open_: bool) -> None:
        self.toggle.setArrowType(Qt.ArrowType.DownArrow if open_ else Qt.ArrowType.RightArrow)
        if self.form is not None:
            self.form.setVisible(open_)
        self.note.setVisible(open_ and self.form is not None and not self.form.fields)

    def _label(self) -> None:
        if self.toggle is None:
            return
        n = len(self.changed_from_defaults())
        total = 0 if self.form is None else len(self.form.fields)
        self.toggle.setText(f"Parameters ({total}" + (f", {n} changed)" if n else ")"))
        self.toggle.setArrowType(Qt.ArrowType.DownArrow if self.toggle.isChecked() else Qt.ArrowType.RightArrow)

    @property
    def widgets(self) -> dict:
        return {} if self.form is None else self.form.widgets

    def set_values(self, values: dict) -> None:
        if self.form is not None:
            self.form.set_values(dict(values or {}))
            self._label()

    def values(self) -> dict:
        return {} if self.form is None else self.form.values()

    def changed_from_defaults(self) -> dict:
        return {} if self.form is None else self.form.changed_from_defaults()
