"""The assemble plugin's registration (entry point ``assemble``): the ``depth_qp`` assembler."""

from __future__ import annotations

from sketchforge.plugin_api import AssembledMesh, Assembler, hookimpl

from .assemble import _params, assemble_detailed
from .cache import AssemblyCache

#: Shared by every assembly through the hook (the app's assembled view, ``replay``): a
#: re-assembly after one layer changed redoes only what depends on that layer.
CACHE = AssemblyCache()

#: Bumped when the same layers and parameters would assemble differently.
VERSION = "2"  # 2: issue 34 (sides, stretches, free parts, full thickness, thin parts refined)


def assemble_layers(layers, params):
    """Assemble the given layers (back to front) into one closed mesh; layers without a mesh
    are skipped. See :func:`sketchforge_assemble.assemble_detailed`."""
    layers = [layer for layer in layers if getattr(layer, "mesh", None) is not None]
    result = assemble_detailed(
        [layer.mesh for layer in layers],
        closed=[bool(layer.closed) for layer in layers],
        params=dict(params or {}),
        names=[layer.name or layer.id for layer in layers],
        cache=CACHE,
    )
    # what the person should know: the parts shown free and why, the parts glued by a
    # stretch of their junction only (issue 34)
    return AssembledMesh(result.mesh.V, result.mesh.F, free=tuple(layers[i].id for i in result.free + result.left_out),
                         warnings=tuple(result.warnings), notes=tuple(result.notes))


DEPTH_QP = Assembler(
    "depth_qp",
    assemble_layers,
    check_params=_params,
    version=VERSION,
    description="Monster Mash assembly (thesis 4.7): front and back sheets, junctions cut and glued, "
                "depth order as a QP on per-vertex offsets, junctions blended and faired",
)


@hookimpl
def sketchforge_assemblers():
    return [DEPTH_QP]
