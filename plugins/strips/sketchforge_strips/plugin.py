"""The strips plugin's registration (entry point ``strips``): the sculpt solver ``strips``."""

from __future__ import annotations

from sketchforge.plugin_api import hookimpl


@hookimpl
def sketchforge_sculpt_solvers():
    from .solver import STRIPS

    return [STRIPS]
