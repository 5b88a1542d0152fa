"""Provenance (issue 39, point 1): which solvers, commands and models a document used, recorded
with their plugin and version, and the one message that names what a file needs and this
installation lacks. Checked on journals and snapshots written by hand, so every rule (named,
unnamed, nested, in a layer's edits, recorded only in ``providers``) has its own input."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.document.commands import Command
from sketchforge.document.provenance import check_available, missing_solvers, record, used_solvers, version_notes
from sketchforge.errors import DocumentFormatError
from sketchforge.geometry.mesh import Mesh
from sketchforge.plugins.hookspecs import hookimpl
from sketchforge.plugins.solvers import Assembler, Inflater, SculptSolver, validate_params
from sketchforge.plugins.testing import FanInflater, make_test_host

SQUARE = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]


@dataclass
class Nudge(Command):
    """A sculpt-kind command (the journal entry names its solver like ``sculpt_isophote``)."""

    name: ClassVar[str] = "nudge"
    solver_kind: ClassVar[str | None] = "sculpt"

    def do(self, doc):
        pass

    def undo(self, doc):
        pass

    def to_dict(self):
        return {"command": self.name}

    @classmethod
    def from_dict(cls, d):
        return cls()


def _glue(layers, params):
    meshes = [l.mesh for l in layers]
    return Mesh(np.vstack([m.V for m in meshes]), np.vstack([m.F for m in meshes[:1]]))


class Extras:
    """Another inflater ('dome', version 4), an assembler ('glue', version 3), a sculpt solver
    ('smooth', version 2) and the sculpt-kind command 'nudge'."""

    @hookimpl
    def sketchforge_inflaters(self):
        fan = FanInflater()
        return [Inflater("dome", fan.inflate, check_params=lambda p: validate_params(p, {"inflation": 1.0}), version="4",
                         holes=False)]

    @hookimpl
    def sketchforge_assemblers(self):
        return [Assembler("glue", _glue, version="3")]

    @hookimpl
    def sketchforge_sculpt_solvers(self):
        return [SculptSolver("smooth", lambda problem, params: None, version="2")]

    @hookimpl
    def sketchforge_commands(self):
        return [Nudge]


EXTRAS = "plugin-1-Extras"


@pytest.fixture
def host():
    return make_test_host(FanInflater(), Extras())


def test_used_solvers_reads_names_defaults_macros_edits_and_the_assembly(host):
    journal = [
        {"command": "add_layer", "id": "a", "name": "A"},
        {"command": "set_inflate_params", "layer": "a", "solver": "dome", "params": {}},
        {"command": "macro", "text": "x", "children": [
            {"command": "nudge", "solver": "smooth"},
            {"command": "macro", "text": "y", "children": [{"command": "nudge", "solver": "deep"}]}]},
        {"command": "set_light", "direction": [1, 0]},
    ]
    assert used_solvers(host, journal, defaults=False) == {"inflate": {"dome"}, "sculpt": {"smooth", "deep"}, "assemble": set()}
    # it inflates, so it is assembled: by the default, here the only assembler installed
    assert used_solvers(host, journal) == {"inflate": {"dome"}, "sculpt": {"smooth", "deep"}, "assemble": {"glue"}}
    # An unnamed solver command ran with the host's default of its kind (only with defaults).
    unnamed = [{"command": "nudge"}, {"command": "set_inflate_params", "layer": "a", "params": {}}]
    assert used_solvers(host, unnamed, defaults=False) == {"inflate": set(), "sculpt": set(), "assemble": set()}
    got = used_solvers(host, unnamed)
    # 'smooth' is the only sculpt solver: the default; two inflaters, neither the built-in: none;
    # an inflating document is assembled, by 'glue', the only assembler
    assert got == {"inflate": set(), "sculpt": {"smooth"}, "assemble": {"glue"}}
    # Layers: a named inflater; a mesh without a name used the default; a layer without a mesh nothing.
    layers = [{"id": "a", "solver": "dome", "edits": [{"command": "nudge", "solver": "smooth"}]},
              {"id": "b", "mesh": {"V": []}}, {"id": "c"}]
    got = used_solvers(host, [], layers, defaults=False)
    assert got == {"inflate": {"dome"}, "sculpt": {"smooth"}, "assemble": set()}
    # A document with meshes is assembled: with the named assembler, else the default.
    assert used_solvers(host, [], layers, {"solver": "glue"}, defaults=False)["assemble"] == {"glue"}
    assert used_solvers(host, [], [{"id": "c"}], None)["assemble"] == set()  # no mesh: nothing assembled


def test_defaults_are_the_hosts_when_it_has_one(host):
    one = make_test_host(FanInflater())
    assert used_solvers(one, [{"command": "set_inflate_params", "layer": "a", "params": {}}]) == {
        "inflate": {"fan"}, "sculpt": set(), "assemble": set()}
    # two inflaters, neither the built-in: no default, nothing is claimed for the unnamed command
    assert used_solvers(host, [{"command": "set_inflate_params", "layer": "a", "params": {}}])["inflate"] == set()


def _doc(host):
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    doc.execute({"command": "set_inflate_params", "layer": "a", "solver": "dome", "params": {"inflation": 2}})
    doc.execute({"command": "set_contour", "layer": "a", "points": SQUARE, "closed": True})
    doc.execute({"command": "set_assembly", "solver": "glue"})
    return doc


def test_record_names_every_command_and_solver_with_its_plugin_and_version(host):
    doc = _doc(host)
    providers = record(doc)
    assert providers["commands"]["add_layer"] == {"plugin": "sketchforge-core", "version": host.provider_version("sketchforge-core")}
    assert set(providers["commands"]) == {"add_layer", "set_inflate_params", "set_contour", "set_assembly"}
    assert providers["solvers"] == {
        "inflate": {"dome": {"plugin": EXTRAS, "version": None, "solver_version": "4"}},
        "assemble": {"glue": {"plugin": EXTRAS, "version": None, "solver_version": "3"}},
    }
    assert providers["reflectance_models"] == {}
    # the file carries it, and what a document needs and lacks is read back from it
    data = ff.document_to_dict(doc)
    assert data["providers"] == providers
    assert missing_solvers(data, host) == []
    fan_only = make_test_host(FanInflater())
    assert missing_solvers(data, fan_only) == [f"the inflater 'dome' (plugin {EXTRAS!r})", f"the assembler 'glue' (plugin {EXTRAS!r})"]


def test_record_lists_only_reflectance_models_other_than_the_default(host):
    doc = _doc(host)
    doc.undo_stack.clear()
    doc.base_journal = [{"command": "nudge", "model": "lambertian"}, {"command": "nudge", "model": "lambertian"}]
    assert record(doc)["reflectance_models"] == {}
    doc.base_journal.append({"command": "nudge", "model": "lambertian", "children": [{"command": "nudge", "model": "lambertian"}]})
    assert record(doc)["reflectance_models"] == {}


def _data(journal=(), layers=(), providers=None, assembly=None):
    data = {"journal": list(journal), "snapshot": {"layers": list(layers)}}
    if assembly is not None:
        data["snapshot"]["assembly"] = assembly
    if providers is not None:
        data["providers"] = providers
    return data


def test_missing_solvers_names_each_with_its_recorded_plugin(host):
    recorded = {"solvers": {"sculpt": {"strips": {"plugin": "strips", "version": "0.1.0", "solver_version": "1"}},
                            "inflate": {"ghost": {"plugin": "ghosts"}}}}
    data = _data(journal=[{"command": "nudge", "solver": "strips"}, {"command": "nudge", "solver": "smooth"},
                          {"command": "set_inflate_params", "layer": "a", "params": {}, "solver": "nowhere"}],
                 providers=recorded)
    out = missing_solvers(data, host)
    assert out == [
        "the inflater 'ghost' (plugin 'ghosts')",
        "the inflater 'nowhere' (its plugin is not recorded in the file)",
        "the sculpt solver 'strips' (plugin 'strips' version 0.1.0)",
    ]
    # A recorded default assembler is not needed; a named one is.
    rec_asm = {"solvers": {"assemble": {"depth_qp": {"plugin": "assemble", "version": "1"}}}}
    assert missing_solvers(_data(layers=[{"id": "a", "solver": "fan", "mesh": {}}], providers=rec_asm), host) == []
    assert missing_solvers(_data(layers=[{"id": "a", "solver": "fan"}], assembly={"solver": "depth_qp"},
                                 providers=rec_asm), host) == ["the assembler 'depth_qp' (plugin 'assemble' version 1)"]
    # Solvers the file records as used are required even where no entry names them (a layer's
    # inflater recorded at save time), except the assembler.
    assert missing_solvers(_data(journal=[{"command": "add_layer", "id": "a", "name": "A"}], providers=recorded), host) == [
        "the inflater 'ghost' (plugin 'ghosts')", "the sculpt solver 'strips' (plugin 'strips' version 0.1.0)"]
    # A malformed file is read as far as it goes.
    assert missing_solvers({"journal": "x", "snapshot": 3, "providers": []}, host) == []
    assert missing_solvers(_data(journal=[{"command": "nudge", "solver": "x"}], providers={"solvers": []}), host) == [
        "the sculpt solver 'x' (its plugin is not recorded in the file)"]


def test_version_notes_explain_a_replay_that_differs_by_a_solver_version(host):
    same = {"solvers": {"inflate": {"dome": {"plugin": EXTRAS, "version": None, "solver_version": "4"}}}}
    assert version_notes(_data(providers=same), host) == []
    older = {"solvers": {"inflate": {"dome": {"plugin": "domes", "version": "0.9", "solver_version": "3"}},
                         "assemble": {"glue": {"plugin": EXTRAS, "version": "1.0", "solver_version": "3"}},
                         "sculpt": {"gone": {"plugin": "x", "solver_version": "1"}, "smooth": "malformed"},
                         "paint": {"brush": {"plugin": "x"}}}}
    notes = version_notes(_data(providers=older), host)
    assert notes == [
        f"the assembler 'glue' was version 3 of plugin {EXTRAS!r} 1.0; installed: version 3 of {EXTRAS!r}",
        f"the inflater 'dome' was version 3 of plugin 'domes' 0.9; installed: version 4 of {EXTRAS!r}",
    ]
    assert version_notes({"providers": "x"}, host) == []


def test_check_available_lists_everything_missing_in_one_line(host):
    check_available(_data(journal=[{"command": "nudge", "solver": "smooth"}]), host, "doc.json")  # nothing missing
    providers = {"commands": {"paint": {"plugin": "brushes", "version": "2.0"}, "smear": {"plugin": "brushes", "version": "2.0"},
                              "warp": {"plugin": "warps"}},
                 "reflectance_models": {"velvet": {"plugin": "cloth", "version": "1"}},
                 "solvers": {"sculpt": {"strips": {"plugin": "strips", "version": "0.1.0"}}}}
    data = _data(journal=[{"command": "paint"}, {"command": "smear", "model": "velvet"}, {"command": "warp"},
                          {"command": "mystery"}, {"command": "nudge", "solver": "strips"}], providers=providers)
    with pytest.raises(DocumentFormatError) as info:
        check_available(data, host, "doc.json")
    assert str(info.value) == (
        "doc.json needs plugins that are not installed: unknown command 'mystery' (its plugin is not recorded in the "
        "file); unknown command 'paint', unknown command 'smear' (from plugin 'brushes' version 2.0); unknown command "
        "'warp' (from plugin 'warps'); unknown reflectance model 'velvet' (from plugin 'cloth' version 1); "
        "it was made with the sculpt solver 'strips' (plugin 'strips' version 0.1.0), not installed either")
    # solvers alone
    with pytest.raises(DocumentFormatError) as info:
        check_available(_data(journal=[{"command": "nudge", "solver": "a"}, {"command": "nudge", "solver": "b"}]), host, "d")
    assert str(info.value) == ("d was made with the sculpt solver 'a' (its plugin is not recorded in the file), the sculpt "
                               "solver 'b' (its plugin is not recorded in the file), which are not installed")
    with pytest.raises(DocumentFormatError, match=r"^d was made with the sculpt solver 'a' \(.*\), which is not installed$"):
        check_available(_data(journal=[{"command": "nudge", "solver": "a"}]), host, "d")
    # a layer's edits and a model named in the snapshot count too
    with pytest.raises(DocumentFormatError, match="unknown command 'paint'"):
        check_available(_data(layers=[{"id": "a", "edits": [{"command": "paint"}]}]), host, "d")
    with pytest.raises(DocumentFormatError, match="unknown reflectance model 'velvet'"):
        check_available(_data(layers=[{"id": "a", "edits": [{"command": "nudge", "model": "velvet"}]}]), host, "d")
    check_available(_data(journal=[{"command": "nudge", "model": "lambertian"}]), host, "d")


def test_a_non_default_reflectance_model_is_recorded_with_its_plugin(fan_host):
    import jax.numpy as jnp

    from sketchforge.plugins.registry import ReflectanceModel

    class Velvet:
        @hookimpl
        def sketchforge_reflectance_models(self):
            return [ReflectanceModel("velvet", lambda n, l: 0.5 * jnp.dot(n, l) + 0.5)]

    host = make_test_host(FanInflater(), Velvet())
    doc = Document(host=host)
    doc.base_journal = [{"command": "add_layer", "id": "a", "name": "A"}, {"command": "nudge", "model": "velvet"},
                        {"command": "nudge", "model": "lambertian"}]
    assert record(doc)["reflectance_models"] == {"velvet": {"plugin": "plugin-1-Velvet", "version": None}}
    # a stand-in host that has no solver registries needs no solver
    from types import SimpleNamespace

    assert missing_solvers(_data(journal=[{"command": "nudge", "solver": "x"}]), SimpleNamespace()) == []
