"""Compile the tool's JAX function ahead of the first edit (call from a background thread)."""

from __future__ import annotations

import numpy as np


def warm_up(model=None) -> None:
    """Trace and compile the reflectance evaluation R, R_p, R_q (``jax.grad`` of the model,
    vmapped over one fixed padded size) that every edit calls: ~0.3 s on first use.

    Shapes do not depend on the layer (inputs are padded), so later edits on any layer reuse
    the compilation.
    """
    from sketchforge.plugin_api import LAMBERTIAN, evaluate_pq

    evaluate_pq(model or LAMBERTIAN, np.zeros(4), np.zeros(4), np.array([1.0, 0.0, 0.0]))
