"""What the app draws after an edit, and how a parameter change re-applies an edit.

The characteristics (the curves the strips run along, thesis 3.1.2) and the landed isophote are
drawn over the layer after each edit; a re-inflation re-runs every sculpt edit. These tests check
the traced curves step by step (their spacing, direction, length and where they stop), the
landed isophote's pieces, and the re-applied edit against a fresh one.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import shapely
from test_sculpt_tool import PICK, RING, STROKE, ellipse_doc, make_tool

from sketchforge.errors import SculptError
from sketchforge_isophote_tool.layerdata import vertex_shading


@pytest.fixture(scope="module")
def result(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK)
    return tool.preview_job(STROKE)()


def _flow(r, P):
    """-∇R (the strips' base direction) interpolated at points P, as the tracer sees it."""
    ld = r.layer
    _, Rp, Rq = vertex_shading(ld.planar, ld.z, ld.light, ld.model)
    return -ld.planar.locator.interpolate(np.column_stack([Rp, Rq]), P)


def _seed_index(line, stroke) -> int:
    return int(np.argmin(shapely.distance(shapely.points(line), stroke)))


def test_the_app_shows_fifteen_characteristics_by_default(result):
    assert len(result.characteristics()) == 15


def test_characteristics_advance_half_an_edge_length_per_step_along_minus_grad_r(result):
    r = result
    step = 0.5 * r.layer.planar.h
    for line in r.characteristics(n=9):
        seg = np.diff(line, axis=0)
        length = np.linalg.norm(seg, axis=1)
        # every step is exactly one step long: no repeated point, no gap, no other step
        assert np.allclose(length, step, rtol=1e-9), (length.min(), length.max(), step)
        # from the back end to the front end, along -∇R (the midpoint rule keeps each chord
        # within a small angle of the direction at its middle)
        mid = line[:-1] + 0.5 * seg
        f = _flow(r, mid)
        cos = np.einsum("ij,ij->i", seg, f) / (length * np.linalg.norm(f, axis=1))
        assert cos.min() > 0.95, cos.min()


def test_characteristics_reach_as_far_as_the_edit_or_stop_at_the_rim(result):
    r = result
    pd = r.layer.planar
    step = 0.5 * pd.h
    n_steps = int(np.ceil(r.reach / step))
    rim = pd.outline.exterior
    stroke = r.stroke
    full = 0
    for line in r.characteristics(n=11):
        assert shapely.contains_xy(pd.outline.buffer(1e-9), line[:, 0], line[:, 1]).all()  # never off the layer
        k = _seed_index(line, stroke)
        for count, end in ((len(line) - 1 - k, line[-1]), (k, line[0])):
            assert count <= n_steps
            if count < n_steps:  # stopped early: the next step would have left the layer
                assert rim.distance(shapely.Point(end)) < step * (1 + 1e-9)
            else:
                full += 1
    assert full > 0  # some run their whole length


def test_characteristics_of_a_stroke_in_two_pieces_start_on_both(result):
    r = result
    P = np.asarray(r.stroke.coords) if r.stroke.geom_type == "LineString" else None
    assert P is not None and len(P) >= 4
    # The band clips a stroke into pieces; the seeds are spread over all of them.
    a, b = P[: len(P) // 2], P[len(P) // 2 :]
    two = dataclasses.replace(r, stroke=shapely.MultiLineString([a, b]))
    lines = two.characteristics(n=6)
    assert len(lines) == 6
    seeds = np.array([line[_seed_index(line, two.stroke)] for line in lines])
    on_a = shapely.distance(shapely.points(seeds), shapely.LineString(a)) < 1e-9
    on_b = shapely.distance(shapely.points(seeds), shapely.LineString(b)) < 1e-9
    assert (on_a | on_b).all() and on_a.any() and on_b.any()


def test_the_landed_isophote_is_shown_in_pieces_and_only_as_lines(result, monkeypatch):
    r = result
    lines = r.new_isophotes()
    assert lines and all(L.ndim == 2 and L.shape[1] == 2 and len(L) >= 2 for L in lines)
    L = max(lines, key=len)
    assert len(L) >= 9
    # Cut the support into two discs over the landed isophote, plus a thin wedge that touches
    # it at a single vertex: two line pieces come back, and no stray point.
    i, j, k = len(L) // 5, 4 * len(L) // 5, len(L) // 2
    t = L[k + 1] - L[k - 1]
    t /= np.linalg.norm(t)
    nrm = np.array([-t[1], t[0]])
    h = r.h
    wedge = shapely.Polygon([L[k], L[k] + 2 * h * nrm + 0.2 * h * t, L[k] + 2 * h * nrm - 0.2 * h * t])
    discs = shapely.union(shapely.Point(L[i]).buffer(0.5 * h), shapely.Point(L[j]).buffer(0.5 * h))
    assert shapely.intersection(shapely.LineString(L), wedge).geom_type == "Point"
    monkeypatch.setattr(type(r), "support", property(lambda self: shapely.union(discs, wedge)))
    pieces = r.new_isophotes()
    assert len(pieces) >= 2 and all(len(p) >= 2 for p in pieces)
    near = [shapely.LineString(p).distance(shapely.Point(q)) < 1e-9 for p in pieces for q in (L[i], L[j])]
    assert sum(near) >= 2


def test_a_parameter_change_re_applies_an_edit_with_its_own_model():
    from test_sculpt_tool_preview import _half_lambert_host

    from sketchforge.document.document import Document

    host = _half_lambert_host()
    entry = {"command": "sculpt_isophote", "layer": "body", "pick": PICK, "band": 0.3, "stroke": STROKE,
             "model": "half_lambert"}
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": RING, "closed": True})
    doc.execute(entry)
    doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"inflation": 1.3}})
    ref = Document(host=host)
    ref.execute({"command": "add_layer", "id": "body"})
    ref.execute({"command": "set_contour", "layer": "body", "points": RING, "closed": True})
    ref.execute({"command": "set_inflate_params", "layer": "body", "params": {"inflation": 1.3}})
    ref.execute(entry)
    assert doc.layer("body").mesh.identical(ref.layer("body").mesh)


