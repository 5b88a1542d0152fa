"""Everything a plugin needs, from one module: ``from sketchforge.plugin_api import ...``.

A plugin imports sketchforge through this module only (and a Qt panel through
``sketchforge.qt.panel_api``); the built-in plugins under ``plugins/`` do too, and a test
enforces it, so they are the worked examples. The README's *Plugin guide* documents each
contract with a complete brush example (``examples/plugins/``), and its section *The public
API* lists every name below. In short:

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
  parameters change. :func:`inflated` gives the layer as inflated, before any edit (kept per
  document: a brush that bounds its change relative to the fresh layer pays no inflation). A
  brush that leaves ``edits`` alone loses its edit on the next
  ``set_inflate_params``. It also implements ``transform_edit(entry, matrix, scale) -> dict``
  (positions through :func:`transform_points`), so that the edit follows its layer when the
  layer is moved, scaled or rotated; without it such a transform is refused
  (:class:`EditNotMovableError`).
- **Tools** (:class:`Tool`) turn press/move/release in document coordinates into commands
  and keep what to draw in ``overlay`` ((k, 2) polylines). Class attributes ``name``,
  ``label``, optional ``shortcut`` (``"Shift+B"``) and ``icon`` (an image path). In the app,
  ``doc.push`` inside a tool is collected and the command prepared on a worker thread.
  :func:`layer_at` finds the layer under a press.
- **Reflectance models** (:class:`ReflectanceModel`): ``R(n, l)`` in ``jax.numpy``, signed
  (negative in shadow); probed at registration. The same definition shades the display
  (:func:`evaluate` on numpy arrays; the app and ``render --model`` offer every model).
- **Solvers** (:class:`Inflater`, :class:`SculptSolver`, :class:`Assembler`): named values in
  the registries ``sketchforge_inflaters``, ``sketchforge_sculpt_solvers``,
  ``sketchforge_assemblers``; each validates its own parameters with ``check_params``
  (:func:`validate_params`, :func:`number`, :func:`choice`, :func:`flag` do the usual work,
  and what they declare is the form the app shows). A sculpt solver gets a
  :class:`SculptProblem` and returns a :class:`SculptSolution`. The host checks what a
  solver returns (an inflater's mesh: :func:`check_front_mesh`).
- **Panels** (:class:`Panel`): widgets for the desktop app (``sketchforge_qt_panels``);
  ``create(app)`` imports Qt itself, so the plugin stays importable headless.
- **Exporters** (:class:`Exporter`): ``write(path, mesh)`` writes to the path it is given
  (the host's temp file: no atomic-write code needed); suffixes like ``".off"``.
- **Caches** (:class:`LRUCache`, keys of array values by :func:`array_key`): one thread-safe
  least-recently-used cache, bounded by entries and/or bytes, optionally keyed weakly by an
  object (derived data of a mesh goes with the mesh).
- **Dataset generators** (:class:`DatasetGenerator`): random shapes and edits for
  ``sketchforge dataset`` (``sketchforge_dataset_generators``).
- **Provenance**: saved documents record which plugin (and version) provided each command
  and the reflectance models edits used; opening one whose plugin is missing says so once.
- **Geometry**: the building blocks the built-in plugins are made of (outlines, meshing,
  Laplacians, fairing, isophotes, bands, point location, the guard in front of native code).
  They are loaded when first used (``jax`` only with the reflectance names), so importing
  this module stays cheap.
"""

from __future__ import annotations

import importlib

