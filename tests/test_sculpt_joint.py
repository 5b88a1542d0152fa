"""Several isophotes redrawn in one edit (issue 35, point 4): ``sculpt_many`` and the
``sculpt_isophotes`` command. Jointly the isophotes land where a sequence of single edits
undoes the first; none ends farther from its stroke than it started (the per-stroke
fallback); crossing strokes of different values are refused in one line, as is a solver that
redraws one isophote per edit; the single edit's host rules hold per stroke (issue 36: a band
narrower than an edge, a stroke moving only in the rim margin, the 60% bound, no tolerance
for a stroke on its isophote); the command is one undo step, re-applies on re-inflation,
follows transforms and replays bit for bit."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from sculpt_helpers import isophote_stroke, stroke_moving_only_in_the_margin

from sketchforge.document import fileformat as ff
from sketchforge.document.document import Document
from sketchforge.errors import DocumentFormatError, NothingToDoError, SculptError
from sketchforge_isophote_tool.gauss_newton import GAUSS_NEWTON
from sketchforge_isophote_tool.joint import sculpt_many
from sketchforge_isophote_tool.pipeline import MAX_CHANGE, sculpt
from sketchforge_isophote_tool.testing import LIGHT, inflated

P1, P2 = [0.3, 0.2], [0.0, -0.05]


@pytest.fixture(scope="module")
def pair():
    """The ellipse and two strokes: the isophotes through P1 and P2, each moved 2.5 edge
    lengths towards its darker side."""
    mesh = inflated("ellipse", 0.04)
    h = 0.04
    s1, c1, _ = isophote_stroke(mesh, P1, offset=2.5 * h, half=0.22)
    s2, c2, _ = isophote_stroke(mesh, P2, offset=2.5 * h, half=0.22)
    return mesh, s1, s2


def test_one_stroke_is_the_single_edit_bit_for_bit(pair):
    mesh, s1, _ = pair
    a = sculpt(mesh, LIGHT, P1, 0.2, s1)
    b = sculpt_many(mesh, LIGHT, [(P1, 0.2, s1)])
    assert np.array_equal(a.mesh.V, b.mesh.V) and b.parts[0].after == a.after


def test_two_isophotes_land_jointly(pair):
    mesh, s1, s2 = pair
    r = sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.2, s2)])
    assert r.rounds == 1 and [p.fraction for p in r.parts] == [1.0, 1.0]
    for p in r.parts:
        assert p.before / p.h > 2.0 and p.after / p.h < 0.6  # moved onto its stroke
    assert r.parts[0].c != r.parts[1].c
    assert "2 isophotes" in r.describe() and "\n" not in r.describe()
    # One after the other, the second edit pulls the first isophote off its stroke.
    from sketchforge_isophote_tool.fidelity import isophote_lines, mean_distance
    from sketchforge_isophote_tool.layerdata import vertex_shading
    from sketchforge_isophote_tool.pipeline import _prepare

    seq = sculpt(sculpt(mesh, LIGHT, P1, 0.2, s1).mesh, LIGHT, P2, 0.2, s2)
    first = _prepare(r.layer, P1, 0.2, s1)  # measured as the joint edit measures it
    E, _, _ = vertex_shading(r.layer.planar, seq.mesh.V[:, 2], LIGHT, r.layer.model)
    seq_first = mean_distance(first.honoured, isophote_lines(r.layer.planar, E, first.c))
    assert seq_first > 2.0 * r.parts[0].after


def test_crossing_strokes_of_different_values_are_refused_in_one_line(pair):
    mesh, s1, s2 = pair
    # A stroke for the second isophote drawn across the first one's stroke.
    mid = s1[len(s1) // 2]
    across = np.array([mid + [-0.08, 0.08], mid, mid + [0.08, -0.08]])
    with pytest.raises(SculptError) as info:
        sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.4, across)])
    text = str(info.value)
    assert text.startswith("strokes 1 and 2 cross") and "different brightness" in text and "\n" not in text


def test_a_solver_that_redraws_one_isophote_per_edit_says_so(pair):
    mesh, s1, s2 = pair
    calls = []
    single = dataclasses.replace(GAUSS_NEWTON, name="single_only", several_isophotes=False,
                                 solve=lambda p, q: calls.append(1) or GAUSS_NEWTON.solve(p, q))
    with pytest.raises(SculptError) as info:
        sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.2, s2)], solver=single)
    assert str(info.value).startswith("the sculpt solver 'single_only' redraws one isophote per edit") and not calls
    assert sculpt_many(mesh, LIGHT, [(P1, 0.2, s1)], solver=single).parts[0].after < 1.0 * 0.04


def test_a_bad_stroke_is_named(pair):
    mesh, s1, _ = pair
    with pytest.raises(SculptError, match=r"^stroke 2: the stroke has no part inside the band"):
        sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.05, s1 + [0.0, 0.6])])


def _spoiled(sol, second, params):
    """The joint answer minus twice the second stroke's own edit: its isophote moves away."""
    return dataclasses.replace(sol, dz=sol.dz - 2.0 * GAUSS_NEWTON.solve(second, params).dz)


