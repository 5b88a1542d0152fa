"""UndoStack semantics (QUndoStack's): push runs, undo/redo, merge, macros, clean state."""

import pytest

from sketchforge.document import Document
from sketchforge.document.commands import AddLayer, RenameLayer, SetContour, SetLight, new_gesture_id
from sketchforge.errors import ContourError, LayerNotFoundError

SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]


def test_push_runs_and_undo_redo_restore(fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    doc.push(SetContour(layer="a", points=SQUARE, closed=True))
    mesh = doc.layer("a").mesh
    assert mesh is not None and doc.undo_stack.index == 2
    doc.undo_stack.undo()
    assert doc.layer("a").mesh is None
    doc.undo_stack.redo()
    assert doc.layer("a").mesh is mesh  # redo reuses the computed mesh: instant and identical
    doc.undo_stack.undo()
    doc.undo_stack.undo()
    assert doc.layers == ()


def test_push_after_undo_drops_redo_tail(fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    doc.push(AddLayer(id="b"))
    doc.undo_stack.undo()
    doc.push(AddLayer(id="c"))
    assert doc.undo_stack.count() == 2 and not doc.undo_stack.can_redo()
    assert doc.layer_ids() == ["a", "c"]


def test_failed_command_changes_nothing(fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    before = doc.layers
    with pytest.raises(ContourError):
        doc.push(SetContour(layer="a", points=[[0, 0], [1, 1]]))
    with pytest.raises(LayerNotFoundError, match="no layer with id 'zz'"):
        doc.push(RenameLayer(layer="zz", new_name="x"))
    assert doc.layers == before and doc.undo_stack.count() == 1


def test_light_drag_merges_into_one_step_but_separate_drags_do_not(fan_host):
    doc = Document(host=fan_host)
    g = new_gesture_id()
    for d in ([1, 0.1], [1, 0.5], [0.2, 1]):
        doc.push(SetLight(direction=d, gesture=g))
    assert doc.undo_stack.count() == 1
    g2 = new_gesture_id()
    doc.push(SetLight(direction=[-1, 0], gesture=g2))
    assert doc.undo_stack.count() == 2
    doc.undo_stack.undo()
    assert doc.light.x == pytest.approx(0.2 / (0.2**2 + 1) ** 0.5)
    doc.undo_stack.undo()
    assert (doc.light.x, doc.light.y) == pytest.approx((2**-0.5, 2**-0.5))
    assert doc.undo_stack.undo_text() == ""


def test_no_merge_across_clean_point(fan_host):
    doc = Document(host=fan_host)
    g = new_gesture_id()
    doc.push(SetLight(direction=[1, 0], gesture=g))
    doc.undo_stack.set_clean()
    doc.push(SetLight(direction=[0, 1], gesture=g))
    assert doc.undo_stack.count() == 2
    doc.undo_stack.undo()
    assert doc.undo_stack.is_clean()


def test_macro_is_one_step_and_undoes_in_reverse(fan_host):
    doc = Document(host=fan_host)
    order = []
    doc.layer_removed.connect(lambda i, layer: order.append(layer.id))
    st = doc.undo_stack
    st.begin_macro("Two layers")
    doc.push(AddLayer(id="a"))
    doc.push(AddLayer(id="b"))
    st.end_macro()
    assert st.count() == 1 and st.undo_text() == "Two layers"
    st.undo()
    assert order == ["b", "a"] and doc.layers == ()
    st.redo()
    assert doc.layer_ids() == ["a", "b"]


def test_clean_state_and_signals(fan_host):
    doc = Document(host=fan_host)
    st = doc.undo_stack
    seen = {"clean": [], "undo_text": [], "can_redo": []}
    st.clean_changed.connect(seen["clean"].append)
    st.undo_text_changed.connect(seen["undo_text"].append)
    st.can_redo_changed.connect(seen["can_redo"].append)
    doc.push(AddLayer(id="a"))
    assert seen["clean"] == [False] and seen["undo_text"] == ["Add layer"]
    st.set_clean()
    st.undo()
    assert seen["clean"] == [False, True, False] and seen["can_redo"] == [True]
    st.redo()
    assert st.is_clean()
    # Dropping the command that led to the clean state makes it unreachable.
    st.undo()
    doc.push(AddLayer(id="b"))
    assert st.clean_index == -1 and not st.is_clean()


def test_abort_macro_restores(fan_host):
    doc = Document(host=fan_host)
    st = doc.undo_stack
    st.begin_macro("x")
    doc.push(AddLayer(id="a"))
    st.abort_macro()
    assert doc.layers == () and st.count() == 0


def test_solver_producing_nan_rolls_back_and_says_so():
    import numpy as np

    from sketchforge.errors import PluginError
    from sketchforge.geometry.mesh import Mesh
    from sketchforge.plugin_api import Inflater
    from sketchforge.plugins.hookspecs import hookimpl
    from sketchforge.plugins.testing import make_test_host

    def nan_mesh(points, closed, params, holes):
        P = np.asarray(points, float)
        V = np.c_[P, np.full(len(P), np.nan)]
        return Mesh(V, [[0, 1, 2]], np.arange(len(P)))

    class NaNInflater:
        @hookimpl
        def sketchforge_inflaters(self):
            return [Inflater("nan", nan_mesh)]

    doc = Document(host=make_test_host(NaNInflater()))
    doc.push(AddLayer(id="a"))
    before = doc.layer("a")
    # Refused by the host's check on what an inflater returns, naming the inflater and its plugin.
    with pytest.raises(PluginError, match=r"^the inflater 'nan' \(plugin 'plugin-0-NaNInflater'\) returned a mesh "
                                          r"with non-finite coordinates at 4 of 4 vertices; nothing was changed$"):
        doc.push(SetContour(layer="a", points=SQUARE))
    assert doc.layer("a") is before and doc.undo_stack.count() == 1
