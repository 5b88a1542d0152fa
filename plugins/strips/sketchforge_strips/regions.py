"""Where the edit acts (thesis 4.3): seeds on the stroke, the strips' sweep S•, the bounded
band B•* and the impacted region M•.

4.3 defines S• as the region covered by the strips that cross the redrawn isophote Γ_iso,
B• = band ∩ S•, B•* = B• without the rim margin Ω*, and M• as the part of S• the change
reaches downstream. The thesis finds S• by seeding strips on the contour where they flow in
(−∇R·n > 0) and keeping those that cross the stroke; measured on the first release, those
strips slide along the rim (at the seeds |cos(flow, n_in)| was 0.05–0.08), leave most of Ω*
uncovered (20% on one letter) and the inflow sign flipped 50–114 times along a contour, so
whole strokes crossed no strip, and strip counts flipped on round-off. Here, as the failure
analysis proposed (2b), the strips are seeded on the stroke itself and traced both ways until
they reach the rim margin: their sweep is S• by definition; the upstream end of each lies on
the contour's side (its initial condition the surface before the edit: δz = 0), which is the
thesis' initial curve on ∂Ω.

Seeds are spread by flux, not evenly along the stroke: a stroke crossing the flow obliquely
gets its strips at the same spacing across the flow, and one running along the flow (a
characteristic initial curve, which 3.1.5 excludes) gets few. The stroke is extended by one
band radius at each end (along its end tangents), because the shading may change up to one
band radius beyond its ends; without it the strips through the stroke's ends would bound S•
right where E = c is asked for, and the change would stop in a cliff there.
"""

from __future__ import annotations

import numpy as np
import shapely


def extend(piece: np.ndarray, length: float) -> np.ndarray:
    """The polyline ``piece`` (k, 2) extended by ``length`` along its end tangents."""
    if len(piece) < 2 or length <= 0:
        return piece
    a = piece[0] - piece[min(2, len(piece) - 1)]
    b = piece[-1] - piece[max(-3, -len(piece))]
    a /= max(np.linalg.norm(a), 1e-300)
    b /= max(np.linalg.norm(b), 1e-300)
    t = np.linspace(0.0, length, 9)[1:, None]
    return np.concatenate([(piece[0] + t * a)[::-1], piece, piece[-1] + t * b])


def flux_seeds(curve: np.ndarray, flow_at, spacing: float, sample: float) -> np.ndarray:
    """Seeds (j, 2) along ``curve`` (k, 2) every ``spacing`` of flux: at equal steps of
    ∫ |t × f| ds, t the unit tangent, f the unit flow direction (``flow_at(P) -> (k, 2)``),
    i.e. at equal distances across the flow. The cumulative flux is continuous in the curve,
    so the seeds move continuously with it (only their count is a whole number)."""
    seg = np.diff(curve, axis=0)
    L = np.linalg.norm(seg, axis=1)
    keep = L > 0
    if not keep.any():
        return np.zeros((0, 2))
    # Sample the flux finely (``sample`` apart) for the quadrature of the cumulative.
    s = np.concatenate([[0.0], np.cumsum(L)])
    u = np.linspace(0.0, s[-1], max(int(np.ceil(s[-1] / sample)), 1) + 1)
    P = np.column_stack([np.interp(u, s, curve[:, 0]), np.interp(u, s, curve[:, 1])])
    T = np.gradient(P, axis=0)
    T /= np.maximum(np.linalg.norm(T, axis=1, keepdims=True), 1e-300)
    f = flow_at(P)
    f = f / np.maximum(np.linalg.norm(f, axis=1, keepdims=True), 1e-300)
    cross = np.abs(T[:, 0] * f[:, 1] - T[:, 1] * f[:, 0])
    cross = np.nan_to_num(cross, nan=0.0)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (cross[1:] + cross[:-1]) * np.diff(u))])
    total = cum[-1]
    n = int(np.ceil(total / spacing)) if total > 0 else 0
    if n == 0:
        return np.zeros((0, 2))
    q = (np.arange(n) + 0.5) * (total / n)
    # Each seed where the cumulative flux reaches its quantile (a monotone interpolation).
    at = np.interp(q, cum, u)
    return np.column_stack([np.interp(at, s, curve[:, 0]), np.interp(at, s, curve[:, 1])])


def triangles_region(V2: np.ndarray, F: np.ndarray, mask: np.ndarray, touching: bool = False, smooth: float = 0.0):
    """The union (shapely) of the triangles with all three vertices in ``mask`` (n,) bool (with
    ``touching``: any of them), for display ("show edit region"); empty geometry when none.
    ``smooth`` > 0 closes and opens it by that distance, so its outline is not a staircase of
    triangle edges."""
    keep = mask[F].any(axis=1) if touching else mask[F].all(axis=1)
    if not keep.any():
        return shapely.GeometryCollection()
    region = shapely.union_all(shapely.polygons(V2[F[keep]])).buffer(0)
    return region.buffer(smooth, quad_segs=4).buffer(-smooth, quad_segs=4) if smooth > 0 else region