def _saboteur(spoil_rounds):
    """gauss_newton, but in the rounds where the first stroke asks for its whole change the
    second isophote is pushed off its stroke: what the host's fallback must undo."""
    seen = []

    def solve(problem, params):
        sol = GAUSS_NEWTON.solve(problem, params)
        first, second = problem.parts
        k = len(first.samples)
        whole = bool(np.all(problem.sample_values[:k] == first.c))
        seen.append(problem.sample_values.copy())
        if whole and len(seen) <= spoil_rounds:
            return _spoiled(sol, second, params)
        return sol

    return dataclasses.replace(GAUSS_NEWTON, name="saboteur", solve=solve), seen


def test_the_per_stroke_fallback_asks_the_others_for_less(pair):
    """When one stroke's isophote would end farther from it than it started, the other strokes
    ask for half of their change (their samples for E + (c - E)/2) and the edit is solved
    again; the stroke itself keeps its whole request."""
    mesh, s1, s2 = pair
    solver, seen = _saboteur(spoil_rounds=1)
    r = sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.2, s2)], solver=solver)
    assert r.rounds == 2 and [p.fraction for p in r.parts] == [0.5, 1.0]
    for p in r.parts:
        assert p.after <= max(p.before, 0.25 * p.h)
    B = _problem_rows(r, P1, s1)
    k = B.shape[0]  # the first stroke's samples come first
    assert np.all(seen[0][:k] == r.parts[0].c) and np.all(seen[0][k:] == r.parts[1].c)
    E_old = B @ r.layer.E
    assert np.allclose(seen[1][:k], E_old + 0.5 * (r.parts[0].c - E_old), rtol=0, atol=1e-12)
    assert np.all(seen[1][k:] == r.parts[1].c)


def _problem_rows(r, pick, stroke):
    from sketchforge_isophote_tool.pipeline import _prepare, build_problem

    e = _prepare(r.layer, pick, 0.2, stroke)
    return build_problem(r.layer, e.c, pick, e.iso, e.band, e.in_band, e.radius, e.pieces, e.honoured, e.before).host_data.B


def test_a_stroke_every_version_leaves_worse_is_refused_by_name(pair):
    mesh, s1, s2 = pair
    solver = dataclasses.replace(GAUSS_NEWTON, name="saboteur", solve=lambda p, q: _always_spoil(None, p, q))
    with pytest.raises(SculptError) as info:
        sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.2, s2)], solver=solver)
    text = str(info.value)
    assert text.startswith("stroke 2 (isophote n·l = ") and "farther from it" in text and "\n" not in text


def _always_spoil(solve, problem, params):
    return _spoiled(GAUSS_NEWTON.solve(problem, params), problem.parts[1], params)


# --- the host's rules of a single edit, per stroke (issue 36) --------------------------------


def test_a_band_narrower_than_one_edge_length_is_refused_naming_the_stroke(pair):
    mesh, s1, s2 = pair
    h = sculpt(mesh, LIGHT, P1, 0.2, s1).h
    with pytest.raises(SculptError) as info:
        sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.9 * h, s2)])
    text = str(info.value)
    assert text.startswith("stroke 2: the band (") and "narrower than one edge length" in text and "\n" not in text


