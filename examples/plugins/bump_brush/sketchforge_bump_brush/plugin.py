"""Hook implementations (entry point ``bump_brush``): registry hooks return lists."""

from sketchforge.plugin_api import hookimpl


@hookimpl
def sketchforge_commands():
    from sketchforge_bump_brush.brush import BumpBrush

    return [BumpBrush]


@hookimpl
def sketchforge_tools():
    from sketchforge_bump_brush.tool import BumpTool

    return [BumpTool]
