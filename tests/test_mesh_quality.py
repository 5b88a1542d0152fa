"""The triangulation's interior is relaxed so that the shading normals are accurate (issue 11:
isophotes wobbled at the triangle scale on Triangle's irregular valences)."""

import numpy as np

from sketchforge.geometry.normals import vertex_normals
from sketchforge.geometry.triangulate import MIN_ANGLE, _min_angles, relax_interior, triangulate_polygon


def _disk(n=200):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[np.cos(t), np.sin(t)]


def test_inflated_disk_shades_like_the_hemisphere():
    from sketchforge_inflate import inflate_stroke

    m = inflate_stroke(_disk(), True, {"resolution": 0.03, "inflation": 1.0, "smoothing": 0.0})
    V = m.V
    r = np.hypot(V[:, 0], V[:, 1])
    exact = np.c_[V[:, 0], V[:, 1], np.sqrt(np.clip(1 - r**2, 0, None))]
    exact /= np.linalg.norm(exact, axis=1)[:, None]
    err = np.degrees(np.arccos(np.clip(np.sum(vertex_normals(V, m.F) * exact, axis=1), -1, 1)))[r < 0.9]
    # without the relaxation: median 0.20°, p95 0.51°, max 1.24°; with it 0.06° / 0.18° / 0.44°
    assert np.median(err) < 0.1 and np.percentile(err, 95) < 0.3 and err.max() < 0.8


def test_relaxation_keeps_the_outline_and_the_angle_guarantee(monkeypatch):
    import sketchforge.geometry.triangulate as T

    rng = np.random.default_rng(5)
    t = np.sort(rng.uniform(0, 2 * np.pi, 60))
    P = np.c_[(1 + 0.3 * rng.random(60)) * np.cos(t), (1 + 0.3 * rng.random(60)) * np.sin(t)]
    tri = triangulate_polygon(P, 0.05)
    monkeypatch.setattr(T, "RELAX_STEPS", 0)
    raw = triangulate_polygon(P, 0.05)
    k = len(tri.boundary)
    assert np.array_equal(tri.F, raw.F) and np.array_equal(tri.V2[:k], P)  # the outline never moves
    assert np.abs(tri.V2 - raw.V2).max() > 0.05 * 0.05  # the interior did move
    ang, cross = _min_angles(tri.V2, tri.F)
    # Triangle keeps MIN_ANGLE except next to sharp input corners (this outline has some):
    # the relaxation never goes below what Triangle delivered
    assert (cross > 0).all() and ang.min() >= min(MIN_ANGLE, _min_angles(raw.V2, raw.F)[0].min())
    # the steps converge: a fifth step moves the vertices far less than the first one did
    # (measured: rms 0.0011 against 0.0071, max 0.013 against 0.14)
    first = relax_interior(raw.V2, raw.F, k, 1) - raw.V2
    fifth = relax_interior(tri.V2, tri.F, k, 1) - tri.V2
    assert np.sqrt(np.mean(fifth**2)) < 0.3 * np.sqrt(np.mean(first**2))
    assert np.abs(fifth).max() < 0.3 * np.abs(first).max()
