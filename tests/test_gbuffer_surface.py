"""Per-pixel normal and height maps of the front surface (``gbuffer.front_surface``) and the
shading as numbers (``gbuffer.reflectance_image``): what a shape-from-shading sample holds."""

import numpy as np
import pytest
from meshes import hemisphere

from sketchforge.geometry import gbuffer as gb
from sketchforge.geometry.mesh import Mesh


def _view(size=160, half=1.1):
    return gb.View(-half, half, size / (2 * half), size, size)


def _centres(view):
    r, c = np.divmod(np.arange(view.width * view.height), view.width)
    return np.c_[view.x0 + (c + 0.5) / view.scale, view.y1 - (r + 0.5) / view.scale].reshape(view.height, view.width, 2)


def test_heights_and_normals_of_a_hemisphere_match_the_exact_surface_at_pixel_centres():
    m = hemisphere(1.0, 0.05)
    view = _view()
    maps = gb.front_surface([m], view)
    xy = _centres(view)
    r = np.hypot(xy[..., 0], xy[..., 1])
    # the mask is the inscribed polygon's inside: every centre within 0.99, none beyond 1
    assert maps.mask[r < 0.99].all() and not maps.mask[r > 1.0].any()
    inner = maps.mask & (r < 0.9)
    exact = np.sqrt(1 - r[inner] ** 2)
    # piecewise linear between vertices of edge 0.05: below the sphere by at most ~h²/(8 z³)
    err = exact - maps.height[inner]
    assert err.min() > -1e-9 and np.percentile(err, 99) < 2e-3
    n = maps.normal[inner].astype(float)
    true = np.c_[xy[inner], exact]
    ang = np.degrees(np.arccos(np.clip(np.sum(n * true, axis=1), -1, 1)))
    assert np.median(ang) < 1.0 and ang.max() < 4.0
    assert np.all(maps.height[~maps.mask] == 0) and np.all(maps.normal[~maps.mask] == 0)
    assert np.all(maps.layer[maps.mask] == 0) and np.all(maps.layer[~maps.mask] == -1)


def test_the_later_layer_is_in_front_even_where_it_is_lower_and_a_closed_mesh_shows_its_front():
    big = hemisphere(1.0, 0.08)
    small = hemisphere(0.3, 0.04)  # lower than the big one everywhere it covers
    view = _view()
    maps = gb.front_surface([big, small], view)
    xy = _centres(view)
    r = np.hypot(xy[..., 0], xy[..., 1])
    front = maps.mask & (r < 0.28)
    assert np.all(maps.layer[front] == 1)
    top = front & (r < 0.2)  # away from the steep rim, where the facets' error grows
    assert np.allclose(maps.height[top], np.sqrt(0.09 - r[top] ** 2), atol=3e-3)
    # a closed mesh: the hemisphere and its mirror image below; the front is the upper sheet
    V = np.array(big.V)
    back = V * [1, 1, -1]
    F = np.array(big.F)
    closed = Mesh(np.r_[V, back], np.r_[F, F[:, ::-1] + len(V)])
    both = gb.front_surface([closed], view)
    assert np.array_equal(both.mask, gb.front_surface([big], view).mask)
    assert np.all(both.height[both.mask] >= -1e-12)
    assert np.all(both.normal[both.mask & (r < 0.9)][:, 2] > 0.3)


def test_the_shading_image_is_max_of_zero_and_the_reflectance_of_the_maps_normals():
    m = hemisphere(1.0, 0.06)
    maps = gb.front_surface([m], _view(120))
    rng = np.random.default_rng(5)
    for _ in range(4):
        light = rng.normal(size=3)
        light[2] = abs(light[2])
        light /= np.linalg.norm(light)
        img = gb.reflectance_image(maps, light, lambda normals, towards: normals @ towards)
        n = maps.normal.astype(np.float64)
        assert np.array_equal(img[maps.mask], np.maximum(0.0, n[maps.mask] @ light))
        assert np.all(img[~maps.mask] == 0)
        assert 0 < (img[maps.mask] > 0).mean() < 1 or light[2] > 0.5
    with pytest.raises(ValueError, match="one finite value per normal"):
        gb.reflectance_image(maps, light, lambda normals, towards: np.ones(3))
    with pytest.raises(ValueError, match="one finite value per normal"):
        gb.reflectance_image(maps, light, lambda normals, towards: np.full(len(normals), np.nan))
