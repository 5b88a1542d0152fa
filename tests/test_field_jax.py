"""JAX field lookups (sketchforge.geometry.field_jax) against numpy barycentric interpolation."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import triangle

from sketchforge.geometry import field_jax as fj
from sketchforge.geometry.locate import TriangleLocator


@pytest.fixture(scope="module")
def disk():
    t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    B = np.column_stack([np.cos(t), np.sin(t)])
    seg = np.column_stack([np.arange(120), (np.arange(120) + 1) % 120])
    out = triangle.triangulate({"vertices": B, "segments": seg}, "pq30a0.0015Q")
    return out["vertices"], out["triangles"].astype(np.int64)


def smooth(P):
    return np.sin(2 * P[:, 0]) * np.cos(1.5 * P[:, 1]) + 0.3 * P[:, 0] ** 2


def test_bucket_field_matches_numpy_barycentric(disk):
    V2, F = disk
    vals = smooth(V2)
    bf = fj.make_bucket_field(V2, F, vals)
    rng = np.random.default_rng(0)
    P = rng.uniform(-0.7, 0.7, (500, 2))
    got, grad = jax.vmap(bf)(jnp.asarray(P))
    ref = TriangleLocator(V2, F).interpolate(vals, P)
    assert np.abs(np.asarray(got)[:, 0] - ref).max() < 1e-12
    # per-face gradient reproduces a linear field exactly
    lin = 2 * V2[:, 0] - 3 * V2[:, 1]
    _, g = jax.vmap(fj.make_bucket_field(V2, F, lin))(jnp.asarray(P))
    assert np.allclose(np.asarray(g)[:, 0], [2, -3], atol=1e-9)


def test_grid_field_close_to_barycentric_and_smooth(disk):
    V2, F = disk
    vals = smooth(V2)
    gf = fj.make_grid_field(V2, F, vals)
    rng = np.random.default_rng(1)
    P = rng.uniform(-0.65, 0.65, (500, 2))
    got, grad = jax.vmap(gf)(jnp.asarray(P))
    ref = TriangleLocator(V2, F).interpolate(vals, P)
    h = 0.06
    # both approximate the same smooth field: differences of the order of the linear
    # interpolation error (h² · |second derivatives|)
    assert np.abs(np.asarray(got)[:, 0] - ref).max() < 2 * h * h
    exact_g = np.column_stack([2 * np.cos(2 * P[:, 0]) * np.cos(1.5 * P[:, 1]) + 0.6 * P[:, 0],
                               -1.5 * np.sin(2 * P[:, 0]) * np.sin(1.5 * P[:, 1])])
    assert np.abs(np.asarray(grad)[:, 0] - exact_g).max() < 0.15


def test_grid_field_reproduces_analytic_node_data():
    origin, sp = np.array([-1.2, -1.2]), 2.4 / (fj.GRID_SIZE - 1)
    x = origin[0] + sp * np.arange(fj.GRID_SIZE)
    X, Y = np.meshgrid(x, x, indexing="ij")
    f = lambda X, Y: np.exp(-(X**2 + Y**2) / 0.2)
    gf = fj.grid_field_from_nodes(f(X, Y)[:, :, None], origin, sp)
    P = np.random.default_rng(2).uniform(-0.9, 0.9, (300, 2))
    v, g = jax.vmap(gf)(jnp.asarray(P))
    assert np.abs(np.asarray(v)[:, 0] - f(P[:, 0], P[:, 1])).max() < 1e-6
    gx = -2 * P[:, 0] / 0.2 * f(P[:, 0], P[:, 1])
    assert np.abs(np.asarray(g)[:, 0, 0] - gx).max() < 1e-4


def test_rasterize_covers_mesh_and_extends_outside(disk):
    V2, F = disk
    origin, sp, face, bary = fj.layer_raster(V2, F)
    G = fj.GRID_SIZE
    x = origin[0] + sp * np.arange(G)
    X, Y = np.meshgrid(x, origin[1] + sp * np.arange(G), indexing="ij")
    r = np.hypot(X, Y)
    assert (face[r < 0.99] >= 0).all() and (face[r > 1.0 + 1e-9] < 0).all()
    nodes = fj.resample(V2[:, 0], F, face, bary)
    assert np.isfinite(nodes).all() and np.abs(nodes).max() <= 1.0 + 1e-12
