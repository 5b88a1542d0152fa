"""The transform, mirror and duplicate commands' rules, each on both sides of its boundary
(issue 39, point 1: a third of the one-line bugs planted in these commands went unnoticed).

Checked against closed forms on a fast fan-inflated layer: where a point goes under a
matrix, which matrices are refused, how heights scale, where a mirror's axis lies, where a copy
lands in the list and what it is called, and that every one of them is one undo step that
journals and replays bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document import commands as C
from sketchforge.errors import DocumentFormatError, ParameterError

T = np.linspace(0.0, 2.0 * np.pi, 40, endpoint=False)
BLOB = np.c_[1.0 + 0.5 * np.cos(T), 2.0 + 0.3 * np.sin(T) + 0.05 * np.cos(3 * T)]
HOLE = np.c_[1.0 + 0.1 * np.cos(T[::5]), 2.0 + 0.05 * np.sin(T[::5])]
RNG = np.random.default_rng(3903)


def doc_with(fan_host, *ids, points=BLOB):
    doc = Document(host=fan_host)
    for k, lid in enumerate(ids):
        doc.execute({"command": "add_layer", "id": lid, "name": lid.upper()})
        doc.execute({"command": "set_contour", "layer": lid, "points": (points + [3.0 * k, 0.0]).tolist(), "closed": True})
    return doc


# --- matrices ------------------------------------------------------------------------------------


def test_check_affine_accepts_what_keeps_a_part_and_refuses_the_rest():
    assert C.check_affine([[1, 0, 2], [0, 1, 3]]).dtype == np.float64
    for ok in ([[1e-3, 0, 0], [0, 1e-3, 0]], [[100.0, 0, 0], [0, 100.0, 0]], [[0, -1, 0], [1, 0, 0]],
               [[2, 1, 0], [0, 0.5, 0]]):
        C.check_affine(ok)  # det 1e-6 and 1e4 are the inclusive ends
    with pytest.raises(ParameterError, match="negative determinant"):
        C.check_affine([[-1, 0, 0], [0, 1, 0]])
    with pytest.raises(ParameterError, match="negative determinant"):
        C.check_affine([[0, 1, 0], [1, 0, 0]])  # a swap of x and y mirrors
    for _det, m in ((0.9e-6, [[0.9e-3, 0, 0], [0, 1e-3, 0]]), (1.01e4, [[101.0, 0, 0], [0, 100.0, 0]]),
                   (0.0, [[1, 1, 0], [1, 1, 0]])):
        with pytest.raises(ParameterError, match="scales the part's area by"):
            C.check_affine(m)
    for bad in ([[1, 0], [0, 1]], [[1, 0, 0]], [[1, 0, 0], [0, 1, 0], [0, 0, 1]]):
        with pytest.raises(ParameterError, match="2x3"):
            C.check_affine(bad)
    for bad in ([[1, 0, float("nan")], [0, 1, 0]], [[float("inf"), 0, 0], [0, 1, 0]]):
        with pytest.raises(ParameterError, match="finite"):
            C.check_affine(bad)
    with pytest.raises(ParameterError, match="matrix of numbers"):
        C.check_affine([[1, 0, "x"], [0, 1, 0]])


def test_transform_points_is_the_affine_map_and_a_pure_move_adds_only():
    P = RNG.normal(size=(30, 2))
    A = np.array([[0.8, -0.3, 1.5], [0.2, 1.1, -0.7]])
    expected = np.array([[A[0, 0] * x + A[0, 1] * y + A[0, 2], A[1, 0] * x + A[1, 1] * y + A[1, 2]] for x, y in P])
    assert np.allclose(C.transform_points(A, P), expected, atol=1e-14)
    move = np.array([[1.0, 0.0, 0.1], [0.0, 1.0, -0.3]])
    assert C.transform_points(move, P).tobytes() == (P + [0.1, -0.3]).tobytes()
    assert C.transform_points(A, P[0]).shape == (1, 2)


def test_compose_scale_and_rotate_about_a_centre():
    c = np.array([2.0, -1.0])
    S = C.scale_about(c, 2.0, 3.0)
    assert np.allclose(C.transform_points(S, c), c)
    assert np.allclose(C.transform_points(S, c + [1.0, 1.0]), c + [2.0, 3.0])
    assert np.allclose(C.scale_about(c, 2.0), C.scale_about(c, 2.0, 2.0))
    R = C.rotate_about(c, np.pi / 2)
    assert np.allclose(C.transform_points(R, c), c)
    assert np.allclose(C.transform_points(R, c + [1.0, 0.0]), c + [0.0, 1.0])  # counter-clockwise
    # compose: the first matrix acts first
    move = [[1, 0, 1.0], [0, 1, 0.0]]
    p = np.array([[3.0, -1.0]])
    assert np.allclose(C.transform_points(C.compose_affine(move, R), p), C.transform_points(R, p + [1.0, 0.0]))
    assert np.allclose(C.transform_points(C.compose_affine(R, move), p), C.transform_points(R, p) + [1.0, 0.0])
    assert np.allclose(C.compose_affine(), np.eye(3)[:2])


# --- transform_layer -----------------------------------------------------------------------------


@pytest.mark.parametrize("matrix", [[[1, 0, 0.3], [0, 1, -0.2]], [[0.6, -0.8, 0.2], [0.8, 0.6, 0.1]],
                                    [[2.0, 0.5, 0.0], [0.0, 1.5, 0.4]], [[0.5, 0, 0], [0, 0.5, 0]]])
def test_a_layer_moves_with_its_stroke_holes_and_mesh_and_heights_scale_by_the_linear_size(fan_host, matrix,
                                                                                            assert_replays):
    doc = doc_with(fan_host, "a")
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0], [0, 1, 0]]})  # a no-op step
    old = doc.layer("a")
    A = np.array(matrix, dtype=np.float64)
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": matrix})
    new = doc.layer("a")
    L = A[:, :2]
    det = L[0, 0] * L[1, 1] - L[0, 1] * L[1, 0]
    assert np.allclose(new.points, old.points @ L.T + A[:, 2], atol=1e-13)
    assert np.allclose(new.mesh.V[:, :2], old.mesh.V[:, :2] @ L.T + A[:, 2], atol=1e-13)
    scale = 1.0 if np.array_equal(L, np.eye(2)) else np.sqrt(det)
    assert np.allclose(new.mesh.V[:, 2], old.mesh.V[:, 2] * scale, atol=1e-14)
    assert new.mesh.F is old.mesh.F and dict(new.params) == dict(old.params)  # no re-inflation
    assert doc.undo_stack.undo_text() == new_text(matrix)
    doc.undo_stack.undo()
    assert doc.layer("a") is old
    doc.undo_stack.redo()
    assert_replays(doc)


def new_text(matrix):
    return C.TransformLayer(layer="a", matrix=matrix).text()


def test_a_transforms_name_says_what_it_does():
    assert new_text([[1, 0, 5], [0, 1, 5]]) == "Move layer"
    assert new_text([[2, 0, 0], [0, 2, 0]]) == "Scale layer"
    assert new_text([[0.6, -0.8, 0], [0.8, 0.6, 0]]) == "Rotate layer"
    assert new_text([[-1, 0, 0], [0, -1, 0]]) == "Rotate layer"  # a half turn, not a negative scale
    assert new_text([[2, 0, 0], [0, 3, 0]]) == "Transform layer"
    assert new_text([[1, 1, 0], [0, 1, 0]]) == "Transform layer"  # a shear has det 1 but is no rotation
    assert C.TranslateLayer(layer="a", offset=(1, 2)).text() == "Move layer"


def test_transform_and_translate_entries_are_checked_when_read():
    ok = C.TransformLayer.from_dict({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 2], [0, 1, 3]]})
    assert ok.matrix == [[1.0, 0.0, 2.0], [0.0, 1.0, 3.0]] and ok.to_dict()["matrix"] == [[1.0, 0.0, 2.0], [0.0, 1.0, 3.0]]
    for bad in ([[1, 0, 2]], [[1, 0], [0, 1]], [[1, 0, True], [0, 1, 0]], [[1, 0, "2"], [0, 1, 0]], [1, 0, 2, 0, 1, 3]):
        with pytest.raises(DocumentFormatError, match="'matrix' must be"):
            C.TransformLayer.from_dict({"command": "transform_layer", "layer": "a", "matrix": bad})
    with pytest.raises(ParameterError):
        C.TransformLayer.from_dict({"command": "transform_layer", "layer": "a", "matrix": [[-1, 0, 0], [0, 1, 0]]})
    t = C.TranslateLayer.from_dict({"command": "translate_layer", "layer": "a", "offset": [0.5, -1]})
    assert t.offset == [0.5, -1.0] and t.to_dict() == {"command": "translate_layer", "layer": "a", "offset": [0.5, -1.0]}
    for bad in ([1], [1, 2, 3]):
        with pytest.raises(DocumentFormatError, match="'offset' must be 2"):
            C.TranslateLayer.from_dict({"command": "translate_layer", "layer": "a", "offset": bad})
    for bad in ((1, float("nan")), (1, 2, 3), "ab"):
        with pytest.raises((ParameterError, ValueError)):
            C.TranslateLayer(layer="a", offset=bad)


def test_a_translate_is_bit_for_bit_a_pure_move(fan_host):
    a = doc_with(fan_host, "a")
    b = doc_with(fan_host, "a")
    a.execute({"command": "translate_layer", "layer": "a", "offset": [0.125, -0.375]})
    b.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.125], [0, 1, -0.375]]})
    assert a.layer("a").same_state(b.layer("a"))
    assert a.layer("a").points.tobytes() == (BLOB + [0.125, -0.375]).tobytes()


# --- mirror_layer --------------------------------------------------------------------------------


def test_mirror_about_its_own_axis_a_number_and_twice_gives_the_stroke_back(fan_host, assert_replays):
    doc = doc_with(fan_host, "a")
    P = doc.layer("a").points
    cx = 0.5 * (P[:, 0].min() + P[:, 0].max())
    doc.execute({"command": "mirror_layer", "layer": "a", "axis": "own"})
    Q = doc.layer("a").points
    assert np.allclose(Q[:, 0], 2 * cx - P[:, 0]) and np.array_equal(Q[:, 1], P[:, 1])
    assert doc.layer("a").mesh is not None and doc.layer("a").edits == ()
    doc.execute({"command": "mirror_layer", "layer": "a", "axis": "own"})
    assert np.allclose(doc.layer("a").points, P, atol=1e-14)
    doc.execute({"command": "mirror_layer", "layer": "a", "axis": 4.0})
    assert np.allclose(doc.layer("a").points[:, 0], 8.0 - P[:, 0])
    assert_replays(doc)
    # a free part asked for its host's axis uses its own
    cmd = C.MirrorLayer(layer="a", axis="host")
    doc.push(cmd)
    assert cmd.used_axis == "own"
    R = doc.layer("a").points
    own = 0.5 * (R[:, 0].min() + R[:, 0].max())
    assert np.allclose(R[:, 0], 2 * own - (8.0 - P[:, 0]))


def test_a_mirror_takes_the_holes_along_and_refuses_a_layer_without_a_stroke(fan_host):
    doc = Document(host=fan_host)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    with pytest.raises(ParameterError, match="has no contour to mirror"):
        doc.execute({"command": "mirror_layer", "layer": "a"})
    assert C.mirror_axis_x(doc, doc.layer("a"), 2.5) == (2.5, "x")
    with pytest.raises(ParameterError, match="finite"):
        C.mirror_axis_x(doc, doc.layer("a"), float("inf"))
    with pytest.raises(ParameterError, match="'host', 'own' or a number"):
        C.mirror_axis_x(doc, doc.layer("a"), "left")
    with pytest.raises(ParameterError, match="'host', 'own' or a number"):
        C.mirror_axis_x(doc, doc.layer("a"), True)
    for bad in ("left", True, None):
        with pytest.raises(DocumentFormatError, match="'axis' must be"):
            C.MirrorLayer.from_dict({"command": "mirror_layer", "layer": "a", "axis": bad})
    old = C.MirrorLayer.from_dict({"command": "mirror_layer", "layer": "a"})
    assert old.axis == "own" and not old.find_twin and old.to_dict() == {"command": "mirror_layer", "layer": "a"}
    assert C.MirrorLayer(layer="a", axis="host", of="b").to_dict() == {"command": "mirror_layer", "layer": "a",
                                                                        "axis": "host", "of": "b"}
    assert C.MirrorLayer.from_dict({"command": "mirror_layer", "layer": "a", "axis": 2}).axis == 2.0


def test_an_attached_part_is_mirrored_about_its_hosts_axis(fan_host, assert_replays):
    doc = Document(host=fan_host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    body = np.c_[2.0 * np.cos(T), np.sin(T)]  # centred on x = 0, from -2 to 2
    doc.execute({"command": "set_contour", "layer": "body", "points": body.tolist(), "closed": True})
    doc.execute({"command": "add_layer", "id": "leg", "name": "Leg"})
    leg = np.array([[0.8, 0.2], [1.0, -1.8], [1.4, -1.8], [1.3, 0.2]])  # open: its junction on the body
    doc.execute({"command": "set_contour", "layer": "leg", "points": leg.tolist(), "closed": False})
    assert C.host_of(doc, doc.layer("leg")).id == "body"
    assert C.mirror_axis_x(doc, doc.layer("leg"), "host") == (pytest.approx(0.0, abs=1e-12), "host")
    cmd = C.MirrorLayer(layer="leg", axis="host")
    doc.push(cmd)
    assert cmd.used_axis == "host"
    assert np.allclose(doc.layer("leg").points, np.c_[-leg[:, 0], leg[:, 1]])
    assert_replays(doc)


# --- duplicate_layer -----------------------------------------------------------------------------


def test_a_copy_goes_just_in_front_by_default_named_and_numbered(fan_host, assert_replays):
    doc = doc_with(fan_host, "a", "b")
    first = doc.push(C.DuplicateLayer(layer="a"))
    assert doc.layer_ids() == ["a", first.new_id, "b"] and first.new_id.startswith("a_copy")
    copy = doc.layer(first.new_id)
    assert copy.name == "A copy" and copy.mesh is doc.layer("a").mesh and copy.points is doc.layer("a").points
    second = doc.push(C.DuplicateLayer(layer="a"))
    assert second.new_id != first.new_id and doc.layer_ids() == ["a", second.new_id, first.new_id, "b"]
    doc.execute({"command": "duplicate_layer", "layer": "b", "index": 0, "id": "front", "name": "Front"})
    assert doc.layer_ids()[0] == "front" and doc.layer("front").name == "Front"
    n = len(doc.layers)
    doc.execute({"command": "duplicate_layer", "layer": "b", "index": n, "id": "last"})
    assert doc.layer_ids()[-1] == "last"
    for bad in (-1, n + 2):
        with pytest.raises(ParameterError, match=f"layer index {bad} is outside 0..{n + 1}"):
            doc.execute({"command": "duplicate_layer", "layer": "b", "index": bad})
    with pytest.raises(ParameterError, match="already exists"):
        doc.execute({"command": "duplicate_layer", "layer": "b", "id": "a"})
    assert_replays(doc)
    before = doc.layer_ids()
    doc.undo_stack.undo()
    assert doc.layer_ids() == [i for i in before if i != "last"]
    doc.undo_stack.redo()
    assert doc.layer("last") is not None and doc.layer_ids() == before


def test_a_copy_moved_aside_moves_its_stroke_mesh_and_holes(fan_host):
    doc = doc_with(fan_host, "a")
    src = doc.layer("a")
    copy = doc.layer(doc.push(C.DuplicateLayer(layer="a", offset=(0.25, -0.5))).new_id)
    assert copy.points.tobytes() == (src.points + [0.25, -0.5]).tobytes()
    assert np.array_equal(copy.mesh.V[:, :2], src.mesh.V[:, :2] + [0.25, -0.5])
    assert np.array_equal(copy.mesh.V[:, 2], src.mesh.V[:, 2])
    for bad in ([1.0], [1.0, float("nan")], [1, 2, 3]):
        with pytest.raises(ParameterError, match="offset must be two finite numbers"):
            doc.push(C.DuplicateLayer(layer="a", offset=bad))
    d = C.DuplicateLayer(layer="a", new_id="z", new_name="Z", index=0, offset=(1, 2)).to_dict()
    assert d == {"command": "duplicate_layer", "layer": "a", "id": "z", "name": "Z", "index": 0, "offset": [1.0, 2.0]}
    assert C.DuplicateLayer.from_dict(d).to_dict() == d
    with pytest.raises(DocumentFormatError, match="'offset' must be 2 numbers"):
        C.DuplicateLayer.from_dict({"command": "duplicate_layer", "layer": "a", "offset": [1, 2, 3]})


def test_redo_puts_back_the_very_copy_and_a_copy_follows_its_own_source(fan_host):
    doc = doc_with(fan_host, "a")
    cmd = doc.push(C.DuplicateLayer(layer="a", offset=(0.25, -0.5)))
    made = doc.layer(cmd.new_id)
    doc.undo_stack.undo()
    assert cmd.new_id not in doc.layer_ids()
    doc.undo_stack.redo()
    assert doc.layer(cmd.new_id) is made  # redo rebuilds nothing: the moved mesh is made once
    # The same command done on another document (a macro replayed on a fresh one) copies
    # that document's layer, never the copy it made before.
    other = doc_with(fan_host, "a", points=0.5 * BLOB)
    cmd.do(other)
    got = other.layer(cmd.new_id)
    assert got.points.tobytes() == (0.5 * BLOB + [0.25, -0.5]).tobytes()
    assert np.array_equal(got.mesh.V[:, :2], other.layer("a").mesh.V[:, :2] + [0.25, -0.5])
    assert doc.layer(cmd.new_id) is made


def test_a_copy_moved_aside_is_the_twin_a_mirror_places(fan_host):
    doc = Document(host=fan_host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": np.c_[2.0 * np.cos(T), np.sin(T)].tolist(),
                 "closed": True})
    doc.execute({"command": "add_layer", "id": "leg", "name": "Leg"})
    leg = np.array([[0.8, 0.2], [1.0, -1.8], [1.4, -1.8], [1.3, 0.2]])
    doc.execute({"command": "set_contour", "layer": "leg", "points": leg.tolist(), "closed": False})
    cid = doc.push(C.DuplicateLayer(layer="leg", offset=(0.4, 0.1))).new_id
    assert C.twin_source(doc, doc.layer(cid)).id == "leg"
    cmd = C.MirrorLayer(layer=cid, axis="host")
    doc.push(cmd)
    assert cmd.of == "leg" and cmd.to_dict()["of"] == "leg"
    assert np.allclose(doc.layer(cid).points, np.c_[-leg[:, 0], leg[:, 1]])  # the original's twin
    # a copy left in place is no twin; nor is one whose stroke changed shape
    doc.execute({"command": "duplicate_layer", "layer": "leg", "id": "inplace"})
    assert C.twin_source(doc, doc.layer("inplace")) is None
    bent = leg + [0.3, 0.0]
    bent[1, 1] -= 0.2
    doc.execute({"command": "add_layer", "id": "other", "name": "Other"})
    doc.execute({"command": "set_contour", "layer": "other", "points": bent.tolist(), "closed": False})
    assert C.twin_source(doc, doc.layer("other")) is None


def test_a_mirror_takes_a_layers_holes_along(real_host):
    doc = Document(host=real_host)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"resolution": 0.1}})
    outline = np.c_[1.0 + np.cos(T), 2.0 + 0.8 * np.sin(T)]
    hole = np.c_[1.3 + 0.2 * np.cos(T[::4]), 2.1 + 0.15 * np.sin(T[::4])]
    doc.execute({"command": "set_contour", "layer": "a", "points": outline.tolist(), "closed": True,
                 "holes": [hole.tolist()]})
    assert len(doc.layer("a").holes) == 1
    doc.execute({"command": "mirror_layer", "layer": "a", "axis": "own"})
    cx = 0.5 * (outline[:, 0].min() + outline[:, 0].max())
    got = doc.layer("a").holes[0]
    assert np.allclose(got[:, 0], 2 * cx - hole[:, 0]) and np.array_equal(got[:, 1], hole[:, 1])
    assert len(doc.layer("a").mesh.holes) == 1  # inflated with its hole where it now is
