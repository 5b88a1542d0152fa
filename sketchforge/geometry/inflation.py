"""Inflation of a flat mesh into a height field (Sýkora et al. 2014, Monster Mash; thesis 3.2).

Solve -Δu = 4 with u = 0 on the boundary, then z = inflation · sqrt(u). Discretised with
finite elements: (-L) u = 4 M 1. The mass matrix on the right-hand side is what makes the
result independent of the resolution (the thesis' ``L z² = k`` with a constant k per vertex
would scale with the triangle size). The constant 4 is chosen so that a disk of radius R gives
exactly the hemisphere z = sqrt(R² - r²) at inflation 1 (u = (R² - r²) for -Δu = 4 in 2D);
other inflations give the ellipsoid of revolution with height inflation·R.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sketchforge.geometry.dirichlet import DirichletSolver
from sketchforge.geometry.laplacian import laplacian_and_mass


def inflation_potential(L, M, boundary) -> np.ndarray:
    """u = z² before scaling: the solution of (-L) u = 4 M 1 with u = 0 on the boundary.

    Parameters
    ----------
    L : (n, n) sparse float64
        Cotangent Laplacian of the planar mesh (negative semi-definite).
    M : (n, n) sparse float64
        Lumped mass matrix.
    boundary : (k,) int64
        Vertices held at u = 0.

    Returns
    -------
    u : (n,) float64, exactly 0 on the boundary; may dip below 0 by rounding where the mesh
        has obtuse triangles (no discrete maximum principle), callers clamp.
    """
    return DirichletSolver(-sp.csc_matrix(L), boundary).solve(4.0 * np.asarray(M.diagonal(), dtype=np.float64))


def inflate_heights(V, F, boundary, inflation: float = 1.0, L=None, M=None) -> np.ndarray:
    """Heights of the inflated blob.

    Parameters
    ----------
    V : (n, 2) or (n, 3) float64
        The planar mesh (any z is ignored by the caller's choice of L, M: pass them to reuse).
    F : (m, 3) int64
    boundary : (k,) int64
        Vertices with z = 0.
    inflation : float
        Height scale; 1 makes a disk a hemisphere.
    L, M : (n, n) sparse float64, optional
        Precomputed cotangent Laplacian and mass matrix of the planar mesh.

    Returns
    -------
    z : (n,) float64, z >= 0, exactly 0 on the boundary.
    """
    if L is None or M is None:
        V = np.asarray(V, dtype=np.float64)
        L, M = laplacian_and_mass(V[:, :2], F)
    u = inflation_potential(L, M, boundary)
    return float(inflation) * np.sqrt(np.maximum(u, 0.0))
