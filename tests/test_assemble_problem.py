"""The depth QP that the assembly builds, and what the assembly reports about its solve, checked
against their definitions (``depth.build_problem``'s docstring and ``AssemblyResult``'s) on a
small document with every kind of layer: a skipped slot, a part behind the body, the body, a
part in front and a free eye.

The problem and the answer are caught on their way through the assembly (spies on
``build_problem`` and ``settle_free_parts``), so what is checked is what the app builds.
"""

from __future__ import annotations

import time
from functools import cache

import numpy as np
import pytest
import scipy.sparse as sp
from assemble_shapes import arc as _arc
from assemble_shapes import assemble_caught
from assemble_shapes import ellipse as _ellipse
from assemble_shapes import inflate as _inflate

from sketchforge.errors import ParameterError
from sketchforge.geometry.mesh import Mesh
from sketchforge_assemble import BACK, FRONT, assemble_detailed
from sketchforge_assemble import diagnostics as dg
from sketchforge_assemble.attach import lo_chain_index
from sketchforge_assemble.depth_rows import _sheet_operators


@cache
def _layers(eye_at=(0.45, -0.3)):
    """(meshes, closed): slot 0 empty, 1 an arm behind the body, 2 the body, 3 an arm in front,
    4 a free eye drawn over the front arm where it leaves the body."""
    body = _inflate(_ellipse(0, 0, 0.6, 0.4), True)
    back_arm = _inflate(_arc(-0.35, 0.2, 0.25, -80, 220), False)
    front_arm = _inflate(_arc(0.35, -0.2, 0.25, 100, 400), False)
    eye = _inflate(_ellipse(*eye_at, 0.06, 0.05, 24), True, 0.03)
    return (None, back_arm, body, front_arm, eye), (False, False, False, False, True)


@cache
def _caught(fillet: float, eye_at=(0.45, -0.3)):
    """(result, build_problem's arguments and answer, settle_free_parts' answer)."""
    meshes, closed = _layers(eye_at)
    return assemble_caught(meshes, closed, {"fillet": fillet})


FILLETS = [0.0, 4.0]


@pytest.mark.parametrize("fillet", FILLETS)
def test_the_energy_is_each_layer_s_dirichlet_energy_plus_its_pull_to_rest(fillet):
    res, got = _caught(fillet)
    sheets, offsets = got["args"][0], got["args"][1]
    reg, stiffness = got["args"][6], got["args"][7]
    P, q, Aeq, beq, Ain, bin_, info = got["out"]
    allxy = np.vstack([s.xy for s in sheets])
    w = reg / np.linalg.norm(allxy.max(0) - allxy.min(0)) ** 2
    assert info["reg_weight"] == pytest.approx(w, rel=1e-12)
    assert abs(P - P.T).max() <= 1e-12
    rest = np.repeat(info["rest_depth"], np.diff(offsets))
    M = sp.block_diag([_sheet_operators(s)[1] for s in sheets]).tocsr()
    # a shift of a layer as a whole costs only the pull: P·1 = w·M·1 (the springs of a blended
    # junction are differences too)
    assert np.abs(P @ np.ones(P.shape[0]) - w * (M @ np.ones(P.shape[0]))).max() <= 1e-9 * w
    if fillet == 0.0:
        # no springs: the blocks are (1 + stiffness on a host)·(-L) + w·M, q pulls towards rest
        for k, s in enumerate(sheets):
            L, Mk = _sheet_operators(s)
            a, b = offsets[k], offsets[k + 1]
            want = (1.0 + (stiffness if s.chains else 0.0)) * (-L) + w * Mk
            assert abs(P[a:b, a:b] - want).max() <= 1e-9
            assert P[a:b].nnz == P[a:b, a:b].nnz  # nothing couples two layers
        assert np.abs(q + w * (M @ rest)).max() <= 1e-12
        assert any(s.chains for s in sheets) and stiffness == 20.0


