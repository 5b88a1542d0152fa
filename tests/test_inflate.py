"""The inflate plugin: disk -> ellipsoid, fairing, mesh contract, junctions, errors, limits."""

import warnings

import numpy as np
import pluggy
import pytest
from inflate_shapes import circle, ellipse, figure_eight, letter_m, min_angles, signed_face_areas, star

from sketchforge.document.layer import DEFAULT_INFLATE_PARAMS
from sketchforge.errors import ContourError, LimitError, ParameterError
from sketchforge.geometry.contour import clean_contour, signed_area
from sketchforge.geometry.inflation import inflate_heights
from sketchforge.geometry.intensity import face_gradient
from sketchforge.geometry.laplacian import laplacian_and_mass
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.triangulate import MAX_VERTICES
from sketchforge.plugins import hookspecs
from sketchforge_inflate import DEFAULT_PARAMS, inflate_stroke
from sketchforge_inflate import plugin as inflate_plugin

FLAT = {"smoothing": 0.0}


def _ellipsoid_error(mesh, height):
    """RMS and max of z minus the exact ellipsoid over the mesh's own boundary radius."""
    r = np.linalg.norm(mesh.V[:, :2], axis=1)
    R = r[mesh.boundary].mean()
    exact = height / R * np.sqrt(np.maximum(R * R - r * r, 0.0))
    err = mesh.V[:, 2] - exact
    return np.sqrt(np.mean(err**2)), np.abs(err).max()


def _rim_slope(mesh):
    """Mean |∇z| over the triangles that touch the boundary."""
    on_rim = np.isin(mesh.F, mesh.boundary).any(axis=1)
    G = face_gradient(mesh.V, mesh.F[on_rim], mesh.V[:, 2])
    return np.hypot(G[:, 0], G[:, 1]).mean()


def _check_contract(mesh):
    assert isinstance(mesh, Mesh)
    assert mesh.V.dtype == np.float64 and mesh.V.shape[1] == 3
    assert mesh.F.dtype == np.int64 and mesh.F.shape[1] == 3
    assert np.all(np.isfinite(mesh.V))
    assert np.all(mesh.V[:, 2] >= 0.0)
    assert np.all(mesh.V[mesh.boundary, 2] == 0.0)
    assert np.all(signed_face_areas(mesh.V, mesh.F) > 0)  # counter-clockwise seen from +z
    # Consistent orientation: every directed edge at most once, boundary edges exactly the loop.
    E = np.vstack([mesh.F[:, [0, 1]], mesh.F[:, [1, 2]], mesh.F[:, [2, 0]]])
    assert len(np.unique(E, axis=0)) == len(E)
    keys = set(map(tuple, E))
    border = {e for e in keys if (e[1], e[0]) not in keys}
    b = mesh.boundary
    assert border == set(zip(b.tolist(), np.roll(b, -1).tolist()))
    assert signed_area(mesh.V[b, :2]) > 0


def test_default_params_match_the_document_defaults():
    assert dict(DEFAULT_PARAMS) == dict(DEFAULT_INFLATE_PARAMS)


def test_disk_inflates_to_an_ellipsoid_converging_under_refinement():
    errors = []
    for h in (0.08, 0.04, 0.02):
        mesh = inflate_stroke(circle(), True, {"resolution": h, "inflation": 0.7, **FLAT})
        _check_contract(mesh)
        rms, _ = _ellipsoid_error(mesh, 0.7)
        errors.append(rms / mesh.V[:, 2].max())
    assert errors[-1] < 0.01
    assert errors[0] > errors[1] > errors[2]


def test_result_does_not_depend_on_drawing_scale():
    a = inflate_stroke(ellipse(), True, {"resolution": 0.05})
    b = inflate_stroke(3.0 * ellipse(), True, {"resolution": 0.15})
    # Same outline scaled; Triangle's interior points differ by rounding, the shape does not.
    assert np.allclose(3.0 * a.V[a.boundary], b.V[b.boundary], atol=1e-9)
    assert abs(b.n_vertices / a.n_vertices - 1.0) < 0.05
    assert b.V[:, 2].max() == pytest.approx(3.0 * a.V[:, 2].max(), rel=2e-3)


