"""Compile the tool's JAX functions ahead of the first edit (call from a background thread)."""

from __future__ import annotations

import numpy as np

from .jaxcache import BATCH_BUCKETS


def warm_up(model=None, solver: str = "rk4", buckets=BATCH_BUCKETS) -> None:
    """Trace and compile every padded batch size of the region-strip and characteristic-strip
    solvers, the reflectance evaluation and the field evaluation, on a small disk layer.

    Shapes do not depend on the layer (fixed grid, padded batches), so later edits on any
    layer reuse these compilations.
    """
    import jax.numpy as jnp

    from sketchforge.geometry import field_jax
    from sketchforge.geometry.mesh import Mesh
    from sketchforge.geometry.reflectance import LAMBERTIAN

    from .characteristics import CHAR_STEPS, integrate_characteristics
    from .layerdata import layer_data
    from .strips import integrate_region_strips

    model = model or LAMBERTIAN
    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    V = np.column_stack([np.r_[0.0, np.cos(t)], np.r_[0.0, np.sin(t)], np.r_[1.0, np.zeros(24)]])
    F = np.column_stack([np.zeros(24, int), np.arange(1, 25), np.r_[np.arange(2, 25), 1]])
    mesh = Mesh(V, F, np.arange(1, 25))
    light = np.array([1.0, 0.0, 0.0])
    ld = layer_data(mesh, light, model)
    field = field_jax.grid_field_from_nodes(ld.E_nodes, ld.raster[0], ld.raster[1])
    field_jax.eval_points(ld.pq_field, np.zeros((1, 2)))
    for b in buckets:
        seeds = np.zeros((b, 2))
        integrate_region_strips(ld, light, model, seeds, 0.1)
        y0 = np.zeros((b, 5))
        integrate_characteristics(y0, field, np.ones_like(ld.dist_nodes), ld.dist_nodes, light, model,
                                  1.0 / CHAR_STEPS, 1.0, 0.1, solver)
    jnp.zeros(1).block_until_ready()
