"""Everything a plugin needs, from one module: ``from sketchforge.plugin_api import ...``.

The README's *Plugin guide* documents each contract with a complete brush example
(``examples/plugins/``). In short:

- **Hooks** (:data:`hookimpl`, the specifications in :mod:`sketchforge.plugins.hookspecs`):
  registry hooks return a *list*; every contribution is checked when the host starts
  (:mod:`sketchforge.plugins.contracts`) and a hook that raises disables its plugin, with a
  message naming it.
- **Commands** change a document, nothing else does. A command that edits one layer
  subclasses :class:`ReplaceLayerCommand` and implements ``compute(doc, old) -> Layer``
  (pure: build a new :class:`Layer` value with :meth:`Layer.evolve`; never mutate ``doc``);
  ``do``/``undo``/``prepare`` (the solve on the app's worker thread) come with it. Journal
  fields are read with :func:`parse_field`, :func:`parse_points`, :func:`parse_vector` (every
  field of a saved file is user-writable). If ``do`` raises anyway, the undo stack restores
  the document as it was and names the plugin.
- **Sculpt edits survive re-inflation**: an edit appends its journal dict to
  ``Layer.edits`` and implements the classmethod ``reapply(doc, layer, entry) -> Layer``;
  :func:`inflate_layer` / :func:`reapply_edits` call it when the outline or the inflation
  parameters change. A brush that leaves ``edits`` alone loses its edit on the next
  ``set_inflate_params``. It also implements ``transform_edit(entry, matrix, scale) -> dict``
  (positions through :func:`transform_points`), so that the edit follows its layer when the
  layer is moved, scaled or rotated; without it such a transform is refused
  (:class:`EditNotMovableError`).
- **Tools** (:class:`Tool`) turn press/move/release in document coordinates into commands
  and keep what to draw in ``overlay`` ((k, 2) polylines). Class attributes ``name``,
  ``label``, optional ``shortcut`` (``"Shift+B"``) and ``icon`` (an image path). In the app,
  ``doc.push`` inside a tool is collected and the command prepared on a worker thread.
- **Reflectance models** (:class:`ReflectanceModel`): ``R(n, l)`` in ``jax.numpy``, signed
  (negative in shadow); probed at registration.
- **Solvers** (:class:`Inflater`, :class:`SculptSolver`, :class:`Assembler`): named values in
  the registries ``sketchforge_inflaters``, ``sketchforge_sculpt_solvers``,
  ``sketchforge_assemblers``; each validates its own parameters with ``check_params``
  (:func:`validate_params`, :func:`number`, :func:`choice`, :func:`flag` do the usual work). A
  sculpt solver gets a :class:`SculptProblem` and returns a :class:`SculptSolution`.
- **Panels** (:class:`Panel`): widgets for the desktop app (``sketchforge_qt_panels``);
  ``create(app)`` imports Qt itself, so the plugin stays importable headless.
- **Exporters** (:class:`Exporter`): ``write(path, mesh)`` writes to the path it is given
  (the host's temp file: no atomic-write code needed); suffixes like ``".off"``.
- **Provenance**: saved documents record which plugin (and version) provided each command
  and the reflectance models edits used; opening one whose plugin is missing says so once.
"""

from __future__ import annotations

from sketchforge.document.commands import (
    Command,
    MacroCommand,
    ReplaceLayerCommand,
    inflate_layer,
    new_gesture_id,
    parse_field,
    parse_points,
    parse_vector,
    reapply_edits,
    transform_points,
)
from sketchforge.document.layer import Layer, Light
from sketchforge.errors import (
    ContourError,
    DocumentFormatError,
    EditNotMovableError,
    ExportError,
    NothingToDoError,
    ParameterError,
    PluginError,
    SculptError,
    SketchforgeError,
    SolverError,
    UnknownSolverError,
)
from sketchforge.geometry.mesh import AssembledMesh, Mesh
from sketchforge.geometry.reflectance_model import ReflectanceModel, Shader
from sketchforge.plugins.hookspecs import hookimpl
from sketchforge.plugins.registry import Exporter, Panel
from sketchforge.plugins.sculpt_problem import SculptProblem, SculptSolution
from sketchforge.plugins.solvers import (
    MAX_PARAMETER,
    Assembler,
    Inflater,
    SculptSolver,
    choice,
    flag,
    no_params,
    number,
    validate_params,
)
from sketchforge.tools.base import Tool

__all__ = [
    "MAX_PARAMETER",
    "AssembledMesh",
    "Assembler",
    "Command",
    "ContourError",
    "DocumentFormatError",
    "EditNotMovableError",
    "ExportError",
    "Exporter",
    "Inflater",
    "Layer",
    "Light",
    "MacroCommand",
    "Mesh",
    "NothingToDoError",
    "Panel",
    "ParameterError",
    "PluginError",
    "ReflectanceModel",
    "ReplaceLayerCommand",
    "SculptError",
    "SculptProblem",
    "SculptSolution",
    "SculptSolver",
    "Shader",
    "SketchforgeError",
    "SolverError",
    "UnknownSolverError",
    "Tool",
    "choice",
    "flag",
    "hookimpl",
    "inflate_layer",
    "new_gesture_id",
    "no_params",
    "number",
    "parse_field",
    "parse_points",
    "parse_vector",
    "reapply_edits",
    "transform_points",
    "validate_params",
]
