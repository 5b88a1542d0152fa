"""The isophote edit `sculpt()`: errors, consistency, locality, repeated edits, compilations,
and the `sculpt_isophote` command."""

import numpy as np
import pytest
import shapely
from scipy.spatial import cKDTree

from sculpt_helpers import isophote_stroke
from sketchforge.errors import NothingToDoError, SculptError
from sketchforge.geometry import field_jax
from sketchforge_isophote_tool import sculpt
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool.isophote import band_around
from sketchforge_isophote_tool.jaxcache import TRACES
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.pipeline import DEFAULT_OPTIONS, integrate_from_entry
from sketchforge_isophote_tool.regions import compute_regions
from sketchforge_isophote_tool.stroke import clip_to_band, prepare_stroke
from sketchforge_isophote_tool.testing import LIGHT, inflated

ISSUE_STROKE = [[0.1, -0.3], [0.15, -0.1], [0.22, 0.1], [0.3, 0.3]]
CASES = [("ellipse", [0.2, 0.1]), ("pillow", [0.2, 0.1]), ("m", [-0.2, 0.35]), ("m", [0.3, 0.45])]


@pytest.fixture(scope="module")
def ellipse():
    return inflated("ellipse", 0.03)


@pytest.fixture(scope="module")
def issue_edit(ellipse):
    return sculpt(ellipse, LIGHT, [0.2, 0.1], 0.3, ISSUE_STROKE)


# --- errors -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kw,msg",
    [
        ({"stroke": [[0.1, 0.1]]}, "at least 2"),
        ({"band": 0.0}, "positive"),
        ({"band": -1}, "positive"),
        ({"pick": [5.0, 5.0]}, "outside the layer"),
        ({"stroke": [[-0.9, -0.1], [-0.8, -0.2]]}, "no part inside the band"),
        ({"stroke": [[0.1, np.nan], [0.2, 0.2]]}, "non-finite"),
        ({"stroke": ISSUE_STROKE + [[1e9, 0.3]]}, "too long"),  # was a MemoryError (600 GiB)
        ({"options": {"solver": "euler"}}, "solver"),
    ],
)
def test_invalid_edits_raise_sculpt_error(ellipse, kw, msg):
    args = {"pick": [0.2, 0.1], "band": 0.3, "stroke": ISSUE_STROKE, "options": None} | kw
    with pytest.raises(SculptError, match=msg):
        sculpt(ellipse, LIGHT, args["pick"], args["band"], args["stroke"], options=args["options"])


# --- consistency ------------------------------------------------------------------------------


@pytest.mark.parametrize("shape,pick", CASES)
def test_strips_on_unchanged_shading_reproduce_heights(shape, pick):
    mesh = inflated(shape, 0.03)
    peak = mesh.V[:, 2].max()
    st, c, iso = isophote_stroke(mesh, pick)
    ld = layer_data(mesh, LIGHT, LAMBERTIAN)
    band = band_around(ld, iso, 0.3)
    stroke = shapely.LineString(clip_to_band(prepare_stroke(st, ld.h), band, ld.h)[0])
    margin = 3 * ld.h
    R = compute_regions(ld, LIGHT, LAMBERTIAN, band, stroke, margin, 2 * ld.h)
    E_old = field_jax.grid_field_from_nodes(ld.E_nodes, ld.raster[0], ld.raster[1])
    strips = integrate_from_entry(ld, LIGHT, LAMBERTIAN, R.M, R.entry, E_old, DEFAULT_OPTIONS, margin)
    S = np.concatenate(strips)
    S = S[shapely.contains_xy(R.M, S[:, 0], S[:, 1])]  # the samples the reconstruction uses
    err = np.abs(S[:, 4] - ld.locator.interpolate(ld.z, S[:, :2])) / peak
    assert err.max() < 0.02


@pytest.mark.parametrize("shape,pick", CASES)
def test_stroke_on_the_isophote_changes_little(shape, pick):
    mesh = inflated(shape, 0.03)
    st, c, _ = isophote_stroke(mesh, pick)
    r = sculpt(mesh, LIGHT, pick, 0.3, st)
    assert r.changed.any()
    assert np.abs(r.mesh.V[:, 2] - mesh.V[:, 2]).max() <= 0.03 * mesh.V[:, 2].max()


# --- locality ---------------------------------------------------------------------------------


