"""Screen-space picking for the 3D view, as pure functions of a 4×4 model-view-projection
matrix (no Qt, so they are tested headlessly).

``mvp`` maps homogeneous document coordinates to clip space; ``size`` is the widget's
(width, height) in pixels, y down.
"""

from __future__ import annotations

import numpy as np


def project(mvp: np.ndarray, P: np.ndarray, size) -> tuple[np.ndarray, np.ndarray]:
    """P (n,3) float64 -> (pixels (n,2) float64, depth (n,) float64 in NDC, smaller = nearer)."""
    h = np.c_[P, np.ones(len(P))] @ np.asarray(mvp, dtype=np.float64).T
    w = np.where(np.abs(h[:, 3]) > 1e-12, h[:, 3], 1e-12)
    ndc = h[:, :3] / w[:, None]
    px = np.c_[(ndc[:, 0] + 1) * 0.5 * size[0], (1 - ndc[:, 1]) * 0.5 * size[1]]
    return px, ndc[:, 2]


def pick_vertex(mvp, P: np.ndarray, size, pos, radius: float = 8.0) -> int | None:
    """The front-most vertex of P (n,3) within ``radius`` pixels of ``pos`` (2,), or None."""
    px, depth = project(mvp, P, size)
    d = np.hypot(px[:, 0] - pos[0], px[:, 1] - pos[1])
    near = np.flatnonzero((d <= radius) & (depth > -1) & (depth < 1))
    if len(near) == 0:
        return None
    return int(near[np.argmin(depth[near])])


def unproject_at_depth(mvp, point: np.ndarray, size, pos) -> np.ndarray:
    """The 3D point under pixel ``pos`` at the screen depth of ``point`` (3,): where a dragged
    pin goes (it moves parallel to the screen)."""
    _, depth = project(mvp, np.asarray(point, dtype=np.float64).reshape(1, 3), size)
    ndc = np.array([2 * pos[0] / size[0] - 1, 1 - 2 * pos[1] / size[1], depth[0], 1.0])
    h = np.linalg.solve(np.asarray(mvp, dtype=np.float64), ndc)
    return h[:3] / h[3]