from sketchforge.cache import LRUCache, array_key
from sketchforge.document.commands import (
    Command,
    MacroCommand,
    ReplaceLayerCommand,
    inflate_layer,
    inflated,
    new_gesture_id,
    parse_field,
    parse_params,
    parse_points,
    parse_vector,
    reapply_edits,
    transform_points,
)
from sketchforge.document.document import Document
from sketchforge.document.layer import Layer, Light
from sketchforge.errors import (
    ContourError,
    DocumentFormatError,
    EditNotMovableError,
    ExportError,
    GeometryError,
    LimitError,
    NothingToDoError,
    ParameterError,
    PluginError,
    SculptError,
    SketchforgeError,
    SolverError,
    UnknownSolverError,
    quote,
    shorten,
)
from sketchforge.geometry.mesh import AssembledMesh, Mesh
from sketchforge.geometry.reflectance_model import ReflectanceModel, Shader
from sketchforge.plugins.hookspecs import hookimpl
from sketchforge.plugins.outputs import check_front_mesh
from sketchforge.plugins.param_forms import ParamField, declare_params, describe_params
from sketchforge.plugins.registry import DatasetGenerator, Exporter, Panel
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
from sketchforge.tools.queries import isophote_through, layer_at

#: Names loaded when first used: {name: (module, attribute)}. The geometry core's modules
#: import SciPy, Triangle, libigl, shapely or JAX; a plugin pays for what it uses.
_LAZY: dict[str, tuple[str, str | None]] = {
    # hosts and documents (tests, scripts, a plugin's own test support)
    "make_host": ("sketchforge.plugins.testing", "make_host"),
    "document_from_dict": ("sketchforge.document.fileformat", "document_from_dict"),
    "load_document": ("sketchforge.document.fileformat", "load"),
    # files
    "write_bytes_atomic": ("sketchforge.atomic", "write_bytes_atomic"),
    "write_obj": ("sketchforge.exporters", "write_obj"),
    "write_ply": ("sketchforge.exporters", "write_ply"),
    "write_stl": ("sketchforge.exporters", "write_stl"),
    "write_gltf": ("sketchforge.exporters", "write_gltf"),
    # the inflation's defaults (a layer's own parameters before any inflater checked them)
    "DEFAULT_INFLATE_PARAMS": ("sketchforge.geometry.inflate_params", "DEFAULT_INFLATE_PARAMS"),
    "check_inflate_params": ("sketchforge.geometry.inflate_params", "check_inflate_params"),
    # native code gets only validated input: guard.points, .finite, .tolerance, .pslg, .mesh,
    # .sparse_system, .qp, .objective, .constraints, .geometry, .polygon, .linestring
    "guard": ("sketchforge.geometry.guard", None),
    # outlines and strokes
    "MAX_COORDINATE": ("sketchforge.geometry.contour", "MAX_COORDINATE"),
    "format_point": ("sketchforge.geometry.contour", "format_point"),
    "signed_area": ("sketchforge.geometry.contour", "signed_area"),
    "validate_stroke": ("sketchforge.geometry.contour", "validate_stroke"),
    "prepare_outline": ("sketchforge.geometry.contour", "prepare_outline"),
    "resample_outline": ("sketchforge.geometry.contour", "resample_outline"),
    "prepare_holes": ("sketchforge.geometry.contour", "prepare_holes"),
    "clean_open_stroke": ("sketchforge.geometry.strokes", "clean_open_stroke"),
    "stroke_closes": ("sketchforge.geometry.parts", "stroke_closes"),
    "overlapped": ("sketchforge.geometry.parts", "overlapped"),
    # meshing and operators
    "MAX_VERTICES": ("sketchforge.geometry.triangulate", "MAX_VERTICES"),
    "MIN_ANGLE": ("sketchforge.geometry.triangulate", "MIN_ANGLE"),
    "check_vertex_budget": ("sketchforge.geometry.triangulate", "check_vertex_budget"),
    "triangulate_polygon": ("sketchforge.geometry.triangulate", "triangulate_polygon"),
    "laplacian_and_mass": ("sketchforge.geometry.laplacian", "laplacian_and_mass"),
    "inflate_heights": ("sketchforge.geometry.inflation", "inflate_heights"),
    "FairingSolver": ("sketchforge.geometry.fairing", "FairingSolver"),
    "squared_laplacian_matrix": ("sketchforge.geometry.fairing", "squared_laplacian_matrix"),
    "DirichletSolver": ("sketchforge.geometry.dirichlet", "DirichletSolver"),
    "gradient_operators": ("sketchforge.geometry.intensity", "gradient_operators"),
    "vertex_normals": ("sketchforge.geometry.normals", "vertex_normals"),
    "face_normals": ("sketchforge.geometry.normals", "face_normals"),
    "interior_edges": ("sketchforge.geometry.mesh_edges", "interior_edges"),
    "edge_angles": ("sketchforge.geometry.mesh_edges", "edge_angles"),
    "layer_normals": ("sketchforge.geometry.heightfield", "layer_normals"),
    "slopes_from_heights": ("sketchforge.geometry.heightfield", "slopes_from_heights"),
    "SlopeLinearisation": ("sketchforge.geometry.heightfield", "SlopeLinearisation"),
    "TriangleLocator": ("sketchforge.geometry.locate", "TriangleLocator"),
    # shading, isophotes and bands
    "LAMBERTIAN": ("sketchforge.geometry.reflectance", "LAMBERTIAN"),
    "evaluate": ("sketchforge.geometry.reflectance", "evaluate"),
    "evaluate_pq": ("sketchforge.geometry.reflectance", "evaluate_pq"),
    "isophotes": ("sketchforge.geometry.isophotes", "isophotes"),
    "isovalue_at": ("sketchforge.geometry.isophotes", "isovalue_at"),
    "select_isophote": ("sketchforge.geometry.isophotes", "select_isophote"),
    "band": ("sketchforge.geometry.band", "band"),
    "band_radius": ("sketchforge.geometry.band", "band_radius"),
    # how parts attach (the one rule the assembly and the app share)
    "FRONT": ("sketchforge.geometry.attachment", "FRONT"),
    "BACK": ("sketchforge.geometry.attachment", "BACK"),
    "find_host": ("sketchforge.geometry.attachment", "find_host"),
    "median_edge_length": ("sketchforge.geometry.attachment", "median_edge_length"),
    "plan_attachments": ("sketchforge.geometry.attachment", "plan_attachments"),
}


