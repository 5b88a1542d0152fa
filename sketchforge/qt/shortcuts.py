"""Every mouse gesture and key of the window, in one table: the help overlay (F1 or ?) shows it
and the README's usage section carries the same rows (a test keeps them equal)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QLabel, QWidget

#: (gesture or keys, what it does), in the order the help overlay lists them.
SHORTCUTS: tuple[tuple[str, str], ...] = (
    ("Left drag (CREATION)", "draw a new part in front of all others"),
    ("Right drag or Shift + left drag", "draw a new part behind the backmost part it overlaps"),
    ("Drag from the selected outline back to it", "redraw that stretch of the selected part's outline"),
    ("Ctrl + left drag", "redraw the selected part's whole outline"),
    ("Alt + left drag", "cut a hole in the selected part (draw a closed loop inside it)"),
    ("Click", "select the part under the pointer"),
    ("Double-click (left / right)", "duplicate the part behind / in front of itself"),
    ("Ctrl+D", "duplicate the selected part, moved aside"),
    ("Arrow keys (drawing focused)", "move the selected part by 10 pixels"),
    ("Page Up / Page Down", "move the selected part one step to the front / back"),
    ("Home / End", "move the selected part to the very front / back"),
    ("Del", "remove the selected part"),
    (
        "Drag the selected part's handles",
        "centre marker: move; corner: scale; knob above: rotate (one undo step per drag)",
    ),
    (
        "Ctrl+M",
        "mirror the selected part about its host's axis (a left leg gives a right leg; a free part about its own)",
    ),
    ("Ctrl+Shift+M", "mirror the selected part about its own axis"),
    ("Ctrl+Z / Ctrl+Shift+Z", "undo (during a computation: cancel it) / redo"),
    ("Click (SCULPTURE)", "pick the isophote there and show its band; drag inside the band to redraw it"),
    (
        "Shift + click (SCULPTURE)",
        "pick another isophote of the same part: redraw each inside its band; applied as one edit when each has a stroke",
    ),
    ("Enter (SCULPTURE)", "apply the strokes drawn so far for the picked isophotes (one undo step)"),
    ("Esc", "cancel the running computation or sculpt stroke"),
    ("F2 / F3 / F4", "EDITING / SCULPTURE / OBSERVATION"),
    (
        "L",
        "light tool: drag to turn the light (a raised light keeps its elevation); the Light panel's disc sets azimuth and elevation",
    ),
    ("Ctrl+0", "fit the drawing in the view"),
    ("Middle drag / wheel", "pan / zoom"),
    ("F1 or ?", "show or hide this list"),
)


def shortcut_html() -> str:
    rows = "".join(f"<tr><td><b>{k}</b>&nbsp;&nbsp;</td><td>{v}</td></tr>" for k, v in SHORTCUTS)
    return f"<h3>Gestures and keys</h3><table cellspacing='3'>{rows}</table><p><i>Any key or click closes this.</i></p>"


def shortcut_markdown() -> str:
    """The README's table."""
    lines = ["| Gesture or key | What it does |", "|---|---|"]
    lines += [f"| {k} | {v} |" for k, v in SHORTCUTS]
    return "\n".join(lines)


class HelpOverlay(QLabel):
    """The shortcut list over the drawing region; any key or click hides it again."""

    def __init__(self, parent: QWidget) -> None:
        super().__init__(parent)
        self.setText(shortcut_html())
        self.setTextFormat(Qt.TextFormat.RichText)
        self.setStyleSheet(
            "QLabel { background: rgba(255, 255, 250, 235); border: 1px solid #888; border-radius: 6px; padding: 12px; }"
        )
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        self.hide()

    def toggle(self) -> None:
        if self.isVisible():
            self.hide()
            return
        self.adjustSize()
        parent = self.parentWidget()
        self.move(max(0, (parent.width() - self.width()) // 2), max(0, (parent.height() - self.height()) // 2))
        self.show()
        self.raise_()
        self.setFocus()

    def keyPressEvent(self, event) -> None:
        self.hide()
        if self.parentWidget() is not None:
            self.parentWidget().setFocus()
        event.accept()

    def mousePressEvent(self, event) -> None:
        self.hide()
        event.accept()
