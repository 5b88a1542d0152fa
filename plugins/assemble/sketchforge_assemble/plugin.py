"""The assemble plugin's registration (entry point ``assemble``): the ``depth_qp`` assembler."""

from __future__ import annotations

from sketchforge.plugin_api import AssembledMesh, Assembler, choice, declare_params, hookimpl, number

from .assemble import DEFAULT_PARAMS, MAX_PARAMS, MIN_PARAMS, _params, assemble_detailed
from .cache import AssemblyCache

#: Shared by every assembly through the hook (the app's assembled view, ``replay``): a
#: re-assembly after one layer changed redoes only what depends on that layer.
CACHE = AssemblyCache()

#: Bumped when the same layers and parameters would assemble differently.
#: 2: issue 34 (sides, stretches, free parts, full thickness, thin parts refined); 3: finer parts
#: faired by edge length; 4: thin hosts faired over their glued face, a try that squashes a limb not kept;
#: 5: a limb's hold let go at the stitching's creases; 6: a limb the fairing thinned under 0.8 of
#: mid-limb faired again with its hold starting inside its host's outline (the neck try), and
#: every part's rim lifted to a fifth of its first ring's height (sheet.rim_lift)
VERSION = "6"


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
                         warnings=tuple(result.warnings), notes=tuple(result.notes), rim_pairs=result.rim_pairs,
                         rim_weights=result.rim_weights)


#: The parameters as the app's form shows them: the ranges and options ``_params`` checks
#: (with its own messages).
FORM = {
    # _params' own ranges, closed at both ends (a value at the minimum is accepted)
    "fillet": number("fillet", MIN_PARAMS["fillet"], MAX_PARAMS["fillet"]),
    "fair": number("fair", 0, 50, integer=True),
    "margin": number("margin", MIN_PARAMS["margin"], MAX_PARAMS["margin"]),
    "gap": number("gap", MIN_PARAMS["gap"], MAX_PARAMS["gap"]),
    "reg": number("reg", MIN_PARAMS["reg"], MAX_PARAMS["reg"]),
    "stiffness": number("stiffness", MIN_PARAMS["stiffness"], MAX_PARAMS["stiffness"]),
    "qp_solver": choice("qp_solver", ("osqp", "active_set")),
    "on_bad_junction": choice("on_bad_junction", ("free", "raise")),
}
HELP = {
    "fillet": "Width of the blended junction, in edge lengths of the part (0: a plain fold)",
    "fair": "Rings of edges smoothed around the ends of a blended junction",
    "margin": "Front/back separation of every part, in edge lengths (the rim is lifted further to round it)",
    "gap": "Clearance between overlapping layers, in edge lengths",
    "reg": "Pull of the parts towards the drawing plane (relative)",
    "stiffness": "How much stiffer a layer with parts glued to it is than the parts",
    "qp_solver": "osqp (a dual active set finishes a row left violated) or the active set alone",
    "on_bad_junction": "A junction that cannot be glued: leave that part free (named in the warnings), "
                       "or refuse the model",
}

DEPTH_QP = Assembler(
    "depth_qp",
    assemble_layers,
    check_params=declare_params(_params, DEFAULT_PARAMS, FORM, HELP, {"qp_solver": "QP solver"}),
    version=VERSION,
    description="Monster Mash assembly (thesis 4.7): front and back sheets, junctions cut and glued, "
                "depth order as a QP on per-vertex offsets, junctions blended and faired",
)


@hookimpl
def sketchforge_assemblers():
    return [DEPTH_QP]


@hookimpl
def sketchforge_dataset_generators():
    from .dataset import CREATURE

    return [CREATURE]
