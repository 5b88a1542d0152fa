"""The per-pixel rasteriser and shading shared by the canvas and ``sketchforge render``."""

import numpy as np
from meshes import hemisphere

from sketchforge.geometry import gbuffer as gb
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.shaders import lambert_shade

BG = np.array([0.95, 0.94, 0.92])
X = np.array([1.0, 0.0, 0.0])


def _view(size=200, half=1.1):
    return gb.View(-half, half, size / (2 * half), size, size)


def _centres(view):
    r, c = np.divmod(np.arange(view.width * view.height), view.width)
    return np.c_[view.x0 + (c + 0.5) / view.scale, view.y1 - (r + 0.5) / view.scale]


def test_normals_are_interpolated_per_pixel_close_to_the_true_sphere():
    m = hemisphere(1.0, 0.08)  # coarse: ~200 triangles, facets would be obvious
    view = _view()
    g = gb.rasterise([m], view)
    xy = _centres(view)[g.pix]
    r = np.hypot(xy[:, 0], xy[:, 1])
    inner = (r < 0.85) & (g.alpha >= 1)
    true = np.c_[xy, np.sqrt(np.maximum(1 - r * r, 0))][inner]
    n = g.normal[inner].astype(float)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    err = np.degrees(np.arccos(np.clip(np.sum(n * true, axis=1), -1, 1)))
    assert np.median(err) < 1.5 and err.max() < 6.0
    # no facets: neighbouring pixels' normals differ by a small fraction of a flat-shaded step
    img = np.zeros((view.height * view.width, 3))
    img[g.pix[inner]] = n
    img = img.reshape(view.height, view.width, 3)
    ok = np.zeros(view.height * view.width, bool)
    ok[g.pix[inner]] = True
    ok = ok.reshape(view.height, view.width)
    both = ok[:, 1:] & ok[:, :-1]
    jump = np.linalg.norm(img[:, 1:] - img[:, :-1], axis=2)[both]
    assert np.percentile(jump, 99.9) < 0.03  # a flat-shaded 0.08-unit facet steps by ~0.08


def test_coverage_antialiases_the_silhouette_and_keeps_the_area():
    m = hemisphere(1.0, 0.05)
    view = _view(300)
    g = gb.rasterise([m], view)
    area_px = g.alpha.astype(float).sum()
    # the mesh's own outline is a polygon inscribed in the unit circle
    V = m.V[:, :2]
    F = m.F
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    d1, d2 = b - a, c - a
    mesh_area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]).sum() * view.scale**2
    assert abs(area_px / mesh_area - 1) < 2e-3
    partial = (g.alpha > 0.05) & (g.alpha < 0.95)
    rim = 2 * np.pi * view.scale  # pixels along the outline
    assert 0.6 * rim < partial.sum() < 2.5 * rim
    hard = gb.rasterise([m], view, antialias=False)
    assert np.all(hard.alpha == 1) and abs(len(hard.pix) / mesh_area - 1) < 1e-2


def test_a_later_layer_covers_and_hides_the_lines_of_the_one_behind():
    back = hemisphere(0.9, 0.06)
    small = hemisphere(0.45, 0.04)
    front = Mesh(small.V + [0.35, 0.1, 0.0], small.F)
    view = _view(240)
    g = gb.rasterise([back, front], view)
    owner = g.front_layer()
    assert (owner == 1).sum() > 2000 and (owner == 0).sum() > 10000
    alone = gb.rasterise([None, front], view)
    with_lines = gb.shade(g, X, lambert_shade, BG, isophotes=8)
    front_alone = gb.shade(alone, X, lambert_shade, BG, isophotes=8)
    from scipy import ndimage

    inside = ndimage.binary_erosion(owner == 1, iterations=3)
    np.testing.assert_array_equal(with_lines[inside], front_alone[inside])
    plain = gb.shade(g, X, lambert_shade, BG)
    behind = ndimage.binary_erosion(owner == 0, iterations=3)
    assert np.any(np.any(plain != with_lines, axis=2)[behind])  # the back layer has lines


def test_isophote_lines_run_straight_where_the_shading_is_exact():
    """Hemisphere, light along +x: the isophote n·l = c is the chord x = c. The coverage-weighted
    centre of each row's line stays within a fraction of a pixel of it (no zig-zag)."""
    m = hemisphere(1.0, 0.04)
    view = _view(220)
    g = gb.rasterise([m], view)
    cov = np.zeros(view.width * view.height)
    cov[g.front >= 0] = gb.isophote_coverage(g, X, 3)
    cov = cov.reshape(view.height, view.width)
    cols = np.arange(view.width) + 0.5
    for c in (0.25, 0.5, 0.75):
        col = (c - view.x0) * view.scale
        band = np.abs(cols - col) < 4
        rows = slice(int(0.3 * view.height), int(0.7 * view.height))
        w = cov[rows][:, band]
        assert np.all(w.sum(axis=1) > 0.8)  # a line in every row
        centre = (w * cols[band]).sum(axis=1) / w.sum(axis=1)
        # wobble: spread around its own mean, and offset from the exact chord
        assert np.std(centre) < 0.35, np.std(centre)
        assert abs(np.mean(centre) - col) < 0.6


