"""Part transforms as commands (issue 12, point 3): transform_layer (move, scale, rotate as
one 2x3 affine), mirror about the host's axis or the part's own, duplicate offset and
selected; attached parts are re-attached by the assembly where their junction now lies."""

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.document.commands import (
    MirrorLayer,
    TransformLayer,
    TranslateLayer,
    compose_affine,
    host_of,
    rotate_about,
    scale_about,
)
from sketchforge.errors import DocumentFormatError, ParameterError

BODY = [[np.cos(t), 0.7 * np.sin(t)] for t in np.linspace(0, 2 * np.pi, 160, endpoint=False)]


def leg(cx):
    """A U-shaped open stroke hanging from the body; its closing segment (the junction) runs
    along y = -0.3, inside the body."""
    down = np.column_stack([np.full(15, cx + 0.15), np.linspace(-0.3, -0.9, 15)])
    t = np.linspace(0.0, np.pi, 20)[1:-1]
    foot = np.column_stack([cx + 0.15 * np.cos(t), -0.9 - 0.15 * np.sin(t)])
    up = np.column_stack([np.full(15, cx - 0.15), np.linspace(-0.9, -0.3, 15)])
    return np.vstack([down, foot, up]).tolist()


def creature(host):
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": BODY, "closed": True,
                 "holes": [[[0.3 + 0.12 * np.cos(t), 0.2 + 0.12 * np.sin(t)] for t in np.linspace(0, 6.28, 40, endpoint=False)]]})
    doc.execute({"command": "add_layer", "id": "leg", "name": "Leg"})
    doc.execute({"command": "set_contour", "layer": "leg", "points": leg(-0.5)})
    return doc


def sculpted_body(host):
    """The body alone, with one isophote edit."""
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": BODY, "closed": True})
    doc.execute({"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3,
                 "stroke": [[0.1, -0.3], [0.15, -0.1], [0.22, 0.1], [0.3, 0.3]]})
    return doc


def test_move_scale_rotate_are_one_command_each_and_undo_restores_bit_for_bit(real_host):
    doc = creature(real_host)
    body0 = doc.layer("body")
    c = np.array([0.2, -0.1])
    A = compose_affine(scale_about(c, 1.5), rotate_about(c, np.radians(30.0)), [[1, 0, 0.3], [0, 1, -0.2]])
    n = doc.undo_stack.count()
    doc.push(TransformLayer(layer="body", matrix=A))
    assert doc.undo_stack.count() == n + 1
    body = doc.layer("body")
    expect = np.asarray(body0.mesh.V[:, :2]) @ A[:, :2].T + A[:, 2]
    assert np.abs(body.mesh.V[:, :2] - expect).max() < 1e-12
    assert np.abs(body.points - (body0.points @ A[:, :2].T + A[:, 2])).max() < 1e-12
    assert np.abs(body.holes[0] - (body0.holes[0] @ A[:, :2].T + A[:, 2])).max() < 1e-12
    # Heights scale with the part's linear size (1.5): the same shape, bigger.
    assert np.abs(body.mesh.V[:, 2] - 1.5 * body0.mesh.V[:, 2]).max() < 1e-12
    assert np.array_equal(body.mesh.F, body0.mesh.F) and len(body.mesh.holes) == 1
    doc.undo_stack.undo()
    assert doc.layer("body").same_state(body0)


def test_transform_journal_replays_bit_identical_and_old_translate_layer_still_loads(tmp_path, real_host):
    doc = creature(real_host)
    doc.push(TransformLayer(layer="leg", matrix=rotate_about([-0.5, -0.35], 0.3)))
    doc.push(TransformLayer(layer="body", matrix=[[1.0, 0.0, 0.125], [0.0, 1.0, -0.25]]))
    path = tmp_path / "t.sketchforge.json"
    ff.save(doc, path)
    assert ff.compare(doc, ff.load(path, host=real_host, use_snapshot=False)) == []
    # An old file's translate_layer: the same bits as the move written as transform_layer.
    old = creature(real_host)
    old.push(TranslateLayer(layer="body", offset=[0.125, -0.25]))
    new = creature(real_host)
    new.push(TransformLayer(layer="body", matrix=[[1.0, 0.0, 0.125], [0.0, 1.0, -0.25]]))
    assert old.layer("body").mesh.identical(new.layer("body").mesh)
    assert old.layer("body").points.tobytes() == new.layer("body").points.tobytes()


