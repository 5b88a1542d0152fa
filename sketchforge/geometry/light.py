"""Setting the light by dragging in the drawing plane (thesis 4.1)."""

from __future__ import annotations

import math

import numpy as np

from sketchforge.document.layer import Light
from sketchforge.errors import ParameterError


def light_from_drag(center: np.ndarray, point: np.ndarray) -> Light:
    """The light pointing from the centre of the drawing region towards the mouse.

    Parameters
    ----------
    center : (2,) float64
        Centre of the drawing region, drawing units.
    point : (2,) float64
        Current mouse position, drawing units.

    Returns
    -------
    Light
        Unit direction of ``point - center`` in the drawing plane.

    Raises
    ------
    ParameterError
        If either point is not finite, or the drag has no length (mouse on the centre).
    """
    c = np.asarray(center, dtype=np.float64).reshape(-1)
    p = np.asarray(point, dtype=np.float64).reshape(-1)
    if c.shape != (2,) or p.shape != (2,):
        raise ParameterError("a light drag needs a 2D centre and a 2D point")
    if not (np.all(np.isfinite(c)) and np.all(np.isfinite(p))):
        raise ParameterError("a light drag needs finite coordinates")
    d = p - c
    # Relative to the coordinates' size, so the test is the same at any zoom.
    scale = max(1.0, float(np.max(np.abs(c))), float(np.max(np.abs(p))))
    if math.hypot(d[0], d[1]) <= 1e-12 * scale:
        raise ParameterError(
            "the light direction is undefined: drag away from the centre of the drawing"
        )
    return Light(float(d[0]), float(d[1]))
