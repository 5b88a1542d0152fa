"""Named solvers (issue 29, points 1 and 5): inflaters, sculpt solvers and assemblers chosen by
name per layer, per edit and per document, each with its own parameters that it checks itself;
one override rule for every hook kind; provenance that names a missing solver; a plugin that
cannot load never gives a traceback; non-finite heights never reach a document."""

from __future__ import annotations

import json

import numpy as np
import pytest
from third_party_solvers import ThirdPartySolvers, probe_params, probe_solve

from sketchforge import cli
from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.document.commands import ReplaceLayerCommand
from sketchforge.errors import DocumentFormatError, ParameterError, PluginError, SolverError, UnknownSolverError
from sketchforge.plugin_api import Assembler, SculptSolver, hookimpl, validate_params
from sketchforge.plugins import default_host, manager
from sketchforge.plugins.testing import FanInflater, make_test_host

ELLIPSE = [[float(np.cos(t)), float(0.7 * np.sin(t))] for t in np.linspace(0, 2 * np.pi, 120, endpoint=False)]
PLUGIN = "plugin-0-ThirdPartySolvers"


def _stroke_beside_isophote(doc, layer, pick, offset):
    """The isophote through ``pick``, shifted by ``offset`` to its darker side (k, 2)."""
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.isophote import picked_isophote
    from sketchforge_isophote_tool.layerdata import layer_data

    ld = layer_data(doc.layer(layer).mesh, doc.light.direction, LAMBERTIAN)
    _, iso = picked_isophote(ld, pick)
    seg = iso.offset_curve(-offset)
    P = np.asarray(seg.coords)
    near = np.linalg.norm(P - np.asarray(pick), axis=1) < 0.35
    return P[near].tolist()


@pytest.fixture
def third_party_doc(make_sketchforge_host, make_sketchforge_document):
    host = make_sketchforge_host(ThirdPartySolvers(), installed=("inflate", "isophote_tool", "assemble"))
    doc = make_sketchforge_document(host, contour=ELLIPSE, layer="a", resolution=0.05)
    doc.execute({"command": "add_layer", "id": "b"})
    doc.execute({"command": "set_inflate_params", "layer": "b", "solver": "rings", "params": {"height": 0.8, "rings": 20}})
    doc.execute({"command": "set_contour", "layer": "b", "points": [[x + 3.0, y] for x, y in ELLIPSE], "closed": True})
    return doc


def test_a_third_party_inflater_and_sculpt_solver_are_chosen_per_layer_and_edit(third_party_doc, assert_replays):
    doc = third_party_doc
    a, b = doc.layer("a"), doc.layer("b")
    assert (a.solver, b.solver) == ("poisson", "rings")
    assert dict(b.params) == {"height": 0.8, "rings": 20}  # the inflater's own parameters, complete
    assert set(a.params) == {"resolution", "inflation", "smoothing"}
    assert abs(b.mesh.V[:, 2].max() - 0.8) < 1e-12 and len(b.mesh.V) == 20 * 120 + 1
    stroke = _stroke_beside_isophote(doc, "a", [0.2, 0.1], 0.08)
    before = doc.layer("a").mesh
    doc.execute({"command": "sculpt_isophote", "layer": "a", "pick": [0.2, 0.1], "band": 0.3, "stroke": stroke,
                 "solver": "probe", "params": {"radius": 4}})
    probed = doc.layer("a")
    assert not probed.mesh.identical(before)
    assert probed.edits[-1]["solver"] == "probe" and probed.edits[-1]["params"] == {"radius": 4}
    doc.execute({"command": "sculpt_isophote", "layer": "a", "pick": [-0.3, 0.2], "band": 0.3,
                 "stroke": _stroke_beside_isophote(doc, "a", [-0.3, 0.2], 0.06)})
    assert doc.layer("a").edits[-1]["solver"] == "gauss_newton"  # none named: the built-in
    assert_replays(doc)  # bit-identical from the journal and from the saved file
    # A parameter change re-applies both edits, each with the solver that made it.
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.1}})
    assert [e["solver"] for e in doc.layer("a").edits] == ["probe", "gauss_newton"]
    assert_replays(doc)