def test_issue_example_is_local(ellipse, issue_edit):
    r = issue_edit
    R = r.regions
    h = layer_data(ellipse, LIGHT, LAMBERTIAN).h
    assert r.stroke.difference(R.M.buffer(1e-9)).length < 1e-6  # stroke ⊂ M•
    assert R.M.difference(R.S.buffer(1e-9)).area < 1e-9  # M• ⊆ S•
    assert R.B_star.difference(R.M.buffer(1e-9)).area < 1e-9
    assert R.max_gap <= 2 * h + 1e-12
    V = ellipse.V
    inM = shapely.contains_xy(R.M, V[:, 0], V[:, 1])
    S = np.concatenate(r.strips)
    d, _ = cKDTree(S[:, :2]).query(V[inM, :2])
    assert d.max() <= 2 * h
    assert not r.changed[~inM].any()
    out = ~inM
    assert r.mesh.V[out].tobytes() == V[out].tobytes()  # bit-identical outside M•
    assert np.array_equal(r.mesh.F, ellipse.F) and np.array_equal(r.mesh.V[:, :2], V[:, :2])
    assert (r.mesh.V[ellipse.boundary, 2] == 0).all()
    assert np.isfinite(r.mesh.V).all() and (r.mesh.V[:, 2] >= 0).all()
    assert set(r.timings) >= {"strips", "regions", "interpolation", "integration", "rbf"}


def test_several_edits_in_a_row(ellipse):
    mesh = ellipse
    for pick, off in [([0.2, 0.1], 0.08), ([0.2, 0.1], -0.05), ([-0.3, -0.3], 0.06)]:
        st, _, _ = isophote_stroke(mesh, pick, off)
        r = sculpt(mesh, LIGHT, pick, 0.3, st)
        assert np.isfinite(r.mesh.V).all() and r.changed.any()
        assert r.mesh.V[~r.changed].tobytes() == mesh.V[~r.changed].tobytes()
        mesh = r.mesh


def test_no_recompile_for_a_layer_of_another_size():
    from sketchforge_isophote_tool import warm_up

    warm_up(buckets=(64, 256))
    before = dict(TRACES)
    for shape, res in [("ellipse", 0.04), ("pillow", 0.035)]:
        m = inflated(shape, res)
        st, _, _ = isophote_stroke(m, [0.2, 0.1], 0.05)
        sculpt(m, LIGHT, [0.2, 0.1], 0.3, st)
    assert dict(TRACES) == before


def test_stroke_far_from_strips_is_nothing_to_do_or_sculpt_error(ellipse):
    # a stroke inside the band but entirely inside the rim margin
    with pytest.raises((NothingToDoError, SculptError)):
        sculpt(ellipse, LIGHT, [0.2, 0.1], 0.3, [[0.999, 0.0], [0.995, 0.05]])


# --- the command ------------------------------------------------------------------------------


def test_command_journal_undo_redo(real_host):
    from sketchforge.document.document import Document

    doc = Document(host=real_host)
    doc.execute({"command": "add_layer", "id": "body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": (np.array(
        [[np.cos(t), 0.7 * np.sin(t)] for t in np.linspace(0, 2 * np.pi, 200, endpoint=False)])).tolist(), "closed": True})
    before = doc.layer("body")
    entry = {"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3, "stroke": ISSUE_STROKE}
    cmd = doc.execute(entry)
    after = doc.layer("body")
    assert not after.mesh.identical(before.mesh)
    assert after.edits[-1] == {**entry, "light": [float(v) for v in doc.light.direction]}
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
    ring = [[np.cos(t), 0.7 * np.sin(t)] for t in np.linspace(0, 2 * np.pi, 200, endpoint=False)]
    doc.execute({"command": "set_contour", "layer": "body", "points": ring, "closed": True})
    doc.execute({"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3, "stroke": ISSUE_STROKE})
    edited = doc.layer("body")
    doc.execute({"command": "set_light", "direction": [-1.0, 0.0, 0.0]})
    doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"inflation": 1.3}})
    rebuilt = doc.layer("body")
    assert len(rebuilt.edits) == 1
    # Same result as: inflate at 1.3 with the original light, then the same edit.
    ref = Document(host=real_host)
    ref.execute({"command": "add_layer", "id": "body"})
    ref.execute({"command": "set_contour", "layer": "body", "points": ring, "closed": True})
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
    ring = [[np.cos(t), 0.7 * np.sin(t)] for t in np.linspace(0, 2 * np.pi, 200, endpoint=False)]
    results = {}
    for model in ("lambertian", "half_lambert"):
        doc = Document(host=host)
        doc.execute({"command": "add_layer", "id": "body"})
        doc.execute({"command": "set_contour", "layer": "body", "points": ring, "closed": True})
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