@pytest.mark.parametrize("matrix, message", [
    ([[1, 0], [0, 1]], "2x3"),
    ([[1, 0, float("nan")], [0, 1, 0]], "finite"),
    ([[-1, 0, 0], [0, 1, 0]], "Mirror layer"),
    ([[1e-4, 0, 0], [0, 1e-4, 0]], "scales the part's area"),
])
def test_bad_transforms_are_refused_with_a_clear_message(matrix, message):
    with pytest.raises(ParameterError, match=message):
        TransformLayer(layer="body", matrix=matrix)
    with pytest.raises(DocumentFormatError, match="matrix"):
        TransformLayer.from_dict({"command": "transform_layer", "layer": "body", "matrix": [[1, 0, 0], [0, True, 0]]})


def test_sculpt_edits_move_with_the_part_and_still_apply(real_host):
    doc = sculpted_body(real_host)
    A = compose_affine(rotate_about([0.0, 0.0], np.radians(90.0)), [[1, 0, 2.0], [0, 1, 0.0]])
    doc.push(TransformLayer(layer="body", matrix=A))
    e = doc.layer("body").edits[0]
    assert np.allclose(e["pick"][:2], A[:, :2] @ [0.2, 0.1] + A[:, 2], atol=1e-12)
    assert np.allclose(e["stroke"][0], A[:, :2] @ [0.1, -0.3] + A[:, 2], atol=1e-12)
    moved = doc.layer("body").mesh
    # A parameter change re-inflates the moved outline and re-applies the moved edit there.
    doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"inflation": 1.0}})
    again = doc.layer("body").mesh
    assert len(doc.layer("body").edits) == 1
    assert np.abs(again.V[:, 2].max() - moved.V[:, 2].max()) < 0.02 * moved.V[:, 2].max()


def test_mirror_about_the_host_axis_gives_the_other_leg_and_twice_is_the_identity(real_host):
    doc = creature(real_host)
    leg0 = np.array(doc.layer("leg").points)
    assert host_of(doc, doc.layer("leg")).id == "body"
    cmd = MirrorLayer(layer="leg")  # the host's axis by default
    doc.push(cmd)
    assert cmd.used_axis == "host"
    leg1 = np.array(doc.layer("leg").points)
    cx = 0.5 * (np.min(np.asarray(BODY)[:, 0]) + np.max(np.asarray(BODY)[:, 0]))
    assert np.abs(leg1[:, 0] - (2 * cx - leg0[:, 0])).max() < 1e-12
    assert leg1[:, 0].mean() > 0.4  # a left leg became a right leg
    doc.push(MirrorLayer(layer="leg"))
    assert np.abs(np.array(doc.layer("leg").points) - leg0).max() < 1e-12
    # The part's own axis on request: the leg stays where it is, flipped.
    doc.push(MirrorLayer(layer="leg", axis="own"))
    own = np.array(doc.layer("leg").points)
    assert abs(own[:, 0].mean() - leg0[:, 0].mean()) < 0.05
    # A free part has no host: its own axis.
    free = MirrorLayer(layer="body")
    doc.push(free)
    assert free.used_axis == "own"


def test_moved_part_is_reattached_where_its_junction_lies(real_host):
    from sketchforge_assemble import assemble_detailed

    doc = creature(real_host)

    def attachments():
        L = doc.layers
        res = assemble_detailed([l.mesh for l in L], [l.closed for l in L], names=[l.id for l in L])
        return [(L[a.upper].id, L[a.lower].id) for a in res.attachments]

    assert attachments() == [("leg", "body")]
    doc.push(TransformLayer(layer="leg", matrix=[[1, 0, 0.6], [0, 1, 0.0]]))  # still over the body
    assert attachments() == [("leg", "body")]
    assert host_of(doc, doc.layer("leg")).id == "body"
    doc.push(TransformLayer(layer="leg", matrix=[[1, 0, 3.0], [0, 1, 0.0]]))  # off the body: free
    assert attachments() == [] and host_of(doc, doc.layer("leg")) is None


