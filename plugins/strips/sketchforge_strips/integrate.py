"""Characteristic strips integrated with diffrax (thesis 4.5), jitted and vmapped over strips.

Each strip is the base characteristic of the surface before the edit, dx/ds = −R_p,
dy/ds = −R_q (3.1.2, 4.3.3), carrying the linearised height change: along it
R_p ∂δz/∂x + R_q ∂δz/∂y = δE becomes dδz/ds = −δE (the failure analysis' fix 4(b): integrate
only the change, so a stroke drawn on the isophote (δE = 0) changes nothing, exactly, and
the error scales with the edit instead of with the surface). The state is (x, y, J) with
J = ∫ δE ds from the seed; δz at a point of the strip is J at its upstream end minus J there.

The strips are parametrised by arc length σ (dx/dσ the unit direction, ds = dσ / |∇R|), so
one integration length — the layer's diameter — covers every strip, and rescaled to t ∈ [0, 1]
so one compiled function serves every layer: the length is an argument. A strip stops where
the rim mask falls to 0 (the rim margin, where the surface turns vertical: 4.3's Ω*).

Solvers: ``tsit5`` (explicit, the default: the system is not stiff and Tsit5 was 2–4× faster
than Kvaerno5 with the same accuracy on the prototype) and ``kvaerno5`` (the thesis' implicit
A-L-stable solver), both with an adaptive PID step controller on the C² field of
:mod:`.field`. One compiled function per (solver, tolerances, saved points, batch size); batch
sizes and saved points are rounded up to powers of four so a session compiles a handful.
"""

from __future__ import annotations

import functools

import numpy as np

#: |∇R| below which the strip's speed is floored (1/|∇R| turns a shading change into a
#: height change; where the shading does not depend on the slope no edit can act).
SPEED_FLOOR = 1e-3
#: Steps a strip may take before it is cut off where it is (never an error: its samples up to
#: there are kept, the rest dropped).
MAX_STEPS = 8192


def _jax():
    import jax

    jax.config.update("jax_enable_x64", True)  # before any array: the strips are float64
    return jax


@functools.lru_cache(maxsize=32)
def _strip_function(integrator: str, rtol: float, atol: float, n_saved: int):
    """The jitted, vmapped integration of a batch of strips (see :func:`integrate_strips`)."""
    jax = _jax()
    import diffrax
    import jax.numpy as jnp

    from .field import bspline_eval

    def rhs(t, y, args):
        coeffs, origin, spacing, length, sign = args
        v = bspline_eval(coeffs, origin, spacing, y[:2])
        d = -v[:2]  # (−R_p, −R_q): the base characteristic's direction
        speed = jnp.sqrt(d[0] * d[0] + d[1] * d[1] + SPEED_FLOOR * SPEED_FLOOR)
        m = jnp.clip(v[3], 0.0, 1.0)  # the rim mask stops the strip in the rim margin
        step = length * m / speed
        return jnp.stack([sign * step * d[0], sign * step * d[1], step * v[2] * sign])

    solver = {"tsit5": diffrax.Tsit5, "kvaerno5": diffrax.Kvaerno5}[integrator]()
    ts = jnp.linspace(0.0, 1.0, n_saved)

    def one(y0, sign, coeffs, origin, spacing, length):
        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(rhs), solver, t0=0.0, t1=1.0, dt0=None, y0=y0,
            args=(coeffs, origin, spacing, length, sign),
            saveat=diffrax.SaveAt(ts=ts),
            stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
            max_steps=MAX_STEPS, throw=False,
        )
        return sol.ys, sol.stats["num_steps"]

    batched = jax.vmap(one, in_axes=(0, 0, None, None, None, None))
    return jax.jit(batched)


def _bucket(n: int, smallest: int) -> int:
    """``n`` rounded up to ``smallest`` times a power of 4: few shapes, so few compilations
    (each costs 2–6 s), for at most 4× the work of the exact shape."""
    size = smallest
    while size < n:
        size *= 4
    return size


def integrate_strips(seeds: np.ndarray, coeffs: np.ndarray, origin: np.ndarray, spacing: float, length: float,
                     n_saved: int, integrator: str = "tsit5", rtol: float = 1e-6, atol: float = 1e-9):
    """Trace every seed's strip downstream and upstream.

    Parameters
    ----------
    seeds : (k, 2) float64
    coeffs : (G, G, 4) float64
        B-spline coefficients of R_p, R_q, δE and the rim mask (:class:`.field.Raster`).
    origin : (2,) float64
    spacing : float
    length : float
        Arc length to integrate each way (drawing units).
    n_saved : int
        Points saved per direction (rounded up to 256 times a power of 4).
    integrator : {"tsit5", "kvaerno5"}
    rtol, atol : float

    Returns
    -------
    down, up : (k, K, 3) float64
        (x, y, J) at K evenly spaced arc lengths from the seed, downstream and upstream; J is
        ∫ δE ds from the seed in the downstream sense (negative upstream). Rows of a strip that
        could not be integrated that far are NaN.
    steps : (2k,) int64
        Steps taken per strip (diagnostics).
    """
    import jax.numpy as jnp

    k = len(seeds)
    K = _bucket(n_saved, 256)
    B = _bucket(2 * k, 64)
    y0 = np.zeros((B, 3))
    y0[:k, :2] = seeds
    y0[k:2 * k, :2] = seeds
    y0[2 * k:, :2] = seeds[0] if k else 0.0  # padding: copies of a real seed, results dropped
    sign = np.ones(B)
    sign[k:2 * k] = -1.0
    fn = _strip_function(integrator, float(rtol), float(atol), K)
    ys, steps = fn(jnp.asarray(y0), jnp.asarray(sign), jnp.asarray(coeffs), jnp.asarray(origin),
                   jnp.asarray(float(spacing)), jnp.asarray(float(length)))
    ys = np.array(ys)
    ys[~np.isfinite(ys).all(axis=2)] = np.nan  # a strip cut off at MAX_STEPS: its later samples
    return ys[:k], ys[k:2 * k], np.asarray(steps)[:2 * k]


#: The (strips, saved points) shapes a typical edit uses (a stroke up to ~120 edge lengths
#: across the flow, a layer up to ~170 edge lengths across): compiled by :func:`warm_up`.
WARM_SHAPES = ((32, 256), (128, 256), (128, 1024))


def warm_up(integrator: str = "tsit5", rtol: float = 1e-6, atol: float = 1e-9) -> None:
    """Compile the strip integration for :data:`WARM_SHAPES` (2–6 s each on first use), so the
    first ``strips`` edit of a session does not wait for it. Any layer reuses them: the
    field's size is fixed and its origin, spacing and the strips' length are arguments."""
    from .field import GRID_SIZE

    coeffs = np.zeros((GRID_SIZE, GRID_SIZE, 4))
    coeffs[:, :, 0] = -1.0  # a uniform flow, mask 0: every strip stops at once
    for strips, saved in WARM_SHAPES:
        integrate_strips(np.zeros((strips, 2)), coeffs, np.zeros(2), 1.0 / GRID_SIZE, 1.0, saved, integrator, rtol, atol)
