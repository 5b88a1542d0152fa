"""Typed errors with messages meant for the person using the app or the CLI.

Every error a user can cause derives from :class:`SketchforgeError`; the CLI prints its
message on one line and the app shows it in a dialog. Anything else escaping is a bug.
"""

import unicodedata

#: An error's sentence is cut to this many characters: every message is one readable line,
#: whatever size of value a file or a script put in it (issue 30: a 5 MB layer id was echoed
#: whole). Values quoted in messages are cut much shorter, by :func:`quote`.
MAX_MESSAGE_CHARS = 2000
#: Characters of a user's value (an id, a name, a command) quoted in a message.
MAX_QUOTED_CHARS = 80


def shorten(text: str, limit: int = MAX_MESSAGE_CHARS) -> str:
    """``text`` cut to at most ``limit`` characters, saying how much was left out."""
    text = str(text)
    if len(text) <= limit:
        return text
    tail = f"… ({len(text) - limit:,} more characters)"
    return text[: max(0, limit - len(tail))] + tail


def quote(value, limit: int = MAX_QUOTED_CHARS) -> str:
    """``repr(value)`` for a message, at most about ``limit`` characters: a long value shows
    its start and its length ("'xxxx…' (5,000,000 characters)")."""
    if isinstance(value, str) and len(value) > limit:
        return repr(value[:limit]) + f"… ({len(value):,} characters)"
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "…"


class SketchforgeError(Exception):
    """Base of every error a user can cause; ``str(err)`` is a complete, readable sentence
    of at most MAX_MESSAGE_CHARS characters."""

    def __str__(self) -> str:
        return shorten(super().__str__())


class ContourError(SketchforgeError, ValueError):
    """A drawn contour cannot become a layer (too short, degenerate, self-intersecting, NaN...)."""


class ParameterError(SketchforgeError, ValueError):
    """A parameter is out of range or of the wrong type."""


class LayerNotFoundError(SketchforgeError, KeyError):
    """A command names a layer id the document does not have."""

    def __str__(self) -> str:  # KeyError would quote the message
        return shorten(str(self.args[0])) if self.args else "layer not found"


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


def printable(text) -> str:
    """``text`` safe for a terminal: control and format characters (escape sequences, line
    breaks, bidi overrides) and lone surrogates are written as ``\\xNN`` / ``\\uNNNN``, so
    a name can never fake or hide an output line, and printing never fails to encode."""
    out = []
    for ch in str(text):
        if unicodedata.category(ch) in ("Cc", "Cf", "Cs", "Zl", "Zp"):
            o = ord(ch)
            out.append(f"\\x{o:02x}" if o < 0x100 else f"\\u{o:04x}")
        else:
            out.append(ch)
    return "".join(out)
