"""Concatenate meshes into one (for exporting several layers without an assembler)."""

from __future__ import annotations

import numpy as np

from sketchforge.geometry.mesh import Mesh


def merge_meshes(meshes: list[Mesh]) -> Mesh:
    """One Mesh holding all of ``meshes``: V stacked, F offset; boundary/junction dropped."""
    offsets = np.cumsum([0] + [m.n_vertices for m in meshes[:-1]])
    V = np.concatenate([m.V for m in meshes]) if meshes else np.zeros((0, 3))
    F = np.concatenate([m.F + o for m, o in zip(meshes, offsets)]) if meshes else np.zeros((0, 3), np.int64)
    return Mesh(V, F)
