"""Checks a plugin's contributions must pass before the host registers them.

Each ``check_*(item, plugin)`` raises :class:`~sketchforge.errors.PluginError` with a one-line
message that names the plugin and says what to fix; the host reports it and leaves the item
out (the plugin's other contributions stay). They run once, when a registry is first built.
"""

from __future__ import annotations

import re

import numpy as np

from sketchforge.errors import PluginError

#: A file suffix as exporters declare it: a dot, then letters/digits (".obj", ".glb").
SUFFIX_RE = re.compile(r"^\.[a-z0-9][a-z0-9_-]*$")

#: Slopes in the shadow of the probe lights, (p, q) = k (l_x, l_y): n·l = -k / sqrt(1 + k²).
_SHADOW_K = (0.5, 1.0, 3.0)
_PROBE_LIGHTS = ((1.0, 0.0, 0.0), (0.6, 0.8, 0.0), (-0.28, 0.96, 0.0))


def _fail(plugin: str, text: str) -> None:
    raise PluginError(f"plugin {plugin!r}: {text}")


def check_command(cls, plugin: str) -> None:
    from sketchforge.document.commands import Command

    if not (isinstance(cls, type) and issubclass(cls, Command)):
        _fail(plugin, f"sketchforge_commands must return Command subclasses, got {cls!r} (ignored)")
    for method in ("do", "undo", "to_dict"):
        if getattr(cls, method) is getattr(Command, method):
            _fail(plugin, f"command {cls.name!r} does not implement {method}() (ignored)")
    if cls.from_dict.__func__ is Command.from_dict.__func__:
        _fail(plugin, f"command {cls.name!r} does not implement from_dict() (ignored)")


def check_tool(cls, plugin: str) -> None:
    from sketchforge.tools.base import Tool

    if not (isinstance(cls, type) and issubclass(cls, Tool)):
        _fail(plugin, f"sketchforge_tools must return Tool subclasses, got {cls!r} (ignored)")
    if not isinstance(getattr(cls, "label", ""), str):
        _fail(plugin, f"tool {cls.name!r}: label must be a string (ignored)")
    shortcut = getattr(cls, "shortcut", "")
    if shortcut is not None and not isinstance(shortcut, str):
        _fail(plugin, f"tool {cls.name!r}: shortcut must be a key sequence string such as 'Shift+B' (ignored)")


def check_shader(shader, plugin: str) -> None:
    from sketchforge.geometry.reflectance_model import Shader

    if not isinstance(shader, Shader) or not callable(shader.shade):
        _fail(plugin, f"sketchforge_shaders must return Shader values with a callable shade, got {shader!r} (ignored)")
    N = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [-0.6, 0.0, 0.8], [0.0, 1.0, 0.0]])
    try:
        C = np.asarray(shader.shade(N, np.array([1.0, 0.0, 0.0])), dtype=np.float64)
    except Exception as exc:  # noqa: BLE001 - foreign code
        _fail(plugin, f"shader {shader.name!r} raised {type(exc).__name__}: {exc} on 4 test normals (ignored)")
    if C.shape != (4, 3) or not np.all(np.isfinite(C)) or C.min() < -1e-9 or C.max() > 1 + 1e-9:
        _fail(plugin, f"shader {shader.name!r} must map (n,3) normals to (n,3) colours in [0, 1], got shape {C.shape} (ignored)")


def check_exporter(exp, plugin: str) -> None:
    from sketchforge.plugins.registry import Exporter

    if not isinstance(exp, Exporter):
        _fail(plugin, f"sketchforge_exporters must return Exporter values, got {exp!r} (ignored)")
    if isinstance(exp.suffixes, str) or not isinstance(exp.suffixes, (tuple, list)) or not exp.suffixes:
        _fail(plugin, f"exporter {exp.name!r}: suffixes must be a non-empty tuple such as ('.off',), got {exp.suffixes!r} (ignored)")
    for s in exp.suffixes:
        if not isinstance(s, str) or not SUFFIX_RE.match(s):
            _fail(plugin, f"exporter {exp.name!r}: suffix {s!r} must be lower case and start with a dot, like '.off' (ignored)")
    if not callable(exp.write):
        _fail(plugin, f"exporter {exp.name!r}: write must be callable as write(path, mesh) (ignored)")
    if (exp.write_document is None) != (exp.handles is None):
        _fail(plugin, f"exporter {exp.name!r}: a document exporter sets both write_document and handles (ignored)")