@pytest.mark.parametrize("fillet", FILLETS)
def test_glue_rows_join_each_junction_vertex_to_its_twin_on_the_host(fillet):
    res, got = _caught(fillet)
    sheets, offsets, front_off, back_off, attachments = got["args"][:5]
    P, q, Aeq, beq, Ain, bin_, info = got["out"]
    Aeq = sp.csr_matrix(Aeq)
    assert sorted((a.upper, a.lower, a.side) for a in attachments) == [(0, 1, BACK), (2, 1, FRONT)]
    assert Aeq.shape[0] == sum(len(sheets[a.upper].junction) for a in attachments) == res.n_equalities
    row = 0
    for a_i, at in enumerate(attachments):
        j = sheets[at.upper].junction
        c = sheets[at.lower].chains[lo_chain_index(attachments, a_i)]
        assert np.abs(sheets[at.upper].xy[j] - sheets[at.lower].xy[c]).max() <= 1e-12  # the same points
        for v, u in zip(j, c):
            r = Aeq.getrow(row)
            assert dict(zip(r.indices.tolist(), r.data.tolist())) == {offsets[at.upper] + v: 1.0,
                                                                         offsets[at.lower] + u: -1.0}
            row += 1
        rhs = beq[row - len(j):row]
        if fillet == 0.0:  # the plain sleeve: the part's facing face lies on the host's face
            if at.side == FRONT:
                want = front_off[at.lower][c] + back_off[at.upper][j]
            else:
                want = -back_off[at.lower][c] - front_off[at.upper][j]
            assert np.abs(rhs - want).max() <= 1e-15
        else:  # the blended junction lifts the part off the host, towards the part
            lift = (rhs - (front_off[at.lower][c] + back_off[at.upper][j]) if at.side == FRONT
                    else -(rhs + back_off[at.lower][c] + front_off[at.upper][j]))
            assert lift.min() >= -1e-15 and lift.max() > 0.0


@pytest.mark.parametrize("fillet", FILLETS)
def test_depth_rows_stack_the_rest_depths_and_count_the_overlapping_pairs(fillet):
    res, got = _caught(fillet)
    sheets, offsets = got["args"][:2]
    P, q, Aeq, beq, Ain, bin_, info = got["out"]
    polys = [s.polygon() for s in sheets]
    pairs = [(i, k) for i in range(len(sheets)) for k in range(i + 1, len(sheets))
             if polys[i].intersection(polys[k]).area > 0]
    assert info["overlapping_pairs"] == len(pairs) == 4  # each arm over the body, the eye over the body and the front arm
    assert Ain.shape[0] == len(bin_) == res.n_inequalities > 0
    # every row involves exactly two layers that overlap
    layer_of = np.repeat(np.arange(len(sheets)), np.diff(offsets))
    Ain = sp.csr_matrix(Ain)
    lay = {(int(layer_of[Ain.indices[Ain.indptr[r]:Ain.indptr[r + 1]]].min()),
            int(layer_of[Ain.indices[Ain.indptr[r]:Ain.indptr[r + 1]]].max())) for r in range(Ain.shape[0])}
    assert lay == set(pairs)
    # each overlapping sheet face's point locator is left in the dict the caller passed (the
    # assembly shares it with the fillets' springs: one locator per sheet face)
    assert {i for i, _ in got["kw"]["locators"]} >= {i for pair in pairs for i in pair}
    # the rest depths stack the layers back to front: at rest every depth row holds, and each
    # layer in front of another sits as low as its rows allow
    rest = np.asarray(info["rest_depth"])
    slack = Ain @ np.repeat(rest, np.diff(offsets)) - bin_
    assert slack.min() >= -1e-12
    assert rest[0] == 0.0 and np.all(rest[1:] > 0)
    for f in range(1, len(sheets)):
        mine = np.flatnonzero(Ain[:, offsets[f]:offsets[f + 1]].sum(axis=1).A.ravel() > 0.5)
        assert len(mine) and slack[mine].min() <= 1e-12, f


@pytest.mark.parametrize("fillet", FILLETS)
def test_the_report_tells_the_truth_about_the_solve(fillet):
    res, got = _caught(fillet)
    meshes, closed = _layers()
    sheets, offsets = got["args"][:2]
    gap = got["args"][5]
    P, q, Aeq, beq, Ain, bin_, info = got["out"]
    x, shift = got["settled"]
    pad = 0.5 * gap
    h = np.median([s.h for s in sheets])
    assert gap == pytest.approx(0.1 * h, rel=1e-12) and res.solver["gap"] == gap
    slack = Ain @ x - bin_
    assert res.max_violation == max(0.0, float(-slack.min())) == 0.0
    assert res.glue_error == pytest.approx(float(np.abs(Aeq @ x - beq).max()), abs=1e-18)
    assert res.glue_error <= 1e-12
    # OSQP leaves every row at least the pad clear: the rows within the pad are the active ones
    assert res.solver["iterations"] == 0
    assert res.n_active == int(np.sum(slack <= pad + 1e-6)) > 0
    # the eye (input slot 4) was lowered onto what it was drawn on: reported by input index
    assert list(res.solver["free_shift"]) == [4] and list(shift) == [3]
    assert res.solver["free_shift"][4] == shift[3] >= 0.0
    if fillet == 0.0:  # at its rest depth the eye hovers over the arm: it is lowered onto it
        assert shift[3] > 0.01
    assert res.solver["rest_depth"] == info["rest_depth"] and res.solver["overlapping_pairs"] == 4
    # input indices everywhere: slot 0 had no mesh
    assert sorted((a.upper, a.lower) for a in res.attachments) == [(1, 2), (3, 2)]
    assert set(np.unique(res.face_layer).tolist()) == {1, 2, 3, 4}
    assert res.components == 2  # the body with its arms, and the eye
    for stage in ("attach", "remesh", "constraints", "solve", "stitch", "total"):
        assert 0.0 <= res.timings[stage] <= got["wall"]
    assert res.timings["total"] >= res.timings["solve"]
    if fillet > 0:
        assert 0.0 <= res.timings["fair"] + res.timings["fair_check"] <= got["wall"]
    assert res.solver["fair_zone"] == (None if fillet == 0.0 else "narrow")
    assert res.mesh.n_faces == len(res.face_layer) == len(res.face_kind)


