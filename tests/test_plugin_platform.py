"""The plugin platform: isolation of broken plugins, all-or-nothing commands, contracts checked
at registration (messages name the plugin), host-side atomic export."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document.commands import Command, ReplaceLayerCommand
from sketchforge.errors import ExportError, PluginError, SketchforgeError
from sketchforge.plugins.hookspecs import hookimpl
from sketchforge.plugins.registry import Exporter, ReflectanceModel, Shader
from sketchforge.plugins.solvers import Inflater
from sketchforge.plugins.testing import FanInflater, make_test_host

TRIANGLE = [[0, 0], [1, 0], [0, 1]]


def fan_doc(*plugins):
    doc = Document(host=make_test_host(FanInflater(), *plugins))
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": TRIANGLE})
    return doc


def test_geometry_core_does_not_import_the_plugin_host():
    code = (
        "import sys, sketchforge.geometry.reflectance, sketchforge.geometry.shaders;"
        "print(sorted(m for m in sys.modules if m.startswith('sketchforge.plugins')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
    from sketchforge.geometry.reflectance_model import ReflectanceModel as Below

    assert ReflectanceModel is Below  # the old import path still works


# --- isolation at start-up ------------------------------------------------------------------


class RaisesInTools:
    """Also provides an exporter: disabling the plugin must drop that too."""

    @hookimpl
    def sketchforge_tools(self):
        raise RuntimeError("tool table corrupted")

    @hookimpl
    def sketchforge_exporters(self):
        return [Exporter("xyz", (".xyz",), lambda p, m: None)]


class GoodShader:
    @hookimpl
    def sketchforge_shaders(self):
        return [Shader("grey", lambda N, l: np.full((len(N), 3), 0.5))]


def test_a_hook_that_raises_disables_its_plugin_only():
    host = make_test_host(RaisesInTools(), GoodShader())
    problems = host.validate()  # what the app calls at start-up: no exception
    assert any("'plugin-0-RaisesInTools' disabled" in p and "tool table corrupted" in p for p in problems)
    assert "xyz" not in host.exporters  # the plugin is gone as a whole, not half-registered
    assert "grey" in host.shaders and "obj" in host.exporters
    assert "plugin-0-RaisesInTools" not in host.plugin_names()
    assert "plugin-0-RaisesInTools" in host.skipped


def test_a_hook_returning_one_object_is_named():
    class OneObject:
        @hookimpl
        def sketchforge_shaders(self):
            return Shader("single", lambda N, l: np.zeros((len(N), 3)))

    host = make_test_host(OneObject())
    assert "single" not in host.shaders and len(host.shaders) == 2  # the core's two are there
    assert any("'plugin-0-OneObject'" in p and "must return a list" in p and "Shader" in p for p in host.problems)


# --- contracts ----------------------------------------------------------------------------------


def models_plugin(*models):
    class Models:
        @hookimpl
        def sketchforge_reflectance_models(self):
            return list(models)

    return Models()


def test_clamped_and_numpy_reflectance_models_are_refused_with_the_reason():
    import jax.numpy as jnp

    clamped = ReflectanceModel("clamped", lambda n, l: jnp.maximum(jnp.dot(n, l), 0.0))
    numpy_model = ReflectanceModel("numpy", lambda n, l: float(np.dot(np.asarray(n), np.asarray(l))))
    signed = ReflectanceModel("wrapped", lambda n, l: 0.7 * jnp.dot(n, l) + 0.3 * jnp.dot(n, l) ** 3)
    host = make_test_host(models_plugin(clamped, numpy_model, signed))
    assert set(host.reflectance_models) == {"lambertian", "wrapped"}
    text = "\n".join(host.problems)
    assert "'clamped' must be signed, not clamped: it is flat in shadow (R = 0, |∇R| = 0" in text
    assert "'numpy' cannot be differentiated by JAX" in text and "jax.numpy" in text
    assert text.count("plugin 'plugin-0-Models'") == 2


def test_exporter_suffixes_are_validated_and_shadowing_named():
    class Formats:
        @hookimpl
        def sketchforge_exporters(self):
            return [
                Exporter("off", ("off",), lambda p, m: None),  # no dot
                Exporter("obj2", (".obj",), lambda p, m: None),  # shadows the core's .obj
                Exporter("xyz", (".xyz",), lambda p, m: None),
            ]

    host = make_test_host(Formats())
    assert set(host.exporters) == {"obj", "ply", "stl", "gltf", "xyz"}
    text = "\n".join(host.problems)
    assert "suffix 'off' must be lower case and start with a dot" in text
    assert "'obj2' claims '.obj', already written by exporter 'obj' of plugin 'sketchforge-core'" in text


# --- all-or-nothing commands ---------------------------------------------------------------------


@dataclass
class HalfApply(Command):
    """Changes the document, then fails: what a buggy plugin command does."""

    name: ClassVar[str] = "half_apply"
    layer: str = "a"

    def do(self, doc):
        old = doc.layer(self.layer)
        doc._replace_layer(_renamed(old))
        doc._set_light(type(doc.light)(0.0, 1.0))
        doc._set_plugin_data("half", {"x": 1})
        doc._remove_layer(0)
        raise ZeroDivisionError("bug after the change")

    def undo(self, doc):
        raise AssertionError("never reached")

    def to_dict(self):
        return {"command": self.name, "layer": self.layer}

    @classmethod
    def from_dict(cls, d):
        return cls(layer=d["layer"])


def _renamed(layer):
    import dataclasses

    return dataclasses.replace(layer, name="changed")


class HalfApplyPlugin:
    @hookimpl
    def sketchforge_commands(self):
        return [HalfApply]


def test_a_command_that_raises_leaves_the_document_exactly_as_before():
    doc = fan_doc(HalfApplyPlugin())
    ref = fan_doc()
    layers, light, index = doc.layers, doc.light, doc.undo_stack.index
    removed = []
    doc.layer_removed.connect(lambda i, l: removed.append(l.id))
    with pytest.raises(PluginError) as info:
        doc.execute({"command": "half_apply", "layer": "a"})
    msg = str(info.value)
    assert "'half_apply'" in msg and "plugin 'plugin-1-HalfApplyPlugin'" in msg and "ZeroDivisionError" in msg
    assert "\n" not in msg and "unchanged" in msg
    assert doc.same_state(ref), doc.differences(ref)
    assert all(a is b for a, b in zip(doc.layers, layers)) and doc.light == light
    assert doc.plugin_data("half") is None and doc.undo_stack.index == index
    assert removed == ["a"]  # views saw the removal ... and then the restore re-inserted it
    assert doc.layer_ids() == ["a"]


def test_a_user_error_from_a_command_still_restores_and_keeps_its_message():
    @dataclass
    class Fails(ReplaceLayerCommand):
        name: ClassVar[str] = "fails_late"

        def do(self, doc):
            doc._set_light(type(doc.light)(0.0, -1.0))
            raise SketchforgeError("the stroke misses the band")

        def to_dict(self):
            return {"command": self.name, "layer": self.layer}

        @classmethod
        def from_dict(cls, d):
            return cls(layer=d["layer"])

    doc = fan_doc()
    light = doc.light
    with pytest.raises(SketchforgeError, match="^the stroke misses the band$"):
        doc.push(Fails(layer="a"))
    assert doc.light == light


# --- host-side export ----------------------------------------------------------------------


class ExportPlugin:
    @hookimpl
    def sketchforge_exporters(self):
        def write_xyz(path, mesh):
            np.savetxt(path, mesh.V, delimiter=",")

        def write_broken(path, mesh):
            with open(path, "w") as fh:
                fh.write("partial")
            raise ValueError("ran out of ideas")

        return [Exporter("xyz", (".xyz",), write_xyz), Exporter("broken", (".brk",), write_broken)]


def test_plugin_exporter_is_atomic_and_errors_are_one_line(tmp_path):
    doc = fan_doc(ExportPlugin())
    host = doc.host
    out = tmp_path / "pts.xyz"
    summary = host.export(out, doc=doc)
    assert np.loadtxt(out, delimiter=",").shape == (4, 3) and "4 vertices" in summary
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pts.xyz"]  # no temp file left

    with pytest.raises(ExportError) as info:
        host.export(tmp_path / "missing" / "pts.xyz", doc=doc)
    assert str(info.value) == f"cannot write {tmp_path / 'missing' / 'pts.xyz'}: the folder {tmp_path / 'missing'} does not exist"

    old = tmp_path / "keep.brk"
    old.write_text("old content")
    with pytest.raises(ExportError) as info:
        host.export(old, doc=doc)
    msg = str(info.value)
    assert "'broken'" in msg and "plugin 'plugin-1-ExportPlugin'" in msg and "ran out of ideas" in msg and "\n" not in msg
    assert old.read_text() == "old content"  # the half-written file never replaced it
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.brk", "pts.xyz"]


# --- provenance ----------------------------------------------------------------------------------


@dataclass
class Tag(ReplaceLayerCommand):
    name: ClassVar[str] = "tag_layer"
    tag: str = ""

    def compute(self, doc, old):
        return _renamed(old) if not self.tag else old.evolve(name=self.tag)

    def to_dict(self):
        return {"command": self.name, "layer": self.layer, "tag": self.tag}

    @classmethod
    def from_dict(cls, d):
        from sketchforge.plugin_api import parse_field

        return cls(layer=parse_field(d, "layer", str, cls.name), tag=parse_field(d, "tag", str, cls.name))


class TagPlugin:
    @hookimpl
    def sketchforge_commands(self):
        return [Tag]


def test_documents_record_providers_and_name_missing_plugins_once():
    import json

    from sketchforge.document import fileformat as ff

    doc = fan_doc(TagPlugin())
    doc.execute({"command": "tag_layer", "layer": "a", "tag": "head"})
    doc.execute({"command": "tag_layer", "layer": "a", "tag": "torso"})
    data = json.loads(ff.dumps(doc))
    assert data["providers"]["commands"]["tag_layer"] == {"plugin": "plugin-1-TagPlugin", "version": None}
    assert data["providers"]["commands"]["set_contour"]["plugin"] == "sketchforge-core"
    data["providers"]["commands"]["tag_layer"]["version"] = "2.1.0"  # as an installed package records it
    assert ff.document_from_dict(json.loads(json.dumps(data)), "tagged.json", host=doc.host).layer("a").name == "torso"

    without = make_test_host(FanInflater())
    with pytest.raises(SketchforgeError) as info:
        ff.document_from_dict(data, "tagged.json", host=without)
    msg = str(info.value)
    assert msg == (
        "tagged.json needs plugins that are not installed: "
        "unknown command 'tag_layer' (from plugin 'plugin-1-TagPlugin' version 2.1.0)"
    )
    assert msg.count("tag_layer") == 1  # two entries, said once


def test_provider_version_of_an_installed_plugin_is_its_distribution_version(real_host):
    from importlib.metadata import version

    assert real_host.provider_version("inflate") == version("sketchforge-inflate")
    assert real_host.provider_version("sketchforge-core") == version("sketchforge")


# --- the pytest plugin for plugin authors -------------------------------------------------------


def test_pytest_fixtures_are_installed_and_strict(tmp_path):
    """A plugin author's test file, run by pytest in a subprocess: the fixtures come from the
    ``pytest11`` entry point, and a strict host fails the test with the host's message."""
    (tmp_path / "test_author.py").write_text(
        "import jax.numpy as jnp\n"
        "from sketchforge.plugin_api import ReflectanceModel, hookimpl\n"
        "from sketchforge.plugins.testing import FanInflater\n"
        "class Clamped:\n"
        "    @hookimpl\n"
        "    def sketchforge_reflectance_models(self):\n"
        "        return [ReflectanceModel('clamped', lambda n, l: jnp.maximum(jnp.dot(n, l), 0.0))]\n"
        "def test_strict(make_sketchforge_host):\n"
        "    make_sketchforge_host(Clamped())\n"
        "def test_document_and_replay(make_sketchforge_host, make_sketchforge_document, assert_replays):\n"
        "    doc = make_sketchforge_document(make_sketchforge_host(FanInflater()))\n"
        "    doc.execute({'command': 'set_light', 'direction': [0.0, 1.0, 0.0]})\n"
        "    assert assert_replays(doc).layer('a').mesh.n_vertices == 49\n"
    )
    res = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:randomly", "-p", "no:cacheprovider", str(tmp_path)],
        capture_output=True, text=True, timeout=300, cwd=tmp_path,
    )
    out = res.stdout + res.stderr
    assert "1 failed, 1 passed" in out, out
    assert "the host refused plugin contributions" in out and "'clamped' must be signed, not clamped" in out


def test_a_solver_hook_bug_names_its_plugin_and_changes_nothing():
    class BadInflater:
        @hookimpl
        def sketchforge_inflaters(self):
            return [Inflater("bad", lambda points, closed, params, holes: np.linalg.inv(np.zeros((2, 2))))]

    doc = Document(host=make_test_host(BadInflater()))
    doc.execute({"command": "add_layer", "id": "a"})
    with pytest.raises(PluginError) as info:
        doc.execute({"command": "set_contour", "layer": "a", "points": TRIANGLE})  # a LinAlgError: a bug
    assert "the inflater 'bad' of plugin 'plugin-0-BadInflater' failed: LinAlgError" in str(info.value)
    assert doc.layer("a").mesh is None and doc.undo_stack.count() == 1
