"""Small value types that registry hooks return."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class ReflectanceModel:
    """Solver-side reflectance.

    ``R(n, l)``: n, l (3,) float64 unit vectors as ``jax.numpy`` arrays -> scalar, written with
    ``jax.numpy`` so the strip solver can differentiate it. Signed: negative in shadow.
    """

    name: str
    R: Callable
    description: str = ""


@dataclass(frozen=True)
class Shader:
    """Display-side shading: ``shade(normals (n,3) float64, light (3,) float64) -> (n,3) float64``
    colours in [0, 1]. Never used by a solver."""

    name: str
    shade: Callable
    description: str = ""


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
