"""Errors the assembly step can raise; both are user-fixable, so both derive from
:class:`sketchforge.errors.SketchforgeError` and carry a complete sentence."""

from __future__ import annotations

from sketchforge.plugin_api import SketchforgeError, SolverError


class AttachmentError(SketchforgeError, ValueError):
    """An open stroke's junction cannot be attached: it spans two layers, runs partly outside
    the layer it should attach to, or crosses another part's junction."""


class DepthOrderError(SolverError):
    """The depth-order constraints cannot all hold (e.g. a part squeezed between two layers
    it is glued to)."""
