"""Pins in the 3D view: an event filter on the OBSERVATION view's GL widget turns clicks and
drags into pin gestures while "Pins" is on (orbit and zoom otherwise, and with the right
button), and draws the pins and the posed model."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QEvent, QObject, Qt
from PySide6.QtWidgets import QWidget

from sketchforge.plugin_api import SketchforgeError
from sketchforge.qt.panel_api import error_text

from ..picking import pick_vertex, unproject_at_depth
from .controller import AnimationController
from .panel import AnimationPanel


class PinInteraction(QObject):
    """Event filter on the 3D view's GL widget: pin clicks and drags when "Pins" is on; orbit
    and zoom otherwise (and with the right button)."""

    def __init__(self, view3d, controller: AnimationController, panel: AnimationPanel) -> None:
        super().__init__(view3d)
        self.view = view3d
        self.c = controller
        self.panel = panel
        self._scatter = None
        self._shown = None  # (pin ids, their positions' bytes, the selected pin) last drawn
        self._installed = None
        controller.pose_ready.connect(self._show_pose)
        controller.changed.connect(self._show_pins)

    def install(self) -> None:
        gl = self.view.gl
        if isinstance(gl, QWidget) and self._installed is not gl:  # (tests put a stand-in there)
            gl.installEventFilter(self)
            self._installed = gl

    def _mvp(self) -> np.ndarray:
        gl = self.view.gl
        # document (x, y, z) -> world (x, -z, y), as View3D places the model
        model = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
        w, h = gl.width(), gl.height()
        proj = np.array(gl.projectionMatrix((0, 0, w, h), (0, 0, w, h)).data()).reshape(4, 4).T
        view = np.array(gl.viewMatrix().data()).reshape(4, 4).T
        return proj @ view @ model

    def eventFilter(self, obj, ev) -> bool:  # noqa: N802 - Qt name
        if not self.panel.pins.isChecked() or self.c.mesh is None:
            return False
        t = ev.type()
        if t == QEvent.Type.KeyPress:
            if ev.key() in (Qt.Key.Key_Delete, Qt.Key.Key_Backspace):
                self.c.remove_selected()
                return True
            if ev.key() == Qt.Key.Key_H:
                self.c.hold_selected()
                return True
            if ev.key() == Qt.Key.Key_Escape:
                self.c.cancel_drag()
                return True
            return False
        if t not in (QEvent.Type.MouseButtonPress, QEvent.Type.MouseMove, QEvent.Type.MouseButtonRelease):
            return False
        if t == QEvent.Type.MouseButtonPress and ev.button() != Qt.MouseButton.LeftButton:
            return False
        pos = ev.position()
        pos = (pos.x(), pos.y())
        size = (self.view.gl.width(), self.view.gl.height())
        try:
            if t == QEvent.Type.MouseButtonPress:
                ids, T = self.c.pin_positions()
                hit = pick_vertex(self._mvp(), T, size, pos, radius=12.0) if len(ids) else None
                if hit is not None:
                    self.c.begin_drag(ids[hit], record=bool(ev.modifiers() & Qt.KeyboardModifier.ShiftModifier))
                    return True
                P = self.c._pose if self.c._pose is not None else self.c.mesh.V
                v = pick_vertex(self._mvp(), P, size, pos, radius=6.0)
                if v is None:
                    return False  # empty space: orbit as usual
                self.c.add_pin(self.c.mesh.V[v])  # a pin lives on the static model
                return True
            if self.c._drag is None:
                return False
            if t == QEvent.Type.MouseMove:
                self.c.drag_to(unproject_at_depth(self._mvp(), self.c._drag["pos"], size, pos))
                return True
            self.c.end_drag()
            return True
        except SketchforgeError as exc:
            self.c.message.emit(error_text(exc))
            return True

    def _show_pose(self, P) -> None:
        item = getattr(self.view, "model_item", None)
        if item is None or self.c.mesh is None:
            return
        item.set_positions(P)  # same triangles as the shown model; normals of the pose
        self._show_pins()

    def _show_pins(self) -> None:
        gl = self.view.gl
        if not isinstance(gl, QWidget):
            return
        import pyqtgraph.opengl as pgl

        ids, T = self.c.pin_positions()
        # a played frame asks twice (with the pose, then with the timeline): only a change is
        # drawn, so still pins never cost the view a repaint
        shown = (tuple(ids), T.tobytes(), self.c.selected)
        if self._scatter is not None and shown == self._shown:
            return
        self._shown = shown
        W = np.c_[T[:, 0], -T[:, 2], T[:, 1]] if len(T) else np.zeros((0, 3))
        colours = np.array([(0.85, 0.15, 0.1, 1.0) if i == self.c.selected else (0.1, 0.3, 0.85, 1.0) for i in ids]).reshape(-1, 4)
        if self._scatter is None:
            self._scatter = pgl.GLScatterPlotItem(pos=W, color=colours, size=14, pxMode=True)
            self._scatter.setGLOptions("translucent")
            self._scatter.setDepthValue(10)
            gl.addItem(self._scatter)
        else:
            self._scatter.setData(pos=W, color=colours)
