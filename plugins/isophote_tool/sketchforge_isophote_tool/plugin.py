"""The isophote tool plugin's hook implementations (entry point ``isophote_tool``)."""

from __future__ import annotations

from sketchforge.plugin_api import hookimpl


@hookimpl
def sketchforge_commands():
    from .command import SculptIsophote, SculptIsophotes

    return [SculptIsophote, SculptIsophotes]


@hookimpl
def sketchforge_sculpt_solvers():
    from .gauss_newton import GAUSS_NEWTON

    return [GAUSS_NEWTON]


@hookimpl
def sketchforge_tools():
    from .tool import SculptIsophoteTool

    return [SculptIsophoteTool]


@hookimpl
def sketchforge_qt_panels():
    from sketchforge.plugin_api import Panel

    return [Panel("isophote_sculpt", "sculpture", _create_panel, label="Isophote sculpt", order=10)]


def _create_panel(app):
    from .qt import create_panel  # Qt: imported only by the app, when it builds its panels

    return create_panel(app)


@hookimpl
def sketchforge_dataset_generators():
    from .dataset import HOLES, ISOPHOTE_EDIT

    return [HOLES, ISOPHOTE_EDIT]