def check_reflectance_model(model, plugin: str) -> None:
    """Probe ``R`` where the height solve will use it: at slopes in the shadow of three
    lights in the drawing plane it must be finite and have a finite, non-zero slope gradient
    from ``jax.grad`` (so it is written with ``jax.numpy``, and not clamped: a ``max(n·l, 0)``
    is flat there). Negative values in shadow are the documented convention but not
    enforced: a model that is a monotone function of n·l (a squared half-Lambert) has the
    same isophotes as Lambert and sculpts correctly in its own units. The core's Lambertian
    model is trusted (it is the reference)."""
    from sketchforge.geometry.reflectance_model import ReflectanceModel

    if not isinstance(model, ReflectanceModel) or not callable(model.R):
        _fail(plugin, f"sketchforge_reflectance_models must return ReflectanceModel values, got {model!r} (ignored)")
    if plugin == "sketchforge-core":
        return
    from sketchforge.geometry.reflectance import reflectance_pq_grad

    f = reflectance_pq_grad(model)
    for light in _PROBE_LIGHTS:
        l = np.array(light)
        for k in _SHADOW_K:
            p, q = k * l[0], k * l[1]
            try:
                r, rp, rq = (float(v) for v in f(p, q, l))
            except Exception as exc:  # noqa: BLE001 - foreign code, any JAX error
                _fail(
                    plugin,
                    f"reflectance model {model.name!r} cannot be differentiated by JAX "
                    f"(write R(n, l) with jax.numpy, not numpy): {type(exc).__name__} (ignored)",
                )
            if not all(np.isfinite(v) for v in (r, rp, rq)):
                _fail(
                    plugin,
                    f"reflectance model {model.name!r} gives a non-finite value or gradient at n·l = {-k / np.hypot(1, k):.2f} (ignored)",
                )
            if abs(rp) + abs(rq) < 1e-12:
                _fail(
                    plugin,
                    f"reflectance model {model.name!r} must be signed, not clamped: it is flat in shadow "
                    f"(R = {r:.3g}, |∇R| = {abs(rp) + abs(rq):.3g} at n·l = {-k / np.hypot(1, k):.2f}), so the "
                    "height solve cannot move its isophotes there; do not use max(·, 0) (ignored)",
                )


#: A parameter no solver takes: ``check_params`` must refuse it (unknown keys are never
#: silently dropped).
PROBE_KEY = "__sketchforge_probe__"


def solver_check(kind: str):
    """The registration check for a solver of ``kind``: the right value type, a callable
    function and ``check_params``, a string version, defaults that are JSON, and an unknown
    parameter refused."""
    from sketchforge.errors import SketchforgeError
    from sketchforge.plugins.solvers import SOLVER_KINDS, SOLVER_TYPES, json_value

    spec, cls = SOLVER_KINDS[kind], SOLVER_TYPES[kind]

    def check(item, plugin: str) -> None:
        if not isinstance(item, cls):
            _fail(plugin, f"{spec.hook} must return {cls.__name__} values, got {type(item).__name__} (ignored)")
        if not callable(getattr(item, spec.call, None)):
            _fail(plugin, f"{spec.what} {item.name!r}: {spec.call} must be callable (ignored)")
        if not callable(item.check_params):
            _fail(plugin, f"{spec.what} {item.name!r}: check_params must be callable as check_params(params) -> dict (ignored)")
        if not isinstance(item.version, str) or not item.version:
            _fail(plugin, f"{spec.what} {item.name!r}: version must be a non-empty string (ignored)")
        if not isinstance(getattr(item, "several_isophotes", False), bool):
            _fail(plugin, f"{spec.what} {item.name!r}: several_isophotes must be True or False (ignored)")
        try:
            defaults = item.check_params({})
        except Exception as exc:  # noqa: BLE001 - foreign code
            _fail(plugin, f"{spec.what} {item.name!r}: check_params({{}}) raised {type(exc).__name__}: {exc}; it must "
                          "return the default parameters (ignored)")
        if not isinstance(defaults, dict) or not json_value(defaults):
            _fail(plugin, f"{spec.what} {item.name!r}: check_params({{}}) must return a dict of JSON values (the "
                          f"defaults), got {type(defaults).__name__} (ignored)")
        try:
            item.check_params({PROBE_KEY: 1})
        except SketchforgeError:
            pass
        except Exception as exc:  # noqa: BLE001 - foreign code
            _fail(plugin, f"{spec.what} {item.name!r}: check_params raised {type(exc).__name__} for an unknown parameter; "
                          "it must raise ParameterError (ignored)")
        else:
            _fail(plugin, f"{spec.what} {item.name!r} accepted the unknown parameter {PROBE_KEY!r}: check_params must "
                          "refuse unknown keys with a ParameterError, never drop them (ignored)")

    return check


def check_panel(panel, plugin: str) -> None:
    from sketchforge.plugins.registry import PANEL_PLACES, Panel

    if not isinstance(panel, Panel):
        _fail(plugin, f"sketchforge_qt_panels must return Panel values, got {type(panel).__name__} (ignored)")
    if panel.place not in PANEL_PLACES:
        _fail(plugin, f"panel {panel.name!r}: place must be one of {', '.join(PANEL_PLACES)}, got {panel.place!r} (ignored)")
    if not callable(panel.create):
        _fail(plugin, f"panel {panel.name!r}: create must be callable as create(app) -> QWidget (ignored)")
    if panel.available is not None and not callable(panel.available):
        _fail(plugin, f"panel {panel.name!r}: available must be callable as available(host) -> bool (ignored)")


def check_dataset_generator(gen, plugin: str) -> None:
    from sketchforge.plugins.registry import DATASET_KINDS, DatasetGenerator

    if not isinstance(gen, DatasetGenerator):
        _fail(plugin, f"sketchforge_dataset_generators must return DatasetGenerator values, got {type(gen).__name__} (ignored)")
    if gen.kind not in DATASET_KINDS:
        _fail(plugin, f"dataset generator {gen.name!r}: kind must be one of {', '.join(DATASET_KINDS)}, got {gen.kind!r} (ignored)")
    if not callable(gen.make):
        _fail(plugin, f"dataset generator {gen.name!r}: make must be callable (ignored)")

