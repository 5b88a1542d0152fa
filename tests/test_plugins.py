"""The plugin host: third-party plugins register and are used; every hook is documented."""

import inspect
import subprocess
import sys

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.plugins import hookspecs
from sketchforge.plugins.hookspecs import hookimpl
from sketchforge.plugins.registry import Exporter, ReflectanceModel
from sketchforge.plugins.testing import FanInflater, make_test_host


class ThirdParty:
    """An outside plugin: a CSV point exporter and a 'half-Lambert' reflectance model."""

    written = []

    @hookimpl
    def sketchforge_exporters(self):
        def write(path, mesh):
            np.savetxt(path, mesh.V, delimiter=",")
            ThirdParty.written.append(path)

        return [Exporter("xyz", (".xyz",), write, "points as CSV")]

    @hookimpl
    def sketchforge_reflectance_models(self):
        import jax.numpy as jnp

        return [ReflectanceModel("half_lambert", lambda n, l: 0.5 * jnp.dot(n, l) + 0.5)]


def test_third_party_exporter_is_used_by_suffix(tmp_path):
    host = make_test_host(FanInflater(), ThirdParty())
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": [[0, 0], [1, 0], [0, 1]]})
    out = tmp_path / "pts.xyz"
    host.exporter_for(out).write(out, doc.layer("a").mesh)
    assert np.loadtxt(out, delimiter=",").shape == (4, 3)
    assert set(host.exporters) >= {"obj", "ply", "stl", "gltf", "xyz"}


def test_third_party_reflectance_model_is_registered_and_differentiable():
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    host = make_test_host(ThirdParty())
    model = host.reflectance_models["half_lambert"]
    n = jnp.array([0.0, 0.6, 0.8])
    l = jnp.array([1.0, 0.0, 0.0])
    g = jax.grad(model.R)(n, l)
    assert np.allclose(np.asarray(g), [0.5, 0.0, 0.0])


def test_duplicate_names_are_refused():
    class Clash:
        @hookimpl
        def sketchforge_exporters(self):
            return [Exporter("obj", (".obj",), lambda p, m: None)]

    host = make_test_host(Clash())
    # The clash is refused, named with both plugins, and the first registration (the core's)
    # stays in use.
    assert host.exporters["obj"].write is not None and host.provider_of(host.exporters["obj"]) == "sketchforge-core"
    assert any("'sketchforge-core'" in p and "'plugin-0-Clash'" in p and "'obj'" in p for p in host.problems)


def test_unknown_export_suffix_is_a_clear_error():
    from sketchforge.errors import ExportError

    host = make_test_host()
    with pytest.raises(ExportError, match="known formats are .glb, .gltf, .obj, .ply, .stl"):
        host.exporter_for("model.fbx")


def test_builtin_plugins_load_through_entry_points():
    host = make_test_host(entry_points=True)
    names = host.plugin_names()
    assert names[0] == "sketchforge-core"
    assert {"inflate", "isophote_tool", "assemble"} <= set(names)


def test_allowlist_limits_entry_points(monkeypatch):
    host = make_test_host(entry_points=True, allowlist=["inflate"])
    assert "inflate" in host.plugin_names() and "assemble" not in host.plugin_names()
    monkeypatch.setenv("SKETCHFORGE_PLUGINS", "")
    host = make_test_host(entry_points=True)
    assert host.plugin_names() == ["sketchforge-core"]


def test_every_hook_is_documented_with_arguments():
    specs = [f for name, f in inspect.getmembers(hookspecs, inspect.isfunction) if name.startswith("sketchforge_")]
    assert len(specs) == 12  # the registries, the pose hook, the panels, the plugin data validators, the dataset generators
    for f in specs:
        doc = inspect.getdoc(f) or ""
        assert len(doc) > 80, f.__name__
        for arg in inspect.signature(f).parameters:
            assert arg in doc, f"{f.__name__} does not document {arg}"
        assert "Return" in doc or "return" in doc, f.__name__


def test_core_imports_without_qt():
    """The numerical core, document, tools and plugin packages never import Qt."""
    code = (
        "import sys\n"
        "import sketchforge.document, sketchforge.document.fileformat, sketchforge.plugins.manager\n"
        "import sketchforge.tools, sketchforge.geometry, sketchforge.cli\n"
        "import pkgutil, importlib, sketchforge.geometry as g\n"
        "for m in pkgutil.iter_modules(g.__path__): importlib.import_module('sketchforge.geometry.' + m.name)\n"
        "import sketchforge_inflate, sketchforge_isophote_tool, sketchforge_assemble, sketchforge_animate\n"
        "import sketchforge_inflate.plugin, sketchforge_isophote_tool.plugin, sketchforge_assemble.plugin\n"
        "import sketchforge_animate.plugin\n"
        "from sketchforge.plugins.manager import default_host\n"
        "h = default_host(); h.commands; h.tools; h.exporters; h.shaders; h.reflectance_models\n"
        # the panels are listed headless: only the app's call to create imports Qt
        "assert {'animation', 'isophote_sculpt'} <= set(h.qt_panels), sorted(h.qt_panels)\n"
        "bad = [m for m in sys.modules if m.startswith(('PySide6', 'pyqtgraph', 'sketchforge.qt', 'shiboken6'))]\n"
        "assert not bad, bad\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr[-2000:]


def test_geometry_core_does_not_import_the_document_or_front_ends():
    """The geometry core is array-in, array-out: it knows neither documents nor Qt."""
    import ast
    from pathlib import Path

    import sketchforge.geometry as g

    offenders = []
    for path in sorted(Path(g.__path__[0]).glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else (
                [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            offenders += [f"{path.name}: {n}" for n in names
                          if n.startswith(("sketchforge.document", "sketchforge.qt", "sketchforge.tools", "PySide6"))]
    assert offenders == []


def test_the_qt_front_end_knows_no_built_in_plugin():
    """Panels, tools and exporters come through hooks: sketchforge/qt imports no plugin package
    and names none of their commands or tools (issue 29: the core stops knowing the built-ins)."""
    import ast
    from pathlib import Path

    import sketchforge

    root = Path(sketchforge.__file__).parent / "qt"
    plugin_packages = ("sketchforge_inflate", "sketchforge_isophote_tool", "sketchforge_assemble", "sketchforge_animate")
    names = ("add_pin", "sculpt_isophote", "gauss_newton", "record_motion")
    offenders = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                offenders += [f"{path.name}: import {a.name}" for a in node.names if a.name.startswith(plugin_packages)]
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith(plugin_packages):
                offenders.append(f"{path.name}: from {node.module}")
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                offenders += [f"{path.name}: {n!r}" for n in names if n in node.value]
    assert offenders == []
