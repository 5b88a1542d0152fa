"""The thesis' strip method as the sculpt solver ``strips`` (issue 29, point 2): strips from the
stroke (4.3) integrated with diffrax (4.5), heights by multiquadric RBF (4.6), the change carried
downstream to the rim; through the command and the app's journal like any solver."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely

from sculpt_helpers import isophote_stroke
from sketchforge.errors import NothingToDoError, ParameterError, SketchforgeError
from sketchforge_isophote_tool import sculpt
from sketchforge_isophote_tool.testing import LIGHT, inflated
from sketchforge_strips.solver import DEFAULT_PARAMS, STRIPS, check_params

ROOT = Path(__file__).resolve().parents[1]
PICK = [0.2, 0.1]


@pytest.fixture(scope="module")
def ellipse():
    return inflated("ellipse", 0.04)


@pytest.fixture(scope="module")
def edit(ellipse):
    stroke, _, _ = isophote_stroke(ellipse, PICK, offset=0.1)
    return stroke, sculpt(ellipse, LIGHT, PICK, 0.3, stroke, solver=STRIPS)


def test_the_package_imports_only_the_plugin_api_from_sketchforge():
    for path in sorted((ROOT / "plugins" / "strips" / "sketchforge_strips").glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else (
                [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 else [])
            for name in names:
                if name and name.split(".")[0] == "sketchforge":
                    assert name == "sketchforge.plugin_api", f"{path.name} imports {name}"


def test_registering_the_plugin_imports_neither_jax_nor_diffrax():
    code = ("import sys\nfrom sketchforge.plugins.manager import PluginHost\n"
            "h = PluginHost.create(allowlist=['strips'])\nassert 'strips' in h.solvers('sculpt'), h.problems\n"
            "print(sorted(m for m in ('jax', 'diffrax') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_the_isophote_lands_where_drawn(ellipse, edit):
    stroke, r = edit
    assert r.solver == "strips" and r.fraction == 1.0
    assert r.after <= max(2.0 * r.h, 0.3 * r.before), (r.before / r.h, r.after / r.h)
    assert r.after < 0.5 * r.h
    info = r.solution.info
    assert info["strips"] >= 10 and info["samples"] > 100  # seeded across the stroke, sampled along


def test_the_change_is_carried_downstream_to_the_rim_and_nothing_moves_upstream(ellipse, edit):
    """SfS fixes heights up to a function constant along the characteristics: the thesis keeps
    the surface upstream of the band and shifts it downstream, to the rim."""
    stroke, r = edit
    V2 = ellipse.V[:, :2]
    dz = r.mesh.V[:, 2] - ellipse.V[:, 2]
    line = shapely.LineString(stroke)
    # The characteristics run roughly towards the light here (an in-plane light at 45°).
    light = LIGHT[:2]
    side = (V2 - np.asarray(stroke).mean(axis=0)) @ light
    far = shapely.distance(shapely.points(V2), line) > 0.3 + 0.2  # beyond the band and its ring
    upstream, downstream = far & (side < 0), far & (side > 0)
    assert upstream.sum() > 50 and downstream.sum() > 20
    # The surface before the band is kept (to the spline's ringing around the shading change:
    # a millionth of the peak).
    assert np.abs(dz[upstream]).max() < 1e-6 * ellipse.V[:, 2].max()
    moved = np.abs(dz[downstream]) > 1e-3 * ellipse.V[:, 2].max()
    assert moved.mean() > 0.3  # the shift reaches the far side
    assert np.all(r.mesh.V[ellipse.boundary, 2] == 0.0)


def test_a_stroke_on_the_isophote_changes_nothing(ellipse):
    stroke, _, _ = isophote_stroke(ellipse, PICK, offset=0.0)
    with pytest.raises(NothingToDoError):
        sculpt(ellipse, LIGHT, PICK, 0.3, stroke, solver=STRIPS)


def test_round_off_in_the_stroke_moves_heights_by_round_off(ellipse, edit):
    stroke, r = edit
    rng = np.random.default_rng(3)
    noisy = np.asarray(stroke) * (1.0 + 1e-12 * rng.standard_normal(np.shape(stroke)))
    r2 = sculpt(ellipse, LIGHT, PICK, 0.3, noisy, solver=STRIPS)
    peak = ellipse.V[:, 2].max()
    assert np.abs(r2.mesh.V[:, 2] - r.mesh.V[:, 2]).max() < 1e-6 * peak
    again = sculpt(ellipse, LIGHT, PICK, 0.3, stroke, solver=STRIPS)
    assert again.mesh.identical(r.mesh)  # the same edit, the same mesh


def test_kvaerno5_and_tsit5_integrate_the_same_strips(ellipse, edit):
    stroke, r = edit
    k = sculpt(ellipse, LIGHT, PICK, 0.3, stroke, solver=STRIPS, params={"integrator": "kvaerno5"})
    dz_t = r.mesh.V[:, 2] - ellipse.V[:, 2]
    dz_k = k.mesh.V[:, 2] - ellipse.V[:, 2]
    assert np.abs(dz_k - dz_t).max() < 1e-3 * np.abs(dz_t).max()
    assert k.after <= max(2.0 * k.h, 0.3 * k.before)


def test_a_self_crossing_stroke_never_reaches_native_code_or_crashes(ellipse):
    # The first release's crash: the isophote shifted into an offset-curve swallowtail. No
    # Triangle call remains on the way (the shading change is on the layer's own triangles).
    stroke, _, _ = isophote_stroke(ellipse, PICK, offset=0.1)
    P = np.asarray(stroke)
    mid = len(P) // 2
    loop = P[mid] + 0.04 * np.column_stack([np.cos(np.linspace(0, 2 * np.pi, 20)), np.sin(np.linspace(0, 2 * np.pi, 20))])
    crossing = np.concatenate([P[:mid], loop, P[mid:]])
    try:
        r = sculpt(ellipse, LIGHT, PICK, 0.3, crossing, solver=STRIPS)
    except SketchforgeError as exc:
        assert "\n" not in str(exc)
    else:
        assert np.isfinite(r.mesh.V).all() and r.after <= max(r.before, 0.25 * r.h)


def test_its_parameters_are_checked_and_unknown_ones_refused():
    assert check_params({}) == DEFAULT_PARAMS
    assert check_params({"integrator": "kvaerno5", "rbf_neighbors": 64})["rbf_neighbors"] == 64
    for bad, message in (({"integrator": "euler"}, "'integrator' must be one of 'tsit5', 'kvaerno5', got 'euler'"),
                         ({"rtol": 0}, "'rtol' must be >= 1e-08, got 0"),
                         ({"rbf_neighbors": 3.5}, "'rbf_neighbors' must be a whole number, got 3.5"),
                         ({"lambda": 0.05}, "unknown parameter 'lambda' (known: ")):
        with pytest.raises(ParameterError) as info:
            check_params(bad)
        assert str(info.value).startswith(message)


def test_a_strips_edit_through_the_command_replays_bit_identically(make_sketchforge_host, make_sketchforge_document,
                                                                 assert_replays):
    host = make_sketchforge_host(installed=("inflate", "isophote_tool", "strips"))
    doc = make_sketchforge_document(host, resolution=0.06)
    mesh = doc.layer("a").mesh
    stroke, _, _ = isophote_stroke(mesh, PICK, offset=0.12)
    doc.execute({"command": "sculpt_isophote", "layer": "a", "pick": PICK, "band": 0.3,
                 "stroke": np.asarray(stroke).tolist(), "solver": "strips", "params": {"rbf_smoothing": 0.1}})
    assert doc.layer("a").edits[-1]["solver"] == "strips"
    assert not doc.layer("a").mesh.identical(mesh)
    replayed = assert_replays(doc)
    assert replayed.layer("a").edits == doc.layer("a").edits
