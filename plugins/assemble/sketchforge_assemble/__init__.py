"""Assemble layers into one closed 2-manifold mesh, Monster Mash style (thesis 3.2, 4.7).

Public API: :func:`assemble_meshes` (layer meshes -> Mesh), :func:`assemble_detailed` (-> an
:class:`AssemblyResult` with diagnostics), :class:`AssemblyCache` (reuse of per-layer work
between assemblies, see :mod:`sketchforge_assemble.cache`), :mod:`sketchforge_assemble.diagnostics` (mesh
checks and the triangle-triangle intersection counter). The pluggy hook lives in
:mod:`sketchforge_assemble.plugin`.
"""

from .assemble import DEFAULT_PARAMS, AssemblyResult, assemble_detailed, assemble_meshes
from .attach import BACK, FRONT, Attachment
from .cache import AssemblyCache
from .errors import AttachmentError, DepthOrderError

__all__ = [
    "DEFAULT_PARAMS",
    "AssemblyCache",
    "AssemblyResult",
    "Attachment",
    "AttachmentError",
    "BACK",
    "DepthOrderError",
    "FRONT",
    "assemble_detailed",
    "assemble_meshes",
]
