"""The isophote tool plugin's hook implementations (entry point ``isophote_tool``)."""

from __future__ import annotations

from sketchforge.plugins.hookspecs import hookimpl


@hookimpl
def sketchforge_commands():
    from .command import SculptIsophote

    return [SculptIsophote]


@hookimpl
def sketchforge_sculpt_solvers():
    from .gauss_newton import GAUSS_NEWTON

    return [GAUSS_NEWTON]


@hookimpl
def sketchforge_tools():
    from .tool import SculptIsophoteTool

    return [SculptIsophoteTool]
