"""Cotangent Laplacian and lumped mass matrix of a triangle mesh (libigl), with F coerced once.

libigl's bindings reject index arrays of another dtype and silently copy non-contiguous ones,
and read out of bounds (a segfault) on a face index out of range, so every call goes through
:func:`sketchforge.geometry.guard.mesh` here (finite V, int64 C-contiguous F in range, no
zero-area triangle) instead of casting at each call site.
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp

from sketchforge.geometry import guard


def _checked(V, F, what: str) -> tuple[np.ndarray, np.ndarray]:
    """(V as (n, 3) float64 C-contiguous, F (m, 3) int64 C-contiguous), after guard.mesh."""
    return _xyz(*guard.mesh(V, F, what))


def _xyz(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # igl's bindings want (n, 3): a planar mesh gets z = 0.
    if V.shape[1] == 2:
        V = np.ascontiguousarray(np.column_stack([V, np.zeros(len(V))]))
    return V, F


def laplacian_and_mass(V, F, what: str = "the mesh", *, checked: bool = False) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """Cotangent Laplacian L and lumped (Voronoi-hybrid) mass matrix M, one check and coercion.

    Parameters
    ----------
    V : (n, 2) or (n, 3) float64
    F : (m, 3) int64
    what : str
        Names the mesh in a :class:`~sketchforge.errors.GeometryError` (see :func:`guard.mesh`).

    Returns
    -------
    L : (n, n) scipy.sparse.csc_matrix float64
        Symmetric, negative semi-definite (libigl's sign: L_ij = ½(cot α_ij + cot β_ij) off the
        diagonal, rows sum to 0). Not divided by the mass: the stiffness matrix of
        piecewise-linear finite elements.
    M : (n, n) scipy.sparse.csc_matrix float64
        Diagonal, positive for every vertex used by a face and 0 for one no face uses; the
        diagonal sums to the mesh area.

    ``checked=True``: V and F are exactly the arrays :func:`guard.mesh` returned for this
    mesh (float64 and int64, C-contiguous, F in range, no zero-area triangle where V lives),
    so they are not checked again; anything else must go through the check.
    """
    V3, F = _xyz(V, F) if checked else _checked(V, F, what)
    L = sp.csc_matrix(igl.cotmatrix(V3, F))
    M = sp.csc_matrix(igl.massmatrix(V3, F, igl.MASSMATRIX_TYPE_VORONOI))
    # libigl sizes the mass matrix by the largest index in F, not by V: vertices after the last
    # one a face uses would be missing, and L and M would not fit together. They have no mass.
    if M.shape != L.shape:
        M.resize(L.shape)
    return L, M