def test_a_layer_without_faces_is_skipped_like_an_empty_slot():
    meshes, closed = _layers()
    empty = Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64))
    a = assemble_detailed(list(meshes), list(closed))
    b = assemble_detailed([empty, *meshes[1:]], list(closed))
    assert a.mesh.identical(b.mesh)
    assert np.array_equal(a.face_layer, b.face_layer)
    with pytest.raises(ParameterError, match="there is no layer with a mesh to assemble"):
        assemble_detailed([None, empty])


@pytest.mark.parametrize("key", ["margin", "gap", "reg", "stiffness"])
@pytest.mark.parametrize("bad", [0, -1.5, float("nan"), "1"])
def test_a_bad_assembly_parameter_is_named_with_its_value(key, bad):
    meshes, closed = _layers()
    with pytest.raises(ParameterError) as err:
        assemble_detailed(list(meshes), list(closed), params={key: bad})
    assert str(err.value) == f"assembly parameter '{key}' must be a positive number, got {bad!r}"


@pytest.mark.parametrize("eye_at", [(0.45, -0.3), (-0.4, 0.3)])
def test_the_glued_groups_solve_reports_its_active_rows_and_status(eye_at):
    # the depth solve without the free eye, straight from the assembly's own QP: what it reports
    # is what its answer shows (at (-0.4, 0.3) the glue moves the back arm past the eye's rest:
    # the eye is lifted whole, and its own rows come within the pad)
    from sketchforge_assemble.depth import solve_without_free_parts

    res, got = _caught(0.0, eye_at)
    sheets, offsets = got["args"][:2]
    P, q, Aeq, beq, Ain, bin_, info = got["out"]
    pad = 0.5 * got["args"][5]
    for free in ([3], []):
        x, sinfo = solve_without_free_parts(P, q, Aeq, beq, Ain, bin_, offsets, free, info["rest_depth"], pad=pad)
        slack = Ain @ x - bin_
        assert slack.min() >= 0.0
        assert sinfo["active"] == int(np.sum(slack <= pad + 1e-6)) > 0
        assert sinfo["osqp_status"] == "solved" and sinfo["groups"] == 1 and sinfo["iterations"] == 0
        assert sinfo["free_in_solve"] == []
        if free:  # the eye left out sits at its rest depth, or lifted whole off what it crosses
            assert (3 in sinfo["free_lifted"]) == (eye_at == (-0.4, 0.3))
            eye = x[offsets[3]:offsets[4]]
            assert np.ptp(eye) == 0.0
            assert eye[0] == pytest.approx(info["rest_depth"][3] + sinfo["free_lifted"].get(3, 0.0), abs=1e-12)


def test_closed_marks_a_part_with_a_junction_as_free():
    meshes, _ = _layers()
    body, arm = meshes[2], meshes[3]
    assert len(arm.junction) > 0
    glued = assemble_detailed([body, arm], [False, False])
    free = assemble_detailed([body, arm], [False, True])
    assert len(glued.attachments) == 1 and glued.components == 1
    assert free.attachments == [] and free.components == 2 and free.n_equalities == 0


def test_an_outline_listed_clockwise_assembles_like_the_same_outline_counter_clockwise():
    meshes, closed = _layers()
    body = meshes[2]
    flipped = Mesh(body.V, body.F, boundary=np.asarray(body.boundary)[::-1].copy(), junction=body.junction,
                   holes=body.holes)
    a = assemble_detailed([meshes[1], body, meshes[3]])
    b = assemble_detailed([meshes[1], flipped, meshes[3]])
    assert a.mesh.identical(b.mesh)