def test_reshading_is_the_same_as_rendering_afresh_and_views_frame_the_meshes():
    m = hemisphere(1.0, 0.06)
    view = gb.View.framing([m], 160, 100, margin=0.1)
    assert view.width == 160 and view.height == 100
    P = view.to_pixels(m.V)
    assert P[:, 1].min() >= 9.9 and P[:, 1].max() <= 90.1  # height-limited, 10% margins
    assert abs(0.5 * (P[:, 0].min() + P[:, 0].max()) - 80) < 1e-9
    g = gb.rasterise([m], view)
    for angle in (0.0, 1.0, 2.5):
        l = np.array([np.cos(angle), np.sin(angle), 0.0])
        a = gb.shade(g, l, lambert_shade, BG, isophotes=4)
        gb._mesh_cache.pop(m, None)  # rasterise afresh, not from the per-mesh cache
        b = gb.shade(gb.rasterise([m], view), l, lambert_shade, BG, isophotes=4)
        np.testing.assert_array_equal(a, b)
        q = gb.shade(g, l, lambert_shade, BG, isophotes=4, bgrx=True)
        np.testing.assert_array_equal(q[:, :, 2::-1], a)
        assert np.all(q[:, :, 3] == 255)


def test_tints_and_outlines_tell_apart_two_layers_that_shade_alike():
    """An eye on a head: two flat disks (same normal, same shade). Without help the eye cannot be
    seen; a per-layer tint changes its colour, an outline darkens a ring along its edge."""
    disk = hemisphere(0.8, 0.06)
    head = Mesh(np.c_[disk.V[:, :2], np.zeros(disk.n_vertices)], disk.F)
    eye = Mesh(np.c_[disk.V[:, :2] * 0.3 + [0.3, 0.2], np.zeros(disk.n_vertices)], disk.F)
    view = _view(200)
    g = gb.rasterise([head, eye], view)
    l = np.array([0.6, 0.0, 0.8])
    plain = gb.shade(g, l, lambert_shade, BG).astype(int)
    owner = g.front_layer()
    from scipy import ndimage

    eye_in = ndimage.binary_erosion(owner == 1, iterations=3)
    head_in = ndimage.binary_erosion(owner == 0, iterations=3)
    assert np.abs(plain[eye_in].mean(axis=0) - plain[head_in].mean(axis=0)).max() < 0.5  # invisible
    tinted = gb.shade(g, l, lambert_shade, BG, tints=[[1, 1, 1], [0.96, 0.99, 1.05]]).astype(int)
    assert np.abs(tinted[eye_in].mean(axis=0) - tinted[head_in].mean(axis=0)).max() >= 4
    lined = gb.shade(g, l, lambert_shade, BG, outline_alpha=0.45).astype(int).sum(axis=2)
    ring = ndimage.binary_dilation(owner == 1, iterations=1) & ~ndimage.binary_erosion(owner == 1, iterations=1)
    assert lined[ring].mean() < plain.sum(axis=2)[ring].mean() - 60
    # the outline of a layer hidden behind another is not drawn
    ring_pix = np.flatnonzero(ring)
    assert np.isin(g.edge_pix, ring_pix).sum() > 100
    hidden = gb.rasterise([eye, head], view)
    assert not np.any(np.isin(hidden.edge_pix, ring_pix))


def test_a_broken_display_shader_is_refused_with_a_clear_message():
    import pytest

    g = gb.rasterise([hemisphere(1.0, 0.1)], _view(40))
    with pytest.raises(ValueError, match="one finite RGB row per normal"):
        gb.shade(g, X, lambda N, l: np.ones((len(N), 4)), BG)
    with pytest.raises(ValueError, match="shape"):
        gb.shade(g, X, lambda N, l: np.full((len(N), 3), np.nan), BG)
    normal = g.normal.copy()
    gb.shade(g, X, lambda N, l: N, BG)  # a shader returning its input never alters the buffer
    np.testing.assert_array_equal(g.normal, normal)


def test_shading_in_place_over_an_earlier_picture_equals_shading_afresh():
    back = hemisphere(0.9, 0.06)
    small = hemisphere(0.45, 0.05)
    g = gb.rasterise([back, Mesh(small.V + [0.35, 0.1, 0.0], small.F)], _view(160))
    picture = gb.shade(g, X, lambert_shade, BG, bgrx=True, isophotes=5, outline_alpha=0.5)
    for angle, K, outline in ((1.0, 0, 0.0), (2.0, 7, 0.5), (4.0, 3, 0.0)):
        l = np.array([np.cos(angle), np.sin(angle), 0.0])
        again = gb.shade(g, l, lambert_shade, BG, bgrx=True, isophotes=K, outline_alpha=outline, out=picture)
        assert again.base is picture or again is picture or np.shares_memory(again, picture)
        fresh = gb.shade(g, l, lambert_shade, BG, bgrx=True, isophotes=K, outline_alpha=outline)
        np.testing.assert_array_equal(again, fresh)