def test_fairing_smooths_the_rim_without_flattening():
    flat = inflate_stroke(circle(), True, {"resolution": 0.03, **FLAT})
    faired = inflate_stroke(circle(), True, {"resolution": 0.03})
    _check_contract(faired)
    assert np.array_equal(flat.F, faired.F)
    assert _rim_slope(faired) < 0.5 * _rim_slope(flat)
    peak0, peak1 = flat.V[:, 2].max(), faired.V[:, 2].max()
    assert abs(peak1 - peak0) < 0.05 * peak0
    # No flattening: at r = 0.8 the faired blob keeps > 95% of the ellipsoid's height.
    r = np.linalg.norm(faired.V[:, :2], axis=1)
    ring = np.abs(r - 0.8) < 0.02
    assert faired.V[ring, 2].mean() > 0.95 * flat.V[ring, 2].mean()


def test_smoothing_zero_is_exactly_the_unfaired_mesh():
    a = inflate_stroke(star()[0], True, {"resolution": 0.05, "inflation": 0.8, "smoothing": 0.0})
    # Bit for bit the sqrt-inflation of the same triangulation, with no fairing applied.
    L, M = laplacian_and_mass(a.V[:, :2], a.F)
    unfaired = inflate_heights(a.V, a.F, a.boundary, 0.8, L, M)
    assert a.V[:, 2].tobytes() == unfaired.tobytes()
    c = inflate_stroke(star()[0], True, {"resolution": 0.05, "inflation": 0.8, "smoothing": 1e-3})
    assert np.array_equal(a.V[:, :2], c.V[:, :2]) and np.array_equal(a.F, c.F)
    assert not np.array_equal(a.V[:, 2], c.V[:, 2])


def test_faired_peak_agrees_across_resolutions():
    peaks = [inflate_stroke(ellipse(), True, {"resolution": h}).V[:, 2].max() for h in (0.04, 0.02)]
    assert abs(peaks[0] - peaks[1]) < 0.01 * peaks[1]


@pytest.mark.parametrize("name", ["disk", "ellipse", "star", "m"])
def test_minimum_angle_respected_away_from_sharp_corners(name):
    pts = {"disk": circle(), "ellipse": ellipse(), "star": star()[0], "m": letter_m()}[name]
    contour = clean_contour(pts, 0.04, closed=True)
    mesh = inflate_stroke(pts, True, {"resolution": 0.04})
    # Triangle keeps our boundary, so the boundary vertices are the contour's, in order.
    assert np.array_equal(mesh.V[mesh.boundary, :2], contour.points)
    P = contour.points
    d_in = P[contour.corners] - P[contour.corners - 1]
    d_out = P[(contour.corners + 1) % len(P)] - P[contour.corners]
    inner = np.degrees(
        np.pi
        - np.arccos(np.einsum("ij,ij->i", d_in, d_out) / (np.linalg.norm(d_in, axis=1) * np.linalg.norm(d_out, axis=1)))
    )
    sharp = contour.corners[inner < 25.0]
    away = ~np.isin(mesh.F, sharp).any(axis=1)
    assert min_angles(mesh.V, mesh.F[away]).min() >= 25.0 - 1e-9


