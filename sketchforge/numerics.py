"""Numerical switches shared by every module that uses JAX.

JAX computes in float32 unless told otherwise. The solvers (reflectance gradients, strip
integration) need float64: the strips integrate over hundreds of steps and a float32 right-hand
side shows up as visible height noise. Every module that imports ``jax`` calls
:func:`enable_x64` at import time, before it creates any array, so the setting holds no matter
which module happens to import JAX first.
"""

from __future__ import annotations

_done = False


def enable_x64() -> None:
    """Switch JAX to 64-bit floats and integers (idempotent, cheap after the first call)."""
    global _done
    if _done:
        return
    import jax

    jax.config.update("jax_enable_x64", True)
    _done = True
