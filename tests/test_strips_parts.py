"""The strips solver's pieces against brute force and closed forms (issue 39, point 1).

tests/test_strips_solver.py checks what an edit does end to end; a wrong index in the grid that
carries the fields, in the B-spline, in the seeds' spacing or in the region shown to the user
moved the answer by less than its tolerances. Each piece here is checked on its own, on seeded
inputs, against an answer computed another way.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from sketchforge_strips.field import GRID_PAD, Raster, bspline_eval, grid_spec, rasterize
from sketchforge_strips.regions import extend, flux_seeds, triangles_region

RNG = np.random.default_rng(3936)


def grid_mesh(nx=7, ny=5, jitter=0.0, seed=0):
    """A triangulated (nx x ny) grid on [0, 2] x [0, 1], both diagonals' directions mixed."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.linspace(0, 2, nx), np.linspace(0, 1, ny), indexing="ij")
    V = np.c_[x.ravel(), y.ravel()]
    inner = np.ones((nx, ny), bool)
    inner[[0, -1], :] = inner[:, [0, -1]] = False
    V[inner.ravel()] += jitter * rng.uniform(-1, 1, size=(int(inner.sum()), 2))
    F = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            a, b, c, d = i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1
            F += [[a, b, c], [a, c, d]] if (i + j) % 2 == 0 else [[a, b, d], [b, c, d]]
    return V, np.array(F, dtype=np.int64)


def test_the_grid_covers_the_points_with_its_padding_and_is_centred():
    for V2 in (RNG.uniform(-3, 5, size=(50, 2)), np.array([[0.0, 0.0], [4.0, 1.0]]), np.array([[1.0, 2.0], [1.0, 7.0]])):
        size = 64
        origin, spacing = grid_spec(V2, size)
        lo, hi = V2.min(axis=0), V2.max(axis=0)
        assert spacing == pytest.approx((hi - lo).max() / (size - 1 - 2 * GRID_PAD))
        u_lo, u_hi = (lo - origin) / spacing, (hi - origin) / spacing
        # the points' box sits in the middle, GRID_PAD nodes from the grid's edges on its long side
        assert np.allclose(u_lo + u_hi, size - 1)
        assert min(u_lo.min(), size - 1 - u_hi.max()) == pytest.approx(GRID_PAD)
        assert (u_lo >= GRID_PAD - 1e-9).all() and (u_hi <= size - 1 - GRID_PAD + 1e-9).all()
    origin, spacing = grid_spec(np.zeros((3, 2)), 32)  # one point: a tiny, finite grid
    assert spacing > 0 and np.isfinite(origin).all()


def _inside(tri: np.ndarray, p: np.ndarray) -> bool:
    return shapely.Polygon(tri).buffer(1e-9).covers(shapely.Point(p))


@pytest.mark.parametrize("jitter", [0.0, 0.12])
def test_every_node_gets_the_triangle_that_covers_it_and_its_barycentric_coordinates(jitter):
    V, F = grid_mesh(jitter=jitter, seed=int(jitter * 100))
    size = 24
    origin, spacing = grid_spec(V, size)
    face, bary = rasterize(V, F, origin, spacing, size)
    union = shapely.union_all([shapely.Polygon(V[f]) for f in F])
    for ix in range(size):
        for iy in range(size):
            node = origin + spacing * np.array([ix, iy])
            f = face[ix, iy]
            if f < 0:
                assert not union.buffer(-1e-7).covers(shapely.Point(node)), (ix, iy)
                continue
            assert union.buffer(1e-7).covers(shapely.Point(node)), (ix, iy)
            assert _inside(V[F[f]], node), (ix, iy, f)
            assert bary[ix, iy].sum() == pytest.approx(1.0) and (bary[ix, iy] >= -1e-9).all()
            assert np.allclose(bary[ix, iy] @ V[F[f]], node, atol=1e-12)
    inside = sum(union.buffer(-1e-7).covers(shapely.Point(origin + spacing * np.array([i, j])))
                 for i in range(size) for j in range(size))
    assert inside > 50 and (face >= 0).sum() >= inside


