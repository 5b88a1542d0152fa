"""Region strips (thesis 4.3.3): dx/ds = -R_p(p, q), dy/ds = -R_q(p, q), p, q from the mesh.

Strips start on the contour where they enter the layer (-∇R·n_in > 0) and stop where they
leave the rim-margin region Ω*. Only their paths matter here (they delimit the cells that give
S•), so they are integrated in arc length (unit speed: the direction -∇R/|∇R|) with fixed-step
RK4 on the smooth (B-spline) p, q field: uniform spacing of samples, no stiffness near the rim
where |∇R| is small.
"""

from __future__ import annotations

import functools

import numpy as np

from sketchforge.numerics import enable_x64

enable_x64()

import jax  # noqa: E402  (x64 before JAX makes any array)
import jax.numpy as jnp  # noqa: E402

from sketchforge.geometry.field_jax import bilinear_eval, bspline_eval
from sketchforge.geometry.reflectance import evaluate_pq, reflectance_pq
from sketchforge.plugins.registry import ReflectanceModel

from .jaxcache import TRACES, run_padded
from .layerdata import LayerData

#: Most RK4 steps per region strip (static: one compiled function per batch size).
REGION_STEPS = 320

#: Steps per chunk of the early-exit loop. The batch stops after the first chunk in which no
#: strip is alive any more: strips leave Ω* after crossing the layer once (~40% of
#: REGION_STEPS, which allows for 2.5 crossings), so most of the fixed-length scan was wasted.
#: A vmapped while-loop would run to the slowest strip anyway; a loop over the whole batch
#: says so explicitly and keeps each chunk a plain vectorised scan.
REGION_CHUNK = 16


@functools.lru_cache(maxsize=8)
def _region_integrator(model: ReflectanceModel):
    grad_r = jax.grad(reflectance_pq(model), argnums=(0, 1))

    def direction(x, coeffs, origin, spacing, l):
        v, _ = bspline_eval(coeffs, origin, spacing, x)
        rp, rq = grad_r(v[0], v[1], l)
        d = -jnp.stack([rp, rq])
        return d / (jnp.linalg.norm(d) + 1e-300)

    def step_one(carry, coeffs, origin, spacing, dist, l, ds, margin):
        x, alive, entered = carry
        k1 = direction(x, coeffs, origin, spacing, l)
        k2 = direction(x + 0.5 * ds * k1, coeffs, origin, spacing, l)
        k3 = direction(x + 0.5 * ds * k2, coeffs, origin, spacing, l)
        k4 = direction(x + ds * k3, coeffs, origin, spacing, l)
        xn = x + ds / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        d = bilinear_eval(dist, origin, spacing, xn)
        inside = d > margin
        # Stop on leaving Ω* after having entered it, or on leaving the layer.
        stop = (entered & ~inside) | (d <= 0.0)
        alive_n = alive & ~stop
        x_out = jnp.where(alive_n, xn, x)
        return (x_out, alive_n, entered | inside)

    step_all = jax.vmap(step_one, in_axes=(0,) + (None,) * 7)
    n_chunks = REGION_STEPS // REGION_CHUNK

    def batch(seeds, coeffs, origin, spacing, dist, l, ds, margin):
        TRACES["region_strips"] += 1
        b = seeds.shape[0]
        args = (coeffs, origin, spacing, dist, l, ds, margin)

        def scan_step(carry, _):
            carry = step_all(carry, *args)
            return carry, (carry[0], carry[1])

        def cond(state):
            k, carry, _, _ = state
            return (k < n_chunks) & jnp.any(carry[1])

        def body(state):
            k, carry, xs, alive = state
            carry, (cx, ca) = jax.lax.scan(scan_step, carry, None, REGION_CHUNK)
            xs = jax.lax.dynamic_update_slice(xs, cx, (k * REGION_CHUNK, 0, 0))
            alive = jax.lax.dynamic_update_slice(alive, ca, (k * REGION_CHUNK, 0))
            return k + 1, carry, xs, alive

        carry0 = (seeds, jnp.ones(b, bool), jnp.zeros(b, bool))
        # Steps never reached stay "not alive", exactly as dead steps of a full scan.
        xs0 = jnp.zeros((n_chunks * REGION_CHUNK, b, 2), seeds.dtype)
        alive0 = jnp.zeros((n_chunks * REGION_CHUNK, b), bool)
        _, _, xs, alive = jax.lax.while_loop(cond, body, (jnp.array(0), carry0, xs0, alive0))
        xs = jnp.concatenate([seeds[:, None], jnp.swapaxes(xs, 0, 1)], axis=1)
        alive = jnp.concatenate([jnp.ones((b, 1), bool), alive.T], axis=1)
        return xs, alive

    return jax.jit(batch)