def test_a_bad_fillet_or_fair_is_named_with_its_value():
    meshes, closed = _layers()
    for bad in (-1.0, float("inf"), "4"):
        with pytest.raises(ParameterError) as err:
            assemble_detailed(list(meshes), list(closed), params={"fillet": bad})
        assert str(err.value) == f"assembly parameter 'fillet' must be a number >= 0, got {bad!r}"
    for bad in (-1, 51, 2.0, True):
        with pytest.raises(ParameterError) as err:
            assemble_detailed(list(meshes), list(closed), params={"fair": bad})
        assert str(err.value) == f"assembly parameter 'fair' must be a whole number of rings from 0 to 50, got {bad!r}"


def test_a_bad_solver_is_named_with_its_value():
    meshes, closed = _layers()
    with pytest.raises(ParameterError) as err:
        assemble_detailed(list(meshes), list(closed), params={"qp_solver": "cg"})
    assert str(err.value) == "assembly parameter 'qp_solver' must be 'osqp' or 'active_set', got 'cg'"


def test_a_fairing_taken_from_the_cache_still_reports_its_time():
    from sketchforge_assemble import AssemblyCache

    meshes, closed = _layers()
    cache = AssemblyCache()
    first = assemble_detailed(list(meshes), list(closed), cache=cache)
    t0 = time.perf_counter()
    again = assemble_detailed(list(meshes), list(closed), cache=cache)
    wall = time.perf_counter() - t0
    assert again.mesh.identical(first.mesh)
    assert 0.0 <= again.timings["fair"] <= wall and again.timings["fair_check"] == 0.0


def test_two_junctions_touching_on_one_layer_keep_apart_and_say_so():
    # two legs side by side whose junctions (the closing segments of their strokes) meet at one
    # point on the body (issue 34: twin ears, legs drawn close): the later keeps the longest
    # stretch of its junction clear of the earlier one's, and the note names both
    from sketchforge.geometry.attachment import SEPARATION_EDGES

    body = _inflate(_ellipse(0, 0, 0.6, 0.4), True)
    def leg(pts):
        pts = np.asarray(pts, float)
        return np.vstack([np.linspace(a, b, 12, endpoint=False) for a, b in zip(pts[:-1], pts[1:])] + [pts[-1:]])

    left = _inflate(leg([[0.0, 0.0], [-0.1, -0.7], [-0.35, -0.7], [-0.25, 0.0]]), False)
    right = _inflate(leg([[0.25, 0.0], [0.35, -0.7], [0.1, -0.7], [0.0, 0.0]]), False)
    res = assemble_detailed([body, left, right], names=["body", "left", "right"])
    assert sorted((a.upper, a.lower, a.side) for a in res.attachments) == [(1, 0, FRONT), (2, 0, FRONT)]
    kept = {a.upper: a.keep for a in res.attachments}
    assert kept[1] is None and kept[2] is not None  # the first drawn keeps all of its junction
    first, last = kept[2]
    J = right.V[right.junction[first:last + 1], :2]
    other = left.V[left.junction, :2]
    gap = np.min(np.linalg.norm(J[:, None] - other[None], axis=2))
    # the separation is in the largest edge length of the three: the body's (median 0.042; the
    # legs, two edge lengths wide, are meshed finer by the inflater)
    h_body = np.median(np.linalg.norm(body.V[body.F[:, 0], :2] - body.V[body.F[:, 1], :2], axis=1))
    assert gap >= SEPARATION_EDGES * 0.9 * h_body and last - first >= 2
    assert len(res.notes) == 1 and "layer 'right' meets 'left'" in res.notes[0] and "'body'" in res.notes[0]
    assert not res.warnings
    _, count = dg.edge_counts(res.mesh.F)
    assert np.all(count == 2) and len(dg.intersecting_pairs(res.mesh.V, res.mesh.F)) == 0
    # moved apart by a few edges, the same two legs attach whole
    apart = _inflate(leg([[0.45, 0.0], [0.55, -0.7], [0.3, -0.7], [0.2, 0.0]]), False)
    res = assemble_detailed([body, left, apart], names=["body", "left", "right"])
    assert sorted((a.upper, a.lower, a.keep) for a in res.attachments) == [(1, 0, None), (2, 0, None)]
    assert not res.notes
def test_assemble_meshes_passes_closed_and_params_on():
    from sketchforge_assemble import assemble_meshes

    meshes, closed = _layers()
    body, arm = meshes[2], meshes[3]
    for cl, params in (([False, True], None), ([False, False], {"fillet": 0.0})):
        assert assemble_meshes([body, arm], cl, params).identical(assemble_detailed([body, arm], cl, params).mesh)
    assert not assemble_meshes([body, arm], [False, True]).identical(assemble_meshes([body, arm]))
