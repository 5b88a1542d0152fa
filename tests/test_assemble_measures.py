"""The assembly's measures checked against brute force on hand-made meshes: the bend across each
edge (which decides whether a blended junction is handed out), connected components, and the
cache's digest of what it is keyed by; and the memory budget's sentence."""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge_assemble import DepthOrderError
from sketchforge_assemble import diagnostics as dg
from sketchforge_assemble.cache import digest


def _hinge(angle_deg: float):
    """Two unit right triangles sharing the edge (0,0,0)-(0,1,0), the second folded by ``angle``."""
    a = np.radians(angle_deg)
    V = np.array([[0, 0, 0], [0, 1, 0], [1, 0, 0], [-np.cos(a), 0, np.sin(a)]], float)
    F = np.array([[0, 2, 1], [0, 1, 3]])
    return V, F


@pytest.mark.parametrize("angle", [0.0, 30.0, 90.0, 150.0, 179.0])
def test_the_bend_across_a_hinge_is_its_fold_angle(angle):
    V, F = _hinge(angle)
    got = dg.dihedral_angles(V, F)
    assert got.shape == (1,)
    assert got[0] == pytest.approx(angle, abs=1e-9)
    # the same hinge listed from another corner of each triangle, and moved anywhere
    rot = np.array([[0.6, -0.8, 0], [0.8, 0.6, 0], [0, 0, 1.0]])
    got2 = dg.dihedral_angles(V @ rot.T + [3.0, -2.0, 5.0], F[:, [1, 2, 0]][::-1])
    assert got2[0] == pytest.approx(angle, abs=1e-9)


def test_bends_are_taken_only_across_edges_of_exactly_two_triangles():
    # a fan of three triangles on one edge (not a surface there) and a border edge: no bend;
    # every other edge of a closed octahedron bends by its dihedral supplement
    V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    F = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    got = dg.dihedral_angles(V, F)
    assert len(got) == 12
    assert np.allclose(got, 180.0 - np.degrees(np.arccos(-1.0 / 3.0)), atol=1e-9)
    fan = np.vstack([F, [[0, 2, 3]]])  # edge 0-2 now in three triangles, 0-3 in three
    assert len(dg.dihedral_angles(V, fan)) == 10
    open_ = F[:-1]  # one face missing: its three edges border the hole
    assert len(dg.dihedral_angles(V, open_)) == 9


def test_components_label_every_vertex_by_the_triangles_joining_them():
    F = np.array([[0, 1, 2], [2, 3, 0], [4, 5, 6], [7, 8, 9], [9, 8, 10]])
    lab = dg.components(F, 12)
    assert len(np.unique(lab)) == 4  # {0-3}, {4-6}, {7-10}, {11} alone
    assert len({lab[0], lab[1], lab[2], lab[3]}) == 1
    assert len({lab[7], lab[8], lab[9], lab[10]}) == 1
    assert len({lab[0], lab[4], lab[7], lab[11]}) == 4
    assert sorted(dg.euler_characteristics(F)) == [1, 1, 1]


def test_digest_tells_bytes_and_types_apart_and_refuses_what_it_cannot_read():
    assert digest(b"ab") == digest(b"ab")
    assert digest(b"ab") != digest(b"ab\x00") != digest("ab")
    assert digest(b"ab", b"c") != digest(b"a", b"bc")  # lengths are part of the digest
    with pytest.raises(TypeError, match="cannot digest object"):
        digest(object())
    with pytest.raises(TypeError, match="cannot digest set"):
        digest((1, {2}))


def test_the_memory_budget_sentence_counts_the_rows_in_play():
    from test_depth_qp import _random_qp

    from sketchforge_assemble.active_set import _WorkingSet
    from sketchforge_assemble.depth import solve_depth

    P, q, Aeq, beq, Ain, bin_ = _random_qp(6, n=2000, n_in=20)
    with pytest.raises(DepthOrderError) as err:
        solve_depth(P, q, Aeq, beq, Ain, bin_, method="active_set", memory_budget=1)
    # the first thing it holds: the P⁻¹cᵀ columns of the glue rows, asked for all at once
    assert f"({len(beq)} rows in play)" in str(err.value)
    import scipy.sparse.linalg as sla

    lu = sla.splu(P.tocsc())
    W = _WorkingSet(lu, Aeq, Ain, lu.solve(-q), beq, bin_, budget=8 * 2000 * (16 + 5) + 16)
    W.z([-1, -2, 0])  # 3 columns cached: 19 of 21 in use
    with pytest.raises(DepthOrderError, match=r"\(6 rows in play\)"):
        W.z([1, 2, 3])  # 3 more would make 22
    assert sorted(W.cache) == [-2, -1, 0]  # nothing half-grown


