"""Hook specifications: the reference for plugin authors.

A plugin is any object or module with functions decorated by ``@hookimpl`` whose names match
the specifications below. Installed plugins register through the entry-point group
``sketchforge`` (see ``plugins/inflate/pyproject.toml`` for a worked example); the
built-in plugins are loaded through exactly that path.

Hooks are grouped by phase:

Solvers are named registries, like every other contribution: a plugin returns a list of
named solver values and a document names the one it uses, so the choice never depends on
installation or registration order:

- :func:`sketchforge_inflaters` (contour -> a layer's front mesh; built-in ``"poisson"``)
- :func:`sketchforge_sculpt_solvers` (wanted shading -> heights; built-in ``"gauss_newton"``,
  and the thesis' ``"strips"``)
- :func:`sketchforge_assemblers` (layers -> one closed mesh; built-in ``"depth_qp"``)

Registries (every implementation is called, results are collected):

- :func:`sketchforge_tools`, :func:`sketchforge_reflectance_models`,
  :func:`sketchforge_shaders`, :func:`sketchforge_commands`, :func:`sketchforge_exporters`,
  the three solver registries above, :func:`sketchforge_qt_panels` (the app's panels) and
  :func:`sketchforge_dataset_generators` (random shapes and edits for ``sketchforge dataset``)

One override rule for every kind: a name belongs to one plugin. A plugin that registers a name
the core already has is refused; two plugins registering the same name is an error naming
both, and the name is left unusable until one of them is uninstalled (never "the last one
registered wins"). The one remaining ``firstresult`` hook, :func:`sketchforge_pose`, follows
the same rule: a second implementation is an error naming both.

pluggy wrappers (``hookwrapper=True`` or ``wrapper=True``) are refused with a message: the host
calls each plugin's hook on its own (so that a failing plugin is named and disabled alone),
so a wrapper would never run.

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


@hookspec
def sketchforge_inflaters():
    """Return a list of inflaters (:class:`sketchforge.plugin_api.Inflater`).

    An inflater turns a drawn stroke into a layer's front surface. Called when the host
    starts; the ``set_contour``, ``set_inflate_params``, ``mirror_layer`` commands (and
    replay) call ``inflate(points, closed, params, holes)`` of the layer's inflater:

    points : (n, 2) float64
        The stroke as drawn, in drawing units (x right, y up), either orientation.
    closed : bool
        True: the whole outline is free. False: if the ends are far apart, the closing segment
        is the junction Γ_conn where the part attaches to the layer below.
    params : dict
        What ``check_params`` returned for the layer's parameters (defaults filled in).
    holes : list of (k_i, 2) float64
        Inner rings to cut out of the part (empty: none); the surface keeps z = 0 on each and
        the mesh lists their loops in ``holes``. An inflater with ``holes=False`` is never
        given any (the host refuses a layer with holes rather than fill them).

    Returns a ``Mesh``: V (n,3) float64 with z >= 0 and z = 0 on the boundary, F (m,3) int64
    counter-clockwise seen from +z, ``boundary`` loop, ``junction`` vertices and ``holes``
    loops. Raises ``ContourError`` for a stroke that cannot be inflated. The built-in
    ``"poisson"`` (plugin ``inflate``) solves -L u = 4M, z = sqrt(u), then fairs (thesis 4.2).
    """


@hookspec
def sketchforge_sculpt_solvers():
    """Return a list of sculpt solvers (:class:`sketchforge.plugin_api.SculptSolver`).

    A sculpt solver turns the shading a redrawn isophote asks for into heights: the
    ``sculpt_isophote`` command calls ``solve(problem, params)`` of the solver its entry names
    (``"solver"``, default ``"gauss_newton"``) with a
    :class:`sketchforge.plugin_api.SculptProblem` (the layer's mesh and shading, the isovalue,
    the band, the cleaned stroke, and the host's shading services) and the dict
    ``check_params`` returned for the entry's ``"params"``. It returns a
    :class:`sketchforge.plugin_api.SculptSolution` (or the height change δz (n,) float64
    alone). Raise ``SculptError`` (one line, what to draw instead) for an edit it cannot make.
    The host keeps the rim at 0 and heights >= 0, refuses non-finite heights and keeps the
    edit only if the isophote ends no farther from the stroke than it was.

    ``problem.light`` is the document's light, anywhere on the hemisphere facing the viewer
    (z >= 0; the thesis has it in the drawing plane): a solver that cannot take a tilted light
    raises a ``SculptError`` that says so in one line rather than return a wrong surface.

    Several isophotes in one edit (the ``sculpt_isophotes`` command) go only to a solver that
    sets ``several_isophotes=True``: its ``problem.parts`` then holds one problem per isophote
    and ``problem.sample_values`` the shading each stroke sample asks for; the host checks
    each stroke as it checks a single one. For any other solver the host refuses such an edit
    in one line naming it ("the sculpt solver 'x' redraws one isophote per edit: ...").
    """


@hookspec
def sketchforge_assemblers():
    """Return a list of assemblers (:class:`sketchforge.plugin_api.Assembler`).

    An assembler builds one closed, oriented 2-manifold mesh from the layers (Monster Mash
    style). Called when the assembled model is needed (observation mode, export) after a
    layer changed: ``assemble(layers, params)`` of the document's assembler
    (``set_assembly``; default ``"depth_qp"``), with ``layers`` the visible layers that have a
    mesh, back to front (read-only ``Layer`` values: ``id``, ``mesh`` whose ``junction`` marks
    Γ_conn, ``closed``), and the dict ``check_params`` returned. Returns one ``Mesh``,
    outward-oriented triangles, ``boundary`` and ``junction`` empty; or an ``AssembledMesh``
    (a ``Mesh`` that also says which layers it could not glue, ``free``, with one sentence
    each in ``warnings``, and ``notes`` on parts glued by a stretch of their junction), which
    the app shows over the model; its ``rim_pairs`` name a part's front and back rim vertices,
    which stand for one round rim and whose normals the display and the exporters share by
    ``rim_weights``. One part that cannot be glued should never refuse the
    whole model (issue 34): assemble it free and say so.
    """


@hookspec(firstresult=True)
def sketchforge_pose(doc, frame):
    """The document's assembled model posed at animation frame ``frame`` (animation plugins).

    Called by ``sketchforge replay DOC --frame N --export OUT``. At most one plugin may
    implement it: a second one is an error naming both (the host calls neither).

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


@hookspec
def sketchforge_qt_panels():
    """Return a list of panels for the desktop app (:class:`sketchforge.plugin_api.Panel`).

    The app builds each panel's widget with ``create(app)`` once, when its window is made,
    and shows it in the controls of its ``place`` ("creation", "sculpture", "observation");
    ``app`` is a :class:`sketchforge.qt.panel_api.AppContext`. Only the app calls ``create``,
    so a plugin imports Qt inside it and stays usable headless. Panels of one place are shown
    in ``order``; ``available(host)`` false leaves one out; a ``create`` that raises (or returns
    no QWidget) is named with its plugin in the status bar and the log and left out, and the
    app starts without it. The animation panel (plugin ``animate``) and the isophote tool's
    SCULPTURE controls (plugin ``isophote_tool``) come through this hook.
    """


@hookspec
def sketchforge_dataset_generators():
    """Return a list of dataset generators (:class:`sketchforge.plugin_api.DatasetGenerator`).

    ``sketchforge dataset`` draws each sample's shape from the ``"shape"`` generators and its
    sculpt edits from the ``"edit"`` generators (both sorted by name; the core knows no shape
    of its own). A shape generator's ``make(rng)`` returns the journal entries that build the
    sample's layers (any installed commands); an edit generator's ``make(doc, layer, model,
    rng)`` returns one journal entry that edits the layer ``layer`` (an id) of ``doc`` under
    its light and the reflectance model named ``model``, or None when it found nothing to
    edit there. ``rng`` is a ``numpy.random.Generator`` seeded by the sample alone: draw every
    random choice from it, so a sample is the same on any worker. Raise a SketchforgeError for
    a draw that cannot be built (the sample draws again). Built in: ``creature`` (plugin
    ``assemble``), ``holes`` and ``isophote`` (plugin ``isophote_tool``).
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