@pytest.mark.parametrize("name", ["star", "m", "overshoot", "jittery"])
def test_shapes_inflate(name):
    rng = np.random.default_rng(3)
    # Head and tail both pass through (1, 0), the head outwards and the tail inwards: the
    # stroke crosses itself there and overshoots by 0.4 rad at each end.
    t = np.linspace(-0.4, 2 * np.pi + 0.4, 500)
    r = 1.0 + 0.3 * t * (2 * np.pi - t) / (4 * np.pi**2)
    pts = {
        "star": star()[0],
        "m": letter_m(),
        "overshoot": np.column_stack([r * np.cos(t), r * np.sin(t)]),
        "jittery": circle(n=3000) + 0.003 * rng.standard_normal((3000, 2)),
    }[name]
    mesh = inflate_stroke(pts, False, {"resolution": 0.04})
    _check_contract(mesh)
    assert len(mesh.junction) == 0
    interior = np.setdiff1d(np.arange(mesh.n_vertices), mesh.boundary)
    assert len(interior) > 50 and np.all(mesh.V[interior, 2] > 0)


def test_open_stroke_keeps_its_junction():
    P = circle(n=300, turns=(2 * np.pi - 1.0) / (2 * np.pi), start=0.5)
    mesh = inflate_stroke(P, False, {"resolution": 0.04})
    _check_contract(mesh)
    J = mesh.junction
    assert len(J) >= 3
    pos = {v: i for i, v in enumerate(mesh.boundary.tolist())}
    assert all((pos[b] - pos[a]) % len(mesh.boundary) == 1 for a, b in zip(J[:-1], J[1:]))
    ends = {tuple(np.round(P[0], 12)), tuple(np.round(P[-1], 12))}
    assert {tuple(np.round(mesh.V[J[0], :2], 12)), tuple(np.round(mesh.V[J[-1], :2], 12))} == ends
    assert np.abs(mesh.V[J, 0] - np.cos(0.5)).max() < 1e-12
    assert np.all(mesh.V[J, 2] == 0.0)
    assert len(inflate_stroke(P, True, {"resolution": 0.04}).junction) == 0


def test_ten_thousand_vertices_reachable():
    mesh = inflate_stroke(circle(), True, {"resolution": 0.024})
    assert 9_000 < mesh.n_vertices < 12_000


def test_hook_implementation_through_pluggy():
    pm = pluggy.PluginManager("sketchforge")
    pm.add_hookspecs(hookspecs)
    pm.register(inflate_plugin)
    (inflaters,) = pm.hook.sketchforge_inflaters()
    assert [i.name for i in inflaters] == ["poisson"]
    poisson = inflaters[0]
    mesh = poisson.inflate(circle(n=100).tolist(), True, poisson.check_params({"resolution": 0.1}), [])
    _check_contract(mesh)


@pytest.mark.parametrize(
    "params, message",
    [
        ({"resolution": 0.0}, "resolution"),
        ({"resolution": -1.0}, "resolution"),
        ({"resolution": float("nan")}, "finite"),
        ({"inflation": float("inf")}, "finite"),
        ({"inflation": -0.1}, "inflation"),
        ({"smoothing": 1.0}, r"\[0, 1\)"),
        ({"smoothing": -0.01}, r"\[0, 1\)"),
        ({"smoothing": "0.5"}, "number"),
        ({"resolution": True}, "number"),
    ],
)
def test_bad_parameters(params, message):
    with pytest.raises(ParameterError, match=message):
        inflate_stroke(circle(), True, params)


def test_missing_keys_take_the_defaults_and_unknown_keys_are_refused():
    a = inflate_stroke(circle(n=100), True, {"resolution": 0.1})
    b = inflate_stroke(circle(n=100), True, {**DEFAULT_PARAMS, "resolution": 0.1})
    assert a.identical(b)
    # A misspelt key would otherwise be dropped and the person never learn why nothing changed.
    with pytest.raises(ParameterError) as info:
        inflate_stroke(circle(n=100), True, {"resolution": 0.1, "colour": "red"})
    assert str(info.value) == "unknown inflation parameter 'colour' (known: resolution, inflation, smoothing)"


@pytest.mark.parametrize(
    "points, message",
    [
        ([[0, 0], [1, 0]], "at least 3"),
        ([[0, 0], [1, 0], [2, 0]], "straight line"),
        ([[0, 0], [1, np.nan], [0, 1]], "finite"),
        ([[0, 0], [1e200, 0], [0, 1e200]], "must lie within"),
        (figure_eight(), "crosses itself"),
    ],
)
def test_bad_contours(points, message):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ContourError, match=message):
            inflate_stroke(points, True, {"resolution": 0.05})


