"""Point location and barycentric interpolation."""

import time

import numpy as np
from meshes import disk, hemisphere

from sketchforge.geometry.locate import TriangleLocator, interpolate, locate


def test_vertices_are_located_exactly():
    m = hemisphere(1.0, 0.1)
    face, bary = locate(m.V, m.F, m.V[:, :2])
    assert np.all(face >= 0)
    np.testing.assert_allclose(interpolate(m.V, m.F, face, bary), m.V, atol=1e-14)
    # The located triangle does contain the vertex.
    assert np.all(np.any(m.F[face] == np.arange(m.n_vertices)[:, None], axis=1))


def test_linear_fields_are_interpolated_exactly_inside_triangles():
    V2, F, _ = disk(1.0, 0.08)
    rng = np.random.default_rng(5)
    r, t = np.sqrt(rng.uniform(0, 0.95, 5000)), rng.uniform(0, 2 * np.pi, 5000)
    P = np.c_[r * np.cos(t), r * np.sin(t)]
    face, bary = locate(V2, F, P)
    assert np.all(face >= 0)
    assert bary.min() >= -1e-10
    np.testing.assert_allclose(bary.sum(axis=1), 1.0, atol=1e-14)
    field = np.c_[V2, 2 * V2[:, 0] - 3 * V2[:, 1] + 1]
    np.testing.assert_allclose(
        interpolate(field, F, face, bary), np.c_[P, 2 * P[:, 0] - 3 * P[:, 1] + 1], atol=1e-13
    )


def test_matches_brute_force_and_reports_outside():
    V2, F, _ = disk(1.0, 0.25)
    rng = np.random.default_rng(2)
    P = rng.uniform(-1.3, 1.3, (2000, 2))
    face, bary = locate(V2, F, P)
    tri = V2[F]
    for i in range(0, 2000, 7):
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        M = np.stack([b - a, c - a], axis=2)
        l = np.linalg.solve(M, (P[i] - a)[:, :, None])[:, :, 0]
        mn = np.minimum(np.minimum(l[:, 0], l[:, 1]), 1 - l.sum(axis=1))
        inside = np.nonzero(mn >= -1e-10)[0]
        if len(inside):
            assert face[i] in inside
        else:
            assert face[i] == -1 and np.all(bary[i] == 0)
    outside = face < 0
    assert np.all(np.isnan(interpolate(V2[:, 0], F, face, bary)[outside]))
    # Points clearly outside the disk polygon are never located.
    assert np.all(face[np.hypot(P[:, 0], P[:, 1]) > 1.0] == -1)


def test_non_finite_and_empty_queries():
    V2, F, _ = disk(1.0, 0.3)
    face, bary = locate(V2, F, np.array([[np.nan, 0.0], [np.inf, 1.0], [0.0, 0.0]]))
    assert face[0] == -1 and face[1] == -1 and face[2] >= 0
    face, bary = locate(V2, F, np.zeros((0, 2)))
    assert face.shape == (0,) and bary.shape == (0, 3)
    face, _ = locate(V2, np.zeros((0, 3), np.int64), np.zeros((3, 2)))
    assert np.all(face == -1)


def test_locate_speed_100k_points_10k_vertices():
    V2, F, _ = disk(1.0, 0.02)  # ~14k vertices
    assert len(V2) >= 10_000
    P = np.random.default_rng(0).uniform(-1.1, 1.1, (100_000, 2))
    t0 = time.perf_counter()
    loc = TriangleLocator(V2, F)
    face, _ = loc.locate(P)
    dt = time.perf_counter() - t0
    # Measured ~0.07 s (build 0.02 s) on a 2-core machine.
    assert dt < 1.0, dt
    assert abs((face >= 0).mean() - np.pi / 4.84) < 0.01
