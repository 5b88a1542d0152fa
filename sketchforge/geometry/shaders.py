"""Display shaders: normals and a light -> colours. Never used by a solver.

A stepped shader has no useful gradient, which is exactly why the solvers use the signed
reflectance models of :mod:`sketchforge.geometry.reflectance` instead.
"""

from __future__ import annotations

import numpy as np

from sketchforge.geometry.reflectance_model import Shader

#: Warm clay base colour, linear RGB in [0, 1].
CLAY = np.array([0.84, 0.74, 0.62])
#: Share of the base colour kept in full shadow, so the shadowed side still reads as a shape.
AMBIENT = 0.30
#: Three cel tones, dark to light (thesis fig. 5.1 uses three tones): shadow, mid, lit.
CEL_TONES = np.array([[0.30, 0.29, 0.31], [0.60, 0.56, 0.52], [0.90, 0.84, 0.76]])
#: n·l thresholds between the cel tones: the shadow line (0) and half brightness.
CEL_THRESHOLDS = (0.0, 0.5)


def _ndotl(normals, light) -> np.ndarray:
    # float32 normals (a per-pixel buffer) stay float32: display precision, half the memory
    N = np.asarray(normals)
    if N.dtype != np.float32:
        N = N.astype(np.float64)
    N = N.reshape(-1, 3)
    l = np.asarray(light, dtype=N.dtype).reshape(3)
    # Column by column: numpy's (k, 3) @ (3,) matvec is ~20x slower for float32 buffers.
    return N[:, 0] * l[0] + N[:, 1] * l[1] + N[:, 2] * l[2]


def lambert_shade(normals: np.ndarray, light: np.ndarray) -> np.ndarray:
    """Clay colour scaled by AMBIENT + (1 - AMBIENT) * max(n·l, 0).

    Parameters
    ----------
    normals : (n, 3) float64 or float32
        Unit normals.
    light : (3,) float64
        Unit direction towards the light.

    Returns
    -------
    (n, 3) in [0, 1], float32 for float32 normals, else float64
    """
    k = _ndotl(normals, light)  # a fresh array: scaled in place (a buffer may hold 10^6 normals)
    np.clip(k, 0.0, 1.0, out=k)
    k *= 1.0 - AMBIENT
    k += AMBIENT
    return k[:, None] * CLAY.astype(k.dtype)  # in [AMBIENT, 1] * CLAY: no clip needed


def cel_shade(normals: np.ndarray, light: np.ndarray) -> np.ndarray:
    """Three-tone toon shading: shadow (n·l <= 0), mid (0 < n·l <= 0.5), lit (n·l > 0.5).

    Parameters
    ----------
    normals : (n, 3) float64
    light : (3,) float64

    Returns
    -------
    (n, 3) in [0, 1], each row one of :data:`CEL_TONES` (float32 for float32 normals)
    """
    e = _ndotl(normals, light)
    tone = (e > CEL_THRESHOLDS[0]).astype(np.int8) + (e > CEL_THRESHOLDS[1])
    return CEL_TONES.astype(e.dtype)[tone]


LAMBERT_SHADER = Shader(
    "lambert", lambert_shade, "Clay Lambertian max(n·l, 0) with a little ambient."
)
CEL_SHADER = Shader(
    "cel", cel_shade, "Three-tone cel shading (shadow, mid, lit), as in thesis fig. 5.1."
)
