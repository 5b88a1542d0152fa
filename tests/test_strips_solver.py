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


def test_the_shift_is_shared_by_both_ends_and_returns_to_zero_across_the_rim_margin(ellipse, edit):
    """SfS fixes heights up to a function constant along the characteristics: the strips carry
    the change to both ends (half each, where both reach the rim margin) and it returns to 0
    smoothly across the margin."""
    from sketchforge_isophote_tool.layerdata import planar_data

    stroke, r = edit
    pd = planar_data(ellipse)
    V2 = ellipse.V[:, :2]
    dz = r.mesh.V[:, 2] - ellipse.V[:, 2]
    peak = ellipse.V[:, 2].max()
    line = shapely.LineString(stroke)
    side = (V2 - np.asarray(stroke).mean(axis=0)) @ LIGHT[:2]  # the flow runs roughly along the light
    far = shapely.distance(shapely.points(V2), line) > 0.3 + 0.2  # beyond the band and its ring
    up, down = far & (side < 0), far & (side > 0)
    big = 0.3 * np.abs(dz).max()
    # Both sides shifted, in opposite directions, each by about half the change across the band.
    assert (dz[up] > big).sum() > 20 and (dz[down] < -big).sum() > 20 or \
        (dz[up] < -big).sum() > 20 and (dz[down] > big).sum() > 20
    assert abs(np.abs(dz[up]).max() - np.abs(dz[down]).max()) < 0.35 * np.abs(dz).max()
    # Across the rim margin the shift returns to 0: no more than the smoothstep of the depth
    # allows (with the final smoothing's slack), and exactly 0 on the rim.
    rho = np.clip(pd.d_rim / pd.margin_v, 0.0, 1.0)
    rho = rho * rho * (3.0 - 2.0 * rho)
    deep = pd.d_rim < 0.5 * pd.margin_v
    assert np.all(np.abs(dz[deep]) <= 1.5 * rho[deep] * np.abs(dz).max() + 1e-3 * peak)
    assert np.all(r.mesh.V[ellipse.boundary, 2] == 0.0)
    assert np.abs(dz).max() < 0.6 * peak


def test_a_stroke_running_into_the_rim_margin_changes_the_shading_no_more_than_it_asks(ellipse):
    """Where the stroke reaches the rim margin (the change is held at 0 there) its constraints
    fade in with the change: asked at full weight right beside the margin, the smoothest change
    bent past the stroke's value beside it, a dark pit twice as deep as the stroke asked."""
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.layerdata import layer_data
    from sketchforge_isophote_tool.shading import bary_rows

    pick = [-0.2, 0.3]
    stroke, c, _ = isophote_stroke(ellipse, pick, offset=-0.12, half=0.4)  # 0.12 towards the light
    r = sculpt(ellipse, LIGHT, pick, 0.3, stroke, solver=STRIPS)
    before, after = layer_data(ellipse, LIGHT, LAMBERTIAN), layer_data(r.mesh, LIGHT, LAMBERTIAN)
    line = shapely.LineString(stroke)
    P = np.array([line.interpolate(t, normalized=True).coords[0] for t in np.linspace(0.0, 1.0, 400)])
    asked = np.abs(c - bary_rows(before.planar, P) @ before.E).max()
    assert np.abs(after.E - before.E).max() <= 1.3 * asked  # 2.05x before the fade, 1.14x now
    assert r.after <= max(2.0 * r.h, 0.3 * r.before), (r.before / r.h, r.after / r.h)


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
    # The paths agree to the adaptive tolerance; the local fits turn that into 0.5% at a few
    # vertices where a neighbourhood of supports changes.
    assert np.abs(dz_k - dz_t).max() < 1e-2 * np.abs(dz_t).max()
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
                         ({"rbf_neighbors": 512}, "'rbf_neighbors' must be <= 64, got 512"),
                         ({"sample_spacing": 0.1}, "'sample_spacing' must be >= 0.25, got 0.1"),
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


