"""Undo that fits in memory (issue 39, point 2).

Every step copied arrays that were already read-only: 200 moves of a 34k-vertex layer kept
489 MB, 2.4 MB a step, while the vertices are 0.8 MB. Now values share read-only arrays, a
transform step keeps its new vertices and nothing else of size, and past a memory budget the
oldest steps are dropped, their journal entries kept (the file and a replay are unchanged), and
the user is told once. Memory figures: benchmarks/bench_undo_memory.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document import commands as C
from sketchforge.document.layer import Layer
from sketchforge.document.undo import DEFAULT_MEMORY_BUDGET
from sketchforge.geometry.mesh import Mesh, frozen_array, unwritable

RNG = np.random.default_rng(3902)
T = np.linspace(0.0, 2.0 * np.pi, 2000, endpoint=False)
BIG = np.c_[np.cos(T), 0.7 * np.sin(T)]  # the fan inflater gives it 2001 vertices


def frozen(a):
    a = np.array(a)
    a.setflags(write=False)
    return a


# --- values share what nobody can write ----------------------------------------------------------


def test_a_mesh_keeps_read_only_arrays_and_copies_anything_writable():
    V = frozen(RNG.normal(size=(4, 3)))
    F = frozen(np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64))
    m = Mesh(V, F, frozen(np.arange(4)))
    assert m.V is V and m.F is F and np.shares_memory(m.boundary, m.boundary)
    # another mesh with the same triangles shares them (a transform step)
    m2 = Mesh(frozen(V + 1.0), m.F, m.boundary, m.junction, m.holes)
    assert m2.F is m.F and m2.boundary is m.boundary and m2.junction is m.junction
    # writable input is copied: changing it later changes nothing
    W = np.array(V)
    m3 = Mesh(W, F)
    W[0, 0] = 99.0
    assert m3.V[0, 0] == V[0, 0] and not m3.V.flags.writeable
    # a read-only view of a writable array can still change under it: copied
    base = np.array(V)
    view = base[:]
    view.setflags(write=False)
    assert not unwritable(view)
    m4 = Mesh(view, F)
    base[1, 1] = -7.0
    assert m4.V[1, 1] == V[1, 1]
    # a read-only view of a read-only array is safe, but a strided one is made contiguous
    assert unwritable(V[1:]) and frozen_array(V[1:], np.float64) is not None
    strided = frozen(RNG.normal(size=(4, 6)))[:, ::2]
    assert not strided.flags.c_contiguous and Mesh(strided, F).V.flags.c_contiguous
    # another dtype is converted (a copy), and lists become arrays
    m5 = Mesh(V.astype(np.float32), F.astype(np.int32))
    assert m5.V.dtype == np.float64 and m5.F.dtype == np.int64
    assert Mesh(V.tolist(), F.tolist()).V.tobytes() == V.tobytes()
    # bytes are immutable: an array on them is shared
    on_bytes = np.frombuffer(V.tobytes(), dtype=np.float64).reshape(4, 3)
    assert unwritable(on_bytes) and Mesh(on_bytes, F).V is on_bytes
    # a memoryview of a bytearray is not
    on_bytearray = np.frombuffer(memoryview(bytearray(V.tobytes())), dtype=np.float64)
    on_bytearray.setflags(write=False)
    assert not unwritable(on_bytearray)


def test_a_layer_keeps_its_read_only_points_and_holes():
    pts = frozen(BIG[:50])
    hole = frozen(0.1 * BIG[:20])
    layer = Layer(id="a", name="A", points=pts, holes=(hole,))
    assert layer.points is pts and layer.holes[0] is hole
    renamed = layer.evolve(name="B")
    assert renamed.points is layer.points and renamed.holes[0] is layer.holes[0]
    src = np.array(BIG[:50])
    copied = Layer(id="a", name="A", points=src)
    src[0] = 5.0
    assert copied.points[0, 0] == BIG[0, 0] and not copied.points.flags.writeable


# --- a transform step keeps at most the vertices it replaces --------------------------------------


def fan_doc(fan_host, points=BIG):
    doc = Document(host=fan_host)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    doc.execute({"command": "set_contour", "layer": "a", "points": points.tolist(), "closed": True})
    return doc


@pytest.mark.parametrize("matrix", [[[1, 0, 0.25], [0, 1, -0.5]], [[0.8, -0.6, 0.1], [0.6, 0.8, 0.0]],
                                    [[1.5, 0.2, 0.0], [0.0, 1.2, 0.3]]])
def test_a_transform_step_keeps_the_new_vertices_and_shares_the_rest(fan_host, matrix):
    doc = fan_doc(fan_host)
    old = doc.layer("a")
    before = doc.undo_stack.history_bytes()
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": matrix})
    new = doc.layer("a")
    assert new.mesh.F is old.mesh.F and new.mesh.boundary is old.mesh.boundary and new.mesh.junction is old.mesh.junction
    assert not np.shares_memory(new.mesh.V, old.mesh.V)
    # what the history holds now beyond the document: the replaced vertices and stroke, no more
    grew = doc.undo_stack.history_bytes() - before
    assert grew == old.mesh.V.nbytes + old.points.nbytes
    # undo and redo give the very values back
    doc.undo_stack.undo()
    assert doc.layer("a") is old
    doc.undo_stack.redo()
    assert doc.layer("a") is new


def test_two_hundred_moves_keep_two_hundred_vertex_arrays(fan_host):
    doc = fan_doc(fan_host)
    layer = doc.layer("a")
    per_step = layer.mesh.V.nbytes + layer.points.nbytes
    base = doc.undo_stack.history_bytes()
    for _ in range(200):
        doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.01], [0, 1, 0.0]]})
    assert doc.undo_stack.history_bytes() - base == 200 * per_step
    assert doc.undo_stack.count() == 202 and doc.undo_stack.dropped == 0
    assert doc.undo_stack.memory_budget == DEFAULT_MEMORY_BUDGET == 10**9


# --- the budget ---------------------------------------------------------------------------------


def test_history_bytes_counts_what_only_the_history_holds(fan_host):
    doc = Document(host=fan_host)
    assert doc.undo_stack.history_bytes() == 0
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    assert doc.undo_stack.history_bytes() == 0  # nothing held but the current layer
    doc.execute({"command": "set_contour", "layer": "a", "points": BIG.tolist(), "closed": True})
    assert doc.undo_stack.history_bytes() == 0  # the old layer had no arrays; the new one is current
    mesh = doc.layer("a").mesh
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 1.0], [0, 1, 0.0]]})
    held = doc.undo_stack.history_bytes()
    assert held == mesh.V.nbytes + BIG.nbytes
    doc.undo_stack.undo()  # the old layer is current again: the history holds the moved one
    assert doc.undo_stack.history_bytes() == held
    doc.execute({"command": "remove_layer", "layer": "a"})  # the redo tail goes; the layer is only in history now
    layer_bytes = mesh.V.nbytes + mesh.F.nbytes + mesh.boundary.nbytes + BIG.nbytes
    assert doc.undo_stack.history_bytes() == layer_bytes


def test_past_the_budget_the_oldest_steps_go_the_journal_stays_and_the_user_is_told_once(fan_host, assert_replays):
    doc = fan_doc(fan_host)
    stack = doc.undo_stack
    told = []
    stack.history_trimmed.connect(told.append)
    layer = doc.layer("a")
    per_step = layer.mesh.V.nbytes + layer.points.nbytes
    stack.memory_budget = 10 * per_step + per_step // 2  # room for ten moves
    moves = [[[1, 0, 0.001 * (i + 1)], [0, 1, 0.0]] for i in range(25)]
    for m in moves:
        doc.execute({"command": "transform_layer", "layer": "a", "matrix": m})
        assert stack.history_bytes() <= stack.memory_budget
    assert stack.count() == stack.index == 10
    assert stack.dropped == 2 + 15  # add_layer and set_contour, then the oldest moves
    assert all(isinstance(c, C.TransformLayer) for c in stack.commands())
    # the journal is whole: every entry in order, and it replays to the same document
    journal = doc.journal()
    assert [e["command"] for e in journal] == ["add_layer", "set_contour"] + ["transform_layer"] * 25
    assert [e["matrix"] for e in journal[2:]] == [[list(map(float, r)) for r in m] for m in moves]
    assert_replays(doc)
    # told once, in one line
    assert len(told) == 1 and "\n" not in told[0]
    assert told[0].startswith("the undo history reached its memory budget of ") and "oldest steps are dropped" in told[0]
    # what is left can be undone, down to the oldest kept state
    target = doc.layer("a")
    for _ in range(10):
        stack.undo()
    assert not stack.can_undo()
    assert doc.layer("a").mesh.V[0, 0] == pytest.approx(layer.mesh.V[0, 0] + sum(0.001 * (i + 1) for i in range(15)))
    for _ in range(10):
        stack.redo()
    assert doc.layer("a") is target


def test_the_saved_state_is_forgotten_only_when_its_step_is_dropped(fan_host):
    doc = fan_doc(fan_host)
    stack = doc.undo_stack
    per_step = doc.layer("a").mesh.V.nbytes + doc.layer("a").points.nbytes
    for _ in range(3):
        doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    stack.set_clean()  # saved after 5 steps
    stack.memory_budget = 3 * per_step + per_step // 2
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    assert stack.dropped > 0 and stack.clean_index == stack.index - 1  # still reachable: one undo
    stack.undo()
    assert stack.is_clean()
    stack.redo()
    for _ in range(6):
        doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    assert stack.clean_index == -1 and not stack.is_clean()  # the saved state's step is gone
    while stack.can_undo():
        stack.undo()
        assert not stack.is_clean()


def test_no_budget_keeps_everything_and_a_budget_never_drops_the_last_step(fan_host):
    doc = fan_doc(fan_host)
    stack = doc.undo_stack
    stack.memory_budget = None
    for _ in range(30):
        doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    assert stack.count() == 32 and stack.dropped == 0
    stack.memory_budget = 0
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    assert stack.count() == 1 and stack.can_undo()  # the newest step stays undoable
    assert len(doc.journal()) == 33


def test_a_macro_is_dropped_whole_and_open_macros_are_never_touched(fan_host, assert_replays):
    doc = fan_doc(fan_host)
    stack = doc.undo_stack
    per_step = doc.layer("a").mesh.V.nbytes + doc.layer("a").points.nbytes
    stack.memory_budget = 3 * per_step
    stack.begin_macro("Wiggle")
    for _ in range(6):
        doc.push(C.TransformLayer(layer="a", matrix=[[1, 0, 0.1], [0, 1, 0.0]]))
    assert stack.dropped == 0 and stack.in_macro()  # nothing is dropped inside a gesture
    stack.end_macro()
    assert stack.commands()[-1].text() == "Wiggle"
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    # the macro held 6 vertex arrays: over the budget, it goes as one step
    assert [c.text() for c in stack.commands()] == ["Move layer"]
    assert [e["command"] for e in doc.journal()] == ["add_layer", "set_contour", "macro", "transform_layer"]
    assert_replays(doc)


def test_views_are_told_when_steps_are_dropped_even_if_the_top_looks_the_same(fan_host):
    doc = fan_doc(fan_host)
    stack = doc.undo_stack
    per_step = doc.layer("a").mesh.V.nbytes + doc.layer("a").points.nbytes
    for _ in range(4):
        doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    stack.memory_budget = 4 * per_step
    changed = []
    doc.history_changed.connect(lambda: changed.append(stack.count()))
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    # each push dropped a step and added one: the index and texts are as before, the rows not
    assert stack.count() == 4 and changed == [4, 4]


def test_the_tally_follows_undo_redo_truncation_and_clear_and_lets_go_of_what_left(fan_host):
    import gc
    import weakref

    doc = fan_doc(fan_host)
    stack = doc.undo_stack
    for _ in range(5):
        doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    per_step = doc.layer("a").mesh.V.nbytes + doc.layer("a").points.nbytes
    assert stack.history_bytes() == 5 * per_step
    for _ in range(3):
        stack.undo()
    assert stack.history_bytes() == 5 * per_step  # the undone states are still held (redo)
    gone = weakref.ref(stack.command(stack.index))
    doc.execute({"command": "rename_layer", "layer": "a", "name": "B"})  # the redo tail goes
    gc.collect()
    assert gone() is None  # nothing keeps a command that left the stack
    assert stack.history_bytes() == 2 * per_step
    first = weakref.ref(stack.command(0))
    stack.clear()
    gc.collect()
    assert first() is None and stack.history_bytes() == 0
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.1], [0, 1, 0.0]]})
    assert stack.history_bytes() == per_step
