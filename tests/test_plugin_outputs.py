"""Every plugin output is checked (issue 37): an inflater's mesh (type, finite, z >= 0, 0 on the
rim, counter-clockwise), an assembler's; a violation is one line naming the solver and its
plugin, with the document unchanged. Two exporters claiming one suffix are refused like two
solvers with one name, whatever the load order. And the CLI: ``sketchforge plugins``,
``render --model`` / ``--shader``, ``info`` on a document whose plugins are missing."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sketchforge import cli
from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.plugin_api import (
    Assembler,
    Exporter,
    Inflater,
    Mesh,
    PluginError,
    check_front_mesh,
    hookimpl,
    no_params,
)
from sketchforge.plugins.testing import FanInflater, make_host

SQUARE = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]


def dome(points, closed, params, holes):
    """A valid front surface: the square's fan with its centre raised."""
    return FanInflater().inflate(points, closed, {"inflation": 1.0, "smoothing": 0.0}, holes)


def _broken(kind: str, rng):
    """An inflater that breaks its contract one way (random sizes, so no case is hand-picked)."""

    def inflate(points, closed, params, holes):
        m = dome(points, closed, params, holes)
        V, F = np.array(m.V), np.array(m.F)
        k = int(rng.integers(0, len(m.boundary)))
        if kind == "tuple":
            return V, F
        if kind == "none":
            return None
        if kind == "nan":
            V[-1, 2] = np.nan
        elif kind == "below":
            V[-1, 2] = -rng.uniform(1e-6, 1.0)
        elif kind == "rim":
            V[m.boundary[k], 2] = rng.uniform(1e-9, 0.5)
        elif kind == "clockwise":
            F = F[:, ::-1]
        elif kind == "one_clockwise":
            F[k] = F[k, ::-1]
        elif kind == "flat":
            F = np.vstack([F, [[0, 1, 1]]])
        elif kind == "empty":
            return Mesh(V, np.zeros((0, 3), np.int64), m.boundary)
        return Mesh(V, F, m.boundary, m.junction)

    return inflate


CASES = {
    "tuple": "returned a tuple of 2 instead of a Mesh",
    "none": "returned None instead of a Mesh",
    "nan": "returned a mesh with non-finite coordinates at 1 of 5 vertices",
    "below": "returned a mesh with heights below 0 at 1 of 5 vertices",
    "rim": "returned a mesh whose rim is not at height 0 (1 of 4 rim vertices",
    "clockwise": "returned a mesh with 4 of 4 triangles clockwise or flat seen from +z",
    "one_clockwise": "returned a mesh with 1 of 4 triangles clockwise or flat seen from +z",
    "flat": "returned a mesh with 1 of 5 triangles clockwise or flat seen from +z",
    "empty": "returned a mesh without a surface (0 triangles",
}


class Sloppy:
    __name__ = "sloppy_solvers"

    def __init__(self, kind, rng):
        self.kind, self.rng = kind, rng

    @hookimpl
    def sketchforge_inflaters(self):
        return [Inflater("sloppy", _broken(self.kind, self.rng), check_params=no_params, holes=False)]


@pytest.mark.parametrize("kind", sorted(CASES))
def test_a_broken_inflater_is_refused_in_one_line_naming_it_and_its_plugin(kind):
    rng = np.random.default_rng(37)
    doc = Document(make_host(Sloppy(kind, rng)))
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_inflate_params", "layer": "a", "solver": "sloppy"})
    before = (doc.layers, doc.undo_stack.index)
    with pytest.raises(PluginError) as info:
        doc.execute({"command": "set_contour", "layer": "a", "points": SQUARE, "closed": True})
    text = str(info.value)
    assert text.startswith(f"the inflater 'sloppy' (plugin 'sloppy_solvers') {CASES[kind]}"), text
    assert text.endswith("nothing was changed") and "\n" not in text and "sketchforge-core" not in text
    assert (doc.layers, doc.undo_stack.index) == before and doc.layer("a").mesh is None


def test_a_valid_mesh_passes_and_the_public_check_says_the_same():
    mesh = dome(SQUARE, True, {}, [])
    assert check_front_mesh(mesh) is mesh
    with pytest.raises(PluginError, match="^the mesh returned a mesh with heights below 0"):
        check_front_mesh(mesh.with_heights(mesh.V[:, 2] - 0.5))


def test_the_built_in_inflater_keeps_the_contract_on_random_outlines(real_host):
    """The checks refuse nothing the built-in makes (random blobs, open and closed, with holes)."""
    rng = np.random.default_rng(2037)
    for i in range(6):
        t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
        r = 1 + 0.25 * np.sin(3 * t + rng.uniform(0, 6)) + 0.1 * rng.normal(size=3) @ np.array([np.cos(t), np.sin(t), np.cos(2 * t)])
        pts = np.c_[r * np.cos(t), 0.7 * r * np.sin(t)]
        holes = [np.c_[0.15 * np.cos(t[::3]), 0.1 * np.sin(t[::3])]] if i % 2 else []
        mesh = real_host.inflate(pts if i % 3 else pts[:60], closed=bool(i % 3), params={"resolution": 0.06}, holes=holes)
        assert check_front_mesh(mesh) is mesh


