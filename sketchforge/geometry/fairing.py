"""Fairing of a height field with the squared-Laplacian energy (thesis 4.2, Weinkauf et al.).

Minimise  α·E(z) + (1-α)·‖z - z0‖²_M  with  E(z) = zᵀ Lᵀ M⁻¹ L z  (4.2.7), z fixed on the
boundary. Setting the gradient to zero gives

    (α Lᵀ M⁻¹ L + (1-α) M) z = (1-α) M z0.

Thesis erratum: 4.2.2 prints the linear term without the factor 2; minimising it as printed
gives exactly half the height. We solve the normal equation above instead.

Units of α: E is invariant under scaling the drawing while ‖z - z0‖²_M scales with length⁴, so
a bare α means nothing until a length unit is fixed (the thesis' α = 2·10⁻⁵ happens to be in
units where its shapes measured ~1, and on a unit disk it pulls the height at r = 0.9 down to
~58% of the ellipsoid). Here the energy is evaluated with lengths measured in ``length_unit``:
dividing the objective by (1-α)/length_unit⁴ gives the equivalent

    (β Lᵀ M⁻¹ L + M) z = M z0,   β = α/(1-α) · length_unit⁴,

so β^(1/4) is the width over which the rim is smoothed. The inflate plugin picks length_unit
from the shape's size, which makes the faired shape independent of scale and resolution.

We keep every row of L in the energy (boundary rows included). The boundary rows penalise the
Laplacian at the rim, where sqrt-inflation has an infinite slope; dropping them would leave the
rim almost as steep as before.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sketchforge.geometry.dirichlet import DirichletSolver


def squared_laplacian_matrix(L, M) -> sp.csc_matrix:
    """Lᵀ M⁻¹ L, the matrix of the discrete squared-Laplacian energy (4.2.7).

    Parameters
    ----------
    L : (n, n) sparse float64, cotangent Laplacian.
    M : (n, n) sparse float64, lumped (diagonal) mass matrix.

    Returns
    -------
    K : (n, n) scipy.sparse.csc_matrix float64, symmetric positive semi-definite.
    """
    L = sp.csc_matrix(L)
    m = np.asarray(M.diagonal(), dtype=np.float64)
    # Vertices used by no face have zero mass and a zero row in L: keep them out of M⁻¹.
    inv = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)
    return sp.csc_matrix(L.T @ sp.diags(inv) @ L)


def fairing_weight(alpha: float, length_unit: float = 1.0) -> float:
    """β = α/(1-α) · length_unit⁴ (see the module docstring). α in [0, 1)."""
    alpha = float(alpha)
    if not 0.0 <= alpha < 1.0:
        raise ValueError(f"alpha must be in [0, 1), got {alpha}")
    return alpha / (1.0 - alpha) * float(length_unit) ** 4


class FairingSolver:
    """Factor the fairing system of one mesh once; fair any number of height fields with it.

    Parameters
    ----------
    L : (n, n) sparse float64
        Cotangent Laplacian of the planar mesh.
    M : (n, n) sparse float64
        Lumped mass matrix of the planar mesh.
    boundary : (k,) int64
        Vertices whose height is kept (z = z0 there, 0 for an inflated blob).
    alpha : float
        Weight α in [0, 1); 0 returns z0 unchanged (bit for bit).
    length_unit : float
        Length in which E is measured (drawing units), see the module docstring.
    """

    def __init__(self, L, M, boundary, alpha: float, length_unit: float = 1.0) -> None:
        self.beta = fairing_weight(alpha, length_unit)
        self._M = sp.csc_matrix(M)
        self._solver = None
        if self.beta > 0.0:
            Q = self.beta * squared_laplacian_matrix(L, M) + self._M
            self._solver = DirichletSolver(Q, boundary)

    def solve(self, z0) -> np.ndarray:
        """
        Parameters
        ----------
        z0 : (n,) float64, the heights to fair.

        Returns
        -------
        z : (n,) float64; z = z0 on the boundary; a copy of z0 when α = 0.
        """
        z0 = np.asarray(z0, dtype=np.float64)
        if self._solver is None:
            return z0.copy()
        fixed_values = z0[self._solver.fixed]
        return self._solver.solve(self._M @ z0, fixed_values)


def fair_heights(L, M, boundary, z0, alpha: float, length_unit: float = 1.0) -> np.ndarray:
    """One-shot :class:`FairingSolver` ``(L, M, boundary, alpha, length_unit).solve(z0)``.

    Returns
    -------
    z : (n,) float64
    """
    return FairingSolver(L, M, boundary, alpha, length_unit).solve(z0)
