"""Properties that bugs planted in a mutation study went through unnoticed (issue 18).

Each test states what a user relies on; the comment names the planted bug it catches.
The stateful per-step undo check lives in test_document_stateful.py.
"""

from __future__ import annotations

import json
import time
import tracemalloc

import numpy as np
import pytest
import scipy.sparse as sp

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.document.autosave import Autosaver, find_recoverable
from sketchforge.document.commands import (
    AddLayer,
    MirrorLayer,
    MoveLayer,
    RemoveLayer,
    RenameLayer,
    SetContour,
    SetLight,
)
from sketchforge.geometry.normals import vertex_normals

# --- undo -----------------------------------------------------------------------------------


def _names(doc):
    return [(l.id, l.name) for l in doc.layers]


def test_aborting_a_two_step_macro_leaves_nothing(fan_host):
    # planted: abort_macro undoing its children first to last
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a", layer_name="Arm"))
    before = ff.document_to_dict(doc)["snapshot"]
    st = doc.undo_stack
    st.begin_macro("gesture")
    doc.push(RenameLayer(layer="a", new_name="first"))
    doc.push(RenameLayer(layer="a", new_name="second"))
    doc.push(AddLayer(id="b"))
    st.abort_macro()
    assert ff.document_to_dict(doc)["snapshot"] == before
    assert doc.layer("a").name == "Arm" and st.count() == 1 and st.index == 1 and not st.in_macro()


def test_undo_of_remove_puts_the_layer_back_where_it_was(fan_host):
    # planted: RemoveLayer.undo re-inserting at the end
    doc = Document(host=fan_host)
    for lid in "abcd":
        doc.push(AddLayer(id=lid))
    doc.push(RemoveLayer(layer="b"))
    assert doc.layer_ids() == ["a", "c", "d"]
    doc.undo_stack.undo()
    assert doc.layer_ids() == ["a", "b", "c", "d"]
    doc.undo_stack.redo()
    assert doc.layer_ids() == ["a", "c", "d"]


@pytest.mark.parametrize("src, dst", [(0, 3), (3, 0), (1, 2), (2, 0)])
def test_undo_of_move_restores_the_order(fan_host, src, dst):
    # planted: MoveLayer.undo with its arguments swapped
    doc = Document(host=fan_host)
    for lid in "abcd":
        doc.push(AddLayer(id=lid))
    order = doc.layer_ids()
    moved = order[src]
    doc.push(MoveLayer(layer=moved, index=dst))
    expect = [l for l in order if l != moved]
    expect.insert(dst, moved)
    assert doc.layer_ids() == expect
    doc.undo_stack.undo()
    assert doc.layer_ids() == order
    doc.undo_stack.redo()
    assert doc.layer_ids() == expect


# --- mirror ---------------------------------------------------------------------------------


def _blob(cx, cy, n=23, seed=3):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 0.5 + 0.2 * rng.random(n)
    # lopsided on purpose: a mirror image differs from the original
    return np.c_[cx + r * np.cos(t) * (1 + 0.5 * np.cos(t) ** 2 * (np.cos(t) > 0)), cy + r * np.sin(t)]


def test_mirror_keeps_the_bounding_box_and_twice_is_the_identity(fan_host):
    # planted: mirror about x = 0 instead of the shape's own axis
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="leg"))
    pts = _blob(3.0, -1.0)
    doc.push(SetContour(layer="leg", points=pts.tolist(), closed=True))
    p0 = np.array(doc.layer("leg").points)
    doc.push(MirrorLayer(layer="leg"))
    p1 = np.array(doc.layer("leg").points)
    lo0, hi0, lo1, hi1 = p0.min(0), p0.max(0), p1.min(0), p1.max(0)
    assert np.allclose(lo0, lo1, atol=1e-12) and np.allclose(hi0, hi1, atol=1e-12)
    cx = 0.5 * (lo0[0] + hi0[0])
    assert np.allclose(p1[:, 0], 2 * cx - p0[:, 0], atol=1e-12) and np.array_equal(p1[:, 1], p0[:, 1])
    assert not np.allclose(np.sort(p1[:, 0]), np.sort(p0[:, 0]), atol=1e-3)  # it did change
    doc.push(MirrorLayer(layer="leg"))
    p2 = np.array(doc.layer("leg").points)
    assert np.abs(p2 - p0).max() < 1e-12


# --- normals --------------------------------------------------------------------------------


