"""Gesture state machines (no Qt): press/move/release in document coordinates -> Commands."""

from sketchforge.tools.base import Tool
from sketchforge.tools.draw import DrawContourTool
from sketchforge.tools.light import LightTool

__all__ = ["DrawContourTool", "LightTool", "Tool"]