def test_an_edit_in_the_document_bounds_its_creases_by_the_layer_as_inflated(make_sketchforge_host,
                                                                          make_sketchforge_document, assert_replays):
    """Issue 36: an edit's crease bounds are relative to the layer before any edit, which the
    document finds again (kept from its inflation, or inflated again on a replay) bit for bit."""
    from sketchforge.plugin_api import LAMBERTIAN
    from sketchforge.plugin_api import inflated as fresh_of
    from sketchforge_isophote_tool.creases import CREASE_MAX, crease_bounds

    host = make_sketchforge_host(installed=("inflate", "isophote_tool", "strips"))
    doc = make_sketchforge_document(host, resolution=0.06)
    first = doc.layer("a").mesh
    for offset in (0.12, -0.08):
        stroke, _, _ = isophote_stroke(doc.layer("a").mesh, PICK, offset=offset)
        before = doc.layer("a").mesh
        doc.execute({"command": "sculpt_isophote", "layer": "a", "pick": PICK, "band": 0.3,
                     "stroke": np.asarray(stroke).tolist(), "solver": "strips"})
    fresh = fresh_of(doc, doc.layer("a"))
    assert fresh.identical(first)
    crease, jump = crease_bounds(fresh, doc.light.direction, LAMBERTIAN)
    assert 0.0 < crease < CREASE_MAX and np.isfinite(jump)  # a 0.06 ellipse: ~9° fresh
    expected = sculpt(before, doc.light.direction, PICK, 0.3, stroke, solver=STRIPS, reference=fresh).mesh
    assert doc.layer("a").mesh.identical(expected)
    assert_replays(doc)


@pytest.mark.parametrize("elevation", [45, 90])
def test_a_tilted_light_lands_without_diverging(elevation):
    """A light above the drawing plane: the characteristic equations hold for any light
    (R_p, R_q of R(n, l)), but the flow stops at the brightest point, where every strip meets
    (README, thesis corrections). The shift is 0 there and the edit stays bounded."""
    mesh = inflated("ellipse", 0.04)
    e = np.radians(elevation)
    light = np.array([np.cos(e) / np.sqrt(2.0), np.cos(e) / np.sqrt(2.0), np.sin(e)])
    peak = mesh.V[:, 2].max()
    landed = 0
    for pick, offset in (([0.2, 0.1], 0.08), ([-0.3, -0.2], -0.08), ([0.4, -0.1], 0.06)):
        stroke, _, _ = isophote_stroke(mesh, pick, offset=offset, light=light)
        r = sculpt(mesh, light, pick, 0.3, stroke, solver=STRIPS)
        assert np.isfinite(r.mesh.V).all() and r.after <= r.before
        assert np.abs(r.mesh.V[:, 2] - mesh.V[:, 2]).max() <= 0.6 * peak + 1e-12
        landed += r.after <= max(2.0 * r.h, 0.3 * r.before)
    assert landed >= 2


def test_one_compiled_integration_serves_every_strip_count_and_layer(ellipse):
    from sketchforge_strips.integrate import _segment_function

    fn = _segment_function("tsit5", False)
    for pick, offset, band in (([0.2, 0.1], 0.1, 0.3), ([-0.3, -0.2], 0.05, 0.2), ([0.1, 0.3], -0.06, 0.4)):
        stroke, _, _ = isophote_stroke(ellipse, pick, offset=offset, half=0.1 + abs(offset))
        sculpt(ellipse, LIGHT, pick, band, stroke, solver=STRIPS)
    other = inflated("pillow", 0.05)
    stroke, _, _ = isophote_stroke(other, [0.2, 0.1], offset=0.1)
    sculpt(other, LIGHT, [0.2, 0.1], 0.3, stroke, solver=STRIPS)
    assert fn._cache_size() == 1


def test_the_compiled_strips_are_kept_for_the_next_process(tmp_path):
    """JAX's persistent compilation cache under the user's cache directory: a second process
    (the app, `replay`) finds the strip integration compiled."""
    code = (f"import sys; sys.path.insert(0, {str(ROOT / 'tests')!r})\n"
            "from sculpt_helpers import isophote_stroke\n"
            "from sketchforge_isophote_tool import sculpt\n"
            "from sketchforge_isophote_tool.testing import LIGHT, inflated\n"
            "from sketchforge_strips.solver import STRIPS\n"
            "import jax\n"
            "m = inflated('ellipse', 0.06)\n"
            "s, _, _ = isophote_stroke(m, [0.2, 0.1], offset=0.1)\n"
            "sculpt(m, LIGHT, [0.2, 0.1], 0.3, s, solver=STRIPS)\n"
            "print(jax.config.jax_compilation_cache_dir)\n")
    env = {**__import__("os").environ, "SKETCHFORGE_CACHE_DIR": str(tmp_path)}
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().splitlines()[-1] == str(tmp_path / "jax")
    kept = [p for p in (tmp_path / "jax").rglob("*") if p.is_file()]
    assert kept, "nothing was written to the compilation cache"


