"""OBSERVATION controls of the assembly: the document's assembler and its parameters, a form
generated from what the assembler declares (:class:`~sketchforge.qt.param_form.SolverForm`).

A choice or an edited value is one ``set_assembly`` command (one undo step; the model is
assembled again when next shown); a value the assembler refuses is one line in the status
bar and the form shows the document's values again.
"""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import QComboBox, QFormLayout, QGroupBox

from sketchforge.errors import SketchforgeError
from sketchforge.qt.param_form import SolverForm


class AssemblyPanel(QGroupBox):
    #: (solver name or None to keep the document's, {key: value} edited)
    assembly_edited = Signal(object, dict)

    def __init__(self, host, parent=None) -> None:
        super().__init__("Assembly", parent)
        self.host = host
        form = QFormLayout(self)
        self.assembler = QComboBox()
        self.assembler.setToolTip("How the layers become one closed model (plugins can add assemblers)")
        form.addRow("Assembler", self.assembler)
        self.params = SolverForm(host, "assemble")
        form.addRow(self.params)
        self._updating = False
        try:
            solvers = dict(host.solvers("assemble"))
            self.default = host.default_solver_name("assemble")
        except SketchforgeError:
            solvers, self.default = {}, None
        for name, solver in sorted(solvers.items(), key=lambda item: (item[0] != self.default, item[0])):
            self.assembler.addItem(name, name)
            self.assembler.setItemData(self.assembler.count() - 1, getattr(solver, "description", "") or name,
                                       Qt.ItemDataRole.ToolTipRole)
        self.setVisible(self.assembler.count() > 0)
        self.assembler.currentIndexChanged.connect(lambda _: self._chosen())
        self.params.edited.connect(lambda d: self._updating or self.assembly_edited.emit(None, dict(d)))

    def _chosen(self) -> None:
        name = self.assembler.currentData()
        if not self._updating and name:
            self.assembly_edited.emit(name, {})

    def show_assembly(self, choice) -> None:
        """Show the document's assembler and parameters (``doc.assembly``)."""
        self._updating = True
        try:
            name = choice.solver or self.default
            i = self.assembler.findData(name)
            if i < 0 and name:
                self.assembler.addItem(f"{name} (not installed)", name)
                i = self.assembler.count() - 1
            if i >= 0:
                self.assembler.setCurrentIndex(i)
            self.params.set_solver(name)
            self.params.set_values(dict(choice.params))
        finally:
            self._updating = False
