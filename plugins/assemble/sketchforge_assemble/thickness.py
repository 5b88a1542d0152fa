"""A part's full thickness at its junction (issue 34, point 5).

Why. Every layer is inflated with height 0 on its whole outline, the junction Γ_conn
included, so a limb thins to nothing at its junction. When the junction lies deep inside the
host that is hidden under the limb; when it lies close to the host's outline, the limb leaves
the host through a thin neck (the issue measured limbs whose depth just outside the host was a
fraction of their depth at mid-limb). A limb should meet its host at its own thickness, as if
it went on into the host: at the glued stretch of the junction the inflation's boundary
condition is the wrong one.

What. The part's heights are changed by a harmonic correction w so that u = z² + w meets the
same Poisson equation as z² inside the part, keeps u = 0 on the rest of the outline, and has no
flux across the glued junction (Neumann there) instead of u = 0:

    -L u = M s  on the interior and the glued junction's inner vertices,   u = 0 elsewhere,
    s = (-L z²) / M  (the part's own source, sculpted and faired as it is)

so w = u - z² is harmonic inside (L w = 0): away from the junction it dies out and the part
keeps its shape and its sculpt edits; at the junction it fills the part out to the thickness
the same inflation gives a limb that does not end there. z_full = √max(u, z²) (never thinner).
The junction's two end vertices stay at 0: the part's front and back meet there, at the ends
of the slit they are glued into.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from sketchforge.plugin_api import laplacian_and_mass

from .sheet import Sheet


def full_thickness(sheet: Sheet, host_region=None, operators=None) -> np.ndarray:
    """(n,) float64: the heights of the part ``sheet`` with its glued junction (``junction``,
    at least 2 vertices) at full thickness (module docstring); ``sheet.z`` where it has none.

    ``host_region`` (shapely polygon, optional): the host's region in the drawing plane. The
    correction then applies in full outside it and fades in over the part's stretch that lies
    over the host, from nothing at the junction to all of it at the host's outline
    (:func:`fade_over_host`): the part lands on the host at the junction as before (no step
    for the host to climb) and leaves the host's outline at its full thickness.
    ``operators``: the sheet's (L, M) (:func:`sketchforge.geometry.laplacian.laplacian_and_mass`),
    if already made (the depth solve uses the same).
    """
    j = sheet.junction
    if len(j) < 3:
        return sheet.z
    L, M = laplacian_and_mass(sheet.xy, sheet.F, checked=True) if operators is None else operators
    L, m = sp.csr_matrix(L), M.diagonal()
    fixed = np.zeros(sheet.n, bool)
    fixed[sheet.boundary] = True
    for hole in sheet.holes:
        fixed[hole] = True
    fixed[j[1:-1]] = False  # the glued stretch: no flux across it
    u0 = sheet.z ** 2
    inner = ~fixed
    inner[j] = False
    s = np.where(inner, -(L @ u0) / np.maximum(m, 1e-300), 0.0)
    # the junction's vertices take the mean source of their inner neighbours
    rows = L[j[1:-1]]
    nb = (rows.data != 0) & inner[rows.indices]
    owner = np.repeat(np.arange(len(j) - 2), np.diff(rows.indptr))
    cnt = np.bincount(owner[nb], minlength=len(j) - 2)
    tot = np.bincount(owner[nb], weights=s[rows.indices[nb]], minlength=len(j) - 2)
    fallback = float(np.median(s[inner])) if inner.any() else 0.0
    s[j[1:-1]] = np.where(cnt > 0, tot / np.maximum(cnt, 1), fallback)
    free = np.flatnonzero(~fixed)
    K = (-L)[free][:, free].tocsc()
    u = np.zeros(sheet.n)
    u[free] = _spd_solve(K, m[free] * s[free])
    if not np.all(np.isfinite(u)):
        return sheet.z
    w = np.maximum(u - u0, 0.0)
    if host_region is not None:
        w *= fade_over_host(sheet.xy, sheet.xy[j], host_region)
    return np.sqrt(u0 + w)


def _spd_solve(K: sp.csc_matrix, b: np.ndarray) -> np.ndarray:
    """K x = b for the symmetric positive definite K (the Dirichlet Laplacian block):
    libigl's sparse Cholesky (half SuperLU's time on a 700-vertex part), SuperLU if that
    fails; NaN when neither can (a part with no fixed vertex left)."""
    import igl

    try:
        x = np.asarray(igl.min_quad_with_fixed(K, -b[:, None], np.zeros(0, np.int64), np.zeros((0, 1)),
                                               sp.csc_matrix((0, K.shape[0])), np.zeros((0, 1)), True)).ravel()
        if x.shape == b.shape and np.all(np.isfinite(x)):
            return x
    except (RuntimeError, ValueError, TypeError):
        pass
    try:
        return splu(K, permc_spec="COLAMD").solve(b)
    except RuntimeError:
        return np.full(len(b), np.nan)


def fade_over_host(xy: np.ndarray, junction_xy: np.ndarray, host_region) -> np.ndarray:
    """(n,) float64 in [0, 1]: 0 on the junction, 1 on and outside the host's outline, and in
    between, over the host, a smoothstep of a / (a + b) with a the distance to the junction and
    b the distance to the host's outline (continuous in the points and the outlines)."""
    import shapely

    from .blend import distance_to

    a = distance_to(xy, junction_xy)
    pts = shapely.points(xy)
    inside = shapely.contains_xy(host_region, xy[:, 0], xy[:, 1])
    b = np.zeros(len(xy))
    if inside.any():
        b[inside] = shapely.distance(host_region.exterior, pts[inside]) if hasattr(host_region, "exterior") else \
            shapely.distance(host_region.boundary, pts[inside])
    t = np.where(inside, a / np.maximum(a + b, 1e-300), 1.0)
    return t * t * (3.0 - 2.0 * t)

