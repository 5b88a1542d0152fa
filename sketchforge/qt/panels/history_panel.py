"""The history panel: a live mirror of ``doc.undo_stack`` (no second truth).

Row 0 is the state before the first command ("<start>"); row i is the state after command i.
The current row is the stack's index; clicking a row undoes or redoes until there.
"""

from __future__ import annotations

from PySide6.QtGui import QFont
from PySide6.QtWidgets import QListWidget, QListWidgetItem


class HistoryPanel(QListWidget):
    def __init__(self, doc, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.enabled_edits = lambda: True  # the window refuses while a solve runs
        self._updating = False
        doc.history_changed.connect(self.rebuild)
        self.currentRowChanged.connect(self._clicked)
        self.rebuild()

    def rebuild(self) -> None:
        stack = self.doc.undo_stack
        self._updating = True
        try:
            self.clear()
            first = "<start>" if not self.doc.base_journal else "<opened file>"
            if getattr(stack, "dropped", 0):
                first = "<older steps dropped>"  # the memory budget's (the journal keeps them)
            self.addItem(QListWidgetItem(first))
            for i, cmd in enumerate(stack.commands()):
                item = QListWidgetItem(cmd.text())
                if i >= stack.index:
                    f = QFont(item.font())
                    f.setItalic(True)
                    item.setFont(f)
                    item.setForeground(self.palette().placeholderText())
                self.addItem(item)
            if stack.clean_index >= 0 and stack.clean_index < self.count():
                it = self.item(stack.clean_index)
                it.setText(it.text() + "   (saved)")
            self.setCurrentRow(stack.index)
        finally:
            self._updating = False

    def _clicked(self, row: int) -> None:
        if self._updating or row < 0:
            return
        if not self.enabled_edits():
            self.rebuild()
            return
        self.doc.undo_stack.set_index(row)
