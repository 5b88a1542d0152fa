"""Small value types that registry hooks return."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

# The value types live below the host (the geometry core uses them); re-exported here, their
# historical path.
from sketchforge.geometry.reflectance_model import ReflectanceModel, Shader

__all__ = ["Exporter", "ReflectanceModel", "Shader"]


@dataclass(frozen=True)
class Exporter:
    """A mesh file format: ``write(path: pathlib.Path, mesh: Mesh) -> None``.

    An exporter of more than one mesh (an animation) also sets ``write_document(path, doc)
    -> str`` (returns a one-line summary) and ``handles(doc) -> bool``; for a document it
    handles, it is chosen over a plain mesh exporter of the same suffix."""

    name: str
    suffixes: tuple[str, ...]
    write: Callable
    description: str = ""
    write_document: Callable | None = None
    handles: Callable | None = None
