"""Help > Plugins: every plugin with its version, what it registers and its problems.

The content is :func:`sketchforge.plugins.inventory.plugin_inventory`, the list
``sketchforge plugins`` prints, so the app and the CLI always agree. Each problem shows once, in
full, numbered, below the plugins (every plugin it names is red and refers to its number), and
stays: the dialog lists them whenever it is opened, and the window keeps a button in its status
bar while there are any (:class:`ProblemsButton`), where a status message would time out.
"""

from __future__ import annotations

import html

from PySide6.QtCore import Qt
from PySide6.QtGui import QBrush, QColor
from PySide6.QtWidgets import (
    QDialog,
    QDialogButtonBox,
    QLabel,
    QPushButton,
    QTextBrowser,
    QTreeWidget,
    QTreeWidgetItem,
    QVBoxLayout,
)

from sketchforge.plugins.inventory import numbered_problems, plugin_inventory, unattributed_problems

PROBLEM_COLOUR = QColor(170, 30, 20)


class PluginsDialog(QDialog):
    """A tree: one top row per plugin ("name", "version", status and the count of what it
    registers), its contributions by kind and its problems as children (plugins with
    problems are expanded)."""

    def __init__(self, host, parent=None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Plugins")
        self.resize(760, 560)
        self.entries = plugin_inventory(host)
        self.extra = unattributed_problems(host, self.entries)
        self.problems = numbered_problems(self.entries, self.extra)
        lay = QVBoxLayout(self)
        n_problems = len(self.problems)
        self.summary = QLabel(f"{len(self.entries)} plugins" + (
            f"; {n_problems} problem{'s' * (n_problems != 1)}" if n_problems else "; no problems"))
        lay.addWidget(self.summary)
        self.tree = QTreeWidget()
        self.tree.setColumnCount(3)
        self.tree.setHeaderLabels(["Plugin", "Version", "Registers"])
        self.tree.setWordWrap(True)
        self.tree.setUniformRowHeights(False)
        for e in self.entries:
            count = sum(len(v) for v in e.registers.values())
            status = "" if e.status == "loaded" else e.status
            text = status or (f"{count} contribution{'s' * (count != 1)}" if count else "nothing")
            if e.problems:
                refs = ", ".join(str(self.problems.index(p) + 1) for p in e.problems)
                text += f" — ⚠ problem{'s' * (len(e.problems) != 1)} {refs} (below)"
            top = QTreeWidgetItem([e.name, e.version or "", text])
            for heading, names in e.registers.items():
                child = QTreeWidgetItem([heading, "", ", ".join(names)])
                child.setToolTip(2, ", ".join(names))
                top.addChild(child)
            if e.problems:
                for col in range(3):
                    top.setForeground(col, QBrush(PROBLEM_COLOUR))
            self.tree.addTopLevelItem(top)
            top.setExpanded(True)
        self.tree.resizeColumnToContents(0)
        self.tree.setColumnWidth(1, 70)
        lay.addWidget(self.tree, 3)
        #: every problem once, in full, numbered
        self.problem_view = QTextBrowser()
        self.problem_view.setOpenLinks(False)
        colour = PROBLEM_COLOUR.name()
        self.problem_view.setHtml("".join(
            f"<p style='color:{colour}; margin:2px 0'><b>{i}.</b> {html.escape(p)}</p>"
            for i, p in enumerate(self.problems, 1)))
        self.problem_view.setVisible(bool(self.problems))
        self.problem_view.setMaximumHeight(170)
        lay.addWidget(QLabel("Problems") if self.problems else QLabel(""), 0)
        lay.addWidget(self.problem_view, 1)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close)
        buttons.rejected.connect(self.reject)
        buttons.accepted.connect(self.accept)
        lay.addWidget(buttons)

    def problem_lines(self) -> list[str]:
        """Every problem as the dialog shows it, once each, in its numbered order."""
        return [p.split(". ", 1)[1] for p in self.problem_view.toPlainText().split("\n") if ". " in p]

    def problem_refs(self, plugin: str) -> str:
        """What the plugin's row says of its problems ("" when it has none)."""
        for i in range(self.tree.topLevelItemCount()):
            top = self.tree.topLevelItem(i)
            if top.text(0) == plugin:
                text = top.text(2)
                return text.split("⚠ ", 1)[1] if "⚠ " in text else ""
        raise KeyError(plugin)


class ProblemsButton(QPushButton):
    """A permanent status-bar button while plugins have problems ("⚠ 2 plugin problems"),
    opening Help > Plugins; hidden when there are none."""

    def __init__(self, open_dialog, parent=None) -> None:
        super().__init__(parent)
        self.setFlat(True)
        self.setCursor(Qt.CursorShape.PointingHandCursor)
        self.setStyleSheet(f"color: {PROBLEM_COLOUR.name()}; padding: 0 6px;")
        self.clicked.connect(open_dialog)
        self.setVisible(False)

    def show_count(self, problems: list[str]) -> None:
        n = len(problems)
        self.setText(f"⚠ {n} plugin problem{'s' * (n != 1)}")
        self.setToolTip("\n".join(problems[:12]) + ("\n…" if n > 12 else "") + "\n\nHelp > Plugins lists them")
        self.setVisible(n > 0)
