"""Factor-once solver for symmetric positive-definite systems with fixed (Dirichlet) values.

Wraps libigl's ``min_quad_with_fixed`` (Eigen sparse Cholesky with an AMD ordering). On this
project's meshes it factors about twice as fast as ``scipy.sparse.linalg.splu`` and agrees with
it to ~1e-13 (measured-facts notes; benchmarks/bench_inflate.py); the factorisation is kept so that
several right-hand sides (inflation, re-fairing after an edit) cost one back-substitution each.
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp

from sketchforge.errors import SolverError
from sketchforge.geometry import guard


class DirichletSolver:
    """Solve ``A x = b`` on the free vertices with ``x = x_fixed`` on the fixed ones.

    Parameters
    ----------
    A : (n, n) sparse float64
        Symmetric; positive definite once the fixed rows and columns are removed.
    fixed : (k,) int64
        Indices of the vertices whose values are prescribed.
    what : str
        Names the system in error messages.

    Raises
    ------
    GeometryError
        From :func:`guard.sparse_system`: A not square or not finite, a fixed index out of
        range, a free row of zeros (igl would read out of bounds or factor a singular matrix).
    SolverError
        The free block is not positive definite (the factorisation failed).

    Notes
    -----
    Solves the free block ``A_ff x_f = b_f - A_fk x_k``; the rows of ``b`` at fixed vertices
    are ignored.
    """

    def __init__(self, A, fixed, what: str = "the linear system") -> None:
        A, self.fixed = guard.sparse_system(A, what, fixed=fixed)
        n = A.shape[0]
        self.n = n
        self.what = what
        self.n_free = n - len(self.fixed)
        self._data = None
        if self.n_free > 0:
            self._data = igl.min_quad_with_fixed_data()
            # igl minimises ½ xᵀ A x + xᵀ B, hence the sign flip of b in solve().
            try:
                igl.min_quad_with_fixed_precompute(A, self.fixed, sp.csc_matrix((0, n)), True, self._data)
            except RuntimeError:
                raise SolverError(
                    f"{what} could not be factorised (it is not positive definite on the free vertices)"
                ) from None

    def solve(self, b, x_fixed=None) -> np.ndarray:
        """
        Parameters
        ----------
        b : (n,) float64
            Right-hand side (its fixed rows are ignored).
        x_fixed : (k,) float64, optional
            Values at the fixed vertices (in the sorted order of ``self.fixed``); default 0.

        Returns
        -------
        x : (n,) float64, with the fixed values copied exactly.
        """
        b = guard.finite(b, (self.n,), f"the right-hand side of {self.what}")
        k = len(self.fixed)
        Y = np.zeros((k, 1)) if x_fixed is None else guard.finite(x_fixed, (k, 1), f"the fixed values of {self.what}")
        if self._data is None:
            x = np.zeros(self.n)
            x[self.fixed] = Y[:, 0]
            return x
        x = igl.min_quad_with_fixed_solve(self._data, -b.reshape(-1, 1), Y, np.zeros((0, 1)))[:, 0]
        x = np.array(x, dtype=np.float64)
        x[self.fixed] = Y[:, 0]  # exact, not just up to the solver's rounding
        return x