def test_a_stroke_moving_only_in_the_rim_margin_is_refused_naming_it(pair):
    mesh, _, s2 = pair
    margin_only, _ = stroke_moving_only_in_the_margin(mesh, [0.2, 0.1], 1.5)
    calls = []
    spy = dataclasses.replace(GAUSS_NEWTON, name="spy", solve=lambda p, q: calls.append(1) or GAUSS_NEWTON.solve(p, q))
    with pytest.raises(SculptError, match=r"^stroke 2: the stroke runs within the rim margin .*draw it further inside"):
        sculpt_many(mesh, LIGHT, [(P2, 0.2, s2), ([0.2, 0.1], 0.3, margin_only)], solver=spy)
    assert not calls  # refused before any solve: nothing changes


def _lump(mesh, amplitude):
    """A bump of ``amplitude`` × the peak far from both strokes."""
    peak = mesh.V[:, 2].max()
    return amplitude * peak * np.exp(-np.sum((mesh.V[:, :2] - [-0.5, -0.2]) ** 2, axis=1) / 0.02)


def test_a_joint_change_over_60_percent_of_the_peak_is_scaled_down_and_says_so(pair):
    mesh, s1, s2 = pair
    lump = _lump(mesh, 1.2)
    huge = dataclasses.replace(GAUSS_NEWTON, name="huge", solve=lambda p, q: GAUSS_NEWTON.solve(p, q).dz + lump)
    r = sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.2, s2)], solver=huge)
    peak = mesh.V[:, 2].max()
    assert np.abs(r.mesh.V[:, 2] - mesh.V[:, 2]).max() <= MAX_CHANGE * peak * (1 + 1e-9)
    assert r.bounded_from == pytest.approx(1.2, abs=0.02)
    for p in r.parts:
        assert p.bounded_from == r.bounded_from and p.fraction == pytest.approx(MAX_CHANGE / r.bounded_from)
        assert p.after < p.before
    text = r.describe()
    assert f"would have changed heights by {r.bounded_from:.0%} of the peak, at most 60% is allowed" in text
    assert "\n" not in text
    # Within the bound nothing is scaled.
    plain = sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.2, s2)])
    assert plain.bounded_from == 0.0 and [p.fraction for p in plain.parts] == [1.0, 1.0]
    # Scaled down and still pulling the isophotes away: refused by stroke, with the figure.
    wrong = dataclasses.replace(GAUSS_NEWTON, name="wrong", solve=lambda p, q: lump - GAUSS_NEWTON.solve(p, q).dz)
    with pytest.raises(SculptError, match=r"^stroke \d \(isophote n·l = .*would change heights by 1\d\d% of the "
                                          r"peak; at most 60% is applied"):
        sculpt_many(mesh, LIGHT, [(P1, 0.2, s1), (P2, 0.2, s2)], solver=wrong)


def _pusher(mesh):
    """gauss_newton plus, in every round, the change of a single edit that moves the first
    isophote 0.12 h towards its brighter side: a stroke within the tolerance ends a little
    farther, still within a quarter edge length (what the first release let through)."""
    h = sculpt(mesh, LIGHT, P1, 0.2, isophote_stroke(mesh, P1, offset=0.1, half=0.22)[0]).h
    other, _, _ = isophote_stroke(mesh, P1, offset=-0.12 * h, half=0.22)
    push = sculpt(mesh, LIGHT, P1, 0.2, other, never_worse=False).mesh.V[:, 2] - mesh.V[:, 2]
    return dataclasses.replace(GAUSS_NEWTON, name="pusher", solve=lambda p, q: GAUSS_NEWTON.solve(p, q).dz + push), h