def test_vertex_normals_weight_faces_by_area():
    # planted: vertex normals averaged without area weights. Vertex 0 has a large face tilted
    # one way and a tiny face tilted the other: the normal follows the large face.
    V = np.array([
        [0.0, 0.0, 0.0],
        [4.0, 0.0, 1.0],   # large face (0, 1, 2), tilted towards -x
        [0.0, 4.0, 0.0],
        [-0.01, 0.0, 0.01],  # small face (0, 2, 3), tilted towards +x
    ])
    F = np.array([[0, 1, 2], [0, 2, 3]], np.int64)
    c = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    areas = 0.5 * np.linalg.norm(c, axis=1)
    assert areas[0] / areas[1] > 50
    want = c.sum(0) / np.linalg.norm(c.sum(0))
    unweighted = (c / np.linalg.norm(c, axis=1)[:, None]).sum(0)
    unweighted /= np.linalg.norm(unweighted)
    N = vertex_normals(V, F)
    assert np.abs(N[0] - want).max() < 1e-12
    assert np.abs(want - unweighted).max() > 0.1  # the two rules really differ here
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0)


# --- attachment -----------------------------------------------------------------------------


def _ellipse(cx, cy, a, b, n=64):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[cx + a * np.cos(t), cy + b * np.sin(t)]


def _u_stroke(x0, x1, y, n=40):
    """An open stroke: a half circle above the segment (x1, y) -> (x0, y); its junction is
    that segment."""
    t = np.linspace(0.0, np.pi, n)
    c, r = 0.5 * (x0 + x1), 0.5 * (x1 - x0)
    return np.c_[c + r * np.cos(t), y + r * np.sin(t)]


def _inflate(points, closed, res=0.04):
    from sketchforge_inflate import inflate_stroke

    return inflate_stroke(points, closed=closed, params={"resolution": res, "inflation": 1.0, "smoothing": 0.5})


def test_a_part_attaches_to_the_nearest_layer_behind_it():
    # planted: attaching to the farthest layer behind instead of the nearest
    from sketchforge_assemble import FRONT, assemble_detailed

    body = _inflate(_ellipse(0, 0, 1.4, 0.9), True)
    plate = _inflate(_ellipse(0, 0, 0.6, 0.4), True)
    part = _inflate(_u_stroke(-0.3, 0.2, 0.0), False)
    assert part.junction.size
    res = assemble_detailed([body, plate, part], names=["body", "plate", "part"])
    assert [(a.upper, a.lower, a.side) for a in res.attachments] == [(2, 1, FRONT)]


def test_a_junction_poking_out_by_four_percent_is_glued_only_inside():
    # planted: junction tolerance raised from 1e-6 to 0.1 of its length (issue 34: the stretch
    # inside is glued, never the part outside the plate)
    import shapely

    from sketchforge_assemble import assemble_detailed

    plate = _inflate(_ellipse(0, 0, 0.6, 0.4), True)
    length = 0.5 / 0.96  # from x = 0.1 to 4% of the junction's length past the rim at x = 0.6
    part = _inflate(_u_stroke(0.1, 0.1 + length, 0.0), False)
    res = assemble_detailed([plate, part], names=["plate", "part"])
    (a,) = res.attachments
    assert a.keep is not None and "runs off 'plate'" in res.notes[0]
    J = part.V[part.junction[a.keep[0]:a.keep[1] + 1], :2]
    assert shapely.contains_xy(shapely.Polygon(plate.V[plate.boundary, :2]), J[:, 0], J[:, 1]).all()
    # the same part 4% shorter, fully inside, is glued whole
    inside = _inflate(_u_stroke(0.1, 0.1 + 0.96 * 0.45, 0.0), False)
    res = assemble_detailed([plate, inside], names=["plate", "part"])
    assert res.attachments[0].keep is None and not res.notes


# --- autosave and recovery ------------------------------------------------------------------


def test_a_light_change_alone_is_autosaved(tmp_path, fan_host):
    # planted: a light change no longer marking the document as changed
    doc = Document(host=fan_host)
    saver = Autosaver(doc, interval_s=0, folder=tmp_path / "auto")
    doc.push(AddLayer(id="a"))
    assert saver.save_now()
    doc.push(SetLight(direction=[0.0, 1.0]))
    assert saver.save_now()
    saved = json.loads(saver.path.read_text("utf-8"))
    back = ff.document_from_dict(saved, "autosave", host=fan_host)
    assert (back.light.x, back.light.y) == (doc.light.x, doc.light.y) == (0.0, 1.0)