def test_too_fine_a_resolution_is_refused_before_triangulating(monkeypatch):
    import sketchforge_inflate.inflate as mod

    def no_triangulation(*a, **k):  # pragma: no cover - must not be reached
        raise AssertionError("triangulated despite the limit")

    monkeypatch.setattr(mod, "triangulate_polygon", no_triangulation)
    monkeypatch.setattr(mod, "resample_outline", no_triangulation)
    with pytest.raises(LimitError) as err:
        inflate_stroke(circle(), True, {"resolution": 1e-4})
    msg = str(err.value)
    assert f"{MAX_VERTICES:,}" in msg and "about" in msg
    est = int(msg.split("about ")[1].split(" vertices")[0].replace(",", ""))
    assert 2e8 < est < 6e8  # π / (0.43·1e-8) · 0.8 ≈ 5.8e8


def test_huge_drawing_with_fine_resolution_hits_the_limit_not_memory():
    with pytest.raises(LimitError):
        inflate_stroke(1e8 * circle(), True, {"resolution": 1.0})


def test_loaded_through_the_entry_point():
    from sketchforge.plugins.manager import PluginHost

    host = PluginHost.create(allowlist=["inflate"])
    assert "inflate" in host.plugin_names()
    _check_contract(host.inflate(circle(n=100), True, {"resolution": 0.1}))


def test_stroke_of_100k_points_inflates():
    rng = np.random.default_rng(5)
    pts = circle(n=100_000) + 1e-4 * rng.standard_normal((100_000, 2))
    mesh = inflate_stroke(pts, False, {"resolution": 0.05})
    _check_contract(mesh)
    assert 1_000 < mesh.n_vertices < 3_000


def test_a_ring_is_faired_by_its_own_width_not_its_outline():
    """With holes, the fairing's length unit comes from the surface's own area and rim length
    (outline minus holes, outline plus hole rims): an annulus 0.4 wide is smoothed like a band
    0.4 wide, so next to its inner rim it stays within 5% of the unfaired height (a unit taken
    from the filled disk would flatten it by far more)."""
    t = np.linspace(0.0, 2.0 * np.pi, 200, endpoint=False)
    outer = np.c_[np.cos(t), np.sin(t)]
    hole = 0.6 * outer[::-1]
    meshes = [inflate_stroke(outer, closed=True, params={"resolution": 0.03, "smoothing": s}, holes=[hole])
              for s in (0.0, 0.5)]
    heights = []
    for m in meshes:
        r = np.hypot(m.V[:, 0], m.V[:, 1])
        heights.append((m.V[:, 2].max(), m.V[(r > 0.63) & (r < 0.66), 2].mean()))
    (peak0, near0), (peak1, near1) = heights
    assert abs(peak1 - peak0) < 0.002 * peak0
    assert 0.95 * near0 < near1 < 0.995 * near0  # smoothed, but only a little


