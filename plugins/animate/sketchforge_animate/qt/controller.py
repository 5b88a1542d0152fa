"""The animation's state in the app: pin gestures become the plugin's commands, the displayed
pose is kept current, recording and playback run on a 24 fps timer.

The app does no math here: poses come from :class:`~sketchforge_animate.pose.Animator`,
solved on one background thread (the factorisation after a pin change takes ~0.2–0.4 s and
the first pose ~1 s at 16k vertices), latest request first, so the window never freezes.
"""

from __future__ import annotations

import threading

import numpy as np
from PySide6.QtCore import QObject, QTimer, Signal

from sketchforge.plugin_api import SketchforgeError, new_gesture_id
from sketchforge.qt.panel_api import error_text

from ..commands import AddPin, CopyMotion, HoldPin, MovePin, RecordMotion, RemovePin
from ..state import FPS, KEY, Animation


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
    """Turns pin gestures into animation commands and keeps the displayed pose current.

    While the loop plays, a timer tick only advances the frame and asks the pose; the view
    changes once, when that pose arrives (``pose_ready``, then ``changed``): the posed model,
    the pins and the timeline are repainted together, one repaint per shown frame (software
    OpenGL pays ~10 ms per repaint of the window at 1280x800, issue 34).
    """

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
        self._frame_unshown = False  # the timer advanced the frame; `changed` waits for its pose
        self._anim_cache = None  # (the document's stored value, its Animation): read per frame
        self.worker = PoseWorker(self)
        self.worker.posed.connect(self._posed)
        self.timer = QTimer(self)
        self.timer.setInterval(int(1000 / FPS))
        self.timer.timeout.connect(self._tick)
        doc.plugin_data_changed.connect(lambda key: self._anim_changed() if key == "animate" else None)

    # --- state ----------------------------------------------------------------------------------
    def animation(self):
        """The document's animation (an empty one where the stored value is malformed)."""
        raw = self.doc.plugin_data(KEY)
        # Parsing and checking the stored value costs ~1 ms at 4 pins x 48 frames, and a played
        # frame asks it several times: parsed once per value (the document replaces the value
        # on every change, it never edits it in place).
        if self._anim_cache is None or self._anim_cache[0] is not raw:
            try:
                anim = Animation.from_json(raw)
            except SketchforgeError:
                anim = Animation()
            self._anim_cache = (raw, anim)
        return self._anim_cache[1]

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
    def _request(self, restart: bool = False) -> bool:
        """Ask the worker for the pose of the current frame and targets; False when there is
        no model to pose."""
        if self.mesh is None:
            return False
        anim = self.animation()
        mesh = self.mesh
        targets = self.current_targets()
        previous = None if restart or self._pose is None else self._pose.copy()
        animator = self._animator
        self._token += 1

        def solve():
            from ..pose import INITIAL_ITERATIONS, Animator  # scipy, the solver: on first use

            a = animator if animator is not None and animator.fits(mesh, anim) else Animator(mesh, anim)
            if a.solver is None:
                return a, np.array(mesh.V)
            if previous is None or a is not animator:
                a.solver.reset()
                return a, a.drag(targets, np.array(mesh.V), INITIAL_ITERATIONS)
            return a, a.drag(targets, previous)

        self.worker.request(self._token, solve)
        return True

    def _posed(self, token, result) -> None:
        if isinstance(result, Exception):
            self.message.emit(f"posing failed: {error_text(result)}")
        else:
            self._animator, self._pose = result
            self.pose_ready.emit(self._pose)
        if self._frame_unshown:  # the timeline follows the pose on screen, in the same repaint
            self._frame_unshown = False
            self.changed.emit()

    def _anim_changed(self) -> None:
        if self.loop and self.frame >= self.loop:
            self.frame %= self.loop
        self._request(
            restart=self._animator is None or not self._animator.fits(self.mesh, self.animation())
            if self.mesh is not None
            else True
        )
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
        if self._request():
            self._frame_unshown = True  # `changed` comes with the pose (_posed)
        else:
            self.changed.emit()

    # --- pin gestures -------------------------------------------------------------------------------
    def add_pin(self, point) -> None:
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
        if self.selected:
            self.push(RemovePin(pin=self.selected))
            self.selected = None
            self.changed.emit()

    def hold_selected(self) -> None:
        if self.selected:
            self.push(HoldPin(pin=self.selected))

    def copy_motion(self) -> None:
        if self.selected and self.animation().pin(self.selected).motion is not None:
            self.clipboard = self.selected
            self.message.emit(f"copied the motion of {self.selected}")
        else:
            self.message.emit("select a pin with a motion to copy")

    def paste_motion(self) -> None:
        if self.clipboard and self.selected:
            self.push(CopyMotion(source=self.clipboard, pin=self.selected))

    def shutdown(self) -> None:
        self.timer.stop()
        self.worker.stop()
