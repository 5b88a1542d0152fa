"""The animate plugin's hook implementations (entry point ``animate``)."""

from __future__ import annotations

from sketchforge.plugin_api import hookimpl


@hookimpl
def sketchforge_commands():
    from .commands import ANIMATION_COMMANDS

    return list(ANIMATION_COMMANDS)


@hookimpl
def sketchforge_exporters():
    from .export import exporter

    return [exporter()]


@hookimpl
def sketchforge_pose(doc, frame):
    from .export import pose_document

    return pose_document(doc, frame)


@hookimpl
def sketchforge_qt_panels():
    from sketchforge.plugin_api import Panel

    return [Panel("animation", "observation", _create_panel, label="Animation")]


def _create_panel(app):
    from .qt import create_panel  # Qt: imported only by the app, when it builds its panels

    return create_panel(app)


@hookimpl
def sketchforge_plugin_data_validators():
    from .state import KEY, validate_json

    return {KEY: validate_json}