def test_provenance_names_every_solver_with_its_plugin_and_version(third_party_doc):
    doc = third_party_doc
    doc.execute({"command": "sculpt_isophote", "layer": "a", "pick": [0.2, 0.1], "band": 0.3,
                 "stroke": _stroke_beside_isophote(doc, "a", [0.2, 0.1], 0.08), "solver": "probe"})
    solvers = ff.document_to_dict(doc)["providers"]["solvers"]
    assert solvers["inflate"]["rings"] == {"plugin": PLUGIN, "version": None, "solver_version": "2"}
    assert solvers["inflate"]["poisson"]["plugin"] == "inflate"
    assert solvers["sculpt"] == {"probe": {"plugin": PLUGIN, "version": None, "solver_version": "3"}}
    assert solvers["assemble"] == {"depth_qp": {"plugin": "assemble", "version": "0.1.0", "solver_version": "6"}}


def test_replay_check_names_a_solver_that_is_not_installed(third_party_doc, tmp_path, capsys):
    doc = third_party_doc
    doc.execute({"command": "sculpt_isophote", "layer": "a", "pick": [0.2, 0.1], "band": 0.3,
                 "stroke": _stroke_beside_isophote(doc, "a", [0.2, 0.1], 0.08), "solver": "probe"})
    path = tmp_path / "made_elsewhere.json"
    ff.save(doc, path)
    code = cli.main(["replay", str(path), "--check"])  # the installed plugins: no "rings", no "probe"
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err[-1] == (f"sketchforge: error: {path} was made with the inflater 'rings' (plugin '{PLUGIN}'), the sculpt "
                       f"solver 'probe' (plugin '{PLUGIN}'), which are not installed")
    # Opening it says the same, once, instead of failing on the first layer.
    with pytest.raises(DocumentFormatError, match="was made with the inflater 'rings'"):
        ff.load(path, default_host())


