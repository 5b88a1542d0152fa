"""Analytic test meshes built with `triangle` (shared by the geometry tests).

Every builder takes a target edge length ``h`` and returns plain arrays or a Mesh, deterministic
for a given ``h``. Surfaces with known normals and gradients:

- hemisphere z = sqrt(ρ² - r²): n = (x, y, z) / ρ; with in-plane light n·l = (x l_x + y l_y)/ρ,
  linear in (x, y), so its isophotes are straight chords.
- Gaussian bump z = A exp(-r² / (2σ²)) on a disk: smooth, non-linear n·l, for interpolation
  error and convergence tests.
"""

from __future__ import annotations

import numpy as np

from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.triangulate import triangulate_polygon


def disk(radius: float = 1.0, h: float = 0.1, center=(0.0, 0.0)):
    """Quality triangulation of a disk.

    Returns
    -------
    V2 : (n, 2) float64
    F : (m, 3) int64, counter-clockwise
    boundary : (b,) int64, the boundary loop in order (the first b vertices)
    """
    nb = max(8, int(np.ceil(2 * np.pi * radius / h)))
    t = 2 * np.pi * np.arange(nb) / nb
    pts = np.c_[radius * np.cos(t), radius * np.sin(t)] + np.asarray(center, dtype=float)
    tri = triangulate_polygon(pts, h, min_angle=30.0)
    return tri.V2, tri.F, tri.boundary


def hemisphere(radius: float = 1.0, h: float = 0.1) -> Mesh:
    """z = sqrt(ρ² - r²) over a disk of radius ρ; z = 0 on the boundary."""
    V2, F, b = disk(radius, h)
    z = np.sqrt(np.maximum(radius**2 - np.einsum("ij,ij->i", V2, V2), 0.0))
    z[b] = 0.0
    return Mesh(np.c_[V2, z], F, boundary=b)


def hemisphere_normals(V: np.ndarray, radius: float = 1.0) -> np.ndarray:
    """Exact unit normals (x, y, z)/ρ of the hemisphere at points V (n, 3)."""
    N = np.array(V, dtype=np.float64)
    N[:, 2] = np.sqrt(np.maximum(radius**2 - N[:, 0] ** 2 - N[:, 1] ** 2, 0.0))
    return N / np.linalg.norm(N, axis=1, keepdims=True)


def gaussian_height(xy: np.ndarray, amp: float = 0.5, sigma: float = 0.35) -> np.ndarray:
    xy = np.asarray(xy, dtype=np.float64)
    return amp * np.exp(-np.einsum("ij,ij->i", xy, xy) / (2 * sigma**2))


def gaussian_normals(xy: np.ndarray, amp: float = 0.5, sigma: float = 0.35) -> np.ndarray:
    """Exact unit normals (-z_x, -z_y, 1)/|.| of the Gaussian bump at points (n, 2)."""
    xy = np.asarray(xy, dtype=np.float64)
    z = gaussian_height(xy, amp, sigma)
    grad = -xy * (z / sigma**2)[:, None]
    n = np.c_[-grad, np.ones(len(xy))]
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def gaussian_intensity_gradient(xy, light, amp: float = 0.5, sigma: float = 0.35) -> np.ndarray:
    """Exact ∇(n·l) in the plane for the Gaussian bump and an in-plane light, (n, 2).

    With p = z_x, q = z_y: n·l = -(p l_x + q l_y) / s, s = sqrt(1 + p² + q²). Differentiated with
    the Hessian of z: for z = A exp(-r²/2σ²), ∇z = -z x/σ², H = z (x xᵀ/σ⁴ - I/σ²).
    """
    xy = np.asarray(xy, dtype=np.float64)
    lx, ly = float(light[0]), float(light[1])
    z = gaussian_height(xy, amp, sigma)
    g = -xy * (z / sigma**2)[:, None]  # (p, q)
    s = np.sqrt(1 + np.einsum("ij,ij->i", g, g))
    H = z[:, None, None] * (xy[:, :, None] * xy[:, None, :] / sigma**4 - np.eye(2) / sigma**2)
    lvec = np.array([lx, ly])
    a = g @ lvec  # p lx + q ly
    # E = -a / s ; ∇E = -(H l)/s + a (H g)/s³
    Hl = H @ lvec
    Hg = np.einsum("kij,kj->ki", H, g)
    return -Hl / s[:, None] + (a / s**3)[:, None] * Hg


def gaussian_bump(
    radius: float = 1.0, h: float = 0.1, amp: float = 0.5, sigma: float = 0.35
) -> Mesh:
    """z = A exp(-r²/(2σ²)) over a disk (not zero at the boundary; a smooth test field)."""
    V2, F, b = disk(radius, h)
    return Mesh(np.c_[V2, gaussian_height(V2, amp, sigma)], F, boundary=b)