def __getattr__(name: str):
    try:
        module, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'sketchforge.plugin_api' has no attribute {name!r}") from None
    value = importlib.import_module(module)
    if attr is not None:
        value = getattr(value, attr)
    globals()[name] = value  # the next lookup is a plain one
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = sorted(
    [
        # hooks and the values registry hooks return
        "hookimpl",
        "Command",
        "MacroCommand",
        "ReplaceLayerCommand",
        "Tool",
        "ReflectanceModel",
        "Shader",
        "Exporter",
        "Panel",
        "DatasetGenerator",
        "Inflater",
        "SculptSolver",
        "Assembler",
        "SculptProblem",
        "SculptSolution",
        # document values and journal fields
        # caches of derived data
        "LRUCache",
        "array_key",
        "Document",
        "Layer",
        "Light",
        "Mesh",
        "AssembledMesh",
        "inflate_layer",
        "inflated",
        "reapply_edits",
        "new_gesture_id",
        "parse_field",
        "parse_params",
        "parse_points",
        "parse_vector",
        "transform_points",
        "layer_at",
        "isophote_through",
        # solver parameters and outputs
        "validate_params",
        "number",
        "MAX_PARAMETER",
        "choice",
        "flag",
        "no_params",
        "declare_params",
        "describe_params",
        "ParamField",
        "check_front_mesh",
        # errors and messages
        "SketchforgeError",
        "ContourError",
        "DocumentFormatError",
        "EditNotMovableError",
        "ExportError",
        "GeometryError",
        "LimitError",
        "NothingToDoError",
        "ParameterError",
        "PluginError",
        "SculptError",
        "SolverError",
        "UnknownSolverError",
        "quote",
        "shorten",
        *_LAZY,
    ]
)
