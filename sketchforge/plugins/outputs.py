"""Checks on what a plugin's solver returns, before the document sees it.

A solver is foreign code: its output is checked the way its contract is written, and a
violation is refused in one line naming the solver and its plugin, with the document left as
it was (the command raises before anything changes). The sculpt host checks a sculpt
solver's heights itself (:mod:`sketchforge_isophote_tool.pipeline`); here are the inflater's
and the assembler's.

An inflater's mesh is a layer's front surface, a height field over its outline:

- a :class:`~sketchforge.geometry.mesh.Mesh` (not a tuple of arrays), with triangles and an
  outline loop of at least 3 vertices;
- finite coordinates;
- heights z >= 0 everywhere and z = 0 exactly on every rim (the outline and each hole's
  loop: the assembly glues the back sheet there);
- every triangle counter-clockwise seen from +z (positive area in the drawing plane): a
  clockwise one folds the surface over itself, and its normals point into the model.
"""

from __future__ import annotations

import numpy as np

from sketchforge.errors import PluginError, quote
from sketchforge.geometry.mesh import Mesh


def _type_name(value) -> str:
    if isinstance(value, tuple):
        return f"a tuple of {len(value)}"
    return "None" if value is None else f"a {type(value).__name__}"


def front_mesh_problem(mesh) -> str | None:
    """Why ``mesh`` is not a valid front surface of a layer (a phrase that completes "the
    inflater 'x' returned ..."), None when it is."""
    if not isinstance(mesh, Mesh):
        return f"{_type_name(mesh)} instead of a Mesh (return Mesh(V, F, boundary, junction, holes))"
    if mesh.n_faces == 0 or len(mesh.boundary) < 3:
        return f"a mesh without a surface ({mesh.n_faces} triangles, an outline loop of {len(mesh.boundary)} vertices)"
    V = mesh.V
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        return f"a mesh with non-finite coordinates at {int(bad.sum())} of {len(V)} vertices"
    z = V[:, 2]
    below = z < 0.0
    if below.any():
        return (f"a mesh with heights below 0 at {int(below.sum())} of {len(V)} vertices (lowest {z.min():.3g}); "
                "heights must be >= 0")
    rim = mesh.rims
    lifted = z[rim] != 0.0
    if lifted.any():
        return (f"a mesh whose rim is not at height 0 ({int(lifted.sum())} of {len(rim)} rim vertices, up to "
                f"{np.abs(z[rim]).max():.3g}); the outline and every hole must stay at z = 0")
    a, b, c = V[mesh.F[:, 0], :2], V[mesh.F[:, 1], :2], V[mesh.F[:, 2], :2]
    area2 = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    clockwise = ~(area2 > 0.0)
    if clockwise.any():
        return (f"a mesh with {int(clockwise.sum())} of {mesh.n_faces} triangles clockwise or flat seen from +z; "
                "every triangle must be counter-clockwise")
    return None


def check_front_mesh(mesh, what: str = "the mesh") -> Mesh:
    """Check a layer's front surface (see the module docstring); returns it.

    Parameters
    ----------
    mesh : Mesh
        What an inflater returned.
    what : str
        Names the mesh's maker in the message ("the inflater 'x' (plugin 'p')").

    Raises
    ------
    PluginError
        One line: "WHAT returned a mesh with heights below 0 at 12 of 480 vertices ...".
    """
    problem = front_mesh_problem(mesh)
    if problem is not None:
        raise PluginError(f"{what} returned {problem}; nothing was changed")
    return mesh


def assembled_mesh_problem(mesh) -> str | None:
    """Why ``mesh`` is not a usable assembled model (None: it is): a Mesh with triangles and
    finite coordinates."""
    if not isinstance(mesh, Mesh):
        return f"{_type_name(mesh)} instead of a Mesh"
    if mesh.n_faces == 0:
        return "a mesh without triangles"
    bad = ~np.isfinite(mesh.V).all(axis=1)
    if bad.any():
        return f"a mesh with non-finite coordinates at {int(bad.sum())} of {len(mesh.V)} vertices"
    return None


def check_solver_output(kind: str, solver, plugin: str | None, result):
    """``result`` of the solver of ``kind`` ("inflate", "assemble"), checked; raises
    PluginError naming the solver and its plugin."""
    from sketchforge.solver_kinds import SOLVER_KINDS

    problem = front_mesh_problem(result) if kind == "inflate" else assembled_mesh_problem(result)
    if problem is not None:
        raise PluginError(f"the {SOLVER_KINDS[kind].what} {quote(solver.name)} (plugin {quote(plugin)}) returned "
                          f"{problem}; nothing was changed")
    return result
