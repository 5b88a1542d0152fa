"""TriangleLocator: meshes of any shape, size and position, and the nearest=True fallbacks.

These tests come from mutants of ``sketchforge/geometry/locate.py`` (the locator's grid set-up
and its main loop) that the rest of the suite did not kill. Expectations never come from the
code under test:

- an elongated strip (far wider than tall, or the other way round) is located against the
  definition: every point inside is found, and its barycentrics rebuild the point;
- ``nearest=True`` answers are compared with themselves under exact symmetries of floating
  point: scaling by a power of two, translating a dyadic mesh by a dyadic offset, and swapping
  the x and y axes change no bit of any difference, product or quotient, so the answer for
  each point (its face and barycentrics) must be the same bits;
- points far from a small mesh take their nearest vertex (brute force over all vertices), and
  non-finite points are reported as outside (-1, zero barycentrics) even with snapping on.
"""

import numpy as np
import pytest

from sketchforge.geometry.locate import TriangleLocator


def _corners_of(V2, F, face, bary):
    """The point (face, bary) stands for: sum_j bary_j * V[F[face, j]]."""
    return np.einsum("kj,kjd->kd", bary, V2[F[face]])


def _jittered_rect(nx, ny, width, height, seed):
    """A structured triangulation of a width x height rectangle whose vertices are jittered by
    up to a tenth of a cell and rounded to multiples of 2**-20 (so the mesh is dyadic and
    translations by powers of two are exact). Jitter keeps every triangle's orientation."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.linspace(0, width, nx + 1), np.linspace(0, height, ny + 1))
    V2 = np.c_[x.ravel(), y.ravel()]
    V2 += rng.uniform(-0.1, 0.1, V2.shape) * [width / nx, height / ny]
    V2 = np.round(V2 * 2**20) / 2**20
    idx = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    F = np.vstack([np.c_[a, b, c], np.c_[a, c, d]])
    return V2, F


def _queries(V2, seed, n=3000):
    """Dyadic query points over a box three times the mesh's extent: inside, just outside and
    well outside, so every branch of nearest=True is taken."""
    rng = np.random.default_rng(seed)
    lo, hi = V2.min(axis=0), V2.max(axis=0)
    ext = hi - lo
    P = rng.uniform(lo - 1.5 * ext, hi + 1.5 * ext, (n, 2))
    near = rng.uniform(lo - 0.1 * ext, hi + 0.1 * ext, (n, 2))
    return np.round(np.vstack([P, near]) * 2**20) / 2**20


# --------------------------------------------------------------------------- plain location


@pytest.mark.parametrize("transpose", [False, True])
@pytest.mark.parametrize("n_cells", [1, 4])
def test_every_point_of_a_long_thin_strip_is_found(transpose, n_cells):
    # A 64 x 1 rectangle (and its 1 x 64 transpose): the point-location structure must cover
    # the whole strip, not only the part near its first corner.
    rng = np.random.default_rng(2)
    if n_cells == 1:  # two triangles, 64:1
        V2 = np.array([[0.0, 0.0], [64.0, 0.0], [64.0, 1.0], [0.0, 1.0]])
        F = np.array([[0, 1, 2], [0, 2, 3]])
        P = rng.uniform([0.0, 0.0], [64.0, 1.0], (2000, 2))
    else:  # eight jittered triangles; the outline is wavy, so keep points well inside it
        V2, F = _jittered_rect(n_cells, 1, 64.0, 1.0, seed=1)
        P = rng.uniform([2.0, 0.2], [62.0, 0.8], (2000, 2))
    if transpose:
        V2, P = V2[:, ::-1].copy(), P[:, ::-1].copy()
    face, bary = TriangleLocator(V2, F).locate(P)
    assert np.all(face >= 0)
    assert bary.min() >= -1e-10
    np.testing.assert_allclose(bary.sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(_corners_of(V2, F, face, bary), P, atol=1e-12)
    # The far end of the strip is really exercised.
    assert np.sum(P[:, 1 if transpose else 0] > 48) > 300


# --------------------------------------------------------------------------- nearest=True invariances


@pytest.fixture(scope="module")
def wide_mesh():
    # 3 x 1: unequal extents, so an x/y mix-up shows; not at the origin, not of unit size.
    V2, F = _jittered_rect(12, 4, 3.0, 1.0, seed=5)
    return V2 + [0.5, 0.25], F


def _snapped(V2, F, P):
    face, bary = TriangleLocator(V2, F).locate(P, nearest=True)
    assert np.all(face >= 0)  # every query is finite, so every one is answered
    return face, bary


@pytest.mark.parametrize("scale", [2.0**-12, 2.0**-4, 2.0**9])
def test_snapping_is_invariant_under_scaling_by_powers_of_two(wide_mesh, scale):
    # The same drawing in other units (exactly representable ones) must snap every point,
    # inside or out, to the same place.
    V2, F = wide_mesh
    P = _queries(V2, seed=6)
    face, bary = _snapped(V2, F, P)
    face_s, bary_s = _snapped(V2 * scale, F, P * scale)
    np.testing.assert_array_equal(face_s, face)
    np.testing.assert_array_equal(bary_s, bary)


@pytest.mark.parametrize("shift", [(1024.0, 0.0), (0.0, -512.0), (-2048.0, 4096.0)])
def test_snapping_is_invariant_under_dyadic_translations(wide_mesh, shift):
    # Moving mesh and points together by a power-of-two offset is exact for this dyadic data;
    # where the mesh sits in the plane must not change any answer.
    V2, F = wide_mesh
    P = _queries(V2, seed=7)
    face, bary = _snapped(V2, F, P)
    face_t, bary_t = _snapped(V2 + shift, F, P + shift)
    np.testing.assert_array_equal(face_t, face)
    np.testing.assert_array_equal(bary_t, bary)


def test_snapping_is_invariant_under_swapping_the_axes(wide_mesh):
    # Swapping x and y mirrors the mesh (its triangles change orientation, which the locator
    # accepts); each point must still get the same triangle and barycentrics.
    V2, F = wide_mesh
    P = _queries(V2, seed=8)
    face, bary = _snapped(V2, F, P)
    face_w, bary_w = _snapped(V2[:, ::-1].copy(), F, P[:, ::-1].copy())
    np.testing.assert_array_equal(face_w, face)
    np.testing.assert_allclose(bary_w, bary, rtol=0, atol=1e-15)


# --------------------------------------------------------------------------- nearest=True fallbacks


def test_points_well_away_from_a_small_mesh_take_their_nearest_vertex():
    # Clipped barycentrics are a snap for points near the outline (curves on it); a point
    # further from the mesh than the mesh is wide gets its nearest vertex instead. The unit
    # square in two triangles; points 1.2 to 1.4 away on every side, off the symmetry lines
    # so the nearest vertex is unique.
    V2 = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    rng = np.random.default_rng(10)
    d = rng.uniform(1.2, 1.4, 40)
    s = rng.uniform(0.05, 0.45, 40) + np.tile([0.0, 0.5], 20)  # along the side, never 0.5
    P = np.vstack([
        np.c_[-d[:10], s[:10]],  # left
        np.c_[s[10:20], -d[10:20]],  # below
        np.c_[1 + d[20:30], s[20:30]],  # right
        np.c_[s[30:], 1 + d[30:]],  # above
    ])
    face, bary = TriangleLocator(V2, F).locate(P, nearest=True)
    nearest = np.argmin(np.linalg.norm(P[:, None, :] - V2[None, :, :], axis=2), axis=1)
    assert np.all(face >= 0)
    np.testing.assert_array_equal(np.sort(bary, axis=1), np.tile([0.0, 0.0, 1.0], (len(P), 1)))
    np.testing.assert_array_equal(F[face, np.argmax(bary, axis=1)], nearest)
    np.testing.assert_array_equal(_corners_of(V2, F, face, bary), V2[nearest])


def test_non_finite_points_stay_outside_with_snapping_on(wide_mesh):
    # Snapping is for finite points; a NaN or infinite query has no nearest anything and must
    # come back as -1 with zero barycentrics, alone or among ordinary points.
    V2, F = wide_mesh
    loc = TriangleLocator(V2, F)
    bad = np.array([[np.nan, 1.0], [2.0, np.inf], [-np.inf, np.nan]])
    for P in (bad, np.vstack([[[1.0, 0.6], [9.0, 9.0]], bad])):
        face, bary = loc.locate(P, nearest=True)
        np.testing.assert_array_equal(face[-3:], -1)
        np.testing.assert_array_equal(bary[-3:], 0.0)
        assert np.all(face[:-3] >= 0)
