"""Solver-side reflectance: signed Lambertian, R(p, q) and R_p, R_q by autodiff, plugin models."""

import jax
import jax.numpy as jnp
import numpy as np
import pluggy
import pytest

from sketchforge.geometry.normals import normals_from_slopes
from sketchforge.geometry.reflectance import (
    LAMBERTIAN,
    evaluate,
    evaluate_pq,
    lambertian,
    reflectance_pq,
    reflectance_pq_grad,
)
from sketchforge.plugins import hookspecs
from sketchforge.plugins.registry import ReflectanceModel

LIGHT = np.array([np.cos(0.7), np.sin(0.7), 0.0])


def _pq_samples(k=40, seed=3):
    rng = np.random.default_rng(seed)
    return rng.uniform(-3, 3, k), rng.uniform(-3, 3, k)


def test_x64_is_on_and_lambertian_is_signed():
    assert jax.config.jax_enable_x64
    n = jnp.array([-1.0, 0.0, 0.0])
    r = lambertian(n, jnp.asarray(LIGHT))
    assert r.dtype == jnp.float64
    assert float(r) == pytest.approx(-np.cos(0.7))  # negative in shadow, not clamped


def test_lambertian_pq_matches_closed_form():
    p, q = _pq_samples()
    R, Rp, Rq = evaluate_pq(LAMBERTIAN, p, q, LIGHT)
    lx, ly = LIGHT[:2]
    s = np.sqrt(1 + p * p + q * q)
    np.testing.assert_allclose(R, -(p * lx + q * ly) / s, atol=1e-15)
    # d/dp of -(p lx + q ly)/s = -lx/s + (p lx + q ly) p / s³
    np.testing.assert_allclose(Rp, -lx / s + (p * lx + q * ly) * p / s**3, atol=1e-14)
    np.testing.assert_allclose(Rq, -ly / s + (p * lx + q * ly) * q / s**3, atol=1e-14)
    assert R.dtype == np.float64


def test_scalar_jitted_helpers_agree_with_batched():
    f = reflectance_pq_grad(LAMBERTIAN)
    r, rp, rq = f(0.3, -1.2, jnp.asarray(LIGHT))
    R, Rp, Rq = evaluate_pq(LAMBERTIAN, [0.3], [-1.2], LIGHT)
    assert float(r) == pytest.approx(R[0], abs=1e-15)
    assert float(rp) == pytest.approx(Rp[0], abs=1e-15)
    assert float(rq) == pytest.approx(Rq[0], abs=1e-15)
    assert float(reflectance_pq(LAMBERTIAN)(0.3, -1.2, jnp.asarray(LIGHT))) == pytest.approx(R[0])


def test_evaluate_numpy_path_matches_jax_path():
    rng = np.random.default_rng(0)
    N = rng.normal(size=(100, 3))
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    copy = ReflectanceModel("lambertian-copy", lambda n, l: jnp.dot(n, l))
    np.testing.assert_allclose(evaluate(LAMBERTIAN, N, LIGHT), N @ LIGHT, atol=0)
    np.testing.assert_allclose(evaluate(copy, N, LIGHT), N @ LIGHT, atol=1e-15)
    assert evaluate(None, N, LIGHT).shape == (100,)


# --- a third-party model registered through the plugin hook --------------------------------

hookimpl = pluggy.HookimplMarker("sketchforge")


def _half_lambert(n, l):
    # Valve's half-Lambert, squared: smooth, positive, non-linear in n·l.
    return (0.5 * jnp.dot(n, l) + 0.5) ** 2


def _soft_rough(n, l):
    # An Oren–Nayar-flavoured smooth model: a roughness term that depends on the view (0,0,1).
    nl = jnp.dot(n, l)
    nv = n[2]
    return nl * (0.8 + 0.2 * nv) + 0.1 * jnp.tanh(3.0 * nl) * (1.0 - nv**2)


class _ThirdPartyPlugin:
    @hookimpl
    def sketchforge_reflectance_models(self):
        return [
            ReflectanceModel("half_lambert", _half_lambert, "((n·l + 1)/2)²"),
            ReflectanceModel("soft_rough", _soft_rough, "smooth rough-ish"),
        ]


def _registered_models():
    pm = pluggy.PluginManager("sketchforge")
    pm.add_hookspecs(hookspecs)
    pm.register(_ThirdPartyPlugin())
    return {m.name: m for group in pm.hook.sketchforge_reflectance_models() for m in group}


@pytest.mark.parametrize("name", ["half_lambert", "soft_rough"])
def test_plugin_model_gradients_match_finite_differences(name):
    model = _registered_models()[name]
    p, q = _pq_samples(30, seed=7)

    def R_np(p, q):
        return evaluate(model, normals_from_slopes(p, q), LIGHT)

    R, Rp, Rq = evaluate_pq(model, p, q, LIGHT)
    np.testing.assert_allclose(R, R_np(p, q), atol=1e-14)
    eps = 1e-6
    fd_p = (R_np(p + eps, q) - R_np(p - eps, q)) / (2 * eps)
    fd_q = (R_np(p, q + eps) - R_np(p, q - eps)) / (2 * eps)
    # Central differences in float64: error ~ eps² R''' + 1e-16/eps ~ 1e-10.
    np.testing.assert_allclose(Rp, fd_p, atol=1e-8)
    np.testing.assert_allclose(Rq, fd_q, atol=1e-8)
    assert np.all(np.isfinite(Rp)) and np.all(np.isfinite(Rq))