def integrate_region_strips(ld: LayerData, light: np.ndarray, model: ReflectanceModel, seeds: np.ndarray, margin: float):
    """Integrate region strips from seed points.

    Parameters
    ----------
    ld : LayerData
    light : (3,) float64
    model : ReflectanceModel
    seeds : (k, 2) float64
        Start points (just inside the contour).
    margin : float
        Rim margin: strips stop when they leave Ω* (distance to the contour < margin).

    Returns
    -------
    list of (j, 2) float64 polylines, one per seed.
    """
    if len(seeds) == 0:
        return []
    fn = _region_integrator(model)
    f = ld.pq_field
    dist = jnp.asarray(ld.dist_nodes)
    # Step: half an edge length, lengthened if needed so REGION_STEPS steps cross the layer
    # about 2.5 times (strips curve; they rarely run longer than that).
    lo, hi = ld.V2.min(axis=0), ld.V2.max(axis=0)
    ds = max(0.5 * ld.h, 2.5 * float(np.linalg.norm(hi - lo)) / REGION_STEPS)
    args = (f.coeffs, f.origin, f.spacing, dist, jnp.asarray(light, jnp.float64), jnp.asarray(ds), jnp.asarray(margin))
    return run_padded(fn, np.asarray(seeds, np.float64), *args)


def contour_runs(ld: LayerData, light: np.ndarray, model: ReflectanceModel, spacing: float):
    """Arcs of the contour where strips enter the layer (-∇R·n_in > 0).

    Returns
    -------
    list of (t0, t1) float
        Arc-length intervals along the outline's exterior ring (counter-clockwise from its first
        point); t1 may exceed the ring length (wrap around).
    """
    coords = np.asarray(ld.outline.exterior.coords)
    L = ld.outline.exterior.length
    n = max(int(np.ceil(L / spacing)), 16)
    t = np.arange(n) * (L / n)
    pts, n_in = ring_points(coords, t)
    inflow = np.einsum("ij,ij->i", flow(ld, light, model, pts), n_in) > 0
    if inflow.all():
        return [(0.0, L)]
    if not inflow.any():
        return []
    start, runs = cyclic_runs(inflow)
    # A run ends half-way between its last inflow sample and the first outflow one.
    return [(t[start] + (k0 - 0.5) * L / n, t[start] + (k1 - 0.5) * L / n) for k0, k1 in runs]


def flow(ld: LayerData, light: np.ndarray, model: ReflectanceModel, P: np.ndarray) -> np.ndarray:
    """Unit strip direction -∇R/|∇R| (k, 2) at points P (k, 2), p and q from the mesh."""
    pq = ld.locator.interpolate(ld.pq, P)
    _, rp, rq = evaluate_pq(model, pq[:, 0], pq[:, 1], light)
    d = -np.column_stack([rp, rq])
    return d / (np.linalg.norm(d, axis=1, keepdims=True) + 1e-300)


def cyclic_runs(ok: np.ndarray) -> tuple[int, list[tuple[int, int]]]:
    """Runs of True in a cyclic boolean array holding at least one False.

    Returns ``start`` (a False entry, so no run wraps past it) and the runs as ``(k0, k1)``:
    entries ``(start + k) % len(ok)`` for ``k0 <= k < k1``, in order.
    """
    n = len(ok)
    start = int(np.argmin(ok))
    runs, cur = [], None
    for k in range(n + 1):
        if ok[(start + k) % n]:
            if cur is None:
                cur = k
        elif cur is not None:
            runs.append((cur, k))
            cur = None
    return start, runs


def ring_points(coords: np.ndarray, t: np.ndarray):
    """Points (k, 2) and inward unit normals (k, 2) at arc lengths t along a closed CCW ring.

    ``coords`` (r+1, 2) repeats its first point at the end (shapely ring coordinates)."""
    d = np.linalg.norm(np.diff(coords, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(d)])
    L = s[-1]

    def at(tt):
        tt = np.mod(tt, L)
        sg = np.clip(np.searchsorted(s, tt, side="right") - 1, 0, len(d) - 1)
        uu = (tt - s[sg]) / np.where(d[sg] > 0, d[sg], 1.0)
        return coords[sg] + uu[:, None] * (coords[sg + 1] - coords[sg])

    t = np.mod(t, L)
    P = at(t)
    # Normal from a centred difference over about one sample, so corners get an averaged normal.
    delta = min(1e-3 * L, 0.5 * float(np.median(d)))
    tang = at(t + delta) - at(t - delta)
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    return P, np.column_stack([-tang[:, 1], tang[:, 0]])
