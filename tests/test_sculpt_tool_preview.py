"""What the app's sculpt tool does around an edit, driven headlessly: the live preview's job, a
cancelled stroke, a reset, the result's one-line description and the JAX warm-up.

The Qt controller runs ``preview_job`` on a worker thread while the person draws
(tests/qt/test_qt_sculpt.py checks that end to end); these are the same calls without a window.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
from test_sculpt_tool import PICK, STROKE, ellipse_doc, make_tool

from sketchforge.errors import SculptError


def test_the_preview_is_the_edit_the_stroke_will_push(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK), tool.message
    job = tool.preview_job(STROKE)
    before = doc.layer("body").mesh
    result = job()
    assert doc.undo_stack.count() == 2 and doc.layer("body").mesh is before  # nothing pushed
    cmd = tool.command_for(STROKE)
    doc.undo_stack.push(cmd)
    after = doc.layer("body").mesh
    assert np.array_equal(result.mesh.F, after.F) and np.array_equal(result.mesh.V, after.V)
    assert result.changed.any() and result.after < result.before


def test_a_preview_job_keeps_the_pick_band_and_stroke_it_was_made_with(real_host):
    # The job runs on a worker thread while the person may already re-pick or change the band:
    # it must compute the edit as it was when the job was made.
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK)
    stroke = np.array(STROKE, dtype=np.float64)
    job = tool.preview_job(stroke)
    reference = tool.preview_job(STROKE)()
    tool.band = 0.15
    tool.pick[:] = [-0.4, 0.2]
    stroke[:] += 0.3
    result = job()
    assert np.array_equal(result.mesh.V, reference.mesh.V)
    assert result.band_radius == reference.band_radius and result.c == reference.c


def test_a_preview_job_can_run_on_a_mesh_other_than_the_layer_s(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK)
    edited = tool.preview_job(STROKE)().mesh
    again = tool.preview_job(STROKE, mesh=edited)()
    assert again.layer.mesh is edited
    assert again.before < tool.preview_job(STROKE)().before  # the edited layer starts closer


@pytest.mark.parametrize("method", ["preview_job", "command_dict", "command_for"])
def test_no_edit_without_a_pick_or_once_its_layer_is_gone(real_host, method):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    with pytest.raises(SculptError, match="pick an isophote first"):
        getattr(tool, method)(STROKE)
    assert tool.pick_at(PICK)
    getattr(tool, method)(STROKE)
    doc.execute({"command": "remove_layer", "layer": "body"})
    with pytest.raises(SculptError, match="pick an isophote first"):
        getattr(tool, method)(STROKE)


def test_cancel_drops_the_stroke_in_progress_and_keeps_the_pick(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK)
    tool.press(STROKE[0])
    tool.move(STROKE[1])
    assert "stroke" in tool.overlay
    tool.cancel()
    assert "stroke" not in tool.overlay and "isophote" in tool.overlay
    assert np.array_equal(tool.pick, PICK)
    tool.move(STROKE[2])  # the button is no longer held: a move draws nothing
    assert "stroke" not in tool.overlay
    assert tool.end_stroke(STROKE[3]).shape == (0, 2) and doc.undo_stack.count() == 2


def test_reset_forgets_the_pick_the_stroke_and_the_message(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert not tool.pick_at([5.0, 5.0]) and tool.message  # off the shape: a message
    assert tool.pick_at(PICK)
    tool.press(STROKE[0])
    tool.move(STROKE[1])
    tool.message = "something to say"
    tool.reset()
    assert tool.pick is None and tool.layer_id is None and tool.isovalue is None
    assert tool.overlay == {} and tool.message == ""
    tool.move(STROKE[2])
    assert tool.overlay == {}
    with pytest.raises(SculptError, match="pick an isophote first"):
        tool.command_for(STROKE)


def test_the_result_describes_the_fidelity_in_edge_lengths(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK)
    r = tool.preview_job(STROKE)()
    h = r.h
    full = r.describe()
    base = f"isophote {r.before / h:.1f} → {r.after / h:.1f} edge lengths from the stroke"
    # This stroke runs out of the band at one end (issue 30: the part left out is said).
    ignored = f"; {r.ignored_fraction:.0%} of the stroke ({r.ignored_length:.3g} drawing units) lay outside the band and was ignored"
    assert r.ignored_length >= 0.5 * h and full == base + ignored
    assert dataclasses.replace(r, ignored_length=0.0, ignored_fraction=0.0).describe() == base
    numbers = [float(x) for x in re.findall(r"\d+\.\d", full)]
    assert numbers[0] > numbers[1] >= 0.0
    half = dataclasses.replace(r, fraction=0.5).describe()
    assert half == base + " (50% of the change: the whole of it overshot)" + ignored
    assert "(25% of the change: the whole of it overshot)" in dataclasses.replace(r, fraction=0.25).describe()


def test_warm_up_compiles_the_reflectance_evaluation_every_edit_calls():
    import jax.numpy as jnp

    from sketchforge.geometry.reflectance import LAMBERTIAN, ReflectanceModel, _batched_pq_grad, evaluate_pq
    from sketchforge_isophote_tool.warmup import warm_up

    assert warm_up() is None
    assert _batched_pq_grad(LAMBERTIAN)._cache_size() >= 1
    # A plugin's model is warmed up as given, not replaced by the default.
    model = ReflectanceModel("test_half_lambert", lambda n, l: 0.5 + 0.5 * jnp.dot(n, l))
    warm_up(model)
    assert _batched_pq_grad(model)._cache_size() == 1
    r, _, _ = evaluate_pq(model, np.zeros(3), np.zeros(3), np.array([1.0, 0.0, 0.0]))
    assert np.allclose(r, 0.5) and _batched_pq_grad(model)._cache_size() == 1  # no new compile


def test_cancel_without_a_stroke_in_progress_is_harmless(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    tool.cancel()  # nothing picked, nothing drawn (Esc pressed twice)
    assert tool.pick_at(PICK)
    tool.cancel()
    assert np.array_equal(tool.pick, PICK) and "isophote" in tool.overlay


def _half_lambert_host():
    import jax.numpy as jnp

    from sketchforge.plugins.hookspecs import hookimpl
    from sketchforge.plugins.registry import ReflectanceModel
    from sketchforge.plugins.testing import make_test_host

    class HalfLambert:
        @hookimpl
        def sketchforge_reflectance_models(self):
            return [ReflectanceModel("half_lambert", lambda n, l: ((jnp.dot(n, l) + 1.0) / 2.0) ** 2)]

    return make_test_host(HalfLambert(), entry_points=True, allowlist=["inflate", "isophote_tool"])


def test_choosing_another_model_re_picks_the_isophote_under_it():
    from sketchforge_isophote_tool.command import _model
    from sketchforge_isophote_tool.isophote import picked_isophote
    from sketchforge_isophote_tool.layerdata import layer_data

    doc = ellipse_doc(_half_lambert_host())
    tool = make_tool(doc, band=0.3)
    tool.set_options({"model": "half_lambert"})  # before any pick: nothing to re-pick
    assert tool.pick is None and tool.options == {"model": "half_lambert"}
    tool.set_options({})
    assert tool.pick_at(PICK)
    lambert = tool.isovalue
    tool.set_options({"model": "half_lambert"})
    ld = layer_data(doc.layer("body").mesh, doc.light.direction, _model(doc, "half_lambert"))
    c, iso = picked_isophote(ld, PICK)
    assert tool.isovalue == c != lambert and np.array_equal(tool.pick, PICK)
    assert np.array_equal(tool.overlay["isophote"], np.asarray(iso.coords))
    assert tool.command_dict(STROKE)["model"] == "half_lambert"
    # Naming the default model stores nothing: the journal entry stays the one of the default.
    tool.set_options({"model": "lambertian"})
    assert tool.options == {} and "model" not in tool.command_dict(STROKE)
    assert tool.isovalue == lambert


def test_the_package_exports_its_public_names_lazily():
    import sketchforge_isophote_tool as pkg
    from sketchforge_isophote_tool import command, gauss_newton, pipeline, tool, warmup

    expected = {
        "sculpt": pipeline.sculpt, "SculptResult": pipeline.SculptResult,
        "DEFAULT_OPTIONS": gauss_newton.DEFAULT_PARAMS, "GAUSS_NEWTON": gauss_newton.GAUSS_NEWTON,
        "warm_up": warmup.warm_up,
        "SculptIsophote": command.SculptIsophote, "SculptIsophoteTool": tool.SculptIsophoteTool,
    }
    assert sorted(pkg.__all__) == sorted(expected)
    for name, obj in expected.items():
        assert getattr(pkg, name) is obj, name
    with pytest.raises(AttributeError) as info:
        pkg.no_such_name  # noqa: B018
    assert info.value.args == ("no_such_name",)
    assert not hasattr(pkg, "sculptresult")


def test_the_characteristics_shown_start_evenly_along_the_stroke(real_host):
    import shapely

    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK)
    r = tool.preview_job(STROKE)()
    n = 7
    lines = r.characteristics(n=n)
    assert len(lines) == n
    pieces = getattr(r.stroke, "geoms", [r.stroke])
    stroke = shapely.LineString(np.concatenate([np.asarray(g.coords) for g in pieces]))
    # Each curve passes through its seed, a vertex on the stroke: where along it?
    at = []
    for line in lines:
        d = shapely.distance(shapely.points(line), stroke)
        k = int(np.argmin(d))
        assert d[k] < 1e-9
        at.append(stroke.project(shapely.Point(line[k])))
    expected = stroke.length * np.arange(1, n + 1) / (n + 1)
    assert np.allclose(at, expected, atol=1e-9 * stroke.length + 1e-12)


def test_the_stroke_shows_from_the_press_and_stays_shown_after_it_ends(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK)
    tool.press(STROKE[0])
    assert np.array_equal(tool.overlay["stroke"], [STROKE[0]])  # the first point at once
    tool.move(STROKE[1])
    points = tool.end_stroke(STROKE[2])
    assert np.array_equal(points, STROKE[:3]) and np.array_equal(tool.overlay["stroke"], STROKE[:3])
    assert doc.undo_stack.count() == 2  # ending a stroke pushes nothing by itself


def test_a_two_point_stroke_is_an_edit_not_a_click(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK)
    tool.message = "left over"
    tool.press(STROKE[0])
    cmd = tool.release(STROKE[-1])  # press here, release there: a straight stroke
    assert cmd is not None and doc.undo_stack.count() == 3
    assert cmd.to_dict()["stroke"] == [STROKE[0], STROKE[-1]]
    assert tool.message == "" and tool.pick is None  # back to picking, nothing to say


def test_a_release_without_a_press_is_a_click(real_host):
    # The press went to another tool (or outside the canvas): the release alone picks.
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.release(PICK) is None
    assert np.array_equal(tool.pick, PICK) and "stroke" not in tool.overlay


def test_a_stroke_without_a_pick_asks_for_one_and_is_not_kept(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    tool.press(STROKE[0])
    tool.move(STROKE[1])
    assert tool.release(STROKE[2]) is None
    assert tool.message == "pick an isophote first (click on the shape), then redraw it"
    assert "stroke" not in tool.overlay and doc.undo_stack.count() == 2


def test_the_journal_entry_names_the_command_and_the_layer(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    assert tool.pick_at(PICK)
    entry = tool.command_dict(STROKE)
    assert entry["command"] == "sculpt_isophote" and entry["layer"] == "body"


def test_a_band_beyond_the_drawing_s_range_is_refused_up_front(real_host):
    # The command refuses a band over 1e9 drawing units; the tool says so when it is set,
    # not at the end of the next stroke (1e300 also made GEOS throw from the band overlay).
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.2)
    assert tool.pick_at(PICK)
    band = tool.overlay["band"]
    for radius in (1e300, 2e9, "1e12"):
        assert not tool.set_band(radius)
        assert "too large" in tool.message and "1e+09" in tool.message
        assert tool.band == 0.2 and tool.overlay["band"] is band
    assert tool.set_band(1e9)  # the largest allowed: the band is the whole layer
    import shapely

    covered = shapely.union_all([shapely.Polygon(r) for r in tool.overlay["band"][:1]])
    assert covered.area == pytest.approx(shapely.Polygon(doc.layer("body").mesh.V[doc.layer("body").mesh.boundary, :2]).area, rel=1e-6)


def test_a_band_that_is_not_a_number_is_refused_with_a_message(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.2)
    assert tool.pick_at(PICK)
    for radius in ("wide", None, [1, 2]):
        assert not tool.set_band(radius)
        assert tool.message == f"the band radius must be a number, got {radius!r}"
        assert tool.band == 0.2


def test_the_preview_uses_the_chosen_model():
    doc = ellipse_doc(_half_lambert_host())
    tool = make_tool(doc, band=0.3)
    tool.set_options({"model": "half_lambert"})
    assert tool.pick_at(PICK)
    preview = tool.preview_job(STROKE)()
    doc.undo_stack.push(tool.command_for(STROKE))
    assert np.array_equal(preview.mesh.V, doc.layer("body").mesh.V)
    assert preview.layer.model.name == "half_lambert"
