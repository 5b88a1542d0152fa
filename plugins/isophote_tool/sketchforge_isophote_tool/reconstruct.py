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

#: Largest fraction of the old rise from ∂Ω* that the height change may flatten (see below).
RISE_LIMIT = 0.5


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
        pts = shapely.points(V2[inM])
        d = shapely.distance(pts, ld.outline.exterior)
        w = np.clip((d - margin) / margin, 0.0, 1.0)
        w = w * w * (3 - 2 * w)
        dz = w * (znew - z_old[inM])
        # Slope-limited fade. Strips that crossed the edited band can reach the rim with heights
        # far from the frozen rim margin's (measured on the "m", c = 0 moved 0.1 toward the dark
        # side: strips running along the top rim 0.1 (20% of the peak) below it). The fade alone
        # packs that mismatch δ into one margin and adds a slope up to 1.5·δ/margin ≈ 2, more
        # than the surface's own slope toward the rim (≈ 1.4 there): the wall reverses, its
        # shading drops from 0.57 to -0.4 and a new c = 0 loop appears far from the stroke.
        # A blend of two surfaces lit from the same side stays lit (n·l > 0 is a half-plane in
        # (p, q) for an in-plane light); only that δ·∇w term can flip it. So where the change
        # flattens the old rise from ∂Ω* (rise = z_old - z_old at the nearest point of ∂Ω*),
        # it is capped at RISE_LIMIT · |rise|: the old slope toward the rim keeps at least
        # about half its value and the fade widens by itself where the mismatch is large,
        # nowhere else (thesis 4.3: small variations near ∂Ω have a large impact).
        Q = shapely.get_coordinates(shapely.shortest_line(pts, ld.omega_star(margin).boundary))[1::2]
        rise = z_old[inM] - ld.locator.interpolate(z_old, Q)
        lim = RISE_LIMIT * np.abs(rise)
        dz = np.where(dz * rise < 0, np.clip(dz, -lim, lim), dz)
        znew = z_old[inM] + dz
    # Strips can dip below the drawing plane (thesis ch. 5): cap at 0.
    z[inM] = np.maximum(znew, 0.0)
    return z, inM
