"""Example reflectance-model plugin: "soft Lambert", R = 0.6 c + 0.4 c³ with c = n·l.

Flatter than Lambert in the mid-tones and steeper at the terminator. The contract (checked
when the host registers it): written with ``jax.numpy`` so the height solve can
differentiate it, and signed: negative in shadow with a gradient there (never
``max(·, 0)``). It is odd in c, so R < 0 exactly where n·l < 0.
"""

from __future__ import annotations

from sketchforge.plugin_api import ReflectanceModel, hookimpl


def soft_lambert(n, l):
    """R(n, l) for (3,) float64 unit vectors as jax arrays -> scalar in [-1, 1]."""
    import jax.numpy as jnp

    c = jnp.dot(n, l)
    return 0.6 * c + 0.4 * c**3


SOFT_LAMBERT = ReflectanceModel("soft_lambert", soft_lambert, "Soft Lambert 0.6 n·l + 0.4 (n·l)³ (signed)")


@hookimpl
def sketchforge_reflectance_models():
    return [SOFT_LAMBERT]
