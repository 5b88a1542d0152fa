"""The assemble plugin's hook implementation (registered by the entry point ``assemble``)."""

from __future__ import annotations

from sketchforge.plugins.hookspecs import hookimpl

from .assemble import assemble_detailed
from .cache import AssemblyCache

#: Shared by every assembly through the hook (the app's assembled view, ``replay``): a
#: re-assembly after one layer changed redoes only what depends on that layer.
CACHE = AssemblyCache()


@hookimpl
def sketchforge_assemble(layers, params):
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
    return result.mesh
