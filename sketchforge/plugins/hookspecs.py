"""Hook specifications: the reference for plugin authors.

A plugin is any object or module with functions decorated by ``@hookimpl`` whose names match
the specifications below. Installed plugins register through the entry-point group
``sketchforge`` (see ``plugins/inflate/pyproject.toml`` for a worked example); the
built-in plugins are loaded through exactly that path.

Hooks are grouped by phase:

Solvers (``firstresult``: pluggy calls implementations last-registered first and stops at the
first result that is not ``None``; plugins are registered in a fixed order, built-ins first,
then entry points sorted by name, so the choice never depends on installation order):

- :func:`sketchforge_inflate`
- :func:`sketchforge_assemble`
- :func:`sketchforge_pose`

Registries (every implementation is called, results are collected; names must be unique):

- :func:`sketchforge_tools`, :func:`sketchforge_reflectance_models`,
  :func:`sketchforge_shaders`, :func:`sketchforge_commands`, :func:`sketchforge_exporters`

Document data (returns a dict, collected when a document is opened):

- :func:`sketchforge_plugin_data_validators`

Each registry hook must return a list. The host calls them plugin by plugin: one that raises
disables its plugin; each contribution is checked (:mod:`sketchforge.plugins.contracts`) and
refused with a message naming the plugin if it breaks its contract (``host.problems``).
Public types for plugin code: :mod:`sketchforge.plugin_api`.
"""

from __future__ import annotations

import pluggy

hookspec = pluggy.HookspecMarker("sketchforge")
hookimpl = pluggy.HookimplMarker("sketchforge")


# --- solvers ---------------------------------------------------------------------------------


@hookspec(firstresult=True)
def sketchforge_inflate(points, closed, params, holes):
    """Turn a drawn stroke into a layer's front surface.

    Called by the ``set_contour`` and ``set_inflate_params`` commands (and on replay).

    Parameters
    ----------
    points : (n, 2) float64
        The stroke as drawn, in drawing units (x right, y up), either orientation.
    closed : bool
        True: the whole outline is free. False: if the ends are far apart, the closing segment
        is the junction Γ_conn where the part attaches to the layer below.
    params : dict
        ``resolution`` (target edge length, drawing units), ``inflation`` (height scale),
        ``smoothing`` (fairing weight α in [0, 1), 0 = none). Unknown keys are ignored.
    holes : list of (k_i, 2) float64
        Inner rings to cut out of the part (empty: none), either orientation; the surface
        keeps z = 0 on each and the returned mesh lists their loops in ``holes``. An
        implementation without this argument cannot make holes: the host refuses a layer
        with holes rather than silently fill them.

    Returns
    -------
    sketchforge.geometry.Mesh
        V (n,3) float64 with z >= 0 and z = 0 on the boundary, F (m,3) int64
        counter-clockwise seen from +z, ``boundary`` loop, ``junction`` vertices and ``holes``
        loops.

    Raises
    ------
    sketchforge.errors.ContourError
        For a stroke that cannot be inflated; the message says what is wrong.
    """


@hookspec(firstresult=True)
def sketchforge_assemble(layers, params):
    """Assemble layers into one closed, oriented 2-manifold mesh (Monster Mash style).

    Called when the assembled model is needed (observation mode, export) after a layer changed.

    Parameters
    ----------
    layers : list of sketchforge.document.Layer
        The visible layers that have a mesh, back to front (later = in front). Read-only:
        use ``layer.id``, ``layer.mesh`` (its ``junction`` marks Γ_conn) and ``layer.closed``.
    params : dict
        Assembly options (plugin specific; empty by default).

    Returns
    -------
    sketchforge.geometry.Mesh
        One mesh, outward-oriented triangles; ``boundary`` and ``junction`` empty.
    """


@hookspec(firstresult=True)
def sketchforge_pose(doc, frame):
    """The document's assembled model posed at animation frame ``frame`` (animation plugins).

    Called by ``sketchforge replay DOC --frame N --export OUT``.

    Parameters
    ----------
    doc : sketchforge.document.Document
        Read-only.
    frame : int
        Frame number >= 0 (24 frames per second; frames past the loop wrap around it).

    Returns
    -------
    sketchforge.geometry.Mesh
        The posed model, with the static model's triangles (same connectivity).
    """


# --- registries ------------------------------------------------------------------------------


@hookspec
def sketchforge_tools():
    """Return a list of tool classes (``sketchforge.tools.Tool`` subclasses).

    A tool turns press/move/release gestures in document coordinates into commands. Called
    once when the host starts; a tool's ``name`` must be unique. ``label``, optional
    ``shortcut`` (``"Shift+B"``) and ``icon`` (an image path) show in the app's tool palette;
    the commands it pushes are prepared on a worker thread there (README, Plugin guide).
    """


@hookspec
def sketchforge_reflectance_models():
    """Return a list of solver-side reflectance models
    (``sketchforge.plugin_api.ReflectanceModel``).

    A model wraps ``R(n, l) -> float`` written with ``jax.numpy`` (n, l: (3,) unit vectors,
    float64), signed (negative in shadow, never clamped) so that R_p, R_q from automatic
    differentiation exist everywhere. Lambertian (``n·l``) is built in. Probed at
    registration: a model ``jax.grad`` cannot trace, or one that is flat in shadow (zero
    gradient: clamped), is refused.
    """


@hookspec
def sketchforge_shaders():
    """Return a list of display shaders (``sketchforge.plugins.registry.Shader``).

    A shader maps per-vertex normals (n,3) and the light (3,) to colours (n,3) in [0, 1]. It is
    for display only; it may be flat or stepped (cel) since no solver differentiates it.
    """


@hookspec
def sketchforge_commands():
    """Return a list of command classes (``sketchforge.document.commands.Command`` subclasses).

    Each class has a unique ``name`` (the journal's ``"command"`` field) and round-trips through
    ``to_dict`` / ``from_dict``, so a plugin's edits are saved and replayed by name.
    """


@hookspec
def sketchforge_exporters():
    """Return a list of exporters (``sketchforge.plugins.registry.Exporter``).

    An exporter has a ``name``, the file ``suffixes`` it writes (lower case with a dot:
    ``".obj"``) and ``write(path, mesh)``. OBJ, PLY, STL and glTF (``.glb``/``.gltf``) are
    built in. An exporter of a whole document (an animated glTF) also sets ``write_document``
    and ``handles`` (see :class:`sketchforge.plugins.registry.Exporter`). The host
    (``host.export``) passes a path in a private temp folder and moves the finished file into
    place atomically; errors become one line naming the plugin.
    """


# --- document data ----------------------------------------------------------------------------


@hookspec
def sketchforge_plugin_data_validators():
    """Return ``{key: validate}`` for the document-level data this plugin keeps
    (``doc.plugin_data(key)``, saved in ``snapshot.plugin_data``).

    ``validate(value)`` is called with the stored JSON value when a document is opened, before
    the document is built; it returns nothing for a value the plugin's own commands could have
    made, and raises a :class:`~sketchforge.errors.SketchforgeError` with a one-line sentence
    otherwise (use the same limits as the commands). The host then refuses the file with a
    ``DocumentFormatError`` naming the key; nothing is loaded and the file is not changed.
    A key no installed plugin validates is loaded as it is (see
    :mod:`sketchforge.plugins.plugin_data`).
    """