def test_recovery_lists_the_newest_autosave_first(tmp_path, fan_host):
    # planted: the recovery list sorted oldest first
    folder = tmp_path / "auto"
    stamps = {}
    for k, saved_at in enumerate([1000.0, 3000.0, 2000.0]):
        doc = Document(host=fan_host)
        doc.push(AddLayer(id=f"l{k}"))
        saver = Autosaver(doc, original_path=tmp_path / f"doc{k}.json", interval_s=0, folder=folder)
        assert saver.save_now()
        data = json.loads(saver.path.read_text("utf-8"))
        data["autosave"]["saved_at"] = saved_at
        saver.path.write_text(json.dumps(data), "utf-8")
        stamps[str((tmp_path / f"doc{k}.json").resolve())] = saved_at
    found = find_recoverable(folder)
    assert [r.saved_at for r in found] == [3000.0, 2000.0, 1000.0]
    assert [stamps[r.original] for r in found] == [3000.0, 2000.0, 1000.0]


# --- sculpt ---------------------------------------------------------------------------------


def test_sculpt_heights_stay_non_negative_when_the_solve_pushes_below(monkeypatch):
    # planted: the z >= 0 clamp of the sculpt removed. The solver's change is made to dig a
    # pit deeper than the layer under the stroke: the surface must stop at the drawing plane.
    from sketchforge.plugin_api import SculptSolver
    from sketchforge_isophote_tool import sculpt
    from sketchforge_isophote_tool.gauss_newton import check_params, solve
    from sketchforge_isophote_tool.testing import LIGHT, inflated

    mesh = inflated("ellipse")
    pushed = {}

    def digging(problem, params):
        dz = solve(problem, params).dz
        d = np.hypot(problem.V[:, 0] - 0.35, problem.V[:, 1])
        pit = -3.0 * problem.z.max() * np.clip(1.0 - d / 0.25, 0.0, 1.0)
        pushed["below"] = int(np.sum(problem.z + dz + pit < 0))
        return dz + pit

    r = sculpt(mesh, LIGHT, [0.2, 0.1], 0.3, [[0.15, -0.3], [0.3, 0.0], [0.15, 0.3]],
               solver=SculptSolver("digging", digging, check_params), never_worse=False)
    z = r.mesh.V[:, 2]
    assert pushed["below"] > 20
    assert z.min() >= 0.0 and np.sum(z == 0.0) >= pushed["below"]


# --- bounded solvers ------------------------------------------------------------------------


def test_a_depth_solve_that_outgrows_its_memory_budget_stops_with_a_clear_error():
    """The active-set method holds one dense column per row it has touched. A problem that
    needs more than its budget (here every one of 400 rows is active) stops early with a
    DepthOrderError instead of growing until the kernel kills the app."""
    from sketchforge_assemble import DepthOrderError
    from sketchforge_assemble.depth import solve_depth

    n = 400
    P = sp.identity(n, format="csc")
    q = np.zeros(n)
    Aeq, beq = sp.csr_matrix((0, n)), np.zeros(0)
    Ain, bin_ = sp.identity(n, format="csr"), np.ones(n)
    budget = 1 << 20
    tracemalloc.start()
    try:
        with pytest.raises(DepthOrderError, match="budget"):
            solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set", memory_budget=budget)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 1.5 * budget
    # with room enough, the same problem solves exactly
    x, info = solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set", memory_budget=16 << 20)
    assert np.abs(x - 1.0).max() < 1e-12 and info["active"] == n


def test_an_infeasible_depth_problem_is_reported_not_ground_through():
    """Rows that contradict each other (x_i >= 1 and x_i <= 0 for 500 unknowns): both solvers
    say so with a DepthOrderError, in a bounded number of steps."""
    from sketchforge_assemble import DepthOrderError
    from sketchforge_assemble.depth import solve_depth

    n = 500
    P = sp.identity(n, format="csc") * 2.0
    q = np.linspace(-1, 1, n)
    Aeq, beq = sp.csr_matrix((0, n)), np.zeros(0)
    I = sp.identity(n, format="csr")
    Ain, bin_ = sp.vstack([I, -I]).tocsr(), np.r_[np.ones(n), np.zeros(n)]
    for method in ("active_set", "osqp"):
        t = time.perf_counter()
        with pytest.raises(DepthOrderError, match="could not be satisfied"):
            solve_depth(P, q, Aeq, beq, Ain, bin_, method=method, max_iter=5 * n)
        # a hang guard, not a speed target: the error must come, not a stall
        assert time.perf_counter() - t < 120
