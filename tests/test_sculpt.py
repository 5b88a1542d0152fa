"""The isophote edit `sculpt()`: errors, the issue's crash case, locality, accumulation,
continuity under round-off, the never-worse guard, and the `sculpt_isophote` command."""

import numpy as np
import pytest
import shapely
import shapely.ops
from sculpt_helpers import fidelity, isophote_stroke

from sketchforge.errors import ParameterError, SculptError, SketchforgeError
from sketchforge.geometry.contour import segment_crossings
from sketchforge.geometry.isophotes import isophotes
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool import sculpt
from sketchforge_isophote_tool.isophote import picked_isophote
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.testing import LIGHT, inflated

ISSUE_STROKE = [[0.1, -0.3], [0.15, -0.1], [0.22, 0.1], [0.3, 0.3]]
CASES = [("ellipse", [0.2, 0.1]), ("pillow", [0.2, 0.1]), ("m", [-0.2, 0.35]), ("m", [0.3, 0.45])]


@pytest.fixture(scope="module")
def ellipse():
    return inflated("ellipse", 0.03)


# --- errors -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kw,msg",
    [
        ({"stroke": [[0.1, 0.1]]}, "at least 2"),
        ({"stroke": [[0.1, 0.1], [0.1, 0.1]]}, "at least 2"),
        ({"band": 0.0}, "positive"),
        ({"band": -1}, "positive"),
        ({"band": "wide"}, "number"),
        ({"pick": [5.0, 5.0]}, "outside the layer"),
        ({"pick": [np.nan, 0.0]}, "finite"),
        ({"stroke": [[-0.9, -0.1], [-0.8, -0.2]]}, "no part inside the band"),
        ({"stroke": [[0.1, np.nan], [0.2, 0.2]]}, "not a finite"),
        ({"stroke": [[0.1, 0.2, 0.3]]}, "pairs"),
        ({"stroke": ISSUE_STROKE + [[1e9, 0.3]]}, "too long"),  # was a MemoryError (600 GiB)
        ({"stroke": ISSUE_STROKE + [[1e300, 0.3]]}, "within"),
        ({"params": {"solver": "euler"}}, r"sculpt solver 'gauss_newton': unknown parameter 'solver' \(known: "),
        ({"params": {"smoothness": -1}}, "smoothness"),
        ({"params": {"steps": 0}}, "steps"),
    ],
)
def test_invalid_edits_raise_sculpt_error(ellipse, kw, msg):
    args = {"pick": [0.2, 0.1], "band": 0.3, "stroke": ISSUE_STROKE, "params": None} | kw
    with pytest.raises((SculptError, ParameterError), match=msg):
        sculpt(ellipse, LIGHT, args["pick"], args["band"], args["stroke"], params=args["params"])


def test_stroke_inside_the_rim_margin_is_refused_with_what_to_do(ellipse):
    with pytest.raises(SculptError, match="rim margin.*draw it further inside"):
        sculpt(ellipse, LIGHT, [0.2, 0.1], 0.3, [[0.999, 0.0], [0.995, 0.05]])


# --- the issue's crash case ---------------------------------------------------------------------


