"""Display shading by a reflectance model: the one ``R(n, l)`` a plugin writes with
``jax.numpy`` shades the canvas, the thumbnails and ``sketchforge render`` too, so a BRDF is
never written twice (once in JAX for the sculpt, once in numpy for the display).

The display evaluates that same function, compiled by JAX, on the per-pixel normals of the
canvas' buffer (numpy float32 arrays, upcast to float64), in fixed chunks of
:data:`CHUNK` normals (the last one padded), so it compiles once per model whatever the view.
The model's own isophote lines (R = j/(K+1)) follow the same per-pixel R, their width kept in
pixels by R's differences between neighbouring pixels of a layer
(:func:`sketchforge.geometry.gbuffer.isophote_coverage`): no gradient is evaluated (it cost
2.3 times the values). The Lambertian model takes a plain numpy path (``N·l``); its colours are
the clay shader's.

The values are the sculpt's: :func:`sketchforge.geometry.reflectance.evaluate_pq` evaluates
the same ``R`` at n(p, q); on a buffer's float32 normals they agree within 1e-6
(``tests/test_model_shading.py``). What it costs on the light-drag path is measured by
``benchmarks/bench_display.py``.
"""

from __future__ import annotations

from functools import cache, lru_cache

import numpy as np

from sketchforge.geometry.reflectance_model import ReflectanceModel
from sketchforge.geometry.shaders import AMBIENT, CLAY

#: Normals per compiled call (2^16: one compile per model; ~15 calls for a full-HD canvas).
CHUNK = 1 << 16


@cache
def _compiled(model: ReflectanceModel):
    """R over a chunk of normals, compiled once per model."""
    from sketchforge.geometry.reflectance import jax  # x64 switched on there

    return jax.jit(jax.vmap(model.R, in_axes=(0, None)))


def reflectance(model: ReflectanceModel, N: np.ndarray, l: np.ndarray) -> np.ndarray:
    """R(n_i, l) at many normals, from the model's own definition.

    Parameters
    ----------
    model : ReflectanceModel
    N : (k, 3) float32 or float64
        Unit normals.
    l : (3,) float64
        Unit direction towards the light.

    Returns
    -------
    (k,) float64
        Signed reflectance.
    """
    from sketchforge.geometry.reflectance import LAMBERTIAN

    l = np.asarray(l, dtype=np.float64).reshape(3)
    k = len(N)
    if model.R is LAMBERTIAN.R:
        N_ = np.asarray(N)
        return N_[:, 0] * l[0] + N_[:, 1] * l[1] + N_[:, 2] * l[2]  # float64 from a float32 buffer
    fn = _compiled(model)
    R = np.empty(k)
    block = np.empty((CHUNK, 3))
    for s in range(0, k, CHUNK):
        n = min(CHUNK, k - s)
        block[:n] = N[s : s + n]
        block[n:] = (0.0, 0.0, 1.0)  # padding: any unit normal
        R[s : s + n] = np.asarray(fn(block, l))[:n]
    return R


class ModelShader:
    """A display shader made from a reflectance model: clay lit by ``AMBIENT + (1 - AMBIENT)
    * clip(R(n, l), 0, 1)`` (for Lambertian, exactly the clay shader), with the model's own
    isophote lines (:meth:`intensity`, the R the lines follow).

    ``shade(N, l)`` and ``intensity(N, l)`` of one buffer and light share one evaluation."""

    def __init__(self, model: ReflectanceModel) -> None:
        self.model = model
        self.name = model.name
        self.description = f"clay lit by the reflectance model {model.name!r}: {model.description}".strip(": ")
        self._last: tuple | None = None

    def intensity(self, N: np.ndarray, l: np.ndarray) -> np.ndarray:
        """R (k,) float64 at the normals ``N`` (cached for the last buffer and light)."""
        l = np.asarray(l, dtype=np.float64).reshape(3)
        last = self._last  # one read: a thumbnail thread may shade meanwhile
        if last is not None and last[1] is N and last[0] == l.tobytes():
            return last[2]
        R = reflectance(self.model, N, l)
        self._last = (l.tobytes(), N, R)
        return R

    def shade(self, N: np.ndarray, l: np.ndarray) -> np.ndarray:
        """(k, 3) colours in [0, 1] (float32 for a float32 buffer, like the clay shader)."""
        R = self.intensity(N, l)
        dtype = np.float32 if np.asarray(N).dtype == np.float32 else np.float64
        k = np.clip(R, 0.0, 1.0).astype(dtype)
        k *= 1.0 - AMBIENT
        k += AMBIENT
        return k[:, None] * CLAY.astype(dtype)

    __call__ = shade


@lru_cache(maxsize=64)
def model_shader(model: ReflectanceModel) -> ModelShader:
    """The display shader of ``model`` (one per model: its compiled function is reused)."""
    return ModelShader(model)
