"""Animation in OBSERVATION mode: pins on the 3D model, posing by dragging, recording, playback.

Gestures (with "Pins" on): click the model to add a pin; drag a pin to pose (one "Move pin"
command per drag); with "Record" on (or Shift held) the drag records the pin's motion at
24 fps while the loop plays, so later recordings run in sync with the first. Delete removes
the selected pin, H pins it in place (drops its motion). Copy / Paste copy a motion between
pins. The timeline shows the frame number; Play / Pause runs the loop.

The app does no math here: poses come from the animate plugin's Animator, solved on a worker
thread (the factorisation after a pin change takes ~0.2–0.4 s and the first pose ~1 s at 16k
vertices), latest request first, so the window never freezes.
"""

from __future__ import annotations

import threading

import numpy as np
from PySide6.QtCore import QEvent, QObject, Qt, QTimer, Signal
from PySide6.QtWidgets import QHBoxLayout, QLabel, QPushButton, QSlider, QVBoxLayout, QWidget

from sketchforge.errors import SketchforgeError
from sketchforge.qt.errors_ui import error_text

FPS = 24


class PoseWorker(QObject):
    """One background thread computing the latest requested pose; older requests are dropped."""

    posed = Signal(object, object)  # (token, vertices (n,3) or exception)

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self._cv = threading.Condition()
        self._pending = None
        self._stop = False
        self.busy = False
        self._thread = threading.Thread(target=self._loop, name="pose-worker", daemon=True)
        self._thread.start()

    def request(self, token, fn) -> None:
        with self._cv:
            self._pending = (token, fn)
            self._cv.notify()

    def stop(self) -> None:
        """Stop the thread (waits for a solve in progress, at most a few seconds)."""
        with self._cv:
            self._stop = True
            self._cv.notify()
        self._thread.join(timeout=10)

    def _loop(self) -> None:
        while True:
            with self._cv:
                while self._pending is None and not self._stop:
                    self._cv.wait()
                if self._stop:
                    return
                token, fn = self._pending
                self._pending = None
                self.busy = True
            try:
                result = fn()
            except Exception as exc:  # noqa: BLE001 - shown on the GUI thread
                result = exc
            self.busy = False
            with self._cv:
                if self._stop:
                    return
                self.posed.emit(token, result)