class TupleAssembler:
    __name__ = "tuple_assembler"

    @hookimpl
    def sketchforge_assemblers(self):
        return [Assembler("pair", lambda layers, params: (layers[0].mesh.V, layers[0].mesh.F), check_params=no_params)]


def test_an_assembler_returning_a_tuple_is_blamed_on_its_own_plugin():
    doc = Document(make_host(FanInflater(), TupleAssembler()))
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": SQUARE, "closed": True})
    with pytest.raises(PluginError, match=r"^the assembler 'pair' \(plugin 'tuple_assembler'\) returned a tuple of 2 "
                                          r"instead of a Mesh; nothing was changed$"):
        doc.assembled()


# --- exporters ----------------------------------------------------------------------------------


class Formats:
    def __init__(self, name, suffixes, document=False):
        self.__name__, self.suffixes, self.document = name, suffixes, document

    @hookimpl
    def sketchforge_exporters(self):
        def write(path, mesh):
            path.write_text(self.__name__)

        if self.document:
            return [Exporter(f"doc_{self.__name__}", self.suffixes, write, write_document=lambda p, d: p.write_text("d"),
                             handles=lambda d: True)]
        return [Exporter(f"fmt_{self.__name__}", self.suffixes, write)]


@pytest.mark.parametrize("order", [("alpha", "beta"), ("beta", "alpha")])
def test_two_exporters_claiming_one_suffix_are_refused_naming_both_whatever_the_order(order, tmp_path):
    plugins = {"alpha": Formats("alpha", (".off", ".aaa")), "beta": Formats("beta", (".off",))}
    host = make_host(FanInflater(), *(plugins[n] for n in order))
    host.validate()
    first, second = order
    line = (f"plugins '{first}' and '{second}' both write '.off' (exporters 'fmt_{first}' and 'fmt_{second}'): error, "
            "neither is used for '.off' until one of them is uninstalled (or left out with SKETCHFORGE_PLUGINS)")
    assert host.problems == [line]
    assert host.problems_of("alpha") == host.problems_of("beta") == [line]
    doc = Document(host)
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": SQUARE, "closed": True})
    with pytest.raises(PluginError) as info:
        host.export(tmp_path / "m.off", doc=doc)
    assert str(info.value) == line and not (tmp_path / "m.off").exists()
    host.export(tmp_path / "m.aaa", doc=doc)  # alpha's other suffix is its own
    assert (tmp_path / "m.aaa").read_text() == "alpha"


def test_two_document_exporters_for_one_suffix_are_refused_too_and_a_mesh_exporter_may_share_it(tmp_path):
    host = make_host(FanInflater(), Formats("anim1", (".glb",), document=True), Formats("anim2", (".glb",), document=True))
    host.validate()
    assert any("plugins 'anim1' and 'anim2' both write '.glb' (document exporters" in p for p in host.problems)
    assert not any("sketchforge-core" in p for p in host.problems)  # sharing the core's .glb is allowed


