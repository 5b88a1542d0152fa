"""One BRDF definition drives the sculpt and the display (issue 37): a reflectance model's
``R(n, l)``, written once with ``jax.numpy``, evaluated on the canvas' numpy buffers, gives the
sculpt's values within 1e-6, the same values draw the model's own isophote lines, and the
Lambertian model's picture is the clay shader's."""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge.geometry import gbuffer as gb
from sketchforge.geometry.model_shading import CHUNK, model_shader, reflectance
from sketchforge.geometry.reflectance import LAMBERTIAN, evaluate_pq
from sketchforge.geometry.reflectance_model import ReflectanceModel
from sketchforge.geometry.shaders import lambert_shade


def _wrap(n, l):
    """Wrapped lighting with a rim term: not a function of n·l alone."""
    import jax.numpy as jnp

    c = jnp.dot(n, l)
    return 0.7 * (c + 0.3) / 1.3 + 0.2 * n[2] * c - 0.1 * n[0] * n[1]


WRAP = ReflectanceModel("wrap_rim", _wrap)


def _soft():
    soft = pytest.importorskip("sketchforge_soft_brdf")
    return soft.SOFT_LAMBERT


def _buffer_normals(rng, k):
    """Unit normals facing the viewer, stored as the canvas stores them (float32)."""
    N = rng.normal(size=(k, 3))
    N[:, 2] = np.abs(N[:, 2]) + 0.05
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    return N.astype(np.float32)


def _lights(rng, k):
    z = rng.uniform(0, 1, k)
    a = rng.uniform(0, 2 * np.pi, k)
    return np.c_[np.sqrt(1 - z * z) * np.cos(a), np.sqrt(1 - z * z) * np.sin(a), z]


@pytest.mark.parametrize("which", ["lambertian", "soft", "wrap"])
def test_the_display_evaluates_the_sculpt_s_own_values_within_1e_6(which):
    model = {"lambertian": LAMBERTIAN, "soft": None, "wrap": WRAP}[which] or _soft()
    rng = np.random.default_rng(37)
    N = _buffer_normals(rng, CHUNK + 1234)  # more than one compiled chunk, the last one padded
    worst = 0.0
    for l in _lights(rng, 4):
        R = reflectance(model, N, l)
        n = N.astype(np.float64)
        p, q = -n[:, 0] / n[:, 2], -n[:, 1] / n[:, 2]  # the slopes the sculpt works with
        E, _, _ = evaluate_pq(model, p, q, l)
        worst = max(worst, float(np.abs(R - E).max()))
        assert R.shape == (len(N),) and R.dtype == np.float64
    assert worst <= 1e-6
    assert reflectance(model, np.zeros((0, 3), np.float32), l).shape == (0,)


def _sphere_buffer(size=160):
    """A hemisphere's G-buffer: a mesh of a dome seen from +z."""
    from sketchforge.geometry.mesh import Mesh

    r = np.linspace(0, 1, 30)[1:]
    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    R, T = np.meshgrid(r, t, indexing="ij")
    xy = np.c_[(R * np.cos(T)).ravel(), (R * np.sin(T)).ravel()]
    V = np.vstack([[0, 0, 1], np.c_[xy, np.sqrt(np.clip(1 - (xy ** 2).sum(1), 0, None))]])
    from scipy.spatial import Delaunay

    F = Delaunay(V[:, :2]).simplices
    a, b, c = V[F[:, 0], :2], V[F[:, 1], :2], V[F[:, 2], :2]
    cw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    F[cw] = F[cw][:, ::-1]
    mesh = Mesh(V, F, np.arange(len(V) - 90, len(V)))
    return gb.rasterise([mesh], gb.View.framing([mesh], size, size, 0.05))


def test_the_lambertian_model_paints_the_clay_shader_s_picture():
    g = _sphere_buffer()
    l = np.array([0.6, 0.0, 0.8])
    clay = gb.shade(g, l, lambert_shade, np.array([0.9, 0.9, 0.9]), isophotes=6)
    shader = model_shader(LAMBERTIAN)
    model = gb.shade(g, l, shader.shade, np.array([0.9, 0.9, 0.9]), isophotes=6, intensity=shader.intensity)
    assert np.abs(clay.astype(int) - model.astype(int)).max() <= 1


def test_a_model_s_isophote_lines_run_where_its_own_r_is_at_a_level():
    soft = _soft()
    g = _sphere_buffer(240)
    l = np.array([0.6, 0.0, 0.8])
    K = 5
    shader = model_shader(soft)
    R = shader.intensity(g.normal, l)
    cov = gb.isophote_coverage(g, l, K, 1.2, R)
    lam = gb.isophote_coverage(g, l, K, 1.2)
    t = R[g.front_frag] * (K + 1)
    off = np.abs(t - np.rint(t))  # from the nearest level of R, in level units
    on, lam_on = cov > 0.9, lam > 0.9
    assert on.sum() > 200 and off[on].max() < 0.1
    # soft Lambert's levels are not Lambert's: Lambert's lines lie far from them
    assert off[lam_on].mean() > 5 * off[on].mean()
    assert (on & lam_on).sum() < 0.5 * on.sum()
