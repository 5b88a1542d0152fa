"""SCULPTURE controls: the tool palette, the tool plugins' own controls (their panels: the
isophote tool's model, solver, band radius...) and what the last edit said."""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QColor, QFont, QIcon, QPainter, QPixmap
from PySide6.QtWidgets import QComboBox, QFormLayout, QGroupBox, QLabel


def letter_icon(label: str, size: int = 20) -> QIcon:
    """A tool without its own icon gets its label's first letter in a rounded square."""
    pix = QPixmap(size, size)
    pix.fill(Qt.GlobalColor.transparent)
    p = QPainter(pix)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    p.setBrush(QColor("#3b6ea5"))
    p.setPen(Qt.PenStyle.NoPen)
    p.drawRoundedRect(0, 0, size, size, 4, 4)
    p.setPen(QColor("white"))
    font = QFont()
    font.setBold(True)
    font.setPixelSize(int(size * 0.7))
    p.setFont(font)
    p.drawText(pix.rect(), Qt.AlignmentFlag.AlignCenter, (label.strip()[:1] or "?").upper())
    p.end()
    return QIcon(pix)


class SculptPanel(QGroupBox):
    """The Sculpture box: the tool palette, the tool plugins' panels (place "sculpture",
    :meth:`add_panel`) and the chosen tool's status line."""

    #: the palette's choice (a tool's registry name)
    tool_selected = Signal(str)

    def __init__(self, parent=None) -> None:
        super().__init__("Sculpture", parent)
        form = QFormLayout(self)
        self._form = form
        self.tool = QComboBox()
        self.tool.setToolTip("Every tool the installed plugins provide (Tools menu: the same list, with shortcuts)")
        self.tool.currentIndexChanged.connect(self._tool_chosen)
        form.addRow("Tool", self.tool)
        self.status = QLabel()
        self.status.setWordWrap(True)
        self.status.setMinimumHeight(48)
        self.status.setAlignment(Qt.AlignmentFlag.AlignTop)
        form.addRow(self.status)

    def add_panel(self, widget) -> None:
        """A plugin's panel, below the palette and the panels added before it."""
        self._form.insertRow(self._form.rowCount() - 1, widget)
        self._align_labels()

    def _align_labels(self) -> None:
        """One label column for the box: the palette's and every panel's form rows line up
        as if they were one form."""
        labels = []
        for form in [self._form, *self.findChildren(QFormLayout)]:
            for row in range(form.rowCount()):
                item = form.itemAt(row, QFormLayout.ItemRole.LabelRole)
                if item is not None and isinstance(item.widget(), QLabel):
                    labels.append(item.widget())
        width = max((label.sizeHint().width() for label in labels), default=0)
        for label in labels:
            label.setMinimumWidth(width)

    def set_tools(self, entries, current: str | None = None, icons: dict | None = None) -> None:
        """The palette: ``entries`` = [(name, label, shortcut)]; ``icons`` {name: QIcon} for
        tools that bring one (the others get their label's letter)."""
        self.tool.blockSignals(True)
        self.tool.clear()
        for name, label, shortcut in entries:
            icon = (icons or {}).get(name) or letter_icon(label)
            self.tool.addItem(icon, f"{label} ({shortcut})" if shortcut else label, name)
        if current is not None:
            i = self.tool.findData(current)
            if i >= 0:
                self.tool.setCurrentIndex(i)
        self.tool.blockSignals(False)

    def show_tool(self, name: str) -> None:
        i = self.tool.findData(name)
        if i >= 0 and i != self.tool.currentIndex():
            self.tool.blockSignals(True)
            self.tool.setCurrentIndex(i)
            self.tool.blockSignals(False)

    def _tool_chosen(self, index: int) -> None:
        name = self.tool.itemData(index)
        if name:
            self.tool_selected.emit(name)

    def show_state(self, controller) -> None:
        self.status.setText(controller.status)
        self.setEnabled(True)
        self.tool.setEnabled(self.tool.count() > 0)
        if controller.tool_name is not None:
            self.show_tool(controller.tool_name)
