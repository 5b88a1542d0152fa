"""The main window's modes: EDITING (its CREATION and SCULPTURE states) and OBSERVATION, the light
tool, which view and panel show and who gets the keys; the sculpt tool's selection, Enter and
Esc."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QWidget


class ModeController:
    """Switches the window's (``win``) mode and state: the central view, the controls shown and
    the canvas's interaction."""

    def __init__(self, win) -> None:
        self.win = win

    def select_tool(self, name: str) -> None:
        """Switch to SCULPTURE with the tool ``name`` (palette, Tools menu, shortcut)."""
        if self.win.mode != "editing" or self.win.state != "sculpture":
            self.win.set_mode("sculpture")
        if self.win.sculpt.select_tool(name):
            self.win.sculpt_panel.show_state(self.win.sculpt)

    def set_mode(self, mode: str) -> None:
        """"editing" (keeps the state), "creation", "sculpture" or "observation"."""
        if mode in ("creation", "sculpture"):
            self.win.set_state(mode)
            mode = "editing"
        self.win.mode = mode
        for b, on in ((self.win.modes.editing, mode == "editing"), (self.win.modes.observation, mode == "observation")):
            b.blockSignals(True)
            b.setChecked(on)
            b.blockSignals(False)
        self.win.modes._enable(mode)
        self.win.light_panel.setVisible(mode == "editing")
        if mode == "observation":
            self.win.center.setCurrentWidget(self.win.view3d)
            self.win.controls.setCurrentWidget(self.win.observe_page)
            self.win.view3d.activate()
        else:
            self.win.view3d.deactivate()
            self.win.center.setCurrentWidget(self.win.canvas)
            self.win.set_state(self.win.state)
        self.win.app_context._set_mode(self.win.mode, self.win.state)
        self.win._focus_center()

    def _focus_center(self) -> None:
        """Keys go to the view after every mode switch: the widget that had focus (a mode
        button, or the canvas just hidden) would otherwise keep it or leave none."""
        widget = self.win.center.currentWidget()
        gl = getattr(widget, "gl", None)
        target = gl if isinstance(gl, QWidget) else widget
        target.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        target.setFocus(Qt.FocusReason.OtherFocusReason)
        self.win.activateWindow()

    def toggle_help(self) -> None:
        self.win.help_overlay.toggle()

    def set_state(self, state: str) -> None:
        self.win.state = state
        self.win.app_context._set_mode(self.win.mode, self.win.state)
        for b, on in ((self.win.modes.creation, state == "creation"), (self.win.modes.sculpture, state == "sculpture")):
            b.blockSignals(True)
            b.setChecked(on)
            b.blockSignals(False)
        if self.win.mode != "editing":
            return
        self.win.controls.setCurrentWidget(self.win.creation_page if state == "creation" else self.win.sculpt_panel)
        self.win._apply_interaction()
        if state == "sculpture":
            self.win.sculpt.reset()
            self.win.sculpt_panel.show_state(self.win.sculpt)
        self.win._focus_center()

    def _light_toggled(self, on: bool) -> None:
        self.win.act_light.setChecked(on)
        self.win._apply_interaction()
        self.win._focus_center()

    def _apply_interaction(self) -> None:
        if self.win.modes.light.isChecked():
            self.win.canvas.set_interaction("light")
        else:
            self.win.canvas.set_interaction("draw" if self.win.state == "creation" else "sculpt")

    def apply_sculpt_strokes(self) -> None:
        """Enter in SCULPTURE: apply the strokes drawn for the picked isophotes as one edit."""
        if self.win.canvas.interaction != "sculpt":
            return
        if self.win._refuse_if_busy():
            return
        self.win.sculpt.apply_drawn()

    def cancel_current(self) -> None:
        """Esc: close the help, stop the running solve, and drop a sculpt stroke being drawn
        with its preview."""
        if self.win.help_overlay.isVisible():
            self.win.help_overlay.hide()
            self.win._focus_center()
            return
        if self.win._pending_strokes:
            self.win.show_message(f"dropped {len(self.win._pending_strokes)} waiting stroke(s)")
        self.win._pending_strokes.clear()
        self.win.runner.cancel()
        if self.win.canvas.interaction == "sculpt":
            self.win.sculpt.cancel()