class AnimationController(QObject):
    """Turns pin gestures into animation commands and keeps the displayed pose current."""

    changed = Signal()  # frame, loop, selection or play state changed
    pose_ready = Signal(object)  # (n,3) float64 vertices of the displayed pose
    message = Signal(str)

    def __init__(self, doc, push, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.push = push  # push(command): the app's command runner, or doc.push in tests
        self.mesh = None  # the assembled model on display
        self.frame = 0
        self.playing = False
        self.recording = False
        self.selected: str | None = None
        self.clipboard: str | None = None
        self._drag = None  # {"pin", "pos", "samples", "start", "record"}
        self._animator = None
        self._pose = None
        self._token = 0
        self.worker = PoseWorker(self)
        self.worker.posed.connect(self._posed)
        self.timer = QTimer(self)
        self.timer.setInterval(int(1000 / FPS))
        self.timer.timeout.connect(self._tick)
        doc.plugin_data_changed.connect(lambda key: self._anim_changed() if key == "animate" else None)

    # --- state ----------------------------------------------------------------------------------
    def animation(self):
        from sketchforge_animate import Animation

        try:
            return Animation.of(self.doc)
        except SketchforgeError:
            return Animation()

    @property
    def loop(self) -> int:
        return self.animation().loop

    def set_mesh(self, mesh) -> None:
        """The view shows a new assembled model (None: none)."""
        if mesh is not None and mesh is self.mesh and self._pose is not None:
            self.pose_ready.emit(self._pose)  # the same model redrawn: show the pose again
            return
        self.mesh = mesh
        self._animator = None
        self._pose = None if mesh is None else np.array(mesh.V)
        self._request(restart=True)

    def current_targets(self) -> np.ndarray:
        anim = self.animation()
        T = anim.targets(self.frame) if anim.pins else np.zeros((0, 3))
        if self._drag is not None:
            i = [p.id for p in anim.pins].index(self._drag["pin"])
            T[i] = self._drag["pos"]
        return T

    def pin_positions(self) -> tuple[list[str], np.ndarray]:
        anim = self.animation()
        return [p.id for p in anim.pins], self.current_targets()

    # --- posing (worker thread) -----------------------------------------------------------------
    def _request(self, restart: bool = False) -> None:
        if self.mesh is None:
            return
        anim = self.animation()
        mesh = self.mesh
        targets = self.current_targets()
        previous = None if restart or self._pose is None else self._pose.copy()
        animator = self._animator
        self._token += 1

        def solve():
            from sketchforge_animate.pose import INITIAL_ITERATIONS, Animator

            a = animator if animator is not None and animator.fits(mesh, anim) else Animator(mesh, anim)
            if a.solver is None:
                return a, np.array(mesh.V)
            if previous is None or a is not animator:
                a.solver.reset()
                return a, a.drag(targets, np.array(mesh.V), INITIAL_ITERATIONS)
            return a, a.drag(targets, previous)

        self.worker.request(self._token, solve)

    def _posed(self, token, result) -> None:
        if isinstance(result, Exception):
            self.message.emit(f"posing failed: {error_text(result)}")
            return
        self._animator, self._pose = result
        self.pose_ready.emit(self._pose)

    def _anim_changed(self) -> None:
        if self.loop and self.frame >= self.loop:
            self.frame %= self.loop
        self._request(restart=self._animator is None or not self._animator.fits(self.mesh, self.animation()) if self.mesh is not None else True)
        self.changed.emit()

    # --- timeline ---------------------------------------------------------------------------------
    def set_playing(self, on: bool) -> None:
        if on and self.loop < 2 and self._drag is None:
            self.message.emit("nothing to play yet: record a motion (Record, or Shift while dragging a pin)")
            on = False
        self.playing = on
        self._sync_timer()
        self.changed.emit()

    def set_frame(self, frame: int) -> None:
        self.frame = int(frame) % self.loop if self.loop else 0
        self._request()
        self.changed.emit()

    def _sync_timer(self) -> None:
        run = self.playing or (self._drag is not None and self._drag["record"])
        if run and not self.timer.isActive():
            self.timer.start()
        elif not run and self.timer.isActive():
            self.timer.stop()

    def _tick(self) -> None:
        if self._drag is not None and self._drag["record"]:
            self._drag["samples"].append(np.array(self._drag["pos"]))
        if self.loop:
            self.frame = (self.frame + 1) % self.loop
        self._request()
        self.changed.emit()

    # --- pin gestures -------------------------------------------------------------------------------
    def add_pin(self, point) -> None:
        from sketchforge_animate.commands import AddPin

        cmd = AddPin(at=tuple(float(v) for v in point))
        self.push(cmd)
        self.selected = cmd.id
        self.changed.emit()

    def begin_drag(self, pin_id: str, record: bool = False) -> None:
        anim = self.animation()
        pos = anim.targets(self.frame)[[p.id for p in anim.pins].index(pin_id)]
        record = record or self.recording
        start = self.frame if anim.loop else 0
        self.selected = pin_id
        self._drag = {"pin": pin_id, "pos": np.array(pos), "samples": [], "start": start, "record": record}
        self._sync_timer()
        self.changed.emit()

    def drag_to(self, point) -> None:
        if self._drag is None:
            return
        self._drag["pos"] = np.asarray(point, dtype=np.float64).reshape(3)
        if not self.timer.isActive():
            self._request()

    def end_drag(self) -> None:
        from sketchforge.document.commands import new_gesture_id
        from sketchforge_animate.commands import MovePin, RecordMotion

        drag, self._drag = self._drag, None
        self._sync_timer()
        if drag is None:
            return
        if drag["record"]:
            if len(drag["samples"]) < 2:
                self.message.emit("the recording was too short: keep dragging for at least two frames")
            else:
                self.push(RecordMotion(pin=drag["pin"], start=drag["start"], samples=np.array(drag["samples"])))
                if not self.playing:
                    self.set_playing(True)
        else:
            anim = self.animation()
            if not np.array_equal(np.array(anim.pin(drag["pin"]).target), drag["pos"]) and anim.pin(drag["pin"]).motion is None:
                self.push(MovePin(pin=drag["pin"], to=tuple(float(v) for v in drag["pos"]), gesture=new_gesture_id()))
            elif anim.pin(drag["pin"]).motion is not None:
                self.message.emit(f"pin {drag['pin']} follows its motion: hold it in place (H) before posing it by hand")
        self.changed.emit()

    def cancel_drag(self) -> None:
        self._drag = None
        self._sync_timer()
        self._request()

    def remove_selected(self) -> None:
        from sketchforge_animate.commands import RemovePin

        if self.selected:
            self.push(RemovePin(pin=self.selected))
            self.selected = None
            self.changed.emit()

    def hold_selected(self) -> None:
        from sketchforge_animate.commands import HoldPin

        if self.selected:
            self.push(HoldPin(pin=self.selected))

    def copy_motion(self) -> None:
        if self.selected and self.animation().pin(self.selected).motion is not None:
            self.clipboard = self.selected
            self.message.emit(f"copied the motion of {self.selected}")
        else:
            self.message.emit("select a pin with a motion to copy")

    def paste_motion(self) -> None:
        from sketchforge_animate.commands import CopyMotion

        if self.clipboard and self.selected:
            self.push(CopyMotion(source=self.clipboard, pin=self.selected))

    def shutdown(self) -> None:
        self.timer.stop()
        self.worker.stop()


class AnimationPanel(QWidget):
    """Pins toggle, Record, Play/Pause, the timeline with the frame number, pin actions."""

    def __init__(self, controller: AnimationController, parent=None) -> None:
        super().__init__(parent)
        self.c = controller
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 8, 0, 0)
        lay.addWidget(QLabel("<b>Animation</b>"))
        row = QHBoxLayout()
        self.pins = QPushButton("Pins")
        self.pins.setCheckable(True)
        self.pins.setToolTip("Click the model to add a pin, drag a pin to pose (Shift: record)")
        self.record = QPushButton("Record")
        self.record.setCheckable(True)
        self.play = QPushButton("Play")
        self.play.setCheckable(True)
        for b in (self.pins, self.record, self.play):
            row.addWidget(b)
        lay.addLayout(row)
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.frame_label = QLabel("")
        lay.addWidget(self.slider)
        lay.addWidget(self.frame_label)
        row2 = QHBoxLayout()
        self.hold = QPushButton("Pin in place")
        self.remove = QPushButton("Remove")
        self.copy = QPushButton("Copy motion")
        self.paste = QPushButton("Paste")
        for b in (self.hold, self.remove, self.copy, self.paste):
            row2.addWidget(b)
        lay.addLayout(row2)
        self.record.toggled.connect(lambda on: setattr(self.c, "recording", on))
        self.play.toggled.connect(self.c.set_playing)
        self.slider.valueChanged.connect(lambda v: self.c.set_frame(v) if v != self.c.frame else None)
        self.hold.clicked.connect(self.c.hold_selected)
        self.remove.clicked.connect(self.c.remove_selected)
        self.copy.clicked.connect(self.c.copy_motion)
        self.paste.clicked.connect(self.c.paste_motion)
        self.c.changed.connect(self.sync)
        self.sync()

    def sync(self) -> None:
        loop = self.c.loop
        self.slider.blockSignals(True)
        self.slider.setRange(0, max(0, loop - 1))
        self.slider.setValue(self.c.frame)
        self.slider.setEnabled(loop > 1)
        self.slider.blockSignals(False)
        self.play.blockSignals(True)
        self.play.setChecked(self.c.playing)
        self.play.setText("Pause" if self.c.playing else "Play")
        self.play.blockSignals(False)
        n = len(self.c.animation().pins)
        sel = f", selected {self.c.selected}" if self.c.selected else ""
        if loop:
            self.frame_label.setText(f"frame {self.c.frame} / {loop} ({loop / FPS:.2f} s at {FPS} fps), {n} pins{sel}")
        else:
            self.frame_label.setText(f"no motion recorded, {n} pins{sel}")
        for b in (self.hold, self.remove, self.copy):
            b.setEnabled(self.c.selected is not None)
        self.paste.setEnabled(self.c.selected is not None and self.c.clipboard is not None)


