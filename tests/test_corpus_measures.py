"""The corpus runner reports what each edit did: checked edit by edit against ``sculpt`` itself.

``run_edits`` turns random edits into the rates that tests/test_sculpt_corpus.py asserts and
benchmarks/bench_sculpt_corpus.py prints. A runner that misreported (a wrong distance, a crash
counted as a refusal, edits of the wrong kind) would make those rates meaningless, so here its
outcomes are compared with running the same edits through ``sculpt`` directly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sketchforge.errors import SculptError
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool import corpus, pipeline
from sketchforge_isophote_tool.corpus import KINDS, Outcome, corpus_layers, random_edit, refusal_reason, run_edits
from sketchforge_isophote_tool.fidelity import beside_distance, isophote_lines
from sketchforge_isophote_tool.layerdata import layer_data, vertex_shading
from sketchforge_isophote_tool.testing import LIGHT


@pytest.fixture(scope="module")
def blob():
    shape, _, mesh, rng = next(corpus_layers(("blob",), per_shape=1, seed=16))
    return shape, mesh, rng.bit_generator.state


def _rng(state) -> np.random.Generator:
    rng = np.random.default_rng()
    rng.bit_generator.state = state
    return rng


def test_each_outcome_is_what_sculpt_returned_for_that_edit(blob):
    shape, mesh, state = blob
    out = run_edits(shape, mesh, _rng(state), LIGHT, edits=4)
    assert [o.kind for o in out] == list(KINDS)  # the kinds in turn
    ld = layer_data(mesh, LIGHT, LAMBERTIAN)
    rng = _rng(state)
    for i, o in enumerate(out):
        e = None
        while e is None:
            e = random_edit(shape, ld, rng, kind=KINDS[i % len(KINDS)])
        assert (o.shape, o.kind, o.move, o.vertices) == (shape, e.kind, e.move, mesh.n_vertices)
        assert 0.0 < o.seconds < 60.0
        try:
            r = pipeline.sculpt(mesh, LIGHT, e.pick, e.band, e.stroke)
        except SculptError as exc:
            assert (o.status, o.reason) == ("refused", str(exc))
            assert math.isnan(o.before) and math.isnan(o.after) and math.isnan(o.fraction)
            assert math.isnan(o.max_dz) and math.isnan(o.beside)
            continue
        assert (o.status, o.reason) == ("ok", "")
        h = ld.h
        assert o.before == pytest.approx(r.before / h, rel=1e-12) and o.after == pytest.approx(r.after / h, rel=1e-12)
        assert o.fraction == r.fraction
        dz = np.abs(r.mesh.V[:, 2] - mesh.V[:, 2]).max() / mesh.V[:, 2].max()
        assert o.max_dz == pytest.approx(dz, rel=1e-12) and 0.0 < o.max_dz < 1.0
        E, _, _ = vertex_shading(ld.planar, r.mesh.V[:, 2], LIGHT, LAMBERTIAN)
        beside = beside_distance(isophote_lines(ld.planar, E, r.c), r.stroke, 0.5 * e.band, h) / h
        assert o.beside == pytest.approx(beside, rel=1e-12)
    assert any(o.status == "ok" for o in out)


def test_a_crash_is_counted_as_a_crash_and_a_refusal_as_a_refusal(blob, monkeypatch):
    shape, mesh, state = blob

    def crash(*a, **k):
        raise RuntimeError("boom")

    monkeypatch.setattr(pipeline, "sculpt", crash)
    out = run_edits(shape, mesh, _rng(state), LIGHT, edits=2)
    assert [(o.status, o.reason) for o in out] == [("crash", "RuntimeError('boom')")] * 2
    assert [o.kind for o in out] == list(KINDS[:2])  # a crash names the kind of edit that crashed
    for o in out:
        assert o.shape == shape and o.vertices == mesh.n_vertices and isinstance(o.move, float)
        assert all(math.isnan(x) for x in (o.before, o.after, o.fraction, o.max_dz, o.beside))
        assert isinstance(o.seconds, float) and 0.0 <= o.seconds < 60.0

    def refuse(*a, **k):
        raise SculptError("draw the stroke inside the band")

    monkeypatch.setattr(pipeline, "sculpt", refuse)
    out = run_edits(shape, mesh, _rng(state), LIGHT, edits=3, kinds=("bump",))
    assert [(o.status, o.reason, o.kind) for o in out] == [("refused", "draw the stroke inside the band", "bump")] * 3
    # Every other field of a refusal: the requested move, no distances, its time and size.
    ld = layer_data(mesh, LIGHT, LAMBERTIAN)
    rng = _rng(state)
    for o in out:
        e = None
        while e is None:
            e = random_edit(shape, ld, rng, kind="bump")
        assert o.shape == shape and o.move == e.move and o.vertices == mesh.n_vertices
        assert all(math.isnan(x) for x in (o.before, o.after, o.fraction, o.max_dz, o.beside))
        assert isinstance(o.seconds, float) and 0.0 <= o.seconds < 60.0


def test_a_layer_that_yields_no_edits_stops_after_a_bounded_number_of_tries(blob, monkeypatch):
    shape, mesh, state = blob
    calls = []

    def none(*a, **k):
        calls.append(1)
        return None

    monkeypatch.setattr(corpus, "random_edit", none)
    assert run_edits(shape, mesh, _rng(state), LIGHT, edits=3) == []
    assert len(calls) == 20 * 3


def _outcome(after, before=10.0, beside=0.0, status="ok"):
    return Outcome("blob", "shift", 3.0, status, "", before, after, 1.0, 0.1, 100, 0.1, beside)


def test_an_edit_lands_within_two_edge_lengths_or_30_percent_of_where_it_started():
    assert _outcome(2.9, before=10.0).lands and not _outcome(3.1, before=10.0).lands
    assert _outcome(1.9, before=4.0).lands and not _outcome(2.1, before=4.0).lands
    assert not _outcome(0.0, status="refused").lands
    # ...and moved: the isophote beside the stroke is within the same distance
    assert _outcome(2.5, before=10.0, beside=2.9).moved
    assert not _outcome(2.5, before=10.0, beside=3.1).moved
    assert not _outcome(3.1, before=10.0, beside=0.0).moved


@pytest.mark.parametrize("message, key", [
    ("the stroke lies in the rim margin: draw it farther in", "stroke in the rim margin"),
    ("the stroke has no part inside the band: draw it nearer", "stroke outside the band"),
    ("this layer cannot take this shading here: draw nearer", "no closer isophote reachable"),
    ("nothing to change: the stroke is on the isophote", "already on the isophote"),
    ("the pick lies outside the layer: click on the shape", "the pick lies outside the layer"),
])
def test_refusals_are_counted_by_reason(message, key):
    assert refusal_reason(message) == key
    assert len(refusal_reason("x" * 100 + ": tail")) == 60