# A fresh process integrating strips on an analytic dome (no mesh: the strips alone are what the
# exported artifact computes): prints a digest of every path and whether diffrax was imported.
_STRIPS_PROCESS = """
import hashlib, sys
import numpy as np
import scipy.ndimage as ndi
from sketchforge_strips.field import GRID_SIZE
from sketchforge_strips.integrate import integrate_paths
G = GRID_SIZE
origin, spacing = np.array([-1.2, -1.2]), 2.4 / (G - 1)
X, Y = np.meshgrid(origin[0] + spacing * np.arange(G), origin[1] + spacing * np.arange(G), indexing="ij")
r = np.hypot(X, Y)
z = np.sqrt(np.clip(1.0 - r * r, 0.05, None))
E = (0.6 * X + 0.3 * Y + 0.74 * z)  # Lambertian shading of the dome under an in-plane-ish light
Rp, Rq = np.gradient(E, spacing)
nodes = np.stack([Rp, Rq, np.clip((0.9 - r) / 0.1, 0.0, 1.0)], axis=2)
coeffs = np.stack([ndi.spline_filter(nodes[:, :, k], order=3, mode="mirror") for k in range(3)], axis=2)
t = np.linspace(0.0, 6.0, 45)  # 45 strips: two batches each way, the last one padded
down, up, _ = integrate_paths(np.stack([0.3 * np.cos(t), 0.3 * np.sin(t)], axis=1), coeffs, origin, spacing, 0.01, 2.0)
h = hashlib.sha256()
for p in down + up:
    h.update(np.ascontiguousarray(p).tobytes())
print(h.hexdigest(), sum(len(p) for p in down + up), "diffrax" in sys.modules)
"""


def _strips_process(cache: Path, compile_cache: Path):
    env = {**__import__("os").environ, "SKETCHFORGE_CACHE_DIR": str(cache),
           "JAX_COMPILATION_CACHE_DIR": str(compile_cache)}
    out = subprocess.run([sys.executable, "-c", _STRIPS_PROCESS], capture_output=True, text=True, timeout=300, env=env)
    assert out.returncode == 0, out.stderr
    digest, points, diffrax = out.stdout.split()
    assert int(points) > 45 * 100  # the strips went somewhere: a digest of nothing proves nothing
    return digest, diffrax == "True"


def test_the_traced_strips_are_exported_for_the_next_process_which_gets_the_same_strips(tmp_path):
    """The first process traces the strip integration through diffrax and keeps it as a
    ``jax.export`` artifact; the next one runs it without importing diffrax, to the bit. An
    artifact changed on disk or cut short is traced anew (and rewritten), and a cache directory
    that cannot be written costs only the tracing: the same strips every time."""
    from sketchforge_strips.integrate import _jax, _load_exported, export_path

    compile_cache = tmp_path / "xla"  # shared by every run: compiling once keeps the test short
    first, traced = _strips_process(tmp_path / "c", compile_cache)
    assert traced
    artifacts = list((tmp_path / "c" / "strips").glob("*.jaxexport"))
    assert len(artifacts) == 1
    assert _strips_process(tmp_path / "c", compile_cache) == (first, False)

    good = artifacts[0].read_bytes()
    middle = len(good) // 2
    flipped = good[:middle] + bytes([good[middle] ^ 0x10]) + good[middle + 1:]
    for bad in (flipped, good[:middle], b"", b"not an artifact at all"):
        artifacts[0].write_bytes(bad)
        assert _load_exported(artifacts[0], _jax()) is None
    artifacts[0].write_bytes(flipped)
    assert _strips_process(tmp_path / "c", compile_cache) == (first, True)
    assert artifacts[0].read_bytes() == good  # traced anew, and kept again
    assert _load_exported(artifacts[0], _jax()) is not None

    blocked = tmp_path / "a-file"
    blocked.write_text("the cache directory's parent is a file: nothing can be written under it")
    assert _strips_process(blocked, compile_cache) == (first, True)
    assert export_path("tsit5", False).name == artifacts[0].name  # the key is this process's too