def _issue_case():
    """Ellipse 1.0 × 0.7 rotated 0.3 rad (300 points), resolution 0.02, light 45°; the pick is
    the vertex on the 0.45 isophote closest to the peak; the stroke is the middle half of that
    isophote shifted 0.1 to its left (an offset curve that crosses itself)."""
    from sketchforge_inflate.inflate import inflate_stroke

    t = np.linspace(0, 2 * np.pi, 300, endpoint=False)
    a = 0.3
    rot = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
    mesh = inflate_stroke(np.column_stack([np.cos(t), 0.7 * np.sin(t)]) @ rot, True, {"resolution": 0.02})
    ld = layer_data(mesh, LIGHT, LAMBERTIAN)
    iso = shapely.LineString(max(isophotes(ld.V2, mesh.F, ld.E, 0.45)[0], key=len))
    near = np.nonzero(shapely.distance(shapely.points(ld.V2), iso) < 0.5 * ld.h)[0]
    pick = ld.V2[near[np.argmin(np.linalg.norm(ld.V2[near] - ld.V2[np.argmax(ld.z)], axis=1))]]
    _, picked = picked_isophote(ld, pick)
    mid = np.asarray(shapely.ops.substring(picked, 0.25 * picked.length, 0.75 * picked.length).coords)
    # Each point moved 0.1 along its own left normal, as a hand would trace it: where the
    # isophote bends tighter than 0.1 the result folds over itself (a swallowtail).
    d = np.gradient(mid, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return mesh, pick, mid + 0.1 * np.column_stack([-d[:, 1], d[:, 0]])


def test_issue_crash_case_is_deterministic_and_lands():
    """Was SIGSEGV on one run and 'Matrix is exactly singular' on the next (duplicate PSLG
    vertices from a self-crossing stroke). Now: no triangulation at all, the same result on
    every run, and the isophote where drawn."""
    mesh, pick, stroke = _issue_case()
    assert len(segment_crossings(stroke, closed=False))  # the failure class: a self-crossing stroke
    raw = np.vstack([stroke, stroke[::-1][1:] + [0.0, 1e-3]])  # and back over itself
    results = [sculpt(mesh, LIGHT, pick, 0.3, stroke) for _ in range(3)]
    assert all(r.mesh.identical(results[0].mesh) for r in results)
    before, after, h = fidelity(results[0])
    assert before > 3 * h and after <= max(2 * h, 0.3 * before)
    r = sculpt(mesh, LIGHT, pick, 0.3, raw)  # the scribble: cleaned, not a crash
    assert np.isfinite(r.mesh.V).all()


# --- consistency ------------------------------------------------------------------------------


@pytest.mark.parametrize("shape,pick", CASES)
def test_stroke_on_the_isophote_changes_little(shape, pick):
    mesh = inflated(shape, 0.03)
    st, c, _ = isophote_stroke(mesh, pick)
    try:
        r = sculpt(mesh, LIGHT, pick, 0.3, st)
    except SketchforgeError as exc:  # "already on the isophote" is an allowed answer
        assert "nothing to change" in str(exc)
        return
    assert np.abs(r.mesh.V[:, 2] - mesh.V[:, 2]).max() <= 0.005 * mesh.V[:, 2].max()


# --- locality ---------------------------------------------------------------------------------


def _check_local(mesh, r):
    V = mesh.V
    d = shapely.distance(shapely.points(V[:, :2]), r.stroke)
    reach = r.reach
    assert reach <= r.band_radius + r.layer.planar.margin + 3 * r.h
    assert not r.changed[d > reach].any()
    out = ~r.changed
    assert r.mesh.V[out].tobytes() == V[out].tobytes()  # bit-identical where unchanged
    assert np.array_equal(r.mesh.F, mesh.F) and np.array_equal(r.mesh.V[:, :2], V[:, :2])
    assert (r.mesh.V[mesh.boundary, 2] == 0).all()
    assert np.isfinite(r.mesh.V).all() and (r.mesh.V[:, 2] >= 0).all()


def test_edit_is_local(ellipse):
    st, _, _ = isophote_stroke(ellipse, [0.2, 0.1], 0.1)
    r = sculpt(ellipse, LIGHT, [0.2, 0.1], 0.3, st)
    _check_local(ellipse, r)
    assert r.changed.sum() > 100
    assert set(r.timings) >= {"layer", "stroke", "zones", "shading", "heights", "check", "total"}


def test_ten_edits_then_a_null_edit_drifts_below_one_percent():
    """Accumulation (issue point 6): every edit local; after 10 edits a stroke drawn on an
    isophote moves heights by at most 1% of the peak (6% with the strip pipeline's seams)."""
    rng = np.random.default_rng(7)
    mesh = inflated("ellipse", 0.03)
    done = 0
    while done < 10:
        ld = layer_data(mesh, LIGHT, LAMBERTIAN)
        pick = ld.V2[rng.choice(np.nonzero((ld.planar.d_rim > 0.2) & (ld.E > 0.1))[0])]
        st, _, _ = isophote_stroke(mesh, pick, rng.uniform(2, 4) * ld.h * rng.choice([-1, 1]), half=0.2)
        try:
            r = sculpt(mesh, LIGHT, pick, 0.25, st)
        except SculptError:
            continue
        _check_local(mesh, r)
        mesh, done = r.mesh, done + 1
    peak = mesh.V[:, 2].max()
    for pick in ([0.1, 0.05], [-0.2, 0.2], [0.3, -0.2]):
        st, _, _ = isophote_stroke(mesh, pick, half=0.2)
        try:
            r = sculpt(mesh, LIGHT, pick, 0.25, st)
        except SketchforgeError as exc:
            assert "nothing to change" in str(exc)
            continue
        assert np.abs(r.mesh.V[:, 2] - mesh.V[:, 2]).max() <= 0.01 * peak


# --- continuity ---------------------------------------------------------------------------------


def _perturbed(a, rng, rel=1e-12):
    a = np.asarray(a, dtype=np.float64)
    return a * (1.0 + rel * rng.uniform(-1, 1, a.shape))


@pytest.mark.parametrize("shape,pick,offset", [("ellipse", [0.2, 0.1], 0.1), ("m", [0.3, 0.45], -0.08), ("pillow", [-0.3, 0.2], 0.06)])
def test_round_off_in_any_input_moves_heights_below_1e6_of_the_peak(shape, pick, offset):
    """Issue point 5: 1e-12 relative noise on the pick, the stroke or the mesh changes the result
    by at most 1e-6 of the peak (no discrete choice flips on round-off)."""
    rng = np.random.default_rng(3)
    mesh = inflated(shape, 0.03)
    st, _, _ = isophote_stroke(mesh, pick, offset)
    ref = sculpt(mesh, LIGHT, pick, 0.3, st).mesh.V[:, 2]
    peak = mesh.V[:, 2].max()
    for _trial in range(2):
        noisy_mesh = Mesh(_perturbed(mesh.V, rng), mesh.F, mesh.boundary, mesh.junction)
        for m, p, s in ((mesh, _perturbed(pick, rng), st), (mesh, pick, _perturbed(st, rng)), (noisy_mesh, pick, st)):
            z = sculpt(m, LIGHT, p, 0.3, s).mesh.V[:, 2]
            assert np.abs(z - ref).max() <= 1e-6 * peak


# --- never worse ------------------------------------------------------------------------------


def test_an_edit_that_would_end_farther_falls_back_or_is_refused(ellipse, monkeypatch):
    """If the height solve's answer moved the isophote away from the stroke, the pipeline keeps
    the best partial edit that brings it closer, or refuses with what to do: never a silent
    worse result."""
    from sketchforge.plugin_api import SculptSolver
    from sketchforge_isophote_tool.gauss_newton import check_params, solve

    def scaled(k):  # the built-in solver's answer times k: the host's guard is for every solver
        return SculptSolver(f"times_{k}", lambda problem, params: k * solve(problem, params).dz, check_params)

    st, _, _ = isophote_stroke(ellipse, [0.2, 0.1], 0.1)
    good = sculpt(ellipse, LIGHT, [0.2, 0.1], 0.3, st)
    # Overshoot: 8x the change puts the isophote past the stroke, farther than before...
    r = sculpt(ellipse, LIGHT, [0.2, 0.1], 0.3, st, solver=scaled(8.0))
    assert r.fraction < 1.0 and r.after < r.before
    # ...and the wrong sign can only be refused.
    with pytest.raises(SculptError, match="farther from the stroke.*draw"):
        sculpt(ellipse, LIGHT, [0.2, 0.1], 0.3, st, solver=scaled(-1.0))
    assert good.fraction == 1.0


# --- thin parts -------------------------------------------------------------------------------


@pytest.mark.parametrize("width", [0.2, 0.3])
def test_a_thin_limb_can_be_sculpted(width):
    from sketchforge_inflate.inflate import inflate_stroke

    arc = np.column_stack([np.linspace(-0.7, 0.7, 50), 0.25 * np.sin(np.linspace(-1.5, 1.5, 50))])
    outline = np.asarray(shapely.LineString(arc).buffer(0.5 * width, quad_segs=16).exterior.coords)[:-1]
    mesh = inflate_stroke(outline, True, {"resolution": 0.03})
    ld = layer_data(mesh, LIGHT, LAMBERTIAN)
    # A pick on the lit flank of the limb's middle, halfway between its ridge and its rim.
    flank = (np.abs(ld.V2[:, 0]) < 0.2) & (np.abs(ld.planar.d_rim - 0.25 * width) < 0.5 * ld.h) & (ld.E > 0.2)
    pick = ld.V2[np.nonzero(flank)[0][0]]
    st, _, _ = isophote_stroke(mesh, pick, 2.0 * ld.h, half=0.3)
    r = sculpt(mesh, LIGHT, pick, 0.4 * width, st)
    before, after, h = fidelity(r)
    assert before > 1.5 * h and after <= max(2 * h, 0.3 * before)
    assert r.changed.sum() > 20


# --- the command ------------------------------------------------------------------------------

RING = [[np.cos(t), 0.7 * np.sin(t)] for t in np.linspace(0, 2 * np.pi, 200, endpoint=False)]


def test_command_journal_undo_redo(real_host):
    from sketchforge.document.document import Document

    doc = Document(host=real_host)
    doc.execute({"command": "add_layer", "id": "body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": RING, "closed": True})
    before = doc.layer("body")
    entry = {"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3, "stroke": ISSUE_STROKE}
    cmd = doc.execute(entry)
    after = doc.layer("body")
    assert not after.mesh.identical(before.mesh)
    # The layer's record of the edit names the solver that made it and the light it used.
    assert after.edits[-1] == {**entry, "light": [float(v) for v in doc.light.direction], "solver": "gauss_newton"}
    assert cmd.to_dict() == entry
    doc.undo_stack.undo()
    assert doc.layer("body").same_state(before)
    doc.undo_stack.redo()
    assert doc.layer("body").same_state(after)
    with pytest.raises(SculptError):
        doc.execute(entry | {"band": 0})
    assert doc.layer("body").same_state(after)


def test_parameter_change_reapplies_edits_with_their_own_light(real_host):
    """Changing inflation re-inflates and re-applies the sculpt edit with the light it was made
    with, even after the light moved; undo restores the edited surface exactly."""
    from sketchforge.document.document import Document

    doc = Document(host=real_host)
    doc.execute({"command": "add_layer", "id": "body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": RING, "closed": True})
    doc.execute({"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3, "stroke": ISSUE_STROKE})
    edited = doc.layer("body")
    doc.execute({"command": "set_light", "direction": [-1.0, 0.0, 0.0]})
    doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"inflation": 1.3}})
    rebuilt = doc.layer("body")
    assert len(rebuilt.edits) == 1
    ref = Document(host=real_host)
    ref.execute({"command": "add_layer", "id": "body"})
    ref.execute({"command": "set_contour", "layer": "body", "points": RING, "closed": True})
    ref.execute({"command": "set_inflate_params", "layer": "body", "params": {"inflation": 1.3}})
    ref.execute({"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3, "stroke": ISSUE_STROKE})
    assert rebuilt.mesh.identical(ref.layer("body").mesh)
    doc.undo_stack.undo()
    assert doc.layer("body").same_state(edited)


def test_third_party_reflectance_model_sculpts_like_lambertian():
    """A model registered by an outside plugin works through the journal command. Squared
    half-Lambert is a monotone function of n·l, so its isophotes are Lambert's: the edit must
    land close to the Lambertian one (not bit-equal: shading is interpolated in its own units)."""
    import jax.numpy as jnp

    from sketchforge.document.document import Document
    from sketchforge.plugins.hookspecs import hookimpl
    from sketchforge.plugins.registry import ReflectanceModel
    from sketchforge.plugins.testing import make_test_host

    class HalfLambert:
        @hookimpl
        def sketchforge_reflectance_models(self):
            return [ReflectanceModel("half_lambert", lambda n, l: ((jnp.dot(n, l) + 1.0) / 2.0) ** 2)]

    host = make_test_host(HalfLambert(), entry_points=True, allowlist=["inflate", "isophote_tool"])
    results = {}
    for model in ("lambertian", "half_lambert"):
        doc = Document(host=host)
        doc.execute({"command": "add_layer", "id": "body"})
        doc.execute({"command": "set_contour", "layer": "body", "points": RING, "closed": True})
        before = doc.layer("body")
        entry = {"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3,
                 "stroke": ISSUE_STROKE, "model": model}
        doc.execute(entry)
        z = doc.layer("body").mesh.V[:, 2]
        assert np.all(np.isfinite(z)) and not doc.layer("body").mesh.identical(before.mesh)
        results[model] = z
        doc.undo_stack.undo()
        assert doc.layer("body").same_state(before)
    peak = results["lambertian"].max()
    assert np.abs(results["half_lambert"] - results["lambertian"]).max() < 0.05 * peak


def test_edits_on_two_threads_at_once_match_the_sequential_ones():
    """The app can have a preview still finishing on one worker while the command's solve
    starts on another: shared caches must not break either."""
    import threading

    from sketchforge_isophote_tool import layerdata, pipeline

    mesh = inflated("pillow", 0.03)
    jobs = [isophote_stroke(mesh, [0.2, 0.1], off)[0] for off in (0.06, 0.08, -0.06, -0.08)]
    want = [sculpt(mesh, LIGHT, [0.2, 0.1], 0.3, st).mesh for st in jobs]
    for _ in range(3):
        layerdata._CACHE.clear(), layerdata._PLANAR.clear(), pipeline._PICKS.clear()
        got, errors = [None] * len(jobs), []

        def run(i):
            try:
                got[i] = sculpt(mesh, LIGHT, [0.2, 0.1], 0.3, jobs[i]).mesh  # noqa: B023 - called in this iteration
            except Exception as exc:  # noqa: BLE001
                errors.append(exc)  # noqa: B023 - called in this iteration

        threads = [threading.Thread(target=run, args=(i,)) for i in range(len(jobs))]
        [t.start() for t in threads]
        [t.join() for t in threads]
        assert not errors
        assert all(g.identical(w) for g, w in zip(got, want))


@pytest.mark.parametrize("damage", ["nan", "zero_area"])
def test_a_damaged_layer_mesh_is_refused_in_one_line_before_native_code(ellipse, damage):
    """A snapshot mesh can be hand-edited: the guard refuses it before libigl sees it."""
    from sketchforge.errors import GeometryError

    V = np.array(ellipse.V)
    F = np.array(ellipse.F)
    if damage == "nan":
        V[F[10, 0], 0] = np.nan
    else:
        V[F[10, 1], :2] = V[F[10, 0], :2]  # two corners of one triangle on top of each other
    with pytest.raises(GeometryError) as info:
        sculpt(Mesh(V, F, ellipse.boundary), LIGHT, [0.2, 0.1], 0.3, ISSUE_STROKE)
    assert "\n" not in str(info.value) and "mesh" in str(info.value)
