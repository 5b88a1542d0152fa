"""The soft Lambert model registers (contracts probed by the host) and its slope gradient
from JAX matches finite differences where the height solve uses it."""

import numpy as np
import pytest
import sketchforge_soft_brdf as plugin


@pytest.fixture
def host(make_sketchforge_host):
    return make_sketchforge_host(plugin)  # strict: fails if the host refuses the model


def test_registered_with_its_provider(host):
    model = host.reflectance_models["soft_lambert"]
    assert model is plugin.SOFT_LAMBERT and host.provider_of(model) == plugin.__name__


def test_values_and_sign(host):
    from sketchforge.plugin_api import evaluate

    rng = np.random.default_rng(3)
    N = rng.normal(size=(200, 3))
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    l = np.array([0.6, 0.8, 0.0])
    c = N @ l
    R = evaluate(plugin.SOFT_LAMBERT, N, l)
    assert np.allclose(R, 0.6 * c + 0.4 * c**3, atol=1e-12)
    assert np.all(np.sign(R) == np.sign(c))  # signed: negative exactly in shadow


def test_slope_gradient_matches_finite_differences(host):
    from sketchforge.plugin_api import evaluate_pq

    rng = np.random.default_rng(4)
    p, q = rng.uniform(-2, 2, 50), rng.uniform(-2, 2, 50)
    l = np.array([1.0, 0.0, 0.0])
    R, Rp, Rq = evaluate_pq(plugin.SOFT_LAMBERT, p, q, l)
    h = 1e-6
    Rp_fd = (evaluate_pq(plugin.SOFT_LAMBERT, p + h, q, l)[0] - evaluate_pq(plugin.SOFT_LAMBERT, p - h, q, l)[0]) / (2 * h)
    Rq_fd = (evaluate_pq(plugin.SOFT_LAMBERT, p, q + h, l)[0] - evaluate_pq(plugin.SOFT_LAMBERT, p, q - h, l)[0]) / (2 * h)
    assert np.allclose(Rp, Rp_fd, atol=1e-7) and np.allclose(Rq, Rq_fd, atol=1e-7)
    assert np.abs(Rp).max() > 0.1  # a real gradient, not a constant