def test_a_stroke_within_the_tolerance_may_not_end_farther_in_a_joint_edit(pair):
    mesh, _, s2 = pair
    pusher, h = _pusher(mesh)
    on, _, _ = isophote_stroke(mesh, P1, offset=0.05 * h, half=0.22)
    edits = [(P1, 0.2, on), (P2, 0.2, s2)]
    # Without the rule the first isophote ends farther, yet within a quarter edge length.
    loose = sculpt_many(mesh, LIGHT, edits, solver=pusher, never_worse=False)
    first = loose.parts[0]
    assert first.before < first.after <= 0.25 * h
    with pytest.raises(SculptError) as info:
        sculpt_many(mesh, LIGHT, edits, solver=pusher)
    text = str(info.value)
    assert text.startswith("stroke 1 (isophote n·l = ") and "lies on its isophote already" in text
    assert "left it farther" in text and "\n" not in text
    # Every stroke within the tolerance: nothing to do, as for a single stroke.
    on2, _, _ = isophote_stroke(mesh, P2, offset=0.05 * h, half=0.22)
    with pytest.raises(NothingToDoError, match="every stroke lies on its isophote already"):
        sculpt_many(mesh, LIGHT, [(P1, 0.2, on), (P2, 0.2, on2)], solver=pusher)
    # The built-in solver on the same strokes: applied with none farther, or refused as done.
    try:
        r = sculpt_many(mesh, LIGHT, [(P1, 0.2, on), (P2, 0.2, s2)])
    except NothingToDoError:
        pass
    else:
        assert all(p.after <= p.before for p in r.parts), [(p.before / h, p.after / h) for p in r.parts]


# --- the command ------------------------------------------------------------------------------


def _doc(host):
    doc = Document(host=host)
    ring = [[math.cos(t), 0.7 * math.sin(t)] for t in np.linspace(0, 2 * math.pi, 120, endpoint=False)]
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    doc.execute({"command": "set_contour", "layer": "a", "points": ring, "closed": True})
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"resolution": 0.05}})
    return doc


def _entry(doc):
    mesh = doc.layer("a").mesh
    light = doc.light.direction
    s1, _, _ = isophote_stroke(mesh, P1, offset=0.1, half=0.22, light=light)
    s2, _, _ = isophote_stroke(mesh, P2, offset=0.1, half=0.22, light=light)
    return {"command": "sculpt_isophotes", "layer": "a",
            "edits": [{"pick": P1, "band": 0.2, "stroke": s1.tolist()}, {"pick": P2, "band": 0.2, "stroke": s2.tolist()}]}


def test_the_command_is_one_step_reapplies_follows_a_move_and_replays(real_host, tmp_path):
    doc = _doc(real_host)
    before = doc.layer("a").mesh
    n = doc.undo_stack.count()
    doc.execute(_entry(doc))
    assert doc.undo_stack.count() == n + 1 and doc.undo_stack.command(n).text() == "Sculpt 2 isophotes"
    edited = doc.layer("a").mesh.V.copy()
    stored = doc.layer("a").edits[-1]
    assert stored["light"] == doc.light.to_list() and stored["solver"] == "gauss_newton"
    # Re-inflation re-applies it, with the light it was made with.
    doc.execute({"command": "set_light", "direction": [0.0, 0.0, 1.0]})
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.2}})
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.0}})
    assert np.array_equal(doc.layer("a").mesh.V, edited)
    # A move takes every isophote of the edit along.
    doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1.0, 0.0, 0.5], [0.0, 1.0, -0.25]]})
    moved = doc.layer("a").edits[-1]
    for old, new in zip(stored["edits"], moved["edits"]):
        assert new["pick"] == [old["pick"][0] + 0.5, old["pick"][1] - 0.25] and new["band"] == old["band"]
        assert np.allclose(np.array(new["stroke"]) - old["stroke"], [0.5, -0.25], atol=1e-15)
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.1}})
    assert len(doc.layer("a").edits) == 1
    # Saved and replayed: bit for bit.
    data = json.loads(ff.dumps(doc))
    assert ff.compare(ff.replay_journal(*ff.validate_header(data, "t"), host=real_host), doc) == []
    assert ff.compare(ff.document_from_dict(data, "t", host=real_host), doc) == []
    # Undone back to the inflated layer.
    while doc.undo_stack.index > n:
        doc.undo_stack.undo()
    assert doc.layer("a").mesh is before


