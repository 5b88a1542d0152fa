"""A light anywhere on the hemisphere facing the viewer (issue 35, point 1): kept in the
document, its file (format version 2; version 1 files keep their in-plane meaning), `render
--light`, the sculpt and the edits it leaves in a layer."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from sketchforge.document import fileformat as ff
from sketchforge.document.document import Document
from sketchforge.document.layer import Light
from sketchforge.errors import DocumentFormatError, ParameterError

sys.path.insert(0, str(Path(__file__).parent / "attack"))
from attack_helpers import assert_one_line_error, run_cli  # noqa: E402

ELLIPSE = [[1.0 * math.cos(t), 0.7 * math.sin(t)] for t in np.linspace(0, 2 * math.pi, 60, endpoint=False)]


def _doc(host, light=None, resolution=0.1):
    doc = Document(host=host, light=light)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    doc.execute({"command": "set_contour", "layer": "a", "points": ELLIPSE, "closed": True})
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"resolution": resolution}})
    return doc


# --- the value ------------------------------------------------------------------------------


def test_the_hemisphere_is_accepted_and_the_back_refused_in_one_line():
    assert Light.from_vector([0, 0, 1]) == Light(0.0, 0.0, 1.0)
    assert Light.from_vector([0, 0, 5]).direction.tolist() == [0.0, 0.0, 1.0]
    tilted = Light.from_vector([0.5, 0.5, 0.707])
    assert abs(np.linalg.norm(tilted.direction) - 1.0) < 1e-15 and tilted.z > 0.7
    for v, words in (([1.0, 0.0, -0.1], "must face the viewer (z >= 0)"), ([0, 0, 0], "must not be the zero vector"),
                     ([0, 0, -1], "must face the viewer"), ([1.0, float("nan"), 0.5], "finite")):
        with pytest.raises(ParameterError) as info:
            Light.from_vector(v)
        assert words in str(info.value) and "\n" not in str(info.value)
    assert Light(1.0, 0.0, -0.0).to_list() == [1.0, 0.0, 0.0]  # -0.0 is in the plane


def test_an_in_plane_light_is_normalised_exactly_as_before():
    """Lights written before they could tilt replay bit for bit: z = 0 normalises by hypot of
    two, as the in-plane Light did (hypot of three may round differently)."""
    rng = np.random.default_rng(35)
    for _ in range(2000):
        x, y = (10.0 ** rng.uniform(-3, 3)) * rng.normal(size=2)
        n = math.hypot(x, y)
        old = (x, y) if abs(n - 1.0) <= 8 * 2.0**-52 else (x / n, y / n)
        assert Light(x, y) == Light(x, y, 0.0) == Light.from_vector([x, y, 0.0])
        assert (Light(x, y).x, Light(x, y).y, Light(x, y).z) == (*old, 0.0)


def test_azimuth_and_elevation_round_trip():
    rng = np.random.default_rng(7)
    for az, el in zip(rng.uniform(-179, 179, 300), rng.uniform(0.5, 89.5, 300)):
        light = Light.from_angle(az, el)
        assert abs(light.angle - az) < 1e-9 and abs(light.elevation - el) < 1e-9
        assert abs(np.linalg.norm(light.direction) - 1.0) < 1e-15
    assert Light.from_angle(123.0, 90.0) == Light(0.0, 0.0, 1.0)
    assert Light.from_angle(30.0) == Light(math.cos(math.radians(30)), math.sin(math.radians(30)))
    assert Light.from_angle(30.0).in_plane and not Light.from_angle(30.0, 1.0).in_plane
    with pytest.raises(ParameterError, match="between 0 and 90"):
        Light.from_angle(0.0, 91.0)
    # A drag keeps the elevation it is given; in the plane it is the thesis' drag, as before.
    assert Light.from_drag([0, 0], [2.0, 0.0]) == Light(1.0, 0.0)
    d = Light.from_drag([0, 0], [0.0, 3.0], elevation=60.0)
    assert abs(d.angle - 90.0) < 1e-12 and abs(d.elevation - 60.0) < 1e-12


# --- the document and its file ----------------------------------------------------------------


def test_set_light_keeps_z_is_one_undo_step_and_replays(fan_host):
    doc = _doc(fan_host)
    before = doc.light
    doc.execute({"command": "set_light", "direction": [0.0, 0.0, 1.0]})
    assert doc.light == Light(0.0, 0.0, 1.0) and doc.journal()[-1]["direction"] == [0.0, 0.0, 1.0]
    doc.undo_stack.undo()
    assert doc.light == before
    doc.undo_stack.redo()
    data = json.loads(ff.dumps(doc))
    assert data["version"] == ff.FORMAT_VERSION == 2 and data["snapshot"]["light"] == [0.0, 0.0, 1.0]
    again = ff.document_from_dict(data, "t", host=fan_host)
    assert again.light == doc.light
    assert ff.compare(again, ff.replay_journal(*ff.validate_header(data, "t"), host=fan_host)) == []


def test_a_header_light_with_z_shades_differently_now(fan_host):
    """The issue's observation: a header light [0.5, 0.5, 0.707] rendered exactly like
    [0.707, 0.707, 0] (mean pixel difference 0). In a version 2 file it is the tilted light."""
    from sketchforge.geometry.raster import render_top

    data = json.loads(ff.dumps(_doc(fan_host)))
    pictures = {}
    for name, light in (("tilted", [0.5, 0.5, 0.707]), ("plane", [0.707, 0.707, 0.0]), ("overhead", [0.0, 0.0, 1.0])):
        d = dict(data, light=light)
        d.pop("snapshot")
        doc = ff.document_from_dict(d, "t", host=fan_host)
        pictures[name] = render_top([doc.layer("a").mesh], doc.light.direction, size=96).astype(float)
    assert np.abs(pictures["tilted"] - pictures["plane"]).mean() > 5.0
    assert np.abs(pictures["overhead"] - pictures["tilted"]).mean() > 5.0


def test_a_version_1_file_keeps_its_in_plane_meaning(fan_host):
    """Before version 2 a z component was dropped: a version 1 file with tilted lights (written
    by hand) still opens with the in-plane lights it meant, and is saved as version 2 with
    entries that say so; a version 1 file as the app wrote it (z = 0) keeps its journal as
    written."""
    journal = [
        {"command": "add_layer", "id": "a", "name": "A"},
        {"command": "set_light", "direction": [0.6, 0.0, 0.8]},
        {"command": "macro", "text": "two", "children": [
            {"command": "set_light", "direction": [0.0, 1.0, 0.0]},
            {"command": "set_light", "direction": [0.0, 3.0, -4.0]},
        ]},
    ]
    v1 = {"format": "sketchforge", "version": 1, "light": [0.5, 0.5, 0.707], "journal": journal}
    doc = ff.document_from_dict(v1, "old.json", host=fan_host)
    assert doc.initial_light == Light(0.5, 0.5) and doc.light == Light(0.0, 1.0)
    assert doc.journal()[1]["direction"] == [0.6, 0.0]
    saved = json.loads(ff.dumps(doc))
    assert saved["version"] == 2 and saved["light"] == Light(0.5, 0.5).to_list()
    again = ff.document_from_dict(saved, "new.json", host=fan_host, use_snapshot=False)
    assert again.light == doc.light and again.initial_light == doc.initial_light
    # A version 1 snapshot's light likewise.
    v1s = dict(v1, snapshot={"light": [0.0, 0.6, 0.8], "layers": []})
    assert ff.document_from_dict(v1s, "old.json", host=fan_host).light == Light(0.0, 1.0)
    # As the app wrote it: unchanged, bit for bit.
    app_made = {"format": "sketchforge", "version": 1, "light": [0.7071, 0.7071, 0.0],
                "journal": [{"command": "set_light", "direction": [0.6, 0.8, 0.0]}]}
    doc = ff.document_from_dict(app_made, "old.json", host=fan_host)
    assert doc.journal() == app_made["journal"] and doc.light == Light(0.6, 0.8)


def test_a_file_from_a_newer_version_is_refused_by_an_old_reader_message(fan_host):
    data = json.loads(ff.dumps(_doc(fan_host)))
    data["version"] = 3
    with pytest.raises(DocumentFormatError, match="format version 3"):
        ff.document_from_dict(data, "t", host=fan_host)


# --- render --light and info ------------------------------------------------------------------


def test_render_light_option(tmp_path, fan_host, monkeypatch):
    import sketchforge.plugins.manager as manager

    monkeypatch.setattr(manager, "default_host", lambda: fan_host)
    doc = _doc(fan_host)
    doc.execute({"command": "set_light", "direction": [0.0, 0.0, 1.0]})
    path = tmp_path / "d.json"
    ff.save(doc, path)
    import sketchforge.geometry.raster as raster

    written = {}
    real_write = raster.write_png
    monkeypatch.setattr(raster, "write_png", lambda p, rgb: (written.__setitem__(str(p), rgb), real_write(p, rgb)))
    shots = {}
    for name, extra in (("doc", []), ("side", ["--light", "1,0,0"]), ("tilted", ["--light=-0.5,0.5,0.7"]),
                        ("same", ["--light", "0,0,2"])):
        out = tmp_path / f"{name}.png"
        res = run_cli("render", path, "--png", out, "--size", "64", *extra)
        assert res.rc == 0, res.err
        assert out.exists()
        shots[name] = np.asarray(written[str(out)], dtype=float)
    assert np.array_equal(shots["doc"], shots["same"])  # the document's own overhead light
    assert np.abs(shots["doc"] - shots["side"]).mean() > 5.0
    assert np.abs(shots["tilted"] - shots["side"]).mean() > 5.0
    assert ff.load(path, host=fan_host).light == Light(0.0, 0.0, 1.0)  # the file is not touched
    assert_one_line_error(run_cli("render", path, "--png", tmp_path / "x.png", "--light", "1,0,-1"),
                          "--light '1,0,-1'", "must face the viewer")
    assert_one_line_error(run_cli("render", path, "--png", tmp_path / "x.png", "--light", "up"),
                          "--light must be 2 or 3 numbers")
    assert not (tmp_path / "x.png").exists()
    res = run_cli("info", path)
    assert res.rc == 0 and "light (0.0000, 0.0000, 1; elevation 90.0°)" in res.out


# --- the sculpt under a tilted light ------------------------------------------------------------


def test_a_sculpt_under_a_tilted_light_uses_it_keeps_it_and_replays(tmp_path, real_host):
    """The edit solves with the 3D light (a different surface than under its in-plane
    shadow), the layer keeps that light for re-applying it, a parameter change re-applies it
    with it even after the light moved, a move turns only its azimuth, and the saved file
    replays bit for bit."""
    from sculpt_helpers import isophote_stroke

    meshes = {}
    for name, v in (("tilted", [0.5, 0.3, 0.8]), ("plane", [0.5, 0.3, 0.0])):
        doc = _doc(real_host, resolution=0.06)
        doc.execute({"command": "set_light", "direction": v})
        mesh = doc.layer("a").mesh
        stroke, _, _ = isophote_stroke(mesh, [0.3, 0.05], offset=0.12, half=0.3, light=doc.light.direction)
        doc.execute({"command": "sculpt_isophote", "layer": "a", "pick": [0.3, 0.05], "band": 0.3, "stroke": stroke.tolist()})
        meshes[name] = doc.layer("a").mesh.V[:, 2].copy()
        if name == "tilted":
            tilted_doc = doc
    assert np.abs(meshes["tilted"] - meshes["plane"]).max() > 1e-3
    doc = tilted_doc
    edit = doc.layer("a").edits[-1]
    assert edit["light"] == doc.light.to_list() and edit["light"][2] > 0.8
    path = tmp_path / "tilted.json"
    ff.save(doc, path)
    res = run_cli("replay", path, "--check")
    assert res.rc == 0 and "replay matches the snapshot" in res.err, res.err
    # Re-applied with its own light after the document's light moved overhead.
    doc.execute({"command": "set_light", "direction": [0.0, 0.0, 1.0]})
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.2}})
    assert not np.array_equal(doc.layer("a").mesh.V[:, 2], meshes["tilted"])
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.0}})
    assert doc.layer("a").edits[-1]["light"] == edit["light"]
    assert np.array_equal(doc.layer("a").mesh.V[:, 2], meshes["tilted"])
    # A rotation by 90° and a scale turn the edit's azimuth; elevation and length stay.
    a = math.radians(90.0)
    doc.execute({"command": "transform_layer", "layer": "a",
                 "matrix": [[2 * math.cos(a), -2 * math.sin(a), 0.0], [2 * math.sin(a), 2 * math.cos(a), 0.0]]})
    moved = doc.layer("a").edits[-1]["light"]
    assert abs(np.linalg.norm(moved) - 1.0) < 1e-12 and moved[2] == edit["light"][2]
    assert abs(math.degrees(math.atan2(moved[1], moved[0])) - (math.degrees(math.atan2(edit["light"][1], edit["light"][0])) + 90)) < 1e-9


def test_an_overhead_edit_follows_a_transform_unchanged():
    from sketchforge_isophote_tool.command import SculptIsophote

    entry = {"command": "sculpt_isophote", "layer": "a", "pick": [0.1, 0.1], "band": 0.2,
             "stroke": [[0.0, 0.0], [0.1, 0.0]], "light": [0.0, 0.0, 1.0]}
    moved = SculptIsophote.transform_edit(entry, [[0.0, -1.5, 1.0], [1.5, 0.0, 0.0]], 1.5)
    assert moved["light"] == [0.0, 0.0, 1.0] and moved["band"] == pytest.approx(0.3)


def test_the_in_plane_drag_turns_a_raised_light_and_keeps_its_elevation(fan_host):
    """The canvas's light drag (LightTool): in the plane as before; a raised light turns about
    the view axis, keeping its elevation, one undo step per drag; straight overhead there is
    nothing to turn: no command, and the tool says why."""
    from sketchforge.tools import LightTool

    def drag(tool, points):
        tool.press(points[0])
        for p in points[1:-1]:
            tool.move(p)
        tool.release(points[-1])

    doc = Document(host=fan_host)
    doc.execute({"command": "set_light", "direction": Light.from_angle(10.0, 40.0).to_list()})
    n = doc.undo_stack.count()
    drag(LightTool(doc), [(0.3, 0.0), (0.0, 0.3), (-0.3, 0.1)])
    assert abs(doc.light.elevation - 40.0) < 1e-9
    assert abs(doc.light.angle - math.degrees(math.atan2(0.1, -0.3))) < 1e-9
    assert doc.undo_stack.count() == n + 1
    doc.undo_stack.undo()
    assert doc.light == Light.from_angle(10.0, 40.0)
    doc.execute({"command": "set_light", "direction": [0.0, 0.0, 1.0]})
    n = doc.undo_stack.count()
    tool = LightTool(doc)
    drag(tool, [(0.3, 0.0), (0.0, 0.3)])
    assert doc.undo_stack.count() == n and doc.light == Light(0.0, 0.0, 1.0)
    assert "straight overhead" in tool.message
