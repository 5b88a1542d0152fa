"""Heights from the new shading (thesis 4.5–4.6): the shape-from-shading equation
R(p, q) = E solved for the change of height δz on the layer's own vertices.

E_v(z) = R(p(z), q(z))_v is the shading the person sees, with the slopes of the layer's
display normals (:func:`sketchforge.geometry.heightfield.slopes_from_heights`: the
area-weighted gradient of w = z² over 2z, smooth up to the rim). Gauss–Newton on

    Σ_v m_v w_v (E_v(z + δz) − Ê_v)²  +  β h ∫_stroke (E(z + δz) − c)² ds
                                    +  α h² δzᵀ L M⁻¹ L δz,     δz = 0 outside U,

where Ê is the target shading (old shading plus the interpolated change), w the data weights
(1 near the stroke, fading into the surrounding ring and the rim margin), the line integral
pins the isophote to the stroke itself (β = ``stroke_weight``: with it, the corpus median
distance after an edit went from 0.6 to 0.35 edge lengths) and U the vertices allowed to
move. Each step solves the linearised equation

    R_p ∂δz/∂x + R_q ∂δz/∂y = Ê − E(z)

— the characteristic (transport) equation of 4.5: its characteristics are the strips'
(x, y) paths, dx/ds = −R_p, dy/ds = −R_q — by least squares on the mesh instead of integrating
strips one by one. What this changes, measured on the failure cases of the strip pipeline:

- the fit is to the shading the person sees, so the isophote lands where drawn to within a
  fraction of an edge length instead of being lost in the strip → RBF → mesh round trip;
- the change vanishes smoothly (C¹, through the squared-Laplacian term) at the edge of U,
  so an edit leaves no seam for the next one to trip over (the null-edit drift of 6% after
  10 edits came from those seams);
- there is no seeding, no strip stopping and no region membership to flip on round-off;
- an edit stays local: SfS fixes heights only up to a function constant along the
  characteristics, so the thesis carried the change downstream to the rim; here the
  squared-Laplacian term returns it to zero within one ring around the band, which is the
  smallest change of shape that puts the isophote where it was drawn.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from sketchforge.plugin_api import DirichletSolver, SlopeLinearisation, SolverError, evaluate_pq

from .layerdata import LayerData

#: Gauss–Newton steps. Measured on corpus edits, the steps shrink ~10x each: the fourth is
#: 2e-5 of the peak (median; 4e-3 at worst), the fifth would be 2e-6. A fixed count, not a
#: tolerance, so that the number of steps never flips on round-off.
GN_STEPS = 4
#: Conjugate-gradient iterations per Gauss–Newton step after the first. Reusing the first
#: step's factorisation as it is (a chord step) oscillated on ~5% of the corpus edits (steps of
#: 30% of the peak that never shrank); refactoring every step cost 20 ms per step at 5k
#: vertices. Preconditioned with it, CG reaches the new step to ~1e-3 in a few iterations.
PCG_ITERATIONS = 4


def _pcg(apply_A, b: np.ndarray, precondition, iterations: int) -> np.ndarray:
    """``iterations`` steps of preconditioned conjugate gradients for A x = b from x = 0
    (A symmetric positive definite, given as a function)."""
    x = np.zeros_like(b)
    r = b.copy()
    zr = precondition(r)
    p = zr.copy()
    rz = float(r @ zr)
    for _ in range(iterations):
        if rz <= 0.0:
            break
        Ap = apply_A(p)
        alpha = rz / float(p @ Ap)
        x += alpha * p
        r -= alpha * Ap
        zr = precondition(r)
        rz_new = float(r @ zr)
        p = zr + (rz_new / rz) * p
        rz = rz_new
    return x


def solve_heights(
    ld: LayerData,
    target: np.ndarray,
    U: np.ndarray,
    w: np.ndarray,
    alpha: float,
    steps: int = GN_STEPS,
    stroke_rows=None,
    c: float = 0.0,
    stroke_weight: float = 0.0,
) -> np.ndarray:
    """The height change δz (n,) that makes the layer's shading follow ``target`` on U.

    Parameters
    ----------
    ld : LayerData
    target : (n,) float64
        Ê, the shading wanted (read on U).
    U : (n,) bool
        Vertices that may move (never contour vertices).
    w : (n,) float64
        Data weights in [0, 1] (read on U).
    alpha : float
        Smoothness weight, in units of h² (scale-free).
    steps : int
        Gauss–Newton steps.
    stroke_rows : ((k, n) sparse float64, (k,) float64) or None
        Barycentric rows of the stroke's quadrature points and their weights: adds
        ``stroke_weight · h · Σ_k w_k (E(P_k) − c)²``, pinning the isophote to the stroke.
    c : float or (k,) float64
        The isovalue (or each stroke sample's wanted shading: a joint edit of several
        isophotes).
    stroke_weight : float

    Returns
    -------
    (n,) float64
        δz, exactly 0 outside U.
    """
    pd = ld.planar
    u = np.nonzero(U)[0]
    dz = np.zeros(len(pd.V2))
    if len(u) == 0:
        return dz
    # Only the rows whose slopes depend on U (U and its one-ring) change: shading is evaluated
    # there alone, and the stroke's barycentric rows are restricted to them.
    rows = np.unique(np.concatenate([pd.Gp[:, u].tocoo().row, u]))
    slopes = SlopeLinearisation(pd.Gp, pd.Gq, rows, u)
    in_u = np.searchsorted(rows, u)  # positions of U's vertices among the rows
    Wd = pd.mass[u] * w[u]
    if stroke_rows is not None:
        B_full, ws = stroke_rows
        fixed_E = ld.E.copy()
        fixed_E[rows] = 0.0
        B_rest = B_full @ fixed_E  # what the vertices whose shading cannot change contribute
        B = B_full[:, rows]
        Ws = stroke_weight * pd.h * ws
    reg = alpha * pd.h**2 * pd.Q[u][:, u]
    x = np.zeros(len(u))
    z = ld.z.copy()
    solver = None
    for _step in range(steps):
        z[u] = ld.z[u] + x
        # The slopes are not linear in z (p = Gp z² / 2z): linearised at this surface.
        lin = slopes.at(z)
        E, Rp, Rq = evaluate_pq(ld.model, lin.p, lin.q, ld.light)

        # J = diag(R_p) Jp + diag(R_q) Jq (rows x U) is applied, never formed: J v gathers
        # slope changes on the rows, Jᵀ y pulls row values back through the slope Jacobians.
        def J(v, Rp=Rp, Rq=Rq, lin=lin):
            dp, dq = lin.apply(v)
            return Rp * dp + Rq * dq

        def Jt(y, Rp=Rp, Rq=Rq, lin=lin):
            return lin.apply_t(Rp * y, Rq * y)

        def weigh(y):  # rows -> rows: the data and stroke weights of the normal equations
            t = np.zeros(len(rows))
            t[in_u] = Wd * y[in_u]
            if stroke_rows is not None:
                t += B.T @ (Ws * (B @ y))
            return t

        res = np.zeros(len(rows))
        res[in_u] = Wd * (E[in_u] - target[u])
        if stroke_rows is not None:
            res += B.T @ (Ws * (B @ E + B_rest - c))
        g = Jt(res) + reg @ x
        if solver is None:
            Ju_p, Ju_q = lin.matrices()
            Jall = (sp.diags(Rp) @ Ju_p + sp.diags(Rq) @ Ju_q).tocsr()
            J0 = Jall[in_u]
            H = J0.T @ sp.diags(Wd) @ J0 + reg
            if stroke_rows is not None:
                Js = B @ Jall
                H = H + Js.T @ sp.diags(Ws) @ Js
            # DirichletSolver checks the system (guard.sparse_system) before libigl factors it.
            solver = DirichletSolver(H.tocsc(), np.zeros(0, np.int64), "the height solve")
            x = x + solver.solve(-g)
        else:
            # Later steps: the Gauss–Newton system at the current surface, by conjugate
            # gradients preconditioned with the first step's factorisation (close to it, so a
            # few iterations do; a fixed count keeps the result continuous in the input).
            x = x + _pcg(lambda v: Jt(weigh(J(v))) + reg @ v, -g, solver.solve, PCG_ITERATIONS)
    if not np.isfinite(x).all():
        raise SolverError("the height solve produced non-finite values; the layer was left unchanged")
    dz[u] = x
    return dz
