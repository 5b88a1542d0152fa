"""Strip integration (thesis 4.5): Horn's characteristic system for (x, y, p, q, z).

    dx/ds = -R_p,  dy/ds = -R_q,  dp/ds = -E_x,  dq/ds = -E_y,  dz/ds = p dx/ds + q dy/ds

(3.1.2 with its dz/ds sign corrected; R_p, R_q by autodiff of the registered model). The
system is autonomous, so it is integrated in arc length of the (x, y) path (every derivative
divided by |∇R|): uniform sample spacing, fixed steps stay accurate near the rim where |∇R| is
small, and saved samples are already about one per fixed distance. E and ∇E come from the
smooth B-spline grid field (C²), so adaptive solvers meet their tolerance.

Start values: (x, y) on the entry part of ∂M•, p, q, z interpolated from the mesh, then
(p, q) projected onto R(p, q) = E(x, y) (admissibility, 3.1.4) by a few Newton steps along ∇R.
Stops: on leaving M• (a rasterised mask), on reaching the rim margin, or at an intensity peak
(|∇R| ≈ 0, which cannot happen with an in-plane light but can with another model or light).

Solvers: ``"rk4"`` (fixed step in ``lax.scan``, default), ``"tsit5"`` and ``"kvaerno5"``
(diffrax, PID step control, terminating event). Each compiles once per padded batch size.
"""

from __future__ import annotations

import functools

import numpy as np

from sketchforge.numerics import enable_x64

enable_x64()

import jax  # noqa: E402  (x64 before JAX makes any array)
import jax.numpy as jnp  # noqa: E402

from sketchforge.geometry.field_jax import bilinear_eval, bspline_eval
from sketchforge.geometry.reflectance import reflectance_pq_grad
from sketchforge.plugins.registry import ReflectanceModel

from .jaxcache import TRACES, run_padded

#: Fixed steps of the "rk4" solver and saved samples of the diffrax solvers (static sizes).
CHAR_STEPS = 256
SOLVERS = ("rk4", "tsit5", "kvaerno5")
PROJECT_ITERS = 8


def _make_rhs(model):
    vg = reflectance_pq_grad(model)  # (p, q, l) -> (R, R_p, R_q)

    def rhs(y, coeffs, origin, spacing, l):
        p, q = y[2], y[3]
        _, Eg = bspline_eval(coeffs, origin, spacing, y[:2])
        _, rp, rq = vg(p, q, l)
        g = jnp.sqrt(rp * rp + rq * rq) + 1e-300
        dx, dy = -rp / g, -rq / g
        return jnp.stack([dx, dy, -Eg[0, 0] / g, -Eg[0, 1] / g, p * dx + q * dy]), g

    def project(y, coeffs, origin, spacing, l):
        e, _ = bspline_eval(coeffs, origin, spacing, y[:2])

        def it(pq, _):
            r, rp, rq = vg(pq[0], pq[1], l)
            g2 = rp * rp + rq * rq + 1e-300
            return pq + (e[0] - r) * jnp.stack([rp, rq]) / g2, None

        pq, _ = jax.lax.scan(it, y[2:4], None, PROJECT_ITERS)
        return y.at[2:4].set(pq)

    return rhs, project


def _inside(y, mask, dist, origin, spacing, margin):
    return (bilinear_eval(mask, origin, spacing, y[:2]) > 0.5) & (bilinear_eval(dist, origin, spacing, y[:2]) > margin)


