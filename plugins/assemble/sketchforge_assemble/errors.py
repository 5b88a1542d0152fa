"""Errors the assembly step can raise; both are user-fixable, so both derive from
:class:`sketchforge.errors.SketchforgeError` and carry a complete sentence."""

from __future__ import annotations

from sketchforge.plugin_api import SketchforgeError, SolverError


class AttachmentError(SketchforgeError, ValueError):
    """An open stroke's junction cannot be attached: no stretch of it lies inside one layer,
    it crosses another part's junction or the layer's outline, or the attachments form a loop.

    ``parts``: the indices (in the assembly's back-to-front list) of the parts whose junction
    is at fault, when known; the assembly frees them and assembles the rest (issue 34)."""

    def __init__(self, message: str, parts=()):
        super().__init__(message)
        self.parts = tuple(int(p) for p in parts)


class DepthOrderError(SolverError):
    """The depth-order constraints cannot all hold (e.g. a part squeezed between two layers
    it is glued to). ``layers``: the layers (sheet indices) of the rows that could not hold,
    when known; ``free``: they are free parts drawn where there is no room for them (the
    assembly leaves them out of the model rather than move the glued ones)."""

    def __init__(self, message: str, layers=(), free: bool = False):
        super().__init__(message)
        self.layers = tuple(int(p) for p in layers)
        self.free = bool(free)