def test_the_vertex_limit_passed_in_is_the_one_checked():
    from sketchforge.errors import LimitError

    t = np.linspace(0.0, 2.0 * np.pi, 100, endpoint=False)
    disk = np.c_[np.cos(t), np.sin(t)]
    n = len(inflate_stroke(disk, closed=True, params={"resolution": 0.05}).V)
    with pytest.raises(LimitError):
        inflate_stroke(disk, closed=True, params={"resolution": 0.05}, max_vertices=n // 2)
    assert len(inflate_stroke(disk, closed=True, params={"resolution": 0.05}, max_vertices=2 * n).V) == n


def _largest_bend(mesh):
    from sketchforge.geometry.mesh_edges import edge_angles, interior_edges

    E, fa, fb = interior_edges(mesh.F)
    return float(edge_angles(mesh.V, mesh.F, fa, fb).max())


def test_a_narrow_part_is_meshed_finer_and_comes_out_round(monkeypatch):
    """An eye or a beak drawn 2-3 edge lengths in size was a faceted lump (issue 34): a part
    narrower than 4 edge lengths is meshed finer, so its triangles bend by at most 25 degrees
    against each other (47 at the asked resolution), at the same height; a part 4 edge lengths
    and more in size is meshed exactly as asked."""
    from sketchforge_inflate.inflate import edge_length_for

    t = np.linspace(0.0, 2.0 * np.pi, 40, endpoint=False)
    eye = np.c_[0.05 * np.cos(t), 0.04 * np.sin(t)]
    fine = inflate_stroke(eye, closed=True, params={"resolution": 0.03})
    assert _largest_bend(fine) < 25.0
    assert 150 < len(fine.V) < 300
    h = np.median(np.linalg.norm(fine.V[fine.F[:, 0], :2] - fine.V[fine.F[:, 1], :2], axis=1))
    assert h < 0.012
    coarse = inflate_stroke(eye, closed=True, params={"resolution": 0.012})
    assert abs(fine.V[:, 2].max() - coarse.V[:, 2].max()) < 0.02 * coarse.V[:, 2].max()
    # wide enough: as asked, vertex for vertex
    from sketchforge_inflate import inflate as inflate_module

    body = np.c_[0.5 * np.cos(t), 0.3 * np.sin(t)]
    assert edge_length_for(0.3, 0.03) == 0.03
    m = inflate_stroke(body, closed=True, params={"resolution": 0.03})
    monkeypatch.setattr(inflate_module, "edge_length_for", lambda size, h: h)
    asked = inflate_stroke(body, closed=True, params={"resolution": 0.03})
    assert np.array_equal(m.V, asked.V) and np.array_equal(m.F, asked.F)
    assert not np.array_equal(inflate_stroke(eye, closed=True, params={"resolution": 0.03}).V, fine.V)


def test_the_finer_edge_length_is_continuous_in_the_part_size():
    """Decisions continuous in the input: a stroke drawn a hair wider never jumps to another
    mesh density. Over sizes from 0.5 to 8 edge lengths the edge length changes by at most its
    steepest slope (1/2 per unit of size) times the step, never grows as the part narrows, is
    the asked one from 4 edge lengths up and at least a quarter of it everywhere."""
    from sketchforge_inflate.inflate import edge_length_for

    h = 0.03
    sizes = np.linspace(0.5 * h, 8 * h, 4001)
    e = np.array([edge_length_for(s, h) for s in sizes])
    step = sizes[1] - sizes[0]
    assert np.max(np.abs(np.diff(e))) <= 0.5 * step + 1e-15
    assert np.all(np.diff(e) >= 0)
    assert np.all(e[sizes >= 4 * h] == h) and np.all(e >= 0.25 * h) and np.all(e <= h)


def test_a_long_thin_stroke_meshed_finer_stays_within_its_vertex_budget():
    """A stroke two edge lengths wide and 60 long (a whisker) is meshed at most 4 times finer
    (16 times the triangles), and where even that would pass the vertex limit it is meshed as
    asked, not refused."""
    x = np.linspace(0.0, 1.8, 200)
    whisker = np.r_[np.c_[x, np.full_like(x, 0.03)], np.c_[x[::-1], np.full_like(x, -0.03)]]
    fine = inflate_stroke(whisker, closed=True, params={"resolution": 0.03})
    h = np.median(np.linalg.norm(fine.V[fine.F[:, 0], :2] - fine.V[fine.F[:, 1], :2], axis=1))
    assert 0.25 * 0.03 * 0.8 < h < 0.5 * 0.03
    capped = inflate_stroke(whisker, closed=True, params={"resolution": 0.03}, max_vertices=len(fine.V) - 1)
    assert len(capped.V) < len(fine.V) / 4
