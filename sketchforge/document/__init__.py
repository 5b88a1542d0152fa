"""The document model (no Qt): layers, light, commands, undo, events, file format."""

from sketchforge.document.commands import Command, MacroCommand, new_gesture_id
from sketchforge.document.document import Document
from sketchforge.document.layer import DEFAULT_INFLATE_PARAMS, Layer, Light

__all__ = ["Command", "Document", "Layer", "Light", "MacroCommand", "DEFAULT_INFLATE_PARAMS", "new_gesture_id"]
