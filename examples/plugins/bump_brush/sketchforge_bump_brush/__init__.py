"""Example brush plugin: the ``bump_brush`` command and the "Bump brush" tool.

A template for a brush: the command subclasses ``ReplaceLayerCommand`` (pure ``compute``,
journal fields read with the parse helpers), records itself in ``Layer.edits`` and implements
``reapply`` so the edit survives a re-inflation; the tool turns a drag into that command.
"""

from sketchforge_bump_brush.brush import BumpBrush, bump
from sketchforge_bump_brush.tool import BumpTool

__all__ = ["BumpBrush", "BumpTool", "bump"]
