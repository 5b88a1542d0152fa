"""Heights at the vertices from the strips (thesis 4.6): a multiquadric RBF, solved locally and
in batches.

Support points: the strips' samples with their height change δz, and the untouched vertices
around the impacted region with δz = 0 ("the vertices outside of M• are seamlessly integrated
into the set"); query points: the vertices of the impacted region. The kernel is the thesis'
multiquadric φ(r) = −sqrt(1 + (εr)²) with a constant term (the multiquadric is conditionally
positive definite of order 1, so a constant makes every local system solvable; a linear term
made those of queries whose nearest supports lie on one strip singular).

Each query is fitted on its ``neighbors`` nearest supports (a dense fit on 4k / 6k points took
1.3 / 3.8 s). The first release called scipy's ``RBFInterpolator``, which solves one small
system per distinct neighbourhood in a Python loop (43k solves, 12.5% of an edit at 76k
vertices); here the systems are built and solved together, a chunk of queries per LAPACK
call.

The thesis gives λ_smooth = 0.05 without the kernel's scale. Here ε = 1 / (``scale`` · h):
the kernel's scale is tied to the edge length, so the same λ smooths the same way on any
layer (with ε = 1 in drawing units a multiquadric is nearly linear over a 0.03 edge and the
fit rings between strips). A sample's smoothing is λ divided by its weight (the rim mask
there), so samples where a strip is stopping fade out continuously instead of being dropped
at a threshold.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

#: Weights below this drop the sample outright (its smoothing would be 1000 λ: no influence).
MIN_WEIGHT = 1e-3
#: Matrix entries of the local systems solved in one batched call (bounds the memory: 2048
#: systems of 33 × 33, 18 MB).
CHUNK_ENTRIES = 2048 * 33 * 33


def rbf_weights(points: np.ndarray, weights: np.ndarray, queries: np.ndarray, h: float, scale: float,
                smoothing: float, neighbors: int):
    """The local multiquadric fits of supports ``points`` (k, 2) with ``weights`` (k,) in
    [0, 1] at ``queries`` (q, 2), as a function: values (k,) at the supports ↦ values (q,) at
    the queries. Linear in the values, so each query's system is solved once, for its row of
    interpolation weights (Aᵀ y = [φ(|x_q − x_j|); 1]), and any number of value vectors is
    then a gather and a dot product.

    Raises
    ------
    ValueError
        Fewer supports than a local fit needs (the caller treats it as nothing to do).
    numpy.linalg.LinAlgError
        A singular local system (duplicate supports with no smoothing).
    """
    keep = np.nonzero(weights >= MIN_WEIGHT)[0]
    P, w = points[keep], weights[keep]
    if len(queries) == 0:
        return lambda values: np.zeros(0)
    if len(P) < 4:
        raise ValueError("too few supports for the RBF")
    k = min(int(neighbors), len(P))
    eps = 1.0 / (scale * h)
    _, idx = cKDTree(P).query(queries, k=k)
    idx = np.sort(idx.reshape(len(queries), k), axis=1)  # the same neighbourhood, the same system
    rows = np.empty((len(queries), k))
    lam = smoothing / w
    chunk = max(16, CHUNK_ENTRIES // ((k + 1) * (k + 1)))
    for s in range(0, len(queries), chunk):
        nb = idx[s:s + chunk]
        c = len(nb)
        # Coordinates relative to the query, in units of 1/ε: small numbers, so the squared
        # distances from the Gram matrix lose nothing to cancellation.
        Xr = (P[nb] - queries[s:s + chunk, None, :]) * eps  # (c, k, 2)
        sq = np.einsum("ckd,ckd->ck", Xr, Xr)
        # In place on a contiguous block (on the strided view of A it took 4× as long).
        K = np.matmul(Xr, Xr.transpose(0, 2, 1))
        K *= -2.0
        K += sq[:, :, None]
        K += sq[:, None, :]
        np.maximum(K, 0.0, out=K)
        K += 1.0
        np.sqrt(K, out=K)
        np.negative(K, out=K)
        K[:, np.arange(k), np.arange(k)] += lam[nb]
        A = np.empty((c, k + 1, k + 1))
        A[:, :k, :k] = K
        A[:, :k, k] = 1.0
        A[:, k, :k] = 1.0
        A[:, k, k] = 0.0
        b = np.empty((c, k + 1, 1))
        b[:, :k, 0] = -np.sqrt(1.0 + sq)
        b[:, k, 0] = 1.0
        # A is symmetric: Aᵀ y = b gives the weights of the k support values.
        rows[s:s + chunk] = np.linalg.solve(A, b)[:, :k, 0]
    sup = keep[idx]

    def apply(values: np.ndarray) -> np.ndarray:
        z = np.asarray(values, np.float64)[sup]
        # Within the range of its own supports: a query off the end of a line of supports (a
        # strip running along the rim margin, the margin's vertices beyond it) is
        # extrapolated, and a multiquadric fitted on one line overshoots across it (measured:
        # a patch of the opposite sign, a fold, beside the last strip of a sweep).
        return np.clip(np.einsum("qk,qk->q", rows, z), z.min(axis=1), z.max(axis=1))

    return apply
