"""Reflectance as a function of the surface gradient (p, q), and batched evaluation.

A :class:`~sketchforge.plugins.registry.ReflectanceModel` gives ``R(n, l)``; the strip
equations need ``R(p, q)`` and its partial derivatives, with the normal
``n = (-p, -q, 1) / sqrt(1 + p² + q²)``. Derivatives come from ``jax.grad`` so any registered
model works.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from sketchforge.plugins.registry import ReflectanceModel

jax.config.update("jax_enable_x64", True)


def _lambertian(n, l):
    # Signed n·l: the solvers need gradients in shadow too (never clamp here).
    return jnp.dot(n, l)


try:  # the shading engineer's built-in model, when present
    from sketchforge.geometry.reflectance import LAMBERTIAN  # type: ignore
except Exception:  # pragma: no cover - fallback until sketchforge.geometry.reflectance exists
    LAMBERTIAN = ReflectanceModel("lambertian", _lambertian, "signed n·l")

#: Points per batched evaluation: one compiled function for any number of points.
CHUNK = 4096


def normal_from_pq(p, q):
    """Unit normal (3,) of the height field with gradient (p, q) = (z_x, z_y)."""
    return jnp.stack([-p, -q, 1.0]) / jnp.sqrt(1.0 + p * p + q * q)


def r_of_pq(model: ReflectanceModel):
    """``f(p, q, l) -> R`` for one point (JAX, differentiable)."""

    def f(p, q, l):
        return model.R(normal_from_pq(p, q), l)

    return f


@functools.lru_cache(maxsize=16)
def _batched(model: ReflectanceModel):
    f = r_of_pq(model)
    g = jax.grad(f, argnums=(0, 1))

    def one(pq, l):
        r = f(pq[0], pq[1], l)
        rp, rq = g(pq[0], pq[1], l)
        return r, jnp.stack([rp, rq])

    return jax.jit(jax.vmap(one, in_axes=(0, None)))


def eval_reflectance(model: ReflectanceModel, pq: np.ndarray, light: np.ndarray):
    """R and (R_p, R_q) at many gradients.

    Parameters
    ----------
    model : ReflectanceModel
    pq : (N, 2) float64
    light : (3,) float64

    Returns
    -------
    R : (N,) float64
    dR : (N, 2) float64
    """
    fn = _batched(model)
    pq = np.asarray(pq, np.float64)
    n = len(pq)
    out_r, out_g = np.empty(n), np.empty((n, 2))
    l = jnp.asarray(light, jnp.float64)
    for s in range(0, max(n, 1), CHUNK):
        block = pq[s : s + CHUNK]
        m = len(block)
        if m == 0:
            break
        pad = np.zeros((CHUNK, 2))
        pad[:m] = block
        r, g = fn(jnp.asarray(pad), l)
        out_r[s : s + m] = np.asarray(r)[:m]
        out_g[s : s + m] = np.asarray(g)[:m]
    return out_r, out_g
