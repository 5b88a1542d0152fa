"""Base characteristics through the stroke, for display (thesis 3.1, 4.3.3).

The (x, y) paths of Horn's strips follow dx/ds = −R_p, dy/ds = −R_q. The height solve
(:mod:`.heights`) solves the linearised equation along exactly these directions; drawing a few
of them through the stroke shows the person along which lines a shading change turns into a
height change. Traced here on the old surface, both ways from points on the stroke, until
they leave the support of the edit or the layer.
"""

from __future__ import annotations

import numpy as np

from .layerdata import LayerData, vertex_shading

#: Curves drawn through a stroke (spread evenly along it).
N_CURVES = 15


def base_characteristics(ld: LayerData, stroke_pieces: list[np.ndarray], reach: float, n: int = N_CURVES) -> list[np.ndarray]:
    """Polylines (k, 2) of the base characteristics through ``n`` points of the stroke.

    Parameters
    ----------
    ld : LayerData
        The layer before the edit.
    stroke_pieces : list of (j, 2) float64
    reach : float
        How far from the stroke to trace (drawing units), each way.
    n : int

    Returns
    -------
    list of (k, 2) float64
    """
    pd = ld.planar
    P = np.concatenate(stroke_pieces)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
    t = np.linspace(0.0, s[-1], n + 2)[1:-1]
    seeds = np.column_stack([np.interp(t, s, P[:, 0]), np.interp(t, s, P[:, 1])])
    _, Rp, Rq = vertex_shading(pd, ld.z, ld.light, ld.model)
    flow = -np.column_stack([Rp, Rq])
    step = 0.5 * pd.h
    n_steps = int(np.ceil(reach / step))
    halves = []
    for sign in (1.0, -1.0):
        x = seeds.copy()
        alive = np.ones(len(x), bool)
        path = [x.copy()]
        for _ in range(n_steps):
            # Midpoint steps on the barycentric interpolant of the per-vertex direction.
            d = _unit(pd.locator.interpolate(flow, x))
            xm = x + 0.5 * step * sign * d
            d = _unit(pd.locator.interpolate(flow, xm))
            xn = x + step * sign * d
            face, _ = pd.locator.locate(xn)
            alive &= face >= 0
            x = np.where(alive[:, None], xn, x)
            path.append(x.copy())
            if not alive.any():
                break
        halves.append(np.stack(path, axis=1))  # (n, steps+1, 2)
    out = []
    for i in range(len(seeds)):
        fwd = _dedupe(halves[0][i])
        back = _dedupe(halves[1][i])[::-1]
        line = np.vstack([back[:-1], fwd])
        if len(line) > 1:
            out.append(line)
    return out


def _unit(d: np.ndarray) -> np.ndarray:
    return d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)


def _dedupe(P: np.ndarray) -> np.ndarray:
    keep = np.concatenate([[True], np.any(P[1:] != P[:-1], axis=1)])
    return P[keep]
