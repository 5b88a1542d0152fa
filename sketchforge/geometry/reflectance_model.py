"""The reflectance model and display shader value types, below both the geometry core and the plugin host.

Lives here (not in :mod:`sketchforge.plugins.registry`, which re-exports it) so the numerical
core never imports the host.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class ReflectanceModel:
    """Solver-side reflectance.

    ``R(n, l)``: n, l (3,) float64 unit vectors as ``jax.numpy`` arrays -> scalar, written with
    ``jax.numpy`` so the strip solver can differentiate it. Signed: negative in shadow.
    """

    name: str
    R: Callable
    description: str = ""


@dataclass(frozen=True)
class Shader:
    """Display-side shading: ``shade(normals (n,3) float64, light (3,) float64) -> (n,3) float64``
    colours in [0, 1]. Never used by a solver."""

    name: str
    shade: Callable
    description: str = ""