def test_an_edit_that_no_longer_applies_refuses_the_change_and_says_which(real_host, monkeypatch):
    from sketchforge_isophote_tool import command

    doc = ellipse_doc(real_host)
    for _ in range(2):
        doc.execute({"command": "sculpt_isophote", "layer": "body", "pick": PICK, "band": 0.3, "stroke": STROKE})
    before = doc.layer("body")
    count = doc.undo_stack.count()
    real_apply = command._apply
    calls = []

    def second_fails(*a, **k):
        calls.append(1)
        if len(calls) == 2:
            raise SculptError("the stroke lies in the rim margin")
        return real_apply(*a, **k)

    monkeypatch.setattr(command, "_apply", second_fails)
    with pytest.raises(SculptError) as info:
        doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"inflation": 1.3}})
    assert str(info.value) == (
        "sculpt edit 2 of layer 'body' no longer applies to the rebuilt surface (the stroke lies in "
        "the rim margin); the change was not made — undo that edit first to change these parameters"
    )
    assert doc.layer("body").same_state(before) and doc.undo_stack.count() == count


def _unit_flow(r):
    def f(x):
        v = _flow(r, np.asarray(x, dtype=np.float64).reshape(1, 2))[0]
        return v / np.linalg.norm(v)
    return f


def test_characteristics_follow_the_flow_to_second_order(result):
    # The tracer takes midpoint steps of half an edge length along -∇R (unit speed). Against a
    # fine RK4 integration of the same interpolated field, 20 steps stay within 1e-4 (~h/250);
    # a first-order step (a midpoint taken backwards, or too far) drifts ~2e-3.
    r = result
    step = 0.5 * r.layer.planar.h

    def f(X):
        v = _flow(r, X)
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    lines = r.characteristics(n=5)
    seeds = [_seed_index(line, r.stroke) for line in lines]
    ref = np.array([line[k] for line, k in zip(lines, seeds)])
    worst = 0.0
    sub = 5
    for i in range(1, 21):
        for _ in range(sub):
            h = step / sub
            k1 = f(ref)
            k2 = f(ref + 0.5 * h * k1)
            k3 = f(ref + 0.5 * h * k2)
            k4 = f(ref + h * k3)
            ref = ref + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        for j, (line, k) in enumerate(zip(lines, seeds)):
            if k + i < len(line):
                worst = max(worst, float(np.linalg.norm(line[k + i] - ref[j])))
    assert 0.0 < worst < 1e-4, worst


def test_characteristics_traced_far_stop_on_the_rim_inside_the_layer(result):
    from sketchforge_isophote_tool.characteristics import base_characteristics

    r = result
    pd = r.layer.planar
    step = 0.5 * pd.h
    pieces = [np.asarray(g.coords) for g in getattr(r.stroke, "geoms", [r.stroke])]
    lines = base_characteristics(r.layer, pieces, reach=10.0, n=9)  # far beyond the layer
    assert len(lines) == 9
    rim = pd.outline.exterior
    for line in lines:
        assert np.allclose(np.linalg.norm(np.diff(line, axis=0), axis=1), step, rtol=1e-9)
        assert shapely.contains_xy(pd.outline.buffer(1e-9), line[:, 0], line[:, 1]).all()
        assert len(line) < 2 * 10.0 / step  # both halves stopped
        for end in (line[0], line[-1]):
            assert rim.distance(shapely.Point(end)) < step * (1 + 1e-9)