def test_node_values_are_the_piecewise_linear_field_and_the_nearest_covered_node_outside():
    V, F = grid_mesh(jitter=0.1, seed=5)
    size = 32
    a, b, c = 0.7, -1.3, 0.25
    field = a * V[:, 0] + b * V[:, 1] + c  # linear: its piecewise-linear interpolant is itself
    raster = Raster(V, F, size)
    out = raster.node_values(field)
    assert out.shape == (size, size, 1)
    covered = raster.face >= 0
    ix, iy = np.nonzero(covered)
    nodes = raster.origin + raster.spacing * np.c_[ix, iy]
    assert np.allclose(out[ix, iy, 0], a * nodes[:, 0] + b * nodes[:, 1] + c, atol=1e-12)
    # outside: the value of a covered node at the least distance (in nodes)
    cov = np.c_[ix, iy]
    for jx, jy in zip(*np.nonzero(~covered)):
        d = np.hypot(cov[:, 0] - jx, cov[:, 1] - jy)
        nearest = d == d.min()
        assert np.any(np.abs(out[ix[nearest], iy[nearest], 0] - out[jx, jy, 0]) < 1e-12), (jx, jy)
    # several fields at once, column by column
    two = raster.node_values(np.c_[field, 2 * field])
    assert two.shape == (size, size, 2) and np.allclose(two[..., 1], 2 * two[..., 0])


def test_the_b_spline_interpolates_the_node_values_and_a_linear_field_between_them():
    pytest.importorskip("jax")
    import jax

    jax.config.update("jax_enable_x64", True)
    V, F = grid_mesh(nx=9, ny=9, jitter=0.05, seed=8)
    V = V * [1.0, 2.0]  # a square layer: no uncovered nodes in the grid's middle
    raster = Raster(V, F, 48)
    a, b = 0.4, -0.9
    field = np.c_[a * V[:, 0] + b * V[:, 1], np.sin(3 * V[:, 0]) * V[:, 1]]
    import jax.numpy as jnp

    coeffs = jnp.asarray(raster.coefficients(field))
    nodes = raster.node_values(field)
    ev = jax.jit(jax.vmap(lambda p: bspline_eval(coeffs, raster.origin, raster.spacing, p)))
    # at the nodes (inside the clamp of the evaluation): the node values
    ij = np.array([[i, j] for i in range(8, 40, 3) for j in range(8, 40, 5)])
    got = np.asarray(ev(raster.origin + raster.spacing * ij))
    assert np.abs(got - nodes[ij[:, 0], ij[:, 1]]).max() < 1e-9
    # between nodes, well inside the layer: a linear field is reproduced exactly
    u = RNG.uniform(14, 34, size=(40, 2))
    P = raster.origin + raster.spacing * u
    got = np.asarray(ev(P))[:, 0]
    assert np.abs(got - (a * P[:, 0] + b * P[:, 1])).max() < 1e-6
    # and the x and y axes are not swapped: a field of x alone varies along x only
    cx = jnp.asarray(raster.coefficients(V[:, 0]))
    ex = jax.vmap(lambda p: bspline_eval(cx, raster.origin, raster.spacing, p))
    Q = raster.origin + raster.spacing * np.array([[20.0, 20.0], [20.0, 28.0], [28.0, 20.0]])
    vx = np.asarray(ex(Q))[:, 0]
    assert abs(vx[1] - vx[0]) < 1e-6 and vx[2] - vx[0] == pytest.approx(8 * raster.spacing, rel=1e-6)