@pytest.mark.parametrize(
    "edit, words",
    [
        ({"edits": []}, "'edits' must list at least one edit"),
        ({"edits": [{"pick": [0, 0], "band": 0.2}]}, "needs the field 'stroke' (edits[0])"),
        (
            {"edits": [{"pick": [0, 0], "band": 0.2, "stroke": [[0, 0], [1, 1]], "c": 1}]},
            "unknown field 'c' (an edit has pick, band and stroke) (edits[0])",
        ),
        (
            {"edits": [{"pick": [0, 0, 0], "band": 0.2, "stroke": [[0, 0], [1, 1]]}]},
            "'pick' must be 2 numbers [x, y] (edits[0])",
        ),
        ({"edits": [[0, 0]]}, "each edit must be an object"),
        ({"edits": [{"pick": [0, 0], "band": 0.2, "stroke": [[0, 0], [1, 1]]}] * 17}, "at most 16 isophotes"),
    ],
)
def test_a_bad_journal_entry_is_one_line_naming_the_edit(real_host, edit, words):
    with pytest.raises(DocumentFormatError) as info:
        real_host.commands.from_dict({"command": "sculpt_isophotes", "layer": "a", **edit})
    assert words in str(info.value) and "\n" not in str(info.value)


def test_a_joint_edit_with_a_one_isophote_solver_changes_nothing(real_host):
    if "strips" not in real_host.solvers("sculpt"):
        pytest.skip("the strips plugin is not installed")
    doc = _doc(real_host)
    before = doc.layer("a").mesh
    with pytest.raises(SculptError, match="^the sculpt solver 'strips' redraws one isophote per edit"):
        doc.execute({**_entry(doc), "solver": "strips"})
    assert doc.layer("a").mesh is before


def test_several_isophotes_must_be_true_or_false_at_registration():
    from sketchforge.plugins.hookspecs import hookimpl
    from sketchforge.plugins.solvers import SculptSolver
    from sketchforge.plugins.testing import make_test_host

    class Plugin:
        __name__ = "vague"

    vague = SculptSolver("vague", GAUSS_NEWTON.solve, check_params=GAUSS_NEWTON.check_params, several_isophotes="yes")
    plugin = Plugin()
    plugin.sketchforge_sculpt_solvers = hookimpl(specname="sketchforge_sculpt_solvers")(lambda: [vague])
    host = make_test_host(plugin)
    assert "vague" not in host.solvers("sculpt")
    assert any("sculpt solver 'vague': several_isophotes must be True or False" in p for p in host.problems), host.problems


def test_every_solver_gets_the_whole_light(real_host, pair):
    """The host hands the 3D light to the solver, z included, for one isophote and several."""
    mesh, s1, s2 = pair
    seen = []
    spy = dataclasses.replace(GAUSS_NEWTON, name="spy", solve=lambda p, q: seen.append(p.light.copy()) or GAUSS_NEWTON.solve(p, q))
    from sketchforge.document.layer import Light

    light = Light.from_angle(30.0, 55.0).direction
    sculpt(mesh, light, P1, 0.2, isophote_stroke(mesh, P1, offset=0.1, half=0.2, light=light)[0], solver=spy)
    sculpt_many(mesh, light, [(P1, 0.2, isophote_stroke(mesh, P1, offset=0.1, half=0.2, light=light)[0]),
                              (P2, 0.2, isophote_stroke(mesh, P2, offset=0.1, half=0.2, light=light)[0])], solver=spy)
    assert len(seen) >= 2 and all(np.array_equal(l, light) for l in seen) and light[2] > 0.8


def test_choosing_another_solver_keeps_the_picks_it_can_take(real_host):
    from sketchforge_isophote_tool.tool import SculptIsophoteTool

    doc = _doc(real_host)
    tool = SculptIsophoteTool(doc, band=0.2)
    assert tool.pick_at(P1)
    assert tool.add_pick_at(P2) and len(tool.picks) == 2
    assert tool.set_band(0.15)  # the newest pick's band
    assert [p.band for p in tool.picks] == [0.2, 0.15]
    tool.set_options({"model": "lambertian", "params": {"smoothness": 1.5}})
    assert [p.band for p in tool.picks] == [0.2, 0.15] and tool.band == 0.15
    assert np.array_equal(tool.picks[1].pick, P2)
    if "strips" in real_host.solvers("sculpt"):
        tool.set_options({"solver": "strips"})
        assert len(tool.picks) == 1 and "redraws one isophote per edit" in tool.message
