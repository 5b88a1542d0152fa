"""The public test helpers of the shipped pytest plugin (issue 37): the layer under a point, the
isophote through a pick and a sculpt-edit builder, used as a plugin author would use them."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from sketchforge.plugin_api import SculptError, isophote_through, layer_at


@pytest.fixture
def doc(make_sketchforge_host, make_sketchforge_document):
    pytest.importorskip("sketchforge_isophote_tool")
    host = make_sketchforge_host(installed=("inflate", "isophote_tool"))
    d = make_sketchforge_document(host, resolution=0.05)
    d.execute({"command": "set_light", "direction": [0.6, 0.5, 0.6245]})
    return d


def test_layer_at_finds_the_front_most_visible_layer_and_not_its_holes(make_sketchforge_host, make_sketchforge_document,
                                                                         sketchforge_layer_at):
    assert sketchforge_layer_at is layer_at
    host = make_sketchforge_host(installed=("inflate",))
    d = make_sketchforge_document(host, resolution=0.08)  # layer "a": an ellipse 1 x 0.7
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    d.execute({"command": "add_layer", "id": "b"})
    d.execute({"command": "set_contour", "layer": "b", "points": np.c_[0.5 + 0.3 * np.cos(t), 0.3 * np.sin(t)].tolist(),
               "closed": True, "holes": [np.c_[0.5 + 0.1 * np.cos(t), 0.1 * np.sin(t)].tolist()]})
    d.execute({"command": "set_inflate_params", "layer": "b", "params": {"resolution": 0.03}})
    rng = np.random.default_rng(5)
    for p in rng.uniform([-1.2, -0.9], [1.2, 0.9], (200, 2)):
        in_a = (p[0] / 1.0) ** 2 + (p[1] / 0.7) ** 2 < 0.97
        r_b = np.hypot(p[0] - 0.5, p[1])
        in_b = 0.11 < r_b < 0.29  # clear of the rims by more than a triangle's sagitta
        out_all = (p[0] / 1.0) ** 2 + (p[1] / 0.7) ** 2 > 1.03 and r_b > 0.31
        got = layer_at(d, p)
        if in_b:
            assert got == "b", p
        elif in_a and (r_b < 0.09 or r_b > 0.31):
            assert got == "a", p  # in b's hole, a shows through
        elif out_all:
            assert got is None, p
    d.execute({"command": "set_layer_visible", "layer": "b", "visible": False})
    assert layer_at(d, [0.5 + 0.2, 0.0]) == "a" and layer_at(d, [np.nan, 0.0]) is None


def test_the_isophote_through_a_pick_is_the_level_of_r_at_the_pick(doc, sketchforge_isophote):
    from sketchforge.plugin_api import LAMBERTIAN, TriangleLocator, evaluate_pq, gradient_operators, slopes_from_heights

    mesh = doc.layer("a").mesh
    V2 = mesh.V[:, :2]
    p, q = slopes_from_heights(*gradient_operators(V2, mesh.F), mesh.V[:, 2])
    E, _, _ = evaluate_pq(LAMBERTIAN, p, q, doc.light.direction)
    loc = TriangleLocator(mesh.V, mesh.F)
    rng = np.random.default_rng(11)
    for pick in rng.uniform([-0.6, -0.4], [0.6, 0.4], (8, 2)):
        c, line = sketchforge_isophote(doc, "a", pick)
        assert (c, line.tobytes()) == (lambda r: (r[0], r[1].tobytes()))(isophote_through(mesh, pick, doc.light.direction))
        face, bary = loc.locate(pick[None])
        at_pick = float((E[mesh.F[face[0]]] * bary[0]).sum())
        assert c == pytest.approx(max(at_pick, 0.0), abs=1e-12)
        assert shapely.LineString(line).distance(shapely.Point(pick)) < 0.05  # through the pick (to a triangle)
        f, b = loc.locate(line[1:-1])
        along = (E[mesh.F[f]] * b).sum(axis=1)
        assert np.abs(along - c).max() < 1e-9  # on the level set, all along
    with pytest.raises(SculptError, match="outside the layer"):
        sketchforge_isophote(doc, "a", [3.0, 3.0])


def test_a_built_sculpt_edit_moves_the_isophote_towards_its_stroke(doc, make_sculpt_edit, sketchforge_isophote):
    pick = np.array([0.3, 0.15])
    entry = make_sculpt_edit(doc, "a", pick, offset=0.06, half=0.2)
    assert set(entry) == {"command", "layer", "pick", "band", "stroke"} and entry["command"] == "sculpt_isophote"
    stroke = shapely.LineString(entry["stroke"])
    c, old = sketchforge_isophote(doc, "a", pick)
    assert stroke.hausdorff_distance(shapely.LineString(old)) > 0.05
    doc.execute(entry)
    assert len(doc.layer("a").edits) == 1
    _, new = sketchforge_isophote(doc, "a", np.asarray(stroke.interpolate(0.5, normalized=True).coords[0]))
    samples = [stroke.interpolate(s, normalized=True) for s in np.linspace(0.2, 0.8, 7)]
    before = np.mean([shapely.LineString(old).distance(s) for s in samples])
    after = np.mean([shapely.LineString(new).distance(s) for s in samples])
    assert after < 0.5 * before
