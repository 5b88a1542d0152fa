"""How far drawn isophotes stray from the exact ones of an analytic surface (wobble).

The analytic surface is the inflation of an ellipse with semi-axes a, b: -Δu = 4, u = 0 on the
ellipse has the exact solution u = k (1 − x²/a² − y²/b²), k = 2 / (1/a² + 1/b²), so the
inflated blob is z = sqrt(u) (a hemisphere for a = b). Its exact normal is ∝ (−∇u, 2z)
everywhere, rim included, so the exact isophote n·l = c at any pixel is known in closed form.
A mesh of the ellipse with z = sqrt(u) at its vertices is what the display sees; the figures
below measure what it draws against that exact field:

- pixel lines (:func:`line_wobble`): for every pixel at the centre of a drawn line (coverage
  >= 0.5), its exact distance to the nearest exact level in pixels, |E − c| / |∇E|; a perfect
  1.2 px line has those within 0.6 px. Per level, the connected pieces of the drawn lines and
  of the lines drawn from the exact normals (one each on an ellipse: a zig-zag that breaks a
  line near the rim shows as more pieces).
- marching-triangles polylines (:func:`polyline_wobble`, the picked isophote and its band):
  the exact distance of their points to the level, in edge lengths, and their count.

Used by ``benchmarks/bench_isophotes.py`` (figures) and ``tests/test_isophote_wobble.py``
(bounds).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class InflatedEllipse:
    """The exact inflation of the ellipse x²/a² + y²/b² <= 1 (inflation 1, no fairing)."""

    a: float
    b: float

    @property
    def k(self) -> float:
        return 2.0 / (1.0 / self.a**2 + 1.0 / self.b**2)

    def height(self, xy: np.ndarray) -> np.ndarray:
        """(n,) z >= 0 at points (n, 2); 0 outside."""
        return np.sqrt(self._u(xy))

    def _u(self, xy):
        xy = np.asarray(xy, dtype=np.float64)
        return np.maximum(self.k * (1.0 - (xy[:, 0] / self.a) ** 2 - (xy[:, 1] / self.b) ** 2), 0.0)

    def normal(self, xy: np.ndarray) -> np.ndarray:
        """(n, 3) unit normals ∝ (−∇u, 2z) (in the plane at and beyond the rim)."""
        xy = np.asarray(xy, dtype=np.float64)
        n = np.column_stack([2 * self.k * xy[:, 0] / self.a**2, 2 * self.k * xy[:, 1] / self.b**2,
                             2.0 * np.sqrt(self._u(xy))])
        return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)

    def shading(self, xy: np.ndarray, light: np.ndarray, eps: float = 1e-6):
        """Exact n·l (n,) and the length of its gradient (n,) (central differences)."""
        l = np.asarray(light, dtype=np.float64).reshape(3)
        E = self.normal(xy) @ l
        gx = (self.normal(xy + [eps, 0.0]) @ l - self.normal(xy - [eps, 0.0]) @ l) / (2 * eps)
        gy = (self.normal(xy + [0.0, eps]) @ l - self.normal(xy - [0.0, eps]) @ l) / (2 * eps)
        return E, np.hypot(gx, gy)

    def mesh(self, outline_points: int, resolution: float):
        """A layer mesh of the ellipse: its outline sampled at ``outline_points`` points,
        triangulated and relaxed as the inflate plugin does at ``resolution``, heights exact.

        Returns
        -------
        Mesh
        """
        from sketchforge.geometry.contour import prepare_outline, resample_outline
        from sketchforge.geometry.mesh import Mesh
        from sketchforge.geometry.triangulate import MIN_ANGLE, triangulate_polygon

        t = 2 * np.pi * np.arange(outline_points) / outline_points
        pts = np.column_stack([self.a * np.cos(t), self.b * np.sin(t)])
        contour = resample_outline(prepare_outline(pts, resolution, closed=True))
        tri = triangulate_polygon(contour.points, contour.edge_length, MIN_ANGLE)
        z = self.height(tri.V2)
        z[tri.boundary] = 0.0
        return Mesh(np.column_stack([tri.V2, z]), tri.F, tri.boundary)


@dataclass(frozen=True)
class LineWobble:
    """Figures of :func:`line_wobble`.

    median, p95, max : float
        Exact distance (px) of the drawn lines' centre pixels to the exact levels.
    pieces, exact_pieces : tuple of int
        Connected pieces of each level's line, drawn and from the exact normals.
    centre_pixels : int
    """

    median: float
    p95: float
    max: float
    pieces: tuple
    exact_pieces: tuple
    centre_pixels: int

    @property
    def extra_pieces(self) -> int:
        return int(sum(max(p - e, 0) for p, e in zip(self.pieces, self.exact_pieces)))


def _pieces(cov_img, level_img, K):
    from scipy import ndimage

    out = []
    for j in range(1, K + 1):
        lab, n = ndimage.label((cov_img > 0) & (level_img == j), structure=np.ones((3, 3)))
        out.append(int(n))
    return tuple(out)


def line_wobble(surface: InflatedEllipse, mesh, view, light, K: int = 8, normals=None, width: float = 1.2) -> LineWobble:
    """Drawn isophote lines of ``mesh`` (alone in ``view``) against the exact surface.

    Parameters
    ----------
    surface : InflatedEllipse
    mesh : Mesh
        A mesh of the surface (e.g. :meth:`InflatedEllipse.mesh`).
    view : gbuffer.View
    light : (3,) float64, unit
    K : int
        Lines at n·l = j / (K + 1), as the display draws them.
    normals : (n, 3) float64 or None
        Vertex normals to draw with instead of the display's own.
    """
    from sketchforge.geometry import gbuffer as gb

    l = np.asarray(light, dtype=np.float64).reshape(3)
    g = gb.rasterise([mesh], view, normals=None if normals is None else [normals])
    W, H = view.width, view.height
    owned = np.nonzero(g.front >= 0)[0]
    r, c = np.divmod(owned, W)
    xy = np.column_stack([view.x0 + (c + 0.5) / view.scale, view.y1 - (r + 0.5) / view.scale])
    E, grad = surface.shading(xy, l)
    level = np.clip(np.rint(E * (K + 1)), 1, K)
    dist = np.abs(E - level / (K + 1)) / np.maximum(grad / view.scale, 1e-12)
    # the 1-px silhouette blends with the background: lines are measured inside it
    inner = g.alpha[g.front_frag] >= 1.0
    cov = gb.isophote_coverage(g, l, K, width)
    centre = (cov >= 0.5) & inner
    d = dist[centre]
    exact_g = replace(g, normal=np.asfortranarray(surface.normal(_fragment_points(g)), dtype=np.float32))
    exact_cov = gb.isophote_coverage(exact_g, l, K, width)
    shown = np.rint(np.clip(gb._dot(g.normal[g.front_frag], l) * (K + 1), 1, K))

    def image(values):
        img = np.zeros(W * H, dtype=np.float64)
        img[owned] = np.where(inner, values, 0)
        return img.reshape(H, W)

    return LineWobble(
        median=float(np.median(d)) if len(d) else float("nan"),
        p95=float(np.percentile(d, 95)) if len(d) else float("nan"),
        max=float(d.max()) if len(d) else float("nan"),
        pieces=_pieces(image(cov), image(shown), K),
        exact_pieces=_pieces(image(exact_cov), image(level), K),
        centre_pixels=int(centre.sum()),
    )


def _fragment_points(g) -> np.ndarray:
    """(k, 2) document points of every fragment's pixel centre."""
    r, c = np.divmod(g.pix, g.view.width)
    return np.column_stack([g.view.x0 + (c + 0.5) / g.view.scale, g.view.y1 - (r + 0.5) / g.view.scale])


def polyline_wobble(surface: InflatedEllipse, mesh, E: np.ndarray, c: float, light) -> tuple[float, float, int]:
    """The marching-triangles isophote E = c of a vertex field against the exact level.

    Returns
    -------
    (p95, max, pieces)
        Exact distance of the polylines' points to the level n·l = c, in mean edge lengths
        (p95 and max, over points more than one edge length inside the rim), and the number
        of polylines.
    """
    from sketchforge.geometry.isophotes import isophotes

    V2 = mesh.V[:, :2]
    lines, _ = isophotes(V2, mesh.F, E, c)
    F = mesh.F
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    h = float(np.linalg.norm(V2[e[:, 0]] - V2[e[:, 1]], axis=1).mean())
    P = np.concatenate(lines) if lines else np.zeros((0, 2))
    inside = surface.height(P) ** 2 > surface.k * (2 * h / min(surface.a, surface.b))  # ~one edge in from the rim
    Ex, grad = surface.shading(P[inside], light)
    d = np.abs(Ex - c) / np.maximum(grad, 1e-12) / h
    if not len(d):
        return float("nan"), float("nan"), len(lines)
    return float(np.percentile(d, 95)), float(d.max()), len(lines)
