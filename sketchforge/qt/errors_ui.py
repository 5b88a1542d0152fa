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


def ask_yes_no(parent: QWidget | None, title: str, text: str) -> bool:
    answer = QMessageBox.question(
        parent, title, text, QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No, QMessageBox.StandardButton.No
    )
    return answer == QMessageBox.StandardButton.Yes