def test_replay_check_explains_a_difference_by_the_solver_versions(third_party_doc, tmp_path, capsys, monkeypatch):
    doc = third_party_doc
    doc.execute({"command": "sculpt_isophote", "layer": "a", "pick": [0.2, 0.1], "band": 0.3,
                 "stroke": _stroke_beside_isophote(doc, "a", [0.2, 0.1], 0.08), "solver": "probe"})
    path = tmp_path / "doc.json"
    ff.save(doc, path)

    class NewerProbe(ThirdPartySolvers):  # version 4: another default, other heights
        @hookimpl
        def sketchforge_sculpt_solvers(self):
            newer = lambda p: validate_params(p, {"radius": 5.0, "amplitudes": 8})  # noqa: E731
            return [SculptSolver("probe", probe_solve, check_params=newer, version="4")]

    host = make_test_host(NewerProbe(), entry_points=True, allowlist=["inflate", "isophote_tool"])
    monkeypatch.setattr(manager, "_default", host)
    assert cli.main(["replay", str(path), "--check"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "replay differs from the saved snapshot: layer 'a': mesh differ" in err
    assert ("(the sculpt solver 'probe' was version 3 of plugin 'plugin-0-ThirdPartySolvers'; installed: version 4 of "
            "'plugin-0-NewerProbe')") in err


@pytest.mark.parametrize("entry, message", [
    ({"command": "set_inflate_params", "layer": "b", "params": {"hieght": 1.0}},
     "inflater 'rings': unknown parameter 'hieght' (known: height, rings)"),
    ({"command": "set_inflate_params", "layer": "b", "params": {"rings": 1}}, "inflater 'rings': 'rings' must be >= 2, got 1"),
    ({"command": "set_inflate_params", "layer": "a", "params": {"resolutoin": 0.1}},
     "inflater 'poisson': unknown inflation parameter 'resolutoin' (known: resolution, inflation, smoothing)"),
    ({"command": "set_inflate_params", "layer": "a", "solver": "ringz", "params": {}},
     "no inflater named 'ringz' is installed (installed: fan, poisson, rings)"),
    ({"command": "sculpt_isophote", "layer": "a", "pick": [0.2, 0.1], "band": 0.3, "stroke": [[0, 0], [0.1, 0.1]],
      "solver": "probe", "params": {"raduis": 2}}, "sculpt solver 'probe': unknown parameter 'raduis' (known: amplitudes, radius)"),
    ({"command": "sculpt_isophote", "layer": "a", "pick": [0.2, 0.1], "band": 0.3, "stroke": [[0, 0], [0.1, 0.1]],
      "params": {"steps": 0}}, "sculpt solver 'gauss_newton': 'steps' must be an integer in 1..50, got 0"),
    ({"command": "set_assembly", "params": {"filet": 2}},
     "assembler 'depth_qp': unknown assembly parameter 'filet' "
     "(known: fair, fillet, gap, margin, on_bad_junction, qp_solver, reg, stiffness)"),
    ({"command": "set_assembly", "solver": "monster"}, "no assembler named 'monster' is installed (installed: depth_qp)"),
])
def test_a_solver_refuses_an_unknown_or_bad_parameter_in_one_line_and_nothing_changes(make_sketchforge_host, entry, message):
    host = make_sketchforge_host(FanInflater(), ThirdPartySolvers(), installed=("inflate", "isophote_tool", "assemble"))
    doc = Document(host=host)
    for e in ({"command": "add_layer", "id": "a"}, {"command": "add_layer", "id": "b"},
              {"command": "set_inflate_params", "layer": "a", "solver": "poisson", "params": {"resolution": 0.06}},
              {"command": "set_contour", "layer": "a", "points": ELLIPSE, "closed": True},
              {"command": "set_inflate_params", "layer": "b", "solver": "rings", "params": {}}):
        doc.execute(e)
    state = (doc.layers, doc.assembly, doc.undo_stack.count())
    with pytest.raises((ParameterError, UnknownSolverError)) as info:
        doc.execute(entry)
    assert str(info.value) == message
    assert (doc.layers, doc.assembly, doc.undo_stack.count()) == state


def test_the_document_assembler_and_its_parameters_are_a_command(make_sketchforge_host, tmp_path):
    seen = []

    class Spy:
        @hookimpl
        def sketchforge_assemblers(self):
            check = lambda p: validate_params(p, {"glue": 1.0, "style": "plain"})  # noqa: E731
            return [Assembler("spy", lambda layers, params: seen.append(dict(params)) or layers[0].mesh, check)]

    host = make_sketchforge_host(FanInflater(), Spy())
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": ELLIPSE, "closed": True})
    doc.assembled()
    doc.execute({"command": "set_assembly", "solver": "spy", "params": {"glue": 2.5}})
    doc.assembled()
    assert seen == [{"glue": 1.0, "style": "plain"}, {"glue": 2.5, "style": "plain"}]  # the only assembler, then named
    doc.execute({"command": "set_assembly", "params": {"style": "round"}})  # merged with the current ones
    assert dict(doc.assembly.params) == {"glue": 2.5, "style": "round"} and doc.assembly.solver == "spy"
    path = tmp_path / "a.json"
    ff.save(doc, path)
    assert json.loads(path.read_text())["snapshot"]["assembly"] == {"solver": "spy", "params": {"glue": 2.5, "style": "round"}}
    again = ff.load(path, host=host)
    assert again.assembly == doc.assembly and not again.differences(doc)
    doc.undo_stack.undo()
    doc.undo_stack.undo()
    assert doc.assembly.solver is None and not doc.assembly.params


class _Named:
    """A plugin whose hooks contribute the given values."""

    def __init__(self, name, **hooks):
        self.__name__ = name
        for hook, values in hooks.items():
            setattr(self, hook, hookimpl(specname=hook)(lambda values=values: list(values)))


def _probe(name="probe", version="1"):
    return SculptSolver(name, probe_solve, check_params=probe_params, version=version)


def test_two_plugins_registering_one_solver_name_is_an_error_naming_both():
    a = _Named("alpha", sketchforge_sculpt_solvers=[_probe()])
    b = _Named("beta", sketchforge_sculpt_solvers=[_probe(version="2")])
    host = make_test_host(a, b)
    assert "probe" not in host.solvers("sculpt")  # neither wins, whatever the order
    assert ("plugins 'alpha' and 'beta' both register the sculpt solver 'probe': error, neither is used until one of "
            "them is uninstalled (or left out with SKETCHFORGE_PLUGINS)") in host.problems
    with pytest.raises(PluginError) as info:
        host.solver("sculpt", "probe")
    assert str(info.value) == ("the sculpt solver 'probe' is registered by both plugins 'alpha' and 'beta'; uninstall one of "
                               "them (or leave one out with SKETCHFORGE_PLUGINS)")
    # Swapping the registration order changes nothing.
    assert "probe" not in make_test_host(b, a).solvers("sculpt")


def test_the_same_rule_holds_for_commands_and_the_core_keeps_its_names():
    from sketchforge.document.commands import RenameLayer
    from sketchforge.geometry.shaders import LAMBERT_SHADER

    class Rename2(RenameLayer):
        pass

    a = _Named("alpha", sketchforge_commands=[Rename2], sketchforge_shaders=[LAMBERT_SHADER.__class__("lambert", LAMBERT_SHADER.shade)])
    host = make_test_host(a)
    assert host.commands.get("rename_layer") is RenameLayer  # the core's
    assert any("the command 'rename_layer' is sketchforge's own; a plugin cannot replace it" in p for p in host.problems)
    assert host.shaders["lambert"] is LAMBERT_SHADER

    class Cmd(RenameLayer):
        name = "twin"

    class Cmd2(RenameLayer):
        name = "twin"

    host = make_test_host(_Named("alpha", sketchforge_commands=[Cmd]), _Named("beta", sketchforge_commands=[Cmd2]))
    with pytest.raises(PluginError, match="the command 'twin' is registered by both plugins 'alpha' and 'beta'"):
        host.commands.get("twin")


def test_two_pose_hooks_are_an_error_naming_both():
    class Poser:
        def __init__(self, name):
            self.__name__ = name

        @hookimpl
        def sketchforge_pose(self, doc, frame):
            return "posed"

    host = make_test_host(Poser("one"), Poser("two"))
    with pytest.raises(PluginError, match="plugins 'two' and 'one' both implement sketchforge_pose|plugins 'one' and 'two' both"):
        host.pose(Document(host=host), 0)
    assert any("both implement sketchforge_pose" in p for p in host.validate())


def test_pluggy_wrappers_legacy_hooks_and_unknown_hooks_are_refused_with_one_line():
    class Wrapper:
        @hookimpl(wrapper=True)
        def sketchforge_sculpt_solvers(self):
            result = yield
            return result

    class Legacy:
        @hookimpl
        def sketchforge_inflate(self, points, closed, params):
            return None

    class Typo:
        @hookimpl
        def sketchforge_shader(self):
            return []

    with pytest.raises(PluginError) as info:
        make_test_host(Wrapper())
    assert "its sketchforge_sculpt_solvers hook is a pluggy wrapper (wrapper=True)" in str(info.value)
    with pytest.raises(PluginError) as info:
        make_test_host(Legacy())
    assert "implements sketchforge_inflate, which was replaced by the named registry sketchforge_inflaters" in str(info.value)
    with pytest.raises(PluginError, match="implements the unknown hook 'sketchforge_shader'"):
        make_test_host(Typo())


@pytest.mark.parametrize("check, message", [
    (lambda p: dict(p), "accepted the unknown parameter '__sketchforge_probe__': check_params must refuse unknown keys"),
    (lambda p: 1 / 0, "check_params({}) raised ZeroDivisionError"),
    (lambda p: {"f": object()} if not p else validate_params(p, {}), "check_params({}) must return a dict of JSON values"),
])
def test_a_solver_that_drops_unknown_parameters_is_refused_at_registration(check, message):
    host = make_test_host(_Named("sloppy", sketchforge_sculpt_solvers=[SculptSolver("sloppy", probe_solve, check_params=check)]))
    assert "sloppy" not in host.solvers("sculpt")
    assert any(message in p and p.startswith("plugin 'sloppy': sculpt solver 'sloppy'") for p in host.problems), host.problems


def test_a_plugin_whose_dependency_is_missing_is_one_line_for_document_and_cli(monkeypatch, tmp_path, capsys):
    from importlib.metadata import EntryPoint

    real = manager.entry_points

    def with_broken(group):
        eps = list(real(group=group))
        return eps + [EntryPoint("zz_needs_diffrax", "sketchforge_no_such_module.plugin", "sketchforge")]

    monkeypatch.setattr(manager, "entry_points", with_broken)
    monkeypatch.setattr(manager, "_default", None)
    doc = Document(manager.default_host())  # no traceback: the other plugins work
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": ELLIPSE, "closed": True})
    assert doc.layer("a").mesh is not None
    line = ("plugin 'zz_needs_diffrax' could not be loaded: ModuleNotFoundError: No module named "
            "'sketchforge_no_such_module'")
    assert line in doc.host.problems
    path = tmp_path / "a.json"
    ff.save(doc, path)
    assert cli.main(["info", str(path)]) == 0
    err = capsys.readouterr().err
    assert err == f"sketchforge: warning: {line}\n"


def test_a_command_that_leaves_non_finite_heights_is_refused_before_the_document(make_sketchforge_host, make_sketchforge_document):
    from dataclasses import dataclass
    from typing import ClassVar

    @dataclass
    class Poison(ReplaceLayerCommand):
        name: ClassVar[str] = "poison"

        def compute(self, doc, old):
            z = np.array(old.mesh.V[:, 2])
            z[len(z) // 2] = np.nan
            return old.evolve(mesh=old.mesh.with_heights(z))

        def to_dict(self):
            return {"command": self.name, "layer": self.layer}

        @classmethod
        def from_dict(cls, d):
            return cls(layer=d["layer"])

    host = make_sketchforge_host(_Named("poisoner", sketchforge_commands=[Poison]), installed=("inflate",))
    doc = make_sketchforge_document(host, resolution=0.1)
    before, count = doc.layer("a"), doc.undo_stack.count()
    with pytest.raises(SolverError) as info:
        doc.execute({"command": "poison", "layer": "a"})
    assert str(info.value) == ("the change would leave layer 'a' with non-finite heights or positions at 1 vertices; it was "
                               "refused and the document is unchanged")
    assert doc.layer("a") is before and doc.undo_stack.count() == count


def test_an_inflater_that_cannot_cut_holes_is_never_given_any(make_sketchforge_host):
    host = make_sketchforge_host(FanInflater())
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a"})
    hole = [[0.1 * np.cos(t), 0.1 * np.sin(t)] for t in np.linspace(0, 2 * np.pi, 20, endpoint=False)]
    with pytest.raises(Exception) as info:
        doc.execute({"command": "set_contour", "layer": "a", "points": ELLIPSE, "closed": True, "holes": [hole]})
    assert "the inflater 'fan' (plugin 'plugin-0-FanInflater') cannot cut holes" in str(info.value)
    assert doc.layer("a").mesh is None


def test_a_layer_switching_inflater_starts_from_the_new_one_s_defaults(make_sketchforge_host):
    host = make_sketchforge_host(FanInflater(), ThirdPartySolvers(), installed=("inflate",))
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": ELLIPSE, "closed": True})
    assert doc.layer("a").solver == "poisson"  # the built-in is the default even beside others
    doc.execute({"command": "set_inflate_params", "layer": "a", "solver": "rings", "params": {"rings": 5}})
    assert doc.layer("a").solver == "rings" and dict(doc.layer("a").params) == {"height": 1.0, "rings": 5}
    doc.undo_stack.undo()
    assert doc.layer("a").solver == "poisson" and doc.layer("a").params["resolution"] == 0.03


def test_inflater_names_must_be_installed_to_open_a_snapshot(make_sketchforge_host, tmp_path):
    host = make_sketchforge_host(FanInflater(), ThirdPartySolvers(), installed=("inflate",))
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_inflate_params", "layer": "a", "solver": "fan", "params": {}})
    doc.execute({"command": "set_contour", "layer": "a", "points": ELLIPSE, "closed": True})
    path = tmp_path / "fan.json"
    ff.save(doc, path)
    other = make_test_host(entry_points=True, allowlist=["inflate"])
    with pytest.raises(DocumentFormatError) as info:
        ff.load(path, host=other)
    assert str(info.value) == f"{path} was made with the inflater 'fan' (plugin 'plugin-0-FanInflater'), which is not installed"
    assert not ff.load(path, host=host).differences(doc)
