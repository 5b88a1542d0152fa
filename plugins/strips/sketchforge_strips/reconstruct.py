"""Heights at the vertices from the strips (thesis 4.6): a multiquadric RBF.

Support points: the strips' samples with their height change δz, and the untouched vertices
around the impacted region and on the rim with δz = 0 ("the vertices outside of M• are
seamlessly integrated into the set"); query points: the vertices of the impacted region. The
kernel is the thesis' multiquadric φ(r) = −sqrt(1 + (εr)²) with a constant term (the
multiquadric is conditionally positive definite of order 1, so a constant makes every local
system solvable; a linear term made those of queries whose nearest supports lie on one strip
singular),
solved on the ``neighbors`` nearest supports of each query (scipy's ``RBFInterpolator``: a
dense fit on 4k / 6k points took 1.3 / 3.8 s, with 64 neighbours 0.19 s).

The thesis gives λ_smooth = 0.05 without the kernel's scale. Here ε = 1 / (``scale`` · h):
the kernel's scale is tied to the edge length, so the same λ smooths the same way on any
layer (with ε = 1 in drawing units a multiquadric is nearly linear over a 0.03 edge and the
fit rings between strips). A sample's smoothing is λ divided by its weight (the rim mask
there), so samples where a strip is stopping fade out continuously instead of being dropped
at a threshold.
"""

from __future__ import annotations

import numpy as np

#: Weights below this drop the sample outright (its smoothing would be 1000 λ: no influence).
MIN_WEIGHT = 1e-3


def rbf_heights(points: np.ndarray, values: np.ndarray, weights: np.ndarray, queries: np.ndarray, h: float,
                scale: float, smoothing: float, neighbors: int) -> np.ndarray:
    """δz (q,) at ``queries`` (q, 2) from supports ``points`` (k, 2) with ``values`` (k,) and
    ``weights`` (k,) in [0, 1].

    Raises
    ------
    ValueError
        Fewer supports than the linear term needs (the caller treats it as nothing to do).
    """
    from scipy.interpolate import RBFInterpolator

    keep = weights >= MIN_WEIGHT
    P, z, w = points[keep], values[keep], weights[keep]
    if len(queries) == 0:
        return np.zeros(0)
    if len(P) < 4:
        raise ValueError("too few supports for the RBF")
    rbf = RBFInterpolator(
        P, z, neighbors=min(int(neighbors), len(P)), smoothing=smoothing / w, kernel="multiquadric",
        epsilon=1.0 / (scale * h), degree=0,
    )
    return np.asarray(rbf(queries), dtype=np.float64)
