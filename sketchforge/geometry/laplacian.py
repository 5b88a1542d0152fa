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


def as_faces(F) -> np.ndarray:
    """F as a C-contiguous (m, 3) int64 array (the only index dtype the igl bindings accept)."""
    F = np.ascontiguousarray(F, dtype=np.int64)
    if F.ndim != 2 or F.shape[1] != 3:
        raise ValueError(f"F must be (m, 3), got shape {F.shape}")
    return F


def as_vertices(V) -> np.ndarray:
    """V as a C-contiguous (n, 3) float64 array; a planar (n, 2) V gets z = 0."""
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] not in (2, 3):
        raise ValueError(f"V must be (n, 2) or (n, 3), got shape {V.shape}")
    if V.shape[1] == 2:
        V = np.column_stack([V, np.zeros(len(V))])
    return np.ascontiguousarray(V)


def _checked(V, F, what: str) -> tuple[np.ndarray, np.ndarray]:
    V, F = guard.mesh(V, F, what)
    return as_vertices(V), F


def cotangent_laplacian(V, F, what: str = "the mesh") -> sp.csc_matrix:
    """Cotangent Laplacian.

    Parameters
    ----------
    V : (n, 2) or (n, 3) float64
    F : (m, 3) int64
    what : str
        Names the mesh in a :class:`~sketchforge.errors.GeometryError` (see
        :func:`guard.mesh`).

    Returns
    -------
    L : (n, n) scipy.sparse.csc_matrix float64
        Symmetric, negative semi-definite (libigl's sign: L_ij = ½(cot α_ij + cot β_ij) off the
        diagonal, rows sum to 0). Not divided by the mass: it is the stiffness matrix of
        piecewise-linear finite elements.
    """
    return sp.csc_matrix(igl.cotmatrix(*_checked(V, F, what)))


def mass_matrix(V, F, what: str = "the mesh") -> sp.csc_matrix:
    """Lumped (Voronoi-hybrid) mass matrix.

    Parameters
    ----------
    V : (n, 2) or (n, 3) float64
    F : (m, 3) int64
    what : str

    Returns
    -------
    M : (n, n) scipy.sparse.csc_matrix float64
        Diagonal, positive for every vertex used by a face; the diagonal sums to the mesh area.
    """
    return sp.csc_matrix(igl.massmatrix(*_checked(V, F, what), igl.MASSMATRIX_TYPE_VORONOI))


def laplacian_and_mass(V, F, what: str = "the mesh") -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """``(cotangent_laplacian(V, F), mass_matrix(V, F))`` with a single check and coercion."""
    V3, F = _checked(V, F, what)
    return (sp.csc_matrix(igl.cotmatrix(V3, F)),
            sp.csc_matrix(igl.massmatrix(V3, F, igl.MASSMATRIX_TYPE_VORONOI)))
