"""Solver-side reflectance models R(n, l) and their slope form R(p, q; l) with gradients.

A model is a :class:`~sketchforge.geometry.reflectance_model.ReflectanceModel` whose ``R(n, l)`` is
written with ``jax.numpy``. It must be signed (negative in shadow, never ``max(·, 0)``): the
height solve follows ∇R and the c = 0 isophote edit needs a gradient in the shadow too
(thesis ch. 4 intro). R_p and R_q come from ``jax.grad`` of R composed with
n(p, q) = (-p, -q, 1) / sqrt(1 + p² + q²), so a plugin model works everywhere the Lambertian one
does. Everything here runs in float64 (:func:`sketchforge.numerics.enable_x64`).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache

import numpy as np

from sketchforge.numerics import enable_x64

enable_x64()

import jax  # noqa: E402  (x64 must be switched on before JAX makes any array)
import jax.numpy as jnp  # noqa: E402

from sketchforge.geometry.reflectance_model import ReflectanceModel  # noqa: E402


def lambertian(n, l):
    """Signed Lambertian reflectance n·l.

    Parameters
    ----------
    n, l : (3,) float64 jax arrays
        Unit surface normal and unit direction towards the light.

    Returns
    -------
    scalar float64, in [-1, 1]
    """
    return jnp.dot(n, l)


LAMBERTIAN = ReflectanceModel(
    "lambertian",
    lambertian,
    "Signed Lambertian n·l (negative in shadow so that its gradient exists everywhere).",
)


def normal_from_pq(p, q):
    """(3,) unit normal (-p, -q, 1) / sqrt(1 + p² + q²) from scalar slopes (jax-traceable)."""
    return jnp.stack([-p, -q, jnp.ones_like(p)]) / jnp.sqrt(1.0 + p * p + q * q)


def _pq_form(R: Callable) -> Callable:
    """R(n, l) composed with n(p, q): ``r(p, q, l)``, not compiled."""

    def r_pq(p, q, l):
        return R(normal_from_pq(p, q), l)

    return r_pq


@cache
def reflectance_pq(model: ReflectanceModel) -> Callable:
    """R(p, q, l) for a model, jit-compiled.

    Parameters
    ----------
    model : ReflectanceModel

    Returns
    -------
    callable
        ``R(p, q, l)``: p, q scalar float64, l (3,) float64 -> scalar float64. Traceable, so it
        can be called inside another ``jax.jit``/``vmap``.
    """
    return jax.jit(_pq_form(model.R))


@cache
def reflectance_pq_grad(model: ReflectanceModel) -> Callable:
    """R and its slope gradient (R_p, R_q) for a model, by ``jax.grad``, jit-compiled.

    Returns
    -------
    callable
        ``f(p, q, l) -> (R, R_p, R_q)``, scalars float64; traceable.
    """
    value_and_grad = jax.value_and_grad(_pq_form(model.R), argnums=(0, 1))

    def f(p, q, l):
        r, (rp, rq) = value_and_grad(p, q, l)
        return r, rp, rq

    return jax.jit(f)


#: Points per compiled batch of :func:`evaluate_pq` (larger inputs are split).
EVAL_CHUNK = 4096


@cache
def _batched_pq_grad(model: ReflectanceModel) -> Callable:
    return jax.jit(jax.vmap(reflectance_pq_grad(model), in_axes=(0, 0, None)))


@cache
def _batched_R(model: ReflectanceModel) -> Callable:
    return jax.jit(jax.vmap(model.R, in_axes=(0, None)))


def evaluate_pq(
    model: ReflectanceModel, p: np.ndarray, q: np.ndarray, l: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """R, R_p, R_q at many slopes, as numpy arrays.

    Parameters
    ----------
    model : ReflectanceModel
    p, q : (k,) float64
    l : (3,) float64
        Unit direction towards the light.

    Returns
    -------
    R, R_p, R_q : (k,) float64
    """
    p = np.ascontiguousarray(p, dtype=np.float64).reshape(-1)
    q = np.ascontiguousarray(q, dtype=np.float64).reshape(-1)
    l = np.asarray(l, dtype=np.float64)
    fn = _batched_pq_grad(model)
    k = len(p)
    if k <= EVAL_CHUNK:
        # Pad to one fixed size: an editor calls this with a different k on every edit, and
        # each new shape would otherwise cost a fresh trace and compile (~0.1 s).
        pad = np.zeros((2, EVAL_CHUNK))
        pad[0, :k], pad[1, :k] = p, q
        r, rp, rq = fn(pad[0], pad[1], l)
        return np.asarray(r)[:k], np.asarray(rp)[:k], np.asarray(rq)[:k]
    parts = [evaluate_pq(model, p[s : s + EVAL_CHUNK], q[s : s + EVAL_CHUNK], l) for s in range(0, k, EVAL_CHUNK)]
    return tuple(np.concatenate(a) for a in zip(*parts))


def evaluate(model: ReflectanceModel | None, N: np.ndarray, l: np.ndarray) -> np.ndarray:
    """E = R(n_i, l) at many unit normals.

    The Lambertian model (or ``None``) takes a plain numpy path (``N @ l``), so shading a
    mesh does not wait for JAX; any other model is vmapped and jit-compiled once per model.

    Parameters
    ----------
    model : ReflectanceModel or None
        None means :data:`LAMBERTIAN`.
    N : (n, 3) float64
        Unit normals.
    l : (3,) float64
        Unit direction towards the light.

    Returns
    -------
    (n,) float64
        Signed intensities.
    """
    N = np.ascontiguousarray(N, dtype=np.float64).reshape(-1, 3)
    l = np.asarray(l, dtype=np.float64).reshape(3)
    if model is None or model is LAMBERTIAN:
        return N @ l
    if len(N) == 0:
        return np.zeros(0)
    return np.asarray(_batched_R(model)(N, l), dtype=np.float64)