def test_the_cli_export_to_a_clashing_suffix_exits_2_naming_both(tmp_path, monkeypatch, capsys):
    from sketchforge.plugins import manager

    doc = Document(make_host(FanInflater()))
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": SQUARE, "closed": True})
    path = tmp_path / "d.json"
    ff.save(doc, path)
    host = make_host(FanInflater(), Formats("alpha", (".off",)), Formats("beta", (".off",)))
    monkeypatch.setattr(manager, "_default", host)
    assert cli.main(["replay", str(path), "--export", str(tmp_path / "m.off")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    clash = "plugins 'alpha' and 'beta' both write '.off'"
    assert err[-1].startswith(f"sketchforge: error: {clash}")
    assert sum(clash in line for line in err) == 1  # one line naming both: never "the first one loaded" wins


# --- the CLI ------------------------------------------------------------------------------------


def test_sketchforge_plugins_lists_every_plugin_version_contributions_and_problems(monkeypatch, capsys):
    from sketchforge.plugins import manager

    host = make_host(Formats("alpha", (".off",)), Formats("beta", (".off",)), installed=("inflate", "assemble"))
    monkeypatch.setattr(manager, "_default", host)
    assert cli.main(["plugins"]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert err == ""  # the problems are listed under their plugins, not warned about as well
    assert lines[0] == f"sketchforge-core {host.provider_version('sketchforge-core')}"
    assert "  exporters: gltf, obj, ply, stl" in lines and "  shaders: cel, lambert" in lines
    i = lines.index(f"inflate {host.provider_version('inflate')}")
    assert lines[i + 1] == "  inflaters: poisson"
    j = lines.index(f"assemble {host.provider_version('assemble')}")
    assert lines[j + 1:j + 3] == ["  assemblers: depth_qp", "  dataset generators: creature"]
    # Each problem once, numbered; alpha and beta both refer to it.
    assert lines[-2:] == ["1 problem:", f"  1. {host.problems[0]}"] and "both write '.off'" in host.problems[0]
    assert lines[lines.index("alpha") + 2] == lines[lines.index("beta") + 2] == "  problem: 1 (below)"


def _doc_with_a_brush(tmp_path):
    pytest.importorskip("sketchforge_bump_brush")
    host = make_host(installed=("inflate", "bump_brush"))
    doc = Document(host)
    for e in ({"command": "add_layer", "id": "a", "name": "Blob"},
              {"command": "set_contour", "layer": "a", "points": (0.8 * np.array(SQUARE)).tolist(), "closed": True},
              {"command": "bump_brush", "layer": "a", "center": [0.1, 0.0], "radius": 0.4, "height": 0.2}):
        doc.execute(e)
    path = tmp_path / "brushed.json"
    ff.save(doc, path)
    return doc, path


def test_info_describes_a_document_whose_plugins_are_missing_and_lists_them(tmp_path, monkeypatch, capsys):
    from sketchforge.plugins import manager

    doc, path = _doc_with_a_brush(tmp_path)
    monkeypatch.setattr(manager, "_default", make_host(installed=("inflate",)))  # no bump brush
    assert cli.main(["info", str(path)]) == 0
    out = capsys.readouterr().out.splitlines()
    mesh = doc.layer("a").mesh
    version = doc.host.provider_version("bump_brush")
    assert out[1] == f"  0: a 'Blob' closed, {mesh.n_vertices} vertices, {mesh.n_faces} triangles, 1 sculpt edits"
    assert out[2:] == [f"{path} needs plugins that are not installed:",
                       f"  the command 'bump_brush' (plugin 'bump_brush' version {version})"]
    # Without its snapshot the layers cannot be known, the rest still is.
    data = json.loads(path.read_text())
    del data["snapshot"]
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps(data))
    assert cli.main(["info", str(bare)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"{bare}: ? layers") and "3 journal entries" in out[0]
    assert out[-1] == f"  the command 'bump_brush' (plugin 'bump_brush' version {version})"
    # Opening it still refuses, naming the same.
    with pytest.raises(Exception, match="needs plugins that are not installed: unknown command 'bump_brush'"):
        ff.load(path, make_host(installed=("inflate",)))


def test_render_chooses_the_shading_by_model_or_shader(tmp_path, capsys):
    pytest.importorskip("sketchforge_soft_brdf")
    src = tmp_path / "d.json"
    doc = Document(make_host(installed=("inflate",)))
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": (0.8 * np.array(SQUARE)).tolist(), "closed": True})
    ff.save(doc, src)
    outs = {}
    for name, args in (("default", []), ("lambertian", ["--model", "lambertian"]), ("soft", ["--model", "soft_lambert"]),
                       ("cel", ["--shader", "cel"]), ("cel_flag", ["--cel"]), ("lambert", ["--shader", "lambert"])):
        png = tmp_path / f"{name}.png"
        assert cli.main(["render", str(src), "--png", str(png), "--size", "96", "--light=0.5,0.3,0.8", *args]) == 0, name
        outs[name] = png.read_bytes()
    assert outs["cel"] == outs["cel_flag"] and outs["lambert"] == outs["default"]
    assert outs["soft"] != outs["default"] and outs["soft"] != outs["cel"]
    capsys.readouterr()
    assert cli.main(["render", str(src), "--png", str(tmp_path / "x.png"), "--model", "velvet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("sketchforge: error: --model 'velvet': no such reflectance model is installed (installed: ")
    assert "lambertian" in err and not (tmp_path / "x.png").exists()
    assert cli.main(["render", str(src), "--png", str(tmp_path / "x.png"), "--shader", "toon"]) == 2
    assert "no such display shader is installed (installed: cel, lambert" in capsys.readouterr().err


def test_the_app_s_host_prints_each_problem_once(monkeypatch, capsys):
    """A plugin that cannot be loaded used to reach stderr two to four times (the host's log, the
    app's 'not loaded' line, its problem line, the inflation child's host): now once."""
    from importlib.metadata import EntryPoint

    from sketchforge.plugins import manager
    from sketchforge.qt.app import plugin_host

    real = manager.entry_points
    broken = EntryPoint("zz_needs_diffrax", "sketchforge_no_such_module.plugin", "sketchforge")
    monkeypatch.setattr(manager, "entry_points", lambda group: list(real(group=group)) + [broken])
    monkeypatch.setenv("SKETCHFORGE_PLUGINS", "inflate,zz_needs_diffrax")
    host = plugin_host()
    manager.PluginHost.create(skip_broken=True)  # the child process builds one too: it prints nothing
    err = capsys.readouterr().err.splitlines()
    line = ("sketchforge: warning: plugin 'zz_needs_diffrax' could not be loaded: ModuleNotFoundError: "
            "No module named 'sketchforge_no_such_module'")
    assert err == [line] and host.problems_of("zz_needs_diffrax") == [line.removeprefix("sketchforge: warning: ")]