def test_handle_geometry_hits_and_drag_matrices():
    from sketchforge.tools import transform as tr

    outline = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])
    h = tr.handles_for(outline, pixel=0.01)
    assert tr.hit(h, [1.0, 0.5]) == "move" and tr.hit(h, [2.03, 1.02]) == "scale2"
    assert tr.hit(h, h.knob + [0.05, 0.0]) == "rotate" and tr.hit(h, [0.6, 0.5]) is None  # elsewhere: draw
    A = tr.drag_matrix(h, "scale2", [2.0, 1.0], [3.0, 1.5])  # the corner pulled out along its diagonal
    assert np.allclose(tr.apply(A, outline), outline * 1.5) and np.allclose(tr.apply(A, [[0.0, 0.0]]), 0.0)
    A = tr.drag_matrix(h, "scale2", [2.0, 1.0], [-5.0, -5.0])  # through the opposite corner: clamped
    assert np.isclose(A[0, 0], tr.MIN_SCALE)
    A = tr.drag_matrix(h, "rotate", h.center + [0.0, 1.0], h.center + [-1.0, 0.0])
    assert np.allclose(A[:, :2], [[0.0, -1.0], [1.0, 0.0]]) and np.allclose(tr.apply(A, [h.center]), h.center)
    assert tr.is_identity(tr.drag_matrix(h, "move", [1.0, 0.5], [1.0, 0.5]))


def test_a_layer_drawn_in_front_of_a_part_is_not_taken_for_its_host(real_host):
    from sketchforge.document.commands import mirror_axis_x

    doc = creature(real_host)
    # a patch drawn after the leg (in front of it) over the leg's junction, centred elsewhere
    patch = [[-0.2 + 0.5 * np.cos(t), -0.3 + 0.3 * np.sin(t)] for t in np.linspace(0, 2 * np.pi, 60, endpoint=False)]
    doc.execute({"command": "add_layer", "id": "patch"})
    doc.execute({"command": "set_contour", "layer": "patch", "points": patch, "closed": True})
    assert host_of(doc, doc.layer("leg")).id == "body"
    assert mirror_axis_x(doc, doc.layer("leg"), "host") == (0.5 * (min(p[0] for p in BODY) + max(p[0] for p in BODY)), "host")
    # the patch itself is free: no layer behind it holds a junction of it
    assert host_of(doc, doc.layer("patch")) is None
    with pytest.raises(ParameterError) as info:
        mirror_axis_x(doc, doc.layer("leg"), "left")
    assert str(info.value) == "a mirror axis is 'host', 'own' or a number, got 'left'"


def test_mirroring_a_sculpted_layer_drops_its_edits_and_undo_brings_them_back(real_host):
    doc = sculpted_body(real_host)
    sculpted = doc.layer("body")
    doc.push(MirrorLayer(layer="body", axis="own"))
    # a mirrored outline is re-inflated like a redraw: the edits, drawn on the old surface, go
    assert doc.layer("body").edits == ()
    fresh = Document(host=real_host)
    fresh.execute({"command": "add_layer", "id": "body", "name": "Body"})
    fresh.execute({"command": "set_contour", "layer": "body", "points": np.asarray(doc.layer("body").points).tolist(), "closed": True})
    assert np.array_equal(doc.layer("body").mesh.V, fresh.layer("body").mesh.V)
    doc.undo_stack.undo()
    assert doc.layer("body").edits == sculpted.edits and len(sculpted.edits) == 1
    assert np.array_equal(doc.layer("body").mesh.V, sculpted.mesh.V)


def test_a_scaled_or_sheared_part_keeps_a_unit_light_on_its_edits(real_host):
    doc = sculpted_body(real_host)
    light0 = np.array(doc.layer("body").edits[0]["light"])
    doc.push(TransformLayer(layer="body", matrix=scale_about([0.0, 0.0], 2.5)))
    light = np.array(doc.layer("body").edits[0]["light"])
    # a uniform scale turns nothing: the same direction, still of unit length
    assert np.abs(light - light0).max() < 1e-15 and doc.layer("body").edits[0]["band"] == pytest.approx(0.75)
    doc.push(TransformLayer(layer="body", matrix=[[1.0, 0.5, 0.0], [0.0, 1.0, 0.0]]))  # a shear
    light = np.array(doc.layer("body").edits[0]["light"])
    v = np.array([[1.0, 0.5], [0.0, 1.0]]) @ light0[:2]
    assert np.hypot(light[0], light[1]) == pytest.approx(1.0, abs=1e-15)
    assert np.abs(light[:2] - v / np.hypot(*v)).max() < 1e-15 and light[2] == light0[2]
