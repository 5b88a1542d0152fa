"""Showing errors: a dialog for commands and files, the status bar for gestures.

Dialogs go through QMessageBox's static functions, so a test patches ``QMessageBox.critical``
(or ``question``) and nothing blocks.
"""

from __future__ import annotations

import sys

from PySide6.QtWidgets import QMessageBox, QWidget

from sketchforge.errors import SketchforgeError


def error_text(exc: BaseException) -> str:
    """A SketchforgeError's message is a full sentence for the person; anything else is a bug,
    shown with its type so that it can be reported."""
    return str(exc) if isinstance(exc, SketchforgeError) else f"internal error ({type(exc).__name__}): {exc}"


def show_error(parent: QWidget | None, title: str, exc: BaseException, details: str = "") -> None:
    if details and not isinstance(exc, SketchforgeError):
        print(details, file=sys.stderr)
    QMessageBox.critical(parent, title, error_text(exc))


def ask_yes_no(parent: QWidget | None, title: str, text: str, default_yes: bool = False) -> bool:
    """Yes or No; Enter answers ``default_yes``. Each caller chooses the default that loses
    nothing (recovering an autosave: Yes; see the README's table of questions)."""
    default = QMessageBox.StandardButton.Yes if default_yes else QMessageBox.StandardButton.No
    answer = QMessageBox.question(parent, title, text, QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No, default)
    return answer == QMessageBox.StandardButton.Yes


def ask_choice(parent: QWidget | None, title: str, text: str, choices: list[str], default: int, cancel: int) -> int:
    """A question with named answers (``choices``, buttons in that order); returns the index
    chosen. Enter answers ``default``, Esc or closing the box ``cancel``. Tests patch this
    function (the window calls it through this module)."""
    box = QMessageBox(QMessageBox.Icon.Question, title, text, QMessageBox.StandardButton.NoButton, parent)
    buttons = []
    for i, label in enumerate(choices):
        role = QMessageBox.ButtonRole.RejectRole if i == cancel else QMessageBox.ButtonRole.AcceptRole
        buttons.append(box.addButton(label, role))
    box.setDefaultButton(buttons[default])
    box.setEscapeButton(buttons[cancel])
    box.exec()
    clicked = box.clickedButton()
    return buttons.index(clicked) if clicked in buttons else cancel
