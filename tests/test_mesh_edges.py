"""The one pairing of each interior edge's two triangles (sketchforge.geometry.mesh_edges), which
the assembly, the sculpt host's crease bounds and the strips solver share."""

import numpy as np
import pytest

from sketchforge.plugin_api import edge_angles, interior_edges


def test_only_edges_of_exactly_two_triangles_are_paired_with_both():
    # a square of two triangles, a third triangle on one rim edge, and a fin: three triangles
    # on the edge (2, 3) make it no interior edge
    F = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 2], [2, 3, 5], [3, 2, 6]])
    E, fa, fb = interior_edges(F)
    assert E.tolist() == [[0, 2], [1, 2]]  # lexicographic, smaller vertex first
    assert sorted(map(sorted, zip(fa.tolist(), fb.tolist()))) == [[0, 1], [0, 2]]
    assert interior_edges(np.array([[0, 1, 2]]))[0].shape == (0, 2)


@pytest.mark.parametrize("fold", [0.0, 60.0, 150.0])
def test_the_angle_across_a_hinge_is_its_fold(fold):
    a = np.radians(fold)
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -np.cos(a), np.sin(a)]], float)
    F = np.array([[0, 1, 2], [1, 0, 3]])
    _, fa, fb = interior_edges(F)
    assert edge_angles(V, F, fa, fb) == pytest.approx([fold], abs=1e-9)
    assert edge_angles(V, F, fb, fa) == pytest.approx([fold], abs=1e-9)  # either way round