def test_extend_continues_a_stroke_along_its_end_tangents():
    piece = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 1.0], [4.0, 2.0]])
    out = extend(piece, 0.8)
    assert len(out) == len(piece) + 16
    assert np.array_equal(out[8:-8], piece)
    # the start runs on from piece[0] away from piece[2], evenly, to 0.8
    assert np.allclose(out[:8][::-1], np.c_[-0.1 * np.arange(1, 9), np.zeros(8)])
    # the end runs on from piece[-1] away from piece[-3]: along (1, 1)/sqrt(2)
    d = np.array([1.0, 1.0]) / np.sqrt(2)
    assert np.allclose(out[-8:], piece[-1] + 0.1 * np.arange(1, 9)[:, None] * d)
    assert extend(piece, 0.0) is piece and extend(piece, -1.0) is piece and extend(piece[:1], 1.0) is not None
    two = np.array([[0.0, 0.0], [0.0, 1.0]])
    out = extend(two, 0.5)
    assert np.allclose(out[0], [0.0, -0.5]) and np.allclose(out[-1], [0.0, 1.5])


def _uniform(direction):
    d = np.asarray(direction, dtype=np.float64)
    return lambda P: np.tile(d, (len(P), 1))


@pytest.mark.parametrize("angle", [90.0, 60.0, 30.0])
def test_seeds_are_evenly_spaced_across_the_flow(angle):
    t = np.deg2rad(angle)
    L = 3.0
    curve = np.array([[0.0, 0.0], [L * np.cos(t), L * np.sin(t)]])
    spacing = 0.25
    seeds = flux_seeds(curve, _uniform([1.0, 0.0]), spacing, 0.01)  # flow along x
    across = L * np.sin(t)  # the curve's extent across the flow
    n = int(np.ceil(across / spacing - 1e-9))
    assert len(seeds) == n
    s = np.linalg.norm(seeds - curve[0], axis=1)  # along the curve
    assert np.allclose(s, (np.arange(n) + 0.5) * L / n, atol=1e-9)
    # the flow's sign and length do not matter
    assert np.allclose(flux_seeds(curve, _uniform([-5.0, 0.0]), spacing, 0.01), seeds)


def test_a_stroke_along_the_flow_gets_no_seed_and_a_bent_one_gets_them_where_it_crosses():
    along = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    assert flux_seeds(along, _uniform([1.0, 0.0]), 0.1, 0.01).shape == (0, 2)
    assert flux_seeds(np.zeros((4, 2)), _uniform([1.0, 0.0]), 0.1, 0.01).shape == (0, 2)
    # an L: 2 along the flow, then 1 across it (the corner's turn adds a sliver of flux)
    ell = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0]])
    seeds = flux_seeds(ell, _uniform([1.0, 0.0]), 0.095, 0.001)
    assert len(seeds) == 11
    assert np.allclose(seeds[:, 0], 2.0, atol=0.01)
    assert np.allclose(seeds[:, 1], (np.arange(11) + 0.5) / 11, atol=0.01)


def test_the_region_shown_is_the_union_of_the_chosen_triangles():
    V, F = grid_mesh(nx=6, ny=4, jitter=0.08, seed=2)
    mask = np.zeros(len(V), bool)
    mask[RNG.choice(len(V), 8, replace=False)] = True

    def area(keep):
        return sum(shapely.Polygon(V[f]).area for f in F[keep])

    every = mask[F].all(axis=1)
    some = mask[F].any(axis=1)
    region = triangles_region(V, F, mask)
    assert region.area == pytest.approx(area(every), abs=1e-12)
    touching = triangles_region(V, F, mask, touching=True)
    assert touching.area == pytest.approx(area(some), rel=1e-9)
    assert touching.area > region.area
    assert triangles_region(V, F, np.zeros(len(V), bool)).is_empty
    # smoothing closes the staircase: it covers what it smooths, and not much more
    smooth = triangles_region(V, F, mask, touching=True, smooth=0.05)
    assert smooth.buffer(0.005).covers(touching)
    assert touching.area - 1e-9 <= smooth.area <= touching.area + 0.1