@functools.lru_cache(maxsize=16)
def _integrator(model: ReflectanceModel, solver: str, rtol: float):
    rhs, project = _make_rhs(model)

    if solver == "rk4":

        def one(y0, coeffs, mask, dist, origin, spacing, l, ds, L, margin):
            TRACES["char_rk4"] += 1
            y0 = project(y0, coeffs, origin, spacing, l)

            def step(carry, _):
                y, alive = carry
                k1, g = rhs(y, coeffs, origin, spacing, l)
                k2, _ = rhs(y + 0.5 * ds * k1, coeffs, origin, spacing, l)
                k3, _ = rhs(y + 0.5 * ds * k2, coeffs, origin, spacing, l)
                k4, _ = rhs(y + ds * k3, coeffs, origin, spacing, l)
                yn = y + ds / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
                ok = alive & _inside(yn, mask, dist, origin, spacing, margin) & (g > 1e-6) & jnp.all(jnp.isfinite(yn))
                return (jnp.where(ok, yn, y), ok), (yn, ok)

            _, (ys, alive) = jax.lax.scan(step, (y0, jnp.array(True)), None, CHAR_STEPS)
            return jnp.concatenate([y0[None], ys]), jnp.concatenate([jnp.array([True]), alive])

        return jax.jit(jax.vmap(one, in_axes=(0,) + (None,) * 9))

    import diffrax

    def one(y0, coeffs, mask, dist, origin, spacing, l, ds, L, margin):
        TRACES[f"char_{solver}"] += 1
        y0 = project(y0, coeffs, origin, spacing, l)
        term = diffrax.ODETerm(lambda t, y, args: rhs(y, coeffs, origin, spacing, l)[0])

        def stop(t, y, args, **kw):
            g = rhs(y, coeffs, origin, spacing, l)[1]
            return ~_inside(y, mask, dist, origin, spacing, margin) | (g <= 1e-6)

        ts = jnp.linspace(0.0, 1.0, CHAR_STEPS + 1) * L
        sol = diffrax.diffeqsolve(
            term,
            diffrax.Tsit5() if solver == "tsit5" else diffrax.Kvaerno5(),
            0.0,
            L,
            ds,
            y0,
            saveat=diffrax.SaveAt(ts=ts),
            stepsize_controller=diffrax.PIDController(rtol=rtol, atol=1e-3 * rtol),
            event=diffrax.Event(stop),
            max_steps=8192,
            throw=False,
        )
        ys = sol.ys
        ok = jnp.all(jnp.isfinite(ys), axis=1)
        # Samples past the stop are inf; the one that triggered the event may lie just outside.
        ok = ok & jax.vmap(lambda y: _inside(y, mask, dist, origin, spacing, margin))(jnp.where(ok[:, None], ys, 0.0))
        ok = jnp.cumprod(ok.astype(jnp.int32)).astype(bool)
        return jnp.where(ok[:, None], ys, y0), ok

    return jax.jit(jax.vmap(one, in_axes=(0,) + (None,) * 9))


def integrate_characteristics(
    y0: np.ndarray,
    E_field,
    mask_nodes: np.ndarray,
    dist_nodes: np.ndarray,
    light: np.ndarray,
    model: ReflectanceModel,
    ds: float,
    length: float,
    margin: float,
    solver: str = "rk4",
    rtol: float = 1e-7,
):
    """Integrate characteristic strips.

    Parameters
    ----------
    y0 : (k, 5) float64
        Start (x, y, p, q, z); p, q are projected onto R = E before integrating.
    E_field : field_jax.GridField
        The (edited) shading, one channel.
    mask_nodes : (G, G) float64
        1 on grid nodes inside the region to stay in (M•, slightly dilated), else 0.
    dist_nodes : (G, G) float64
        Distance to the contour at the grid nodes.
    light : (3,) float64
    model : ReflectanceModel
    ds : float
        Step ("rk4") or initial step (diffrax), arc length.
    length : float
        Longest strip integrated (arc length); rk4 uses ``CHAR_STEPS`` steps of ``ds``, so
        callers pass ``ds = length / CHAR_STEPS`` there.
    margin : float
        Strips stop closer than this to the contour.
    solver : {"rk4", "tsit5", "kvaerno5"}
    rtol : float
        Relative tolerance of the adaptive solvers.

    Returns
    -------
    ys : list of (j, 5) float64
        Samples along each strip until it stops (the start included, after projection).
    """
    if solver not in SOLVERS:
        raise ValueError(f"unknown strip solver {solver!r}; choose one of {SOLVERS}")
    if len(y0) == 0:
        return []
    fn = _integrator(model, solver, float(rtol))
    args = (
        E_field.coeffs,
        jnp.asarray(mask_nodes, jnp.float64),
        jnp.asarray(dist_nodes, jnp.float64),
        E_field.origin,
        E_field.spacing,
        jnp.asarray(light, jnp.float64),
        jnp.asarray(ds, jnp.float64),
        jnp.asarray(length, jnp.float64),
        jnp.asarray(margin, jnp.float64),
    )
    return run_padded(fn, np.asarray(y0, np.float64), *args)