def test_a_characteristic_runs_through_triangle_zero_like_any_other(result):
    # Triangle 0 is a triangle like the others: a curve stepping into it goes on (or stops at
    # the rim just past it), rather than ending there as if it had left the layer.
    from sketchforge.geometry.locate import locate
    from sketchforge_isophote_tool.characteristics import base_characteristics

    r = result
    pd = r.layer.planar
    step = 0.5 * pd.h
    c0 = pd.V2[pd.F[0]].mean(axis=0)
    d = _unit_flow(r)(c0)
    perp = np.array([-d[1], d[0]])
    for sign in (1.0, -1.0):  # start one step before triangle 0, on whichever side is inside
        x0 = c0 - sign * step * d
        if locate(pd.V2, pd.F, x0[None])[0][0] >= 0:
            break
    stroke = np.array([x0 - 0.01 * step * perp, x0 + 0.01 * step * perp])
    (line,) = base_characteristics(r.layer, [stroke], reach=r.reach, n=1)
    face, _ = locate(pd.V2, pd.F, line)
    k = _seed_index(line, shapely.LineString(stroke))
    assert face[k] != 0 and (face == 0).any()


def test_stroke_samples_integrate_any_cubic_along_the_stroke_exactly():
    # The stroke's misfit is a line integral; two Gauss points per segment integrate every
    # polynomial of degree 3 along each segment exactly (the squared residual of a linear field
    # is of degree 2). Checked against the closed form on a bent, unevenly sampled stroke.
    from sketchforge_isophote_tool.stroke import stroke_samples

    pieces = [np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.5, 2.5]]), np.array([[3.0, 1.0], [3.0, 1.25]])]
    S = stroke_samples(pieces)
    assert S.P.shape == (2 * 4, 2) and S.w.shape == (8,)

    def f(X):
        x, y = X[..., 0], X[..., 1]
        return 1.0 + x ** 3 - 2.0 * x * y ** 2 + 0.5 * y

    exact = 0.0
    for P in pieces:  # per segment: ∫0^1 f(a + t (b - a)) |b - a| dt by 40-point Gauss-Legendre
        tt, ww = np.polynomial.legendre.leggauss(40)
        t, w = 0.5 * (tt + 1.0), 0.5 * ww
        for a, b in zip(P[:-1], P[1:]):
            exact += np.linalg.norm(b - a) * np.sum(w * f(a + t[:, None] * (b - a)))
    assert np.sum(S.w * f(S.P)) == pytest.approx(exact, rel=1e-13)
    assert S.w.sum() == pytest.approx(1.0 + 2.0 + np.sqrt(0.5) + 0.25, rel=1e-14)  # the length
    # every sample lies on its segment, strictly inside it
    seg_a = np.concatenate([np.vstack([P[:-1]] * 2) for P in pieces])  # both points of a piece, in turn
    seg_b = np.concatenate([np.vstack([P[1:]] * 2) for P in pieces])
    t = np.einsum("ij,ij->i", S.P - seg_a, seg_b - seg_a) / np.einsum("ij,ij->i", seg_b - seg_a, seg_b - seg_a)
    assert np.all((t > 0.2) & (t < 0.8))
    assert np.allclose(seg_a + t[:, None] * (seg_b - seg_a), S.P, atol=1e-15)


def test_the_gauss_newton_step_s_conjugate_gradients_solve_n_unknowns_in_n_steps():
    # Conjugate gradients on an n x n SPD system reach the solution in n steps (in exact
    # arithmetic); a wrong update of the search direction loses that. Also with a Jacobi
    # preconditioner, and a zero right-hand side stops at once.
    from sketchforge_isophote_tool.heights import _pcg

    rng = np.random.default_rng(7)
    Q = rng.standard_normal((8, 8))
    A = Q @ Q.T + 0.5 * np.eye(8)
    b = rng.standard_normal(8)
    x = np.linalg.solve(A, b)
    for precondition in (lambda r: r.copy(), lambda r: r / np.diag(A)):
        got = _pcg(lambda v: A @ v, b, precondition, 8)
        assert np.abs(got - x).max() < 1e-8 * np.abs(x).max()
        assert np.abs(_pcg(lambda v: A @ v, b, precondition, 3) - x).max() > 1e-4  # not yet after 3
    assert np.array_equal(_pcg(lambda v: A @ v, np.zeros(8), lambda r: r.copy(), 8), np.zeros(8))


def test_a_layer_mesh_with_a_flat_triangle_is_refused_by_name():
    from sketchforge.errors import GeometryError
    from sketchforge.geometry.mesh import Mesh
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.layerdata import layer_data

    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    F = np.array([[0, 1, 2], [1, 3, 4], [1, 4, 2], [0, 3, 1]])  # the last one is flat (on y = 0)
    mesh = Mesh(V=V, F=F, boundary=np.array([0, 3, 4, 2]), junction=np.zeros(0, np.int64))
    with pytest.raises(GeometryError) as info:
        layer_data(mesh, np.array([1.0, 0.0, 0.0]), LAMBERTIAN)
    assert str(info.value).startswith("the layer's mesh has a triangle of zero area")