class PinInteraction(QObject):
    """Event filter on the 3D view's GL widget: pin clicks and drags when "Pins" is on; orbit
    and zoom otherwise (and with the right button)."""

    def __init__(self, view3d, controller: AnimationController, panel: AnimationPanel) -> None:
        super().__init__(view3d)
        self.view = view3d
        self.c = controller
        self.panel = panel
        self._scatter = None
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
        from sketchforge_animate.picking import pick_vertex, unproject_at_depth

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
        W = np.c_[T[:, 0], -T[:, 2], T[:, 1]] if len(T) else np.zeros((0, 3))
        colours = np.array([(0.85, 0.15, 0.1, 1.0) if i == self.c.selected else (0.1, 0.3, 0.85, 1.0) for i in ids]).reshape(-1, 4)
        if self._scatter is None:
            self._scatter = pgl.GLScatterPlotItem(pos=W, color=colours, size=14, pxMode=True)
            self._scatter.setGLOptions("translucent")
            self._scatter.setDepthValue(10)
            gl.addItem(self._scatter)
        else:
            self._scatter.setData(pos=W, color=colours)


class _DocumentValues:
    """What a document exporter reads, taken on the GUI thread (immutable values), so the
    export can run on a worker while the user goes on editing."""

    def __init__(self, doc) -> None:
        self._mesh = doc.export_mesh()
        self._data = {k: doc.plugin_data(k) for k in doc.plugin_data_keys}

    def export_mesh(self, layer_id=None):
        return self._mesh

    def plugin_data(self, key, default=None):
        return self._data.get(key, default)


def export_document_in_background(window, exporter, path) -> bool:
    """Run ``exporter.write_document`` on a worker thread with the progress indicator, through
    the host (temp file, atomic rename, one-line errors naming the plugin)."""
    values = _DocumentValues(window.doc)  # may raise SketchforgeError: the caller shows it

    def done(summary):
        window.show_message(f"exported {path} ({summary})")

    def failed(exc, tb):
        from sketchforge.qt.errors_ui import show_error

        show_error(window, "Cannot export", exc, tb)

    window.jobs.start(lambda: window.host.export(path, doc=values), done, failed, label="Exporting animation")
    return True