def test_distance_to_a_polyline_within_reach_is_exact_and_infinite_beyond():
    from sketchforge_assemble.blend import distance_to

    rng = np.random.default_rng(5)
    line = np.cumsum(rng.normal(0, 0.1, (150, 2)), axis=0)  # more than one chunk of 64 segments
    xy = rng.uniform(line.min(0) - 1.0, line.max(0) + 1.0, (400, 2))
    # brute force: the nearest point of every segment
    a, b = line[:-1], line[1:]
    ab = b - a
    t = np.clip(np.einsum("nsk,sk->ns", xy[:, None] - a[None], ab) / np.einsum("sk,sk->s", ab, ab), 0, 1)
    want = np.min(np.linalg.norm(xy[:, None] - (a[None] + t[..., None] * ab[None]), axis=2), axis=1)
    assert np.allclose(distance_to(xy, line), want, atol=1e-12)
    reach = 0.3
    got = distance_to(xy, line, reach)
    lo, hi = line.min(0) - reach, line.max(0) + reach
    near = np.all((xy >= lo) & (xy <= hi), axis=1)
    assert 0 < near.sum() < len(xy)
    assert np.allclose(got[near], want[near], atol=1e-12)
    assert np.all(np.isinf(got[~near]))


def test_box_pairs_of_fewer_than_two_boxes_or_of_points():
    none = dg.box_pairs(np.zeros((1, 3)), np.ones((1, 3)))
    assert none.shape == (0, 2) and none.dtype == np.int64
    assert dg.box_pairs(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0, 2)
    # boxes of zero extent (points): those at one place overlap (closed boxes), the rest do not
    P = np.array([[0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 0, 0]], float)
    assert dg.box_pairs(P, P.copy()).tolist() == [[0, 1], [0, 3], [1, 3]]


def test_a_fold_back_onto_itself_bends_by_180_degrees_not_nan():
    # a plain sleeve folds by 180 degrees; with round-off the normals' dot product dips below -1
    # (about one random fold in six), and the bend must still read 180, not NaN (a NaN bend
    # passes every "bend > limit" check)
    rng = np.random.default_rng(0)
    for _ in range(60):
        P = rng.normal(size=(3, 3))
        V = np.vstack([P, P[2]])
        got = dg.dihedral_angles(V, np.array([[0, 1, 2], [1, 0, 3]]))
        assert got.shape == (1,) and got[0] == pytest.approx(180.0, abs=1e-5)


def test_box_pairs_of_boxes_that_overlap_nowhere():
    lo = np.array([[0.0, 0, 0], [2.0, 0, 0]])
    got = dg.box_pairs(lo, lo + 1.0)
    assert got.shape == (0, 2) and got.dtype == np.int64


def test_the_pair_check_called_from_its_own_pool_does_not_deadlock(monkeypatch):
    # the two-thread split is skipped on the pool's own threads: two checks running there at
    # once would each wait for the pool they occupy
    monkeypatch.setattr(dg, "SPLIT_FROM", 10)
    rng = np.random.default_rng(2)
    c = rng.uniform(0, 1, (200, 1, 3))
    V = (c + rng.normal(0, 0.05, (200, 3, 3))).reshape(-1, 3)
    F = np.arange(600).reshape(200, 3)
    want = dg.intersecting_pairs(V, F, among=np.arange(200))
    jobs = [dg._pool().submit(dg.intersecting_pairs, V, F, None, 200_000, np.arange(200)) for _ in range(2)]
    for job in jobs:
        assert job.result(timeout=60).tolist() == want.tolist()


def test_box_pairs_of_many_points_spread_apart_are_exact():
    # every box a point (collapsed triangles), spread over a unit cube: the grid must stay
    # finite (it divided by a cell of 1e-300 and cast 1e300 to int64)
    rng = np.random.default_rng(9)
    lo = rng.integers(0, 4, (200, 3)) / 4.0  # points on a coarse lattice: many coincide
    hi = lo.copy()
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy warns of a cast of inf or 1e300 to int64
        got = dg.box_pairs(lo, hi)
    i, j = np.triu_indices(200, 1)
    hit = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1)
    assert got.tolist() == np.c_[i[hit], j[hit]].tolist()
