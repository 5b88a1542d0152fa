"""The isophote sculpt gesture tool (``SculptIsophoteTool``), driven headlessly: pick, band,
options and stroke in document coordinates, no window. The Qt controller drives this same tool
(tests/qt/test_qt_sculpt.py checks the app end to end)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from sketchforge.errors import SculptError

TOOL = "sculpt_isophote"
RING = [[np.cos(t), 0.7 * np.sin(t)] for t in np.linspace(0, 2 * np.pi, 200, endpoint=False)]
PICK = [0.2, 0.1]
STROKE = [[0.1, -0.3], [0.15, -0.1], [0.22, 0.1], [0.3, 0.3]]


def ellipse_doc(host):
    """An inflated ellipse "body" (1 x 0.7) under the default light."""
    from sketchforge.document.document import Document

    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": RING, "closed": True})
    return doc


def make_tool(doc, **kw):
    return doc.host.tools[TOOL](doc, **kw)


def mean_edge(mesh) -> float:
    F = mesh.F
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    return float(np.linalg.norm(mesh.V[e[:, 0], :2] - mesh.V[e[:, 1], :2], axis=1).mean())


def test_the_plugin_registers_the_tool(real_host):
    from sketchforge_isophote_tool.tool import SculptIsophoteTool

    assert real_host.tools[TOOL] is SculptIsophoteTool


def test_pick_fills_the_overlay_with_the_isophote_through_the_pick_and_its_band(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.2)
    assert tool.pick_at(PICK), tool.message
    ov = tool.overlay
    assert ov["layer"] == "body" and tool.layer_id == "body"
    assert np.array_equal(tool.pick, PICK)
    iso = ov["isophote"]
    assert iso.dtype == np.float64 and iso.ndim == 2 and iso.shape[1] == 2 and len(iso) > 2
    h = mean_edge(doc.layer("body").mesh)  # one edge length
    assert shapely.LineString(iso).distance(shapely.Point(PICK)) < h
    # the isovalue is the shading at the pick, under the document's light
    assert 0.0 < ov["isovalue"] == tool.isovalue <= 1.0
    # the band: polygon rings around the isophote, containing the pick, inside the layer
    assert ov["band"] and all(r.ndim == 2 and r.shape[1] == 2 and np.array_equal(r[0], r[-1]) for r in ov["band"])
    band = shapely.Polygon(ov["band"][0])
    assert band.contains(shapely.Point(PICK))
    mesh = doc.layer("body").mesh
    assert shapely.Polygon(mesh.V[mesh.boundary, :2]).buffer(1e-9).contains(band)
    assert doc.undo_stack.count() == 2  # picking edits nothing

    # set_band recomputes the band overlay
    area = band.area
    assert tool.set_band(0.1) and tool.band == 0.1
    assert shapely.Polygon(tool.overlay["band"][0]).area < area


def test_pick_uses_the_commands_reflectance_model(real_host):
    from sketchforge_isophote_tool.command import _model
    from sketchforge_isophote_tool.isophote import picked_isophote
    from sketchforge_isophote_tool.layerdata import layer_data

    doc = ellipse_doc(real_host)
    tool = make_tool(doc)
    assert tool.pick_at(PICK)
    ld = layer_data(doc.layer("body").mesh, doc.light.direction, _model(doc, "lambertian"))
    c, iso = picked_isophote(ld, PICK)
    assert tool.isovalue == c
    assert np.array_equal(tool.overlay["isophote"], np.asarray(iso.coords))
    with pytest.raises(SculptError, match="no reflectance model"):
        tool.set_options({"model": "no_such_model"})
    with pytest.raises(SculptError, match="unknown"):
        tool.set_options({"colour": "red"})
    assert tool.options == {} and tool.isovalue == c  # a refused option changes nothing
    assert "model" not in tool.command_dict(STROKE)


def test_a_stroke_pushes_the_same_edit_as_the_headless_command(real_host):
    doc, ref = ellipse_doc(real_host), ellipse_doc(real_host)
    assert doc.layer("body").mesh.identical(ref.layer("body").mesh)
    tool = make_tool(doc, band=0.3)
    # a click picks
    tool.press(PICK)
    assert tool.release(PICK) is None
    assert tool.layer_id == "body" and np.array_equal(tool.pick, PICK)
    # press-move-release redraws the isophote and pushes the command synchronously
    tool.press(STROKE[0])
    for p in STROKE[1:-1]:
        tool.move(p)
    assert np.array_equal(tool.overlay["stroke"], STROKE[:-1])
    cmd = tool.release(STROKE[-1])
    assert cmd is not None and doc.undo_stack.count() == 3
    entry = {"command": "sculpt_isophote", "layer": "body", "pick": PICK, "band": 0.3, "stroke": STROKE}
    assert cmd.to_dict() == entry
    ref.execute(entry)
    got, want = doc.layer("body").mesh, ref.layer("body").mesh
    assert np.array_equal(got.F, want.F)
    assert np.array_equal(got.V, want.V)  # bit for bit
    assert not np.array_equal(got.V[:, 2], ellipse_doc(real_host).layer("body").mesh.V[:, 2])
    # back to picking
    assert tool.pick is None and tool.overlay == {}
    doc.undo_stack.undo()
    assert doc.layer("body").mesh.identical(ellipse_doc(real_host).layer("body").mesh)


def test_command_for_builds_without_pushing(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.25)
    with pytest.raises(SculptError, match="pick an isophote first"):
        tool.command_for(STROKE)
    assert tool.pick_at(PICK)
    cmd = tool.command_for(STROKE)
    assert doc.undo_stack.count() == 2
    assert cmd.to_dict() == {"command": "sculpt_isophote", "layer": "body", "pick": PICK, "band": 0.25, "stroke": STROKE}


def test_a_pick_off_the_shapes_gives_a_message_and_no_state(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc)
    assert tool.pick_at(PICK)
    assert not tool.pick_at([3.0, 3.0])
    assert "not on a visible shape" in tool.message
    assert tool.pick is None and tool.layer_id is None and tool.isovalue is None and tool.overlay == {}
    # a drag without a pick pushes nothing and says why
    tool.press([0.1, 0.1])
    tool.move([0.2, 0.2])
    assert tool.release([0.3, 0.3]) is None
    assert "pick an isophote first" in tool.message and doc.undo_stack.count() == 2
    # a hidden layer cannot be picked
    doc.execute({"command": "set_layer_visible", "layer": "body", "visible": False})
    assert not tool.pick_at(PICK) and tool.pick is None


@pytest.mark.parametrize("radius", [0.0, -0.2, float("nan")])
def test_a_band_that_is_not_positive_gives_a_message(real_host, radius):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.2)
    assert tool.pick_at(PICK)
    band = tool.overlay["band"]
    assert not tool.set_band(radius)
    assert "positive" in tool.message
    assert tool.band == 0.2 and tool.overlay["band"] is band  # the old band stays
