"""A closed lens stitched like an assembled part (front, back, a thin rim bridge), for the
rim-pair tests of the normals and the 3D view."""

import numpy as np
from meshes import hemisphere


def lens(separation, radius: float = 1.0, h: float = 0.1, flat: float = 0.5):
    """A part's front (z = flat·hemisphere + s/2) and back (its mirror image) joined at the rim
    by a bridge of two triangles per rim edge, as :func:`sketchforge_assemble.stitch.build_mesh`
    joins them. ``separation`` s is a number or an (n,) array over the disk's vertices (the
    front and back rim vertex of each rim point are s apart there).

    Returns V (2n, 3) float64, F (m, 3) int64 (outward), rim_pairs (r, 2) int64 (front, back)."""
    m = hemisphere(radius, h)
    n = len(m.V)
    s = np.broadcast_to(np.asarray(separation, dtype=np.float64), (n,))
    z = flat * m.V[:, 2] + 0.5 * s
    V = np.vstack([np.c_[m.V[:, :2], z], np.c_[m.V[:, :2], -z]])
    b = m.boundary
    xy = m.V[b, :2]
    if np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]) < 0:
        b = b[::-1]  # the outline counter-clockwise, the surface on its left
    a_, b_ = b, np.roll(b, -1)
    F = np.vstack([m.F, m.F[:, ::-1] + n, np.c_[b_, a_, a_ + n], np.c_[b_, a_ + n, b_ + n]])
    return V, F, np.c_[b, b + n]
