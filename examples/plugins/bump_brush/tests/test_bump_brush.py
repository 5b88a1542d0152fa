"""The bump brush through sketchforge's pytest fixtures (``make_sketchforge_host``,
``make_sketchforge_document``, ``assert_replays``), as a plugin author tests a brush."""

import numpy as np
import pytest
import sketchforge_bump_brush.plugin as plugin
from sketchforge_bump_brush import BumpTool


@pytest.fixture
def doc(make_sketchforge_host, make_sketchforge_document):
    host = make_sketchforge_host(plugin, installed=("inflate",))  # strict: contracts must pass
    return make_sketchforge_document(host)


def bump_entry(**kw):
    return {"command": "bump_brush", "layer": "a", "center": [0.1, 0.0], "radius": 0.4, "height": 0.2, **kw}


def test_bump_raises_inside_the_disc_only(doc):
    before = doc.layer("a").mesh
    doc.execute(bump_entry())
    after = doc.layer("a").mesh
    dz = after.V[:, 2] - before.V[:, 2]
    d = np.hypot(before.V[:, 0] - 0.1, before.V[:, 1])
    inside = d < 0.4
    assert np.all(dz[~inside] == 0.0) and np.all(dz[before.boundary] == 0.0)
    expected = 0.2 * (1 - (d[inside] / 0.4) ** 2) ** 2
    assert np.allclose(dz[inside], expected, atol=1e-12)
    assert dz.max() > 0.15  # a vertex near the centre rose by most of the height
    assert np.array_equal(after.F, before.F)


def test_tool_drag_is_one_exact_undo_step(doc):
    before = doc.layer("a")
    tool = BumpTool(doc)
    tool.press([0.0, 0.0])
    tool.move([0.0, 0.1])
    assert set(tool.overlay) == {"disc", "drag"} and tool.overlay["disc"].shape == (49, 2)
    cmd = tool.release([0.0, 0.15])
    assert cmd.height == pytest.approx(0.15) and doc.undo_stack.index == 3
    after = doc.layer("a")
    doc.undo_stack.undo()
    assert doc.layer("a").same_state(before)
    doc.undo_stack.redo()
    assert doc.layer("a").same_state(after)


def test_brush_replays_bit_identically(doc, assert_replays):
    doc.execute(bump_entry())
    doc.execute(bump_entry(center=[-0.3, 0.2], height=-0.05))
    replayed = assert_replays(doc)
    assert len(replayed.layer("a").edits) == 2


def test_bump_survives_reinflation(doc):
    """Through Layer.edits / reapply: a new inflation parameter keeps the bump."""
    doc.execute(bump_entry())
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.5}})
    layer = doc.layer("a")
    assert [e["command"] for e in layer.edits] == ["bump_brush"]
    doc.undo_stack.undo()
    doc.undo_stack.undo()  # back to the plain surface, then the same parameter without a bump
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.5}})
    plain = doc.layer("a").mesh
    dz = layer.mesh.V[:, 2] - plain.V[:, 2]
    assert dz.max() == pytest.approx(0.2 * (1 - (np.hypot(plain.V[:, 0] - 0.1, plain.V[:, 1]).min() / 0.4) ** 2) ** 2)


def test_bad_journal_fields_are_one_line_errors(doc):
    from sketchforge.plugin_api import DocumentFormatError, NothingToDoError

    with pytest.raises(DocumentFormatError, match="'radius' must be in"):
        doc.execute(bump_entry(radius=-1.0))
    with pytest.raises(NothingToDoError, match="brush over the shape"):
        doc.execute(bump_entry(center=[5.0, 5.0]))
    assert doc.undo_stack.index == 2  # nothing was recorded


@pytest.mark.parametrize("matrix", [[[1.0, 0.0, 2.0], [0.0, 1.0, 0.5]], [[0.0, -2.0, 0.25], [2.0, 0.0, 0.0]]],
                         ids=["move", "turn and double"])
def test_a_moved_bump_is_reapplied_where_the_part_now_is(doc, make_sketchforge_document, matrix):
    """Through transform_edit: after transform_layer a re-inflation puts the bump on the moved
    part, exactly as on a part drawn there with the bump drawn there (scaled with it)."""
    doc.execute(bump_entry())
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": matrix})
    edit = doc.layer("a").edits[0]
    A = np.array(matrix)
    s = np.sqrt(np.linalg.det(A[:, :2]))
    assert np.allclose(edit["center"], A[:, :2] @ [0.1, 0.0] + A[:, 2], rtol=0, atol=1e-15)
    assert edit["radius"] == pytest.approx(0.4 * s) and edit["height"] == pytest.approx(0.2 * s)
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.5}})

    there = make_sketchforge_document(doc.host, contour=doc.layer("a").points)
    there.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.5}})
    there.execute(bump_entry(center=edit["center"], radius=edit["radius"], height=edit["height"]))
    assert doc.layer("a").points.tobytes() == there.layer("a").points.tobytes()
    assert doc.layer("a").mesh.identical(there.layer("a").mesh)
