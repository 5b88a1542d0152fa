"""The animation in the desktop app (OBSERVATION): pins on the 3D model, posing by dragging,
recording, playback. Built by the app through the plugin's ``sketchforge_qt_panels`` hook;
only the app imports this package (it imports Qt).

Gestures (with "Pins" on): click the model to add a pin; drag a pin to pose (one "Move pin"
command per drag); with "Record" on (or Shift held) the drag records the pin's motion at
24 fps while the loop plays, so later recordings run in sync with the first. Delete removes
the selected pin, H pins it in place (drops its motion). Copy / Paste copy a motion between
pins. The timeline shows the frame number; Play / Pause runs the loop.

Modules: :mod:`.controller` (state, commands, the pose worker), :mod:`.panel` (the widgets),
:mod:`.pins` (the 3D view's mouse and the pins drawn there).
"""

from __future__ import annotations

from .controller import AnimationController, PoseWorker
from .panel import AnimationPanel
from .pins import PinInteraction

__all__ = ["AnimationController", "AnimationPanel", "PinInteraction", "PoseWorker", "create_panel"]


def create_panel(app) -> AnimationPanel:
    """The Animation panel for the app ``app`` (a :class:`sketchforge.qt.panel_api.AppContext`):
    its controller runs every command through ``app.run`` (worker thread, progress, crash
    record), follows the assembled model the 3D view shows and stops its pose thread when the
    window closes. The controller is ``panel.c``."""
    ctl = AnimationController(app.doc, lambda cmd: app.run(cmd, label="Animating"), app)
    panel = AnimationPanel(ctl)
    pins = PinInteraction(app.view3d, ctl, panel)
    ctl.message.connect(app.show_message)

    def shown(mesh) -> None:
        ctl.set_mesh(mesh)
        pins.install()

    app.view3d.assembled_shown.connect(shown)
    app.closing.connect(ctl.shutdown)
    return panel
