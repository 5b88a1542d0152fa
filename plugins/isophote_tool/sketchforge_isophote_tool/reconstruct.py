"""Shape reconstruction (thesis 4.6): heights of M•'s vertices from the strips by RBF.

Multiquadric kernel on local support (scipy ``RBFInterpolator`` with ``neighbors``), a linear
polynomial term and smoothing λ (the thesis' 0.05). scipy's multiquadric is
-sqrt(1 + (ε r)²); we set ε = 1 / (kernel_scale · h) with h the mean edge length, so the kernel
is scaled to the mesh rather than to the drawing units (with ε = 1 and neighbours a few edge
lengths apart the kernel is nearly flat and the fit is ill-conditioned).

Support: strip samples inside M•, thinned to about one per edge length, plus a ring of
untouched vertices around M• (their current heights; contour vertices at 0).
"""

from __future__ import annotations

import numpy as np
import shapely
from scipy.interpolate import RBFInterpolator

from sketchforge.errors import SolverError

from .layerdata import LayerData


def thin(P: np.ndarray, cell: float) -> np.ndarray:
    """Indices of a subset of points P (k, 2), at most one per square cell (the first one)."""
    key = np.floor(P / cell).astype(np.int64)
    _, first = np.unique(key, axis=0, return_index=True)
    return np.sort(first)


def reconstruct_heights(
    ld: LayerData,
    M,
    strips: list[np.ndarray],
    smoothing: float = 0.05,
    kernel_scale: float = 4.0,
    neighbors: int = 40,
    ring: float = 3.0,
    margin: float = 0.0,
):
    """New heights for the vertices inside M•.

    Parameters
    ----------
    ld : LayerData
    M : shapely Polygon
        The impacted region M•.
    strips : list of (j, 5) float64
        Integrated strips (x, y, p, q, z).
    smoothing : float
        λ of (K + λI) a = z (4.6.1).
    kernel_scale : float
        Kernel scale in edge lengths (ε = 1 / (kernel_scale · h)).
    neighbors : int
        Local support size.
    ring : float
        Width, in edge lengths, of the ring of untouched vertices used as support.

    Returns
    -------
    z : (n,) float64
        All heights: vertices outside M• and contour vertices keep theirs exactly.
    inM : (n,) bool
        Vertices whose height was recomputed.
    """
    h = ld.h
    V2, z_old = ld.V2, ld.z
    inM = shapely.contains_xy(M, V2[:, 0], V2[:, 1]) & ~ld.is_contour
    z = z_old.copy()
    if not inM.any():
        return z, inM
    Mr = M.buffer(ring * h)
    ringv = shapely.contains_xy(Mr, V2[:, 0], V2[:, 1]) & ~inM
    S = np.concatenate(strips) if strips else np.zeros((0, 5))
    if len(S):
        S = S[shapely.contains_xy(M, S[:, 0], S[:, 1])]
        S = S[thin(S[:, :2], 0.75 * h)]
    P = np.concatenate([S[:, :2], V2[ringv]])
    vals = np.concatenate([S[:, 4], z_old[ringv]])
    if len(P) < 4:
        return z, np.zeros_like(inM)
    rbf = RBFInterpolator(
        P,
        vals,
        neighbors=min(neighbors, len(P)),
        kernel="multiquadric",
        epsilon=1.0 / (kernel_scale * h),
        smoothing=smoothing,
        degree=1,
    )
    znew = rbf(V2[inM])
    if not np.isfinite(znew).all():
        raise SolverError("the height reconstruction produced non-finite values")
    if margin > 0:
        d = shapely.distance(shapely.points(V2[inM]), ld.outline.exterior)
        w = np.clip((d - margin) / margin, 0.0, 1.0)
        w = w * w * (3 - 2 * w)
        znew = z_old[inM] + w * (znew - z_old[inM])
    # Strips can dip below the drawing plane (thesis ch. 5): cap at 0.
    z[inM] = np.maximum(znew, 0.0)
    return z, inM
