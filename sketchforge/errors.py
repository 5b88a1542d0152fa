"""Typed errors with messages meant for the person using the app or the CLI.

Every error a user can cause derives from :class:`SketchforgeError`; the CLI prints its
message on one line and the app shows it in a dialog. Anything else escaping is a bug.
"""


class SketchforgeError(Exception):
    """Base of every error a user can cause; ``str(err)`` is a complete, readable sentence."""


class ContourError(SketchforgeError, ValueError):
    """A drawn contour cannot become a layer (too short, degenerate, self-intersecting, NaN...)."""


class ParameterError(SketchforgeError, ValueError):
    """A parameter is out of range or of the wrong type."""


class LayerNotFoundError(SketchforgeError, KeyError):
    """A command names a layer id the document does not have."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else "layer not found"


class UnknownCommandError(SketchforgeError, ValueError):
    """A journal entry names a command that no installed plugin provides."""


class DocumentFormatError(SketchforgeError, ValueError):
    """A document file is not a valid sketchforge document (names the file and the field)."""


class SculptError(SketchforgeError, ValueError):
    """An isophote edit cannot be applied (stroke outside the band, pick outside the layer...)."""


class SolverError(SketchforgeError, RuntimeError):
    """A numerical solver failed or produced non-finite values; the command was rolled back."""


class ExportError(SketchforgeError, OSError):
    """A mesh could not be written (unknown format, missing folder...)."""


class LimitError(SketchforgeError, ValueError):
    """An input exceeds a documented size limit (too many points, triangles or commands)."""


class NothingToDoError(SketchforgeError):
    """An edit would change nothing; the message says why (e.g. an empty impacted region)."""


class GeometryError(SketchforgeError, ValueError):
    """Geometry cannot safely reach a native library (Triangle, libigl, OSQP, GEOS): non-finite
    or huge coordinates, crossing constrained segments, degenerate triangles, inconsistent
    shapes... Raised by :mod:`sketchforge.geometry.guard` before the native call."""


class EditsDoNotApplyError(SketchforgeError):
    """A redrawn outline's sculpt edits do not apply to its new surface (nothing changed)."""


class EditNotMovableError(SketchforgeError):
    """A layer cannot be moved, scaled or rotated because one of its edits cannot follow it
    (its command does not implement ``Command.transform_edit``, or refuses this transform);
    nothing changed."""


class PluginError(SketchforgeError):
    """A plugin misbehaved (a hook raised, returned the wrong type, broke a contract); the
    message names the plugin. The document is left as it was before."""


class UnknownSolverError(SketchforgeError, ValueError):
    """A document or command names a solver (inflater, sculpt solver, assembler) that no
    installed plugin provides; the message lists the installed ones."""
