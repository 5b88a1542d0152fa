"""The guard in front of native code (sketchforge.geometry.guard): unit tests with numbers, and
property tests that throw hostile polylines at every entry point outside the sculpt plugin.

Why the property tests run in a child process. A native library that is handed bad geometry
does not raise: Triangle segfaults (a PSLG whose segments use a duplicated vertex crashed it
on every run we tried), igl.cotmatrix segfaults on an out-of-range face. In-process, such a
crash kills pytest and every later test with it. So each property test runs its hypothesis
loop in a fresh interpreter (``python -X faulthandler``) and asserts that it exits with status
0: a crash becomes an ordinary test failure showing the signal (-11 = SIGSEGV) and, thanks to
faulthandler, the Python stack of the example that crashed; any other failure shows
hypothesis' falsifying example. The loops are derandomized (the same examples every run) and
small, so the file runs in well under a minute on two cores.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import shapely
import triangle
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from sketchforge.errors import GeometryError, SculptError, SketchforgeError, SolverError
from sketchforge.geometry import guard
from sketchforge.geometry.band import band
from sketchforge.geometry.contour import MAX_COORDINATE
from sketchforge.geometry.dirichlet import DirichletSolver
from sketchforge.geometry.laplacian import laplacian_and_mass
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.triangulate import _format_area, triangulate_polygon

HERE = Path(__file__).resolve().parent
SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
RING4 = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])


def _one_sentence(exc: BaseException) -> str:
    msg = str(exc)
    assert msg.strip() and "\n" not in msg, repr(msg)
    return msg


def _area(out) -> float:
    V, T = out["vertices"], out["triangles"]
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    return float(np.sum(np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])) / 2)


# --- points -----------------------------------------------------------------------------------


def test_points_returns_contiguous_float64_and_names_the_input_when_refusing():
    P = guard.points([[0, 1], [2, 3]], "the stroke")
    assert P.dtype == np.float64 and P.flags.c_contiguous and P.tolist() == [[0, 1], [2, 3]]
    assert guard.points(np.zeros((0, 2)), "x").shape == (0, 2)
    for bad, words in (([[0, 0], [np.nan, 1]], "not a finite number (point 1"),
                       ([[0, 0], [np.inf, 1]], "not a finite number"),
                       ([[0, 0], [2 * MAX_COORDINATE, 1]], "reaching 2e+09"),
                       ([[0, 0, 0]], "shape (k, 2)"),
                       ([[0, "a"]], "must be an array of numbers")):
        with pytest.raises(GeometryError, match="^the stroke") as err:
            guard.points(bad, "the stroke")
        assert words in _one_sentence(err.value)
    assert guard.points([[MAX_COORDINATE, -MAX_COORDINATE]], "x").shape == (1, 2)  # the bound is inclusive


# --- pslg -------------------------------------------------------------------------------------


def test_four_identical_copies_of_a_vertex_become_one_and_triangle_meshes_every_time():
    # The square's first corner drawn four times: raw, this PSLG segfaults Triangle.
    V = np.vstack([SQUARE, SQUARE[:1], SQUARE[:1], SQUARE[:1]])
    S = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [5, 6], [6, 0]])
    data, index = guard.pslg(V, S, 0.0, return_index=True)
    assert data["vertices"].tolist() == SQUARE.tolist()
    assert index.tolist() == [0, 1, 2, 3, 0, 0, 0]
    assert sorted(map(sorted, data["segments"].tolist())) == [[0, 1], [0, 3], [1, 2], [2, 3]]
    assert data["vertices"].dtype == np.float64 and data["vertices"].flags.c_contiguous
    assert data["segments"].dtype == np.int32 and data["segments"].flags.c_contiguous
    first = None
    for _ in range(20):
        out = triangle.triangulate(data, "pq25a0.01YQ")
        assert _area(out) == pytest.approx(1.0, rel=1e-12)
        first = out["triangles"] if first is None else first
        assert np.array_equal(out["triangles"], first)


def test_near_duplicates_merge_into_the_first_within_the_tolerance_only():
    V = np.vstack([SQUARE, SQUARE[2:3] + 1e-12])
    S = np.array([[0, 1], [1, 4], [4, 2], [2, 3], [3, 0]])
    data = guard.pslg(V, S, None)  # default: 1e-9 of the extent
    assert data["vertices"].tolist() == SQUARE.tolist()  # the kept point has its exact coordinates
    assert len(data["segments"]) == 4  # 4 -> 2 became zero-length and was dropped
    kept = guard.pslg(V, S, 0.0)  # 0: only bit-identical copies merge
    assert len(kept["vertices"]) == 5 and len(kept["segments"]) == 5


def test_merging_is_greedy_in_input_order_and_does_not_chain():
    P = np.array([[0.0, 0], [0.6, 0], [1.2, 0], [1.7, 0]])
    far = [[0.6, 50.0], [50.0, 25.0]]  # far from the others (and off their line)
    data, index = guard.pslg(np.vstack([P, far]), None, 1.0, return_index=True)
    # 0.6 joins 0; 1.2 is 1.2 from 0 (no chain through 0.6), so it is kept and takes 1.7.
    assert data["vertices"].tolist() == [[0.0, 0], [1.2, 0], *far]
    assert index.tolist() == [0, 0, 1, 1, 2, 3]
    data, index = guard.pslg(np.vstack([P[::-1], far]), None, 1.0, return_index=True)  # input order decides
    assert data["vertices"].tolist() == [[1.7, 0], [0.6, 0], *far] and index.tolist() == [0, 0, 1, 1, 2, 3]


class _CountingTree(cKDTree):
    """cKDTree that counts its ball queries (the only per-point loop of the merge)."""

    ball_queries = 0

    def query_ball_point(self, *args, **kwargs):
        type(self).ball_queries += 1
        return super().query_ball_point(*args, **kwargs)


def test_many_copies_of_a_corner_merge_with_a_sort_and_one_ball_query(monkeypatch):
    monkeypatch.setattr(guard, "cKDTree", _CountingTree)
    monkeypatch.setattr(_CountingTree, "ball_queries", 0)
    V = np.vstack([SQUARE, np.repeat(SQUARE[2:3], 20_000, axis=0), [[-0.0, 0.0]]])  # -0.0 == 0.0
    data, index = guard.pslg(V, RING4, 1e-6, return_index=True)
    assert data["vertices"].tolist() == SQUARE.tolist()
    assert np.all(index[4:-1] == 2) and index[-1] == 0
    assert _CountingTree.ball_queries == 0  # bit-identical copies: the sort alone
    # 20 000 distinct points within 1e-9 of a corner: the corner asks for its ball once and
    # takes them all; none of them asks again (not 2e8 pairs, not 20 000 queries)
    jitter = SQUARE[2] + 1e-9 * np.random.default_rng(0).uniform(-1, 1, (20_000, 2))
    data, index = guard.pslg(np.vstack([SQUARE, jitter]), RING4, 1e-6, return_index=True)
    assert data["vertices"].tolist() == SQUARE.tolist() and np.all(index[4:] == 2)
    assert _CountingTree.ball_queries == 1


def test_duplicate_and_reversed_segments_are_dropped_keeping_the_first():
    data = guard.pslg(SQUARE, np.array([[0, 1], [1, 0], [1, 2], [2, 3], [0, 1], [3, 0], [2, 2]]), 0.0)
    assert data["segments"].tolist() == [[0, 1], [1, 2], [2, 3], [3, 0]]


@pytest.mark.parametrize("V, S, words", [
    # a bowtie: its two diagonals cross at (0.5, 0.5)
    ([[0, 0], [1, 1], [1, 0], [0, 1]], [[0, 1], [1, 2], [2, 3], [3, 0]], "two segments that cross near (0.5, 0.5)"),
    # a T: vertex 4 at (0.5, 0) is on the bottom edge, which does not end there
    ([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [0.5, 0.5]], [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5]],
     "point at (0.5, 0) on the segment from (0, 0) to (1, 0)"),
    # a spike: 2 -> 3 runs back along 1 -> 2 (the segments overlap)
    ([[0, 0], [1, 0], [1, 1], [1, 0.5], [0, 1]], [[0, 1], [1, 2], [2, 3], [3, 4], [4, 0]], "on the segment from"),
    # two diagonals crossing
    ([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 2], [1, 3]], "cross near (0.5, 0.5)"),
    # a free vertex (no segment of its own) on a diagonal
    ([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]], [[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]],
     "point at (0.5, 0.5) on the segment from (0, 0) to (1, 1)"),
])
def test_crossing_touching_and_overlapping_segments_are_refused(V, S, words):
    with pytest.raises(GeometryError) as err:
        guard.pslg(np.array(V, float), np.array(S), 0.0)
    assert words in _one_sentence(err.value)


def test_a_near_miss_is_refused_within_the_tolerance_and_accepted_beyond_it():
    V = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 1e-6], [0.5, 0.5]])
    S = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [4, 5]])
    with pytest.raises(GeometryError, match="closer than 1e-05"):
        guard.pslg(V, S, 1e-5)
    data = guard.pslg(V, S, 1e-7)
    out = triangle.triangulate(data, "pQ")
    assert len(out["vertices"]) == 6 and _area(out) == pytest.approx(1.0)


def test_a_refused_graph_names_the_input_points_and_segments_at_fault():
    # a T: input point 5 (its copy 6 merged into it) lies on input segment 1
    V = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [2, 2], [0.5, 0], [0.5, 0], [0.5, 0.5]])
    S = np.array([[0, 1], [0, 1], [1, 2], [2, 3], [3, 0], [6, 7]])  # segment 1 repeats 0: dropped
    with pytest.raises(guard.PslgError) as err:
        guard.pslg(V, S, 0.0)
    assert err.value.points == (5,) and err.value.segments == (0,) and err.value.at.tolist() == [0.5, 0.0]
    # two crossing chords, given after the ring: rows 4 and 5
    V = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    with pytest.raises(guard.PslgError) as err:
        guard.pslg(V, np.vstack([RING4, [[0, 2], [1, 3]]]), 0.0)
    assert err.value.points == () and err.value.segments == (4, 5) and err.value.at.tolist() == [0.5, 0.5]
    assert isinstance(err.value, GeometryError) and "cross near (0.5, 0.5)" in _one_sentence(err.value)


@pytest.mark.parametrize("V, S, words", [
    ([[0, 0], [1, 0]], [[0, 1]], "2 distinct points"),
    ([[0, 0], [0, 0], [0, 0], [0, 0]], None, "1 distinct points"),
    ([[0, 0], [1, 1], [2, 2], [3, 3]], [[0, 3]], "one straight line"),
    ([[0, 0], [1, 0], [0, 1]], [[0, 1], [1, 7]], "point 7, outside 0..2"),
    ([[0, 0], [1, 0], [0, 1]], [[0.0, 1.0]], "must be integers"),
    ([[0, 0], [1, 0], [np.nan, 1]], [[0, 1]], "not a finite number"),
])
def test_what_triangle_would_reject_or_misread_is_refused(V, S, words):
    with pytest.raises(GeometryError) as err:
        guard.pslg(np.array(V, float), S, 0.0, what="the test graph")
    msg = _one_sentence(err.value)
    assert msg.startswith("the test graph") and words in msg


def test_pslg_without_segments_is_a_point_set():
    data = guard.pslg(SQUARE, None, 0.0)
    assert set(data) == {"vertices"}  # Triangle rejects an empty segment array
    assert _area(triangle.triangulate(data, "Q")) == pytest.approx(1.0)


def test_triangulate_polygon_refuses_what_it_cannot_mesh_in_order():
    with pytest.raises(GeometryError, match=r"two points closer than 1e-09 drawing units near \(0, 0\)"):
        triangulate_polygon(np.vstack([SQUARE, SQUARE[:1] + 1e-13]), 0.3)
    with pytest.raises(GeometryError, match="^the outline has a point that is not a finite number"):
        triangulate_polygon([[0, 0], [1, 0], [np.nan, 1]], 0.3)
    with pytest.raises(GeometryError, match="^the outline must be an array of shape"):
        triangulate_polygon(np.zeros((4, 3)), 0.3)
    with pytest.raises(GeometryError, match="cross"):
        triangulate_polygon(np.array([[0, 0], [1, 1], [1, 0], [0, 1]], float), 0.3)
    tri = triangulate_polygon(SQUARE, 0.3)  # clean input: unchanged contract
    assert np.array_equal(tri.V2[:4], SQUARE) and tri.boundary.tolist() == [0, 1, 2, 3]


# --- mesh (libigl) ----------------------------------------------------------------------------


def test_mesh_coerces_faces_once_and_refuses_what_igl_would_crash_on():
    V = np.array([[0.0, 0], [1, 0], [0, 1], [1, 1]])
    F = np.array([[0, 1, 2], [1, 3, 2]], dtype=np.int32)
    V2, F2 = guard.mesh(V, F[:, :].T.copy().T)  # a non-contiguous int32 F
    assert F2.dtype == np.int64 and F2.flags.c_contiguous and np.array_equal(F2, F) and V2.shape == (4, 2)
    for bad_F, words in (([[0, 1, 4]], "point 4, outside 0..3"),   # igl.cotmatrix segfaults on this
                         ([[0, 1, -1]], "point -1"),
                         ([[0.0, 1.0, 2.0]], "must be integers"),
                         ([[0, 1]], "shape (k, 3)"),
                         ([[0, 1, 1]], "zero area in the drawing plane (triangle 0"),
                         ([[0, 1, 2], [0, 3, 3]], "zero area in the drawing plane (triangle 1")):
        with pytest.raises(GeometryError) as err:
            guard.mesh(V, np.array(bad_F), "the layer's mesh")
        assert _one_sentence(err.value).startswith("the layer's mesh") and words in str(err.value)


def test_zero_area_is_measured_where_the_vertices_live():
    flat = np.array([[0.0, 0], [1, 0], [2, 0]])  # collinear in the plane: infinite cotangents
    with pytest.raises(GeometryError, match="zero area in the drawing plane"):
        laplacian_and_mass(flat, np.array([[0, 1, 2]]))
    wall = np.array([[0.0, 0, 0], [1, 0, 0], [0, 0, 1]])  # vertical in 3D: a fine surface triangle
    L, M = laplacian_and_mass(wall, np.array([[0, 1, 2]]))
    assert np.isfinite(L.toarray()).all() and M.diagonal().sum() == pytest.approx(0.5)
    sliver = np.array([[0.0, 0], [1, 0], [0.5, 1e-13]])  # 2·area / longest² = 1e-13 <= AREA_TOL
    with pytest.raises(GeometryError):
        guard.mesh(sliver, [[0, 1, 2]])
    guard.mesh(np.array([[0.0, 0], [1, 0], [0.5, 1e-6]]), [[0, 1, 2]])  # thin, not degenerate


# --- sparse systems and the QP ----------------------------------------------------------------


def test_sparse_system_checks_shapes_values_and_singular_free_rows():
    A = sp.csc_matrix(np.array([[2.0, -1, 0], [-1, 2, 0], [0, 0, 0]]))
    with pytest.raises(GeometryError, match="row 2 of the matrix is all zeros"):
        guard.sparse_system(A, "the system")
    # the empty row is fixed, so eliminated: fine
    A2, fixed = guard.sparse_system(A, "the system", fixed=[2, 2])
    assert fixed.tolist() == [2] and A2.format == "csc" and A2.dtype == np.float64
    for args, kw, words in (((np.ones((2, 3)),), {}, "square"),
                            ((sp.csc_matrix(np.diag([1.0, np.nan])),), {}, "not a finite number"),
                            ((np.eye(3),), {"fixed": [0, 3]}, "point 3, outside 0..2")):
        with pytest.raises(GeometryError) as err:
            guard.sparse_system(*args, **kw)
        assert words in _one_sentence(err.value)


def test_dirichlet_solver_refuses_an_unused_vertex_instead_of_factoring_a_singular_matrix():
    V = np.array([[0.0, 0], [1, 0], [0, 1], [5, 5]])  # vertex 3: used by no triangle
    L, M = laplacian_and_mass(V, np.array([[0, 1, 2]]))
    with pytest.raises(GeometryError, match="row 3 .* all zeros"):
        DirichletSolver(-L, [0, 1])
    x = DirichletSolver(-L + sp.eye(4), [0, 1]).solve(np.ones(4))
    assert np.isfinite(x).all()
    with pytest.raises(GeometryError, match="right-hand side"):
        DirichletSolver(-L + sp.eye(4), [0, 1]).solve([1.0, np.nan, 0.0, 0.0])
    with pytest.raises(GeometryError, match="outside"):
        DirichletSolver(-L + sp.eye(4), [0, 9])


def test_qp_checks_shapes_values_and_bounds():
    P, q, A = sp.eye(2), np.zeros(2), sp.csc_matrix(np.array([[1.0, 0], [0, 1], [1, 1]]))
    l, u = np.array([0.0, -np.inf, 1.0]), np.array([1.0, 2.0, np.inf])
    out = guard.qp(P, q, A, l, u, "the QP")
    assert out[0].format == "csc" and out[3].tolist() == l.tolist() and out[4].tolist() == u.tolist()
    for args, words in (((P, [0.0, np.nan], A, l, u), "linear term of the QP"),
                        ((P, q, A, [0.0, np.nan, 1.0], u), "NaN"),
                        ((P, q, A, [np.inf, 0, 0], u), "+inf"),
                        ((P, q, A, l, [1.0, -np.inf, 1.0]), "-inf"),
                        ((P, q, A, [2.0, 0, 0], u), "row 0 has lower bound 2 above its upper bound 1"),
                        ((P, q, A[:, :1], l, u), "1 columns for 2 unknowns"),
                        ((P, q, A, l[:2], u), "2 lower bounds for 3 constraint rows"),
                        ((sp.csc_matrix(np.diag([1.0, np.inf])), q, A, l, u), "not a finite number")):
        with pytest.raises(GeometryError) as err:
            guard.qp(*args, what="the QP")
        assert words in _one_sentence(err.value)


def test_depth_solve_refuses_a_nan_before_osqp_sees_it():
    from sketchforge_assemble.depth import solve_depth

    P = sp.eye(2, format="csc")
    Ain, bin_ = sp.csr_matrix(np.array([[1.0, -1.0]])), np.array([0.1])
    x, _ = solve_depth(P, np.zeros(2), sp.csr_matrix((0, 2)), np.zeros(0), Ain, bin_)
    assert x[0] - x[1] >= 0.1 - 1e-9
    for method in ("osqp", "active_set"):
        with pytest.raises(GeometryError, match="the depth-order problem"):
            solve_depth(P, np.array([0.0, np.nan]), sp.csr_matrix((0, 2)), np.zeros(0), Ain, bin_, method=method)


# --- shapely / GEOS ---------------------------------------------------------------------------


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")  # shapely, building the NaN line
def test_geometry_repairs_polygons_and_refuses_what_geos_cannot_compute_with():
    good = shapely.Polygon(SQUARE)
    assert guard.geometry(good) is good  # valid input passes untouched
    bowtie = guard.polygon([[0, 0], [1, 1], [1, 0], [0, 1]], "the outline")
    assert bowtie.is_valid and bowtie.geom_type == "MultiPolygon" and bowtie.area == pytest.approx(0.5)
    spike = guard.polygon([[0, 0], [1, 0], [1, 1], [1, 2], [1, 1], [0, 1]], "the outline")
    assert spike.is_valid and spike.geom_type == "Polygon" and spike.area == pytest.approx(1.0)
    with pytest.raises(GeometryError, match="not a finite number"):
        guard.geometry(shapely.LineString([[0, 0], [np.nan, 1]]), "the junction")
    with pytest.raises(GeometryError, match="reaching 1e\\+200"):
        guard.geometry(shapely.Polygon([[0, 0], [1e200, 0], [0, 1]]), "the outline")
    with pytest.raises(GeometryError, match="fewer than 3 distinct points"):
        guard.polygon([[0, 0], [1, 1], [0, 0], [1, 1]], "the outline")
    with pytest.raises(GeometryError, match="fewer than 2 distinct points"):
        guard.linestring([[1, 1], [1, 1]], "the junction of layer 'arm'")
    with pytest.raises(GeometryError, match="is not a valid LineString"):
        guard.geometry(shapely.LineString([[1, 1], [1, 1]]), "the junction")


def test_assembly_refuses_hand_edited_meshes_with_one_sentence():
    from sketchforge_assemble import assemble_meshes

    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.3, 0.2]])
    F = np.array([[0, 1, 3], [1, 2, 3], [2, 0, 3]])
    ok = assemble_meshes([Mesh(V, F, np.array([0, 1, 2]))], [True])
    assert ok.n_faces > 0
    for bad_V, bad_F in ((np.where(np.arange(12).reshape(4, 3) == 9, 1e300, V), F),  # huge coordinate
                         (np.where(np.arange(12).reshape(4, 3) == 9, np.nan, V), F),  # NaN
                         (V, np.vstack([F, [[0, 1, 1]]]))):  # a zero-area triangle
        with pytest.raises(GeometryError) as err:
            assemble_meshes([Mesh(bad_V, bad_F, np.array([0, 1, 2]))], [True])
        assert "the mesh of layer 'layer 0'" in _one_sentence(err.value)  # the default name


def test_mesh_measures_area_in_the_plane_when_asked():
    wall = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 0, 1]])  # vertical: fine in 3D, flat in the plane
    guard.mesh(wall, [[0, 1, 2]])
    with pytest.raises(GeometryError, match="zero area in the drawing plane"):
        guard.mesh(wall, [[0, 1, 2]], "the height field", planar=True)


def test_the_maximum_area_says_which_number_is_wrong():
    for bad in (float("inf"), float("nan"), -1.0):
        with pytest.raises(GeometryError) as err:
            _format_area(bad)
        msg = _one_sentence(err.value)
        assert "is not a finite positive number" in msg and "too fine" not in msg
    with pytest.raises(GeometryError, match="is 0, so the resolution is too fine"):
        _format_area(0.0)
    assert _format_area(0.5) == "0.5"


def test_band_keeps_its_sculpt_error_for_an_outline_without_area_and_the_guards_for_bad_numbers():
    line = np.array([[0.0, 0], [0.5, 0]])
    with pytest.raises(SculptError, match="no outline to clip the band to"):
        band(line, 0.1, np.array([[0.0, 0], [1, 1], [0, 0], [1, 1]]))
    with pytest.raises(GeometryError, match="^the layer's outline has a point that is not a finite number"):
        band(line, 0.1, np.array([[0.0, 0], [1, 0], [np.nan, 1]]))
    assert band(line, 0.1, 2 * SQUARE - 1).area > 0


def test_dirichlet_solver_says_so_when_the_free_block_is_not_positive_definite():
    A = sp.diags([1.0, -1.0, 1.0]).tocsc()  # free block diag(-1, 1): indefinite
    with pytest.raises(SolverError) as err:
        DirichletSolver(A, [0], "the test system")
    assert _one_sentence(err.value) == (
        "the test system could not be factorised (it is not positive definite on the free vertices)"
    )


def test_active_set_alone_solves_a_problem_without_glue_rows():
    from sketchforge_assemble.depth import solve_depth

    # min ½|x|² with x0 - x1 >= 0.1: the row is active, x = (0.05, -0.05). No glue rows: the
    # working set holds depth rows only (its minimiser indexed the empty glue arrays).
    P = sp.eye(2, format="csc")
    Ain, bin_ = sp.csr_matrix(np.array([[1.0, -1.0]])), np.array([0.1])
    x, info = solve_depth(P, np.zeros(2), sp.csr_matrix((0, 2)), np.zeros(0), Ain, bin_, method="active_set")
    assert x == pytest.approx([0.05, -0.05], abs=1e-12) and info["active"] == 1 and info["iterations"] >= 1
    for bad in ((Ain, np.array([np.nan])), (sp.csr_matrix(np.array([[1.0, np.inf]])), bin_)):
        with pytest.raises(GeometryError, match="^the depth-order problem"):
            solve_depth(P, np.zeros(2), sp.csr_matrix((0, 2)), np.zeros(0), *bad, method="active_set")


def test_objective_and_constraints_check_the_parts_of_a_qp():
    P, q = guard.objective(np.eye(2), [1.0, 2.0], "the QP")
    assert P.format == "csc" and q.tolist() == [1.0, 2.0]
    A, l, u = guard.constraints(np.array([[1.0, 0]]), [0.0], None, 2, "the QP", fmt="csr")
    assert A.format == "csr" and l.tolist() == [0.0] and u is None
    for args, words in (((np.array([[1.0, 0]]), [np.inf], None, 2), "+inf"),
                        ((np.array([[1.0, 0]]), None, [-np.inf], 2), "-inf"),
                        ((np.array([[1.0, 0]]), [0.0], None, 3), "2 columns for 3 unknowns")):
        with pytest.raises(GeometryError) as err:
            guard.constraints(*args, what="the QP")
        assert words in _one_sentence(err.value)


# --- the assembly's messages name the real culprit ---------------------------------------------


def _assemble_pair(body, head, **params):
    from sketchforge_assemble.assemble import assemble_detailed

    return assemble_detailed([body, head], [True, False], params, names=["Body", "Head"])


@pytest.fixture(scope="module")
def pair():
    return _damaged_pair()


def _repeat_a_point(j):
    return np.insert(j, 2, j[2])


def _turn_back(j):
    j = np.array(j)
    j[2], j[3] = j[3], j[2]  # a zigzag: the junction turns back along itself
    return j


@pytest.mark.parametrize("bend, message", [
    (_repeat_a_point, "The junction of layer 'Head' has two points closer than"),
    (_turn_back, "The junction of layer 'Head' touches itself near"),
])
def test_a_broken_junction_is_blamed_not_the_outline(pair, bend, message):
    from sketchforge_assemble.errors import AttachmentError

    body, head = pair
    broken = Mesh(head.V, head.F, head.boundary, bend(head.junction))
    with pytest.raises(AttachmentError) as err:
        _assemble_pair(body, broken, on_bad_junction="raise")
    msg = _one_sentence(err.value)
    assert msg.startswith(message) and "outline" not in msg
    # by default the head is assembled free, and the warning says why (issue 34)
    res = _assemble_pair(body, broken)
    assert res.free == [1] and len(res.warnings) == 1 and message[0].lower() + message[1:] in res.warnings[0]


def test_two_coinciding_vertices_of_the_lower_layer_are_blamed_on_that_layer(pair):
    from sketchforge_assemble.errors import AttachmentError

    body, head = pair
    V = np.array(body.V)
    interior = np.setdiff1d(np.arange(len(V)), body.boundary)
    low = interior[V[interior, 1] < -0.3]  # far from the head's junction (y ~ 0.48)
    a = low[0]
    b = next(v for v in low[1:] if not np.any(np.isin(body.F, [a, v]).sum(axis=1) == 2))  # not a neighbour
    V[b, :2] = V[a, :2]
    with pytest.raises(AttachmentError) as err:
        _assemble_pair(Mesh(V, body.F, body.boundary), head, on_bad_junction="raise")
    msg = _one_sentence(err.value)
    assert msg.startswith("Two vertices of layer 'Body' are closer than") and "junction" not in msg
    # by default the head, which could not be cut in, is free and the model is assembled
    res = _assemble_pair(Mesh(V, body.F, body.boundary), head)
    assert res.free == [1] and "two vertices of layer 'Body' are closer than" in res.warnings[0]


def test_a_layer_flat_in_the_plane_is_refused_once_by_name(pair):
    body, head = pair
    V = np.array(head.V)
    f = head.F[0]
    V[f[2], :2] = 0.5 * (V[f[0], :2] + V[f[1], :2])  # zero area in the plane, not in 3D (z differs)
    assert np.linalg.norm(np.cross(V[f[1]] - V[f[0]], V[f[2]] - V[f[0]])) > 1e-6
    with pytest.raises(GeometryError) as err:
        _assemble_pair(body, Mesh(V, head.F, head.boundary, head.junction))
    msg = _one_sentence(err.value)
    assert msg.startswith("the mesh of layer 'Head' has a triangle of zero area in the drawing plane"), msg


def test_a_one_point_junction_is_a_junction_problem_not_a_crash(pair):
    from sketchforge_assemble.errors import AttachmentError

    body, head = pair
    one = Mesh(head.V, head.F, head.boundary, np.repeat(head.junction[:1], 2))  # both ends at one vertex
    result = _assemble_pair(body, one, on_bad_junction="free")
    assert result.attachments == [] and result.components == 2
    assert len(result.warnings) == 1
    assert result.warnings[0].startswith("the junction of layer 'Head' has fewer than 2 distinct points")
    with pytest.raises(AttachmentError) as err:
        _assemble_pair(body, one, on_bad_junction="raise")
    assert _one_sentence(err.value).startswith("The junction of layer 'Head' has fewer than 2 distinct points")


# --- property tests: hostile polylines at every entry point, in a child process ---------------

#: Outcome counts of the property loops, printed by the child (the parent checks that both
#: results and refusals happened, so the generator really reaches the native calls).
OUTCOMES: Counter = Counter()


def _outcome(kind: str, fn):
    try:
        result = fn()
    except SketchforgeError as exc:
        _one_sentence(exc)
        OUTCOMES[f"{kind}: {type(exc).__name__}"] += 1
        return None
    OUTCOMES[f"{kind}: {'result' if result is not None else 'None'}"] += 1
    return result


MUTATIONS = ("dup", "near", "spike", "collinear", "on_segment", "loop", "tiny", "reverse")


def _mutate(P: np.ndarray, m: str, rng) -> np.ndarray:
    n = len(P)
    i = int(rng.integers(n))
    if m == "dup":  # exact copies, right after the point or somewhere else
        k = int(rng.integers(1, 4))
        at = i + 1 if rng.random() < 0.5 else int(rng.integers(n + 1))
        return np.insert(P, at, np.repeat(P[i:i + 1], k, axis=0), axis=0)
    if m == "near":  # 1e-12 of the size apart
        d = rng.normal(size=2)
        return np.insert(P, i + 1, P[i] + 1e-12 * d / np.linalg.norm(d), axis=0)
    if m == "spike":  # turn back along the segment just drawn
        t = rng.uniform(0.2, 0.8)
        return np.insert(P, i + 1, P[i] + t * (P[i - 1] - P[i]), axis=0)
    if m == "collinear":  # a run of points on one segment
        j = (i + 1) % n
        t = np.linspace(0, 1, int(rng.integers(3, 8)))[1:-1, None]
        return np.insert(P, i + 1, P[i] + t * (P[j] - P[i]), axis=0)
    if m == "on_segment":  # a point exactly on top of another segment
        j = (i + n // 2) % n
        return np.insert(P, i + 1, 0.5 * (P[j] + P[(j + 1) % n]), axis=0)
    if m == "loop":  # reverse a stretch: a figure eight
        a, b = sorted(rng.choice(n + 1, 2, replace=False))
        Q = P.copy()
        Q[a:b] = Q[a:b][::-1]
        return Q
    if m == "tiny":  # the whole stroke collapses to a few ulps
        return P[0] + 1e-15 * (P - P[0])
    return P[::-1].copy()


@st.composite
def polylines(draw, scaled: bool = True):
    """(k, 2) float64: a star-shaped ring, an open arc or random points, then up to three
    mutations (duplicates, near duplicates 1e-12 apart, spikes, collinear runs, points on other
    segments, loops), scaled from 1e-9 to 1e9 and sometimes given a NaN, inf or huge value."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n = draw(st.integers(3, 24))
    kind = draw(st.sampled_from(["star", "arc", "random"]))
    if kind == "random":
        P = rng.uniform(-1, 1, (n, 2))
    else:
        span = 2 * np.pi if kind == "star" else rng.uniform(0.8, 1.6) * np.pi
        t = np.sort(rng.uniform(0, span, n))
        r = rng.uniform(0.4, 1.0, n)
        P = np.c_[r * np.cos(t), r * np.sin(t)]
    for m in draw(st.lists(st.sampled_from(MUTATIONS), max_size=3)):
        P = _mutate(P, m, rng)
    if scaled:
        P = P * draw(st.sampled_from([1e-9, 1e-6, 1.0, 1.0, 1e3, 4e8])) + draw(st.sampled_from([0.0, 0.0, 3.0, 5e8]))
    special = draw(st.sampled_from([None] * 8 + ["nan", "inf", "huge"]))
    if special is not None:
        P[int(rng.integers(len(P)))] = {"nan": np.nan, "inf": np.inf, "huge": 1e200}[special]
    return P


PROPERTY = dict(derandomize=True, deadline=None, database=None, suppress_health_check=list(HealthCheck))


@settings(max_examples=400, **PROPERTY)
@given(P=polylines(), closed=st.booleans(), extra=st.integers(0, 3), tol=st.sampled_from([None, 0.0, 1e-3]),
       opts=st.sampled_from(["pQ", "pYQ", "pq20YQ"]), seed=st.integers(0, 2**16))
def _pslg_then_triangle(P, closed, extra, tol, opts, seed):
    """guard.pslg, then a real triangle.triangulate on whatever it accepts."""
    rng = np.random.default_rng(seed)
    n = len(P)
    S = np.c_[np.arange(n), (np.arange(n) + 1) % n][: n if closed else n - 1]
    S = np.vstack([S, rng.integers(0, n, (extra, 2))])  # random chords: more crossings
    finite = P[np.isfinite(P).all(axis=1)]
    t = None if tol is None else tol * float(np.ptp(finite, axis=0).max() if len(finite) else 1.0)
    data = _outcome("pslg", lambda: guard.pslg(P, S, t, what="the random graph"))
    if data is None:
        return
    V = data["vertices"]
    assert np.isfinite(V).all() and len(V) >= 3
    assert data["segments"].dtype == np.int32 and data["segments"].min() >= 0 and data["segments"].max() < len(V)
    out = _outcome("triangle", lambda: triangle.triangulate(data, opts))
    assert np.isfinite(out["vertices"]).all()
    if opts == "pQ":
        # No crossing, no vertex on a segment: a constrained Delaunay triangulation adds nothing.
        assert len(out["vertices"]) == len(V)
    if "triangles" in out:
        assert out["triangles"].min() >= 0 and out["triangles"].max() < len(out["vertices"])


@settings(max_examples=120, **PROPERTY)
@given(P=polylines(), closed=st.booleans(), edges=st.sampled_from([6, 12, 20]))
def _inflate(P, closed, edges):
    """The inflate plugin's entry point (a real Triangle, libigl and fairing run)."""
    from sketchforge_inflate.inflate import inflate_stroke

    finite = P[np.isfinite(P).all(axis=1)]
    extent = float(np.ptp(finite, axis=0).max()) if len(finite) else 1.0
    resolution = extent / edges if extent > 0 else 1.0  # a few hundred vertices at most
    mesh = _outcome("inflate", lambda: inflate_stroke(P, closed, {"resolution": resolution}, max_vertices=4000))
    if mesh is not None:
        assert np.isfinite(mesh.V).all() and mesh.n_faces > 0


@settings(max_examples=50, **PROPERTY)
@given(layers=st.lists(st.tuples(polylines(scaled=False), st.booleans(), st.sampled_from([0.0, 0.4, 0.9])),
                       min_size=2, max_size=3),
       scale=st.sampled_from([1e-6, 1.0, 1e3]))
def _assembly(layers, scale):
    """A document of two or three random layers (add_layer, set_contour), then the assembly
    hook through Document.assembled (Triangle again, libigl, OSQP, GEOS)."""
    from sketchforge.document import Document
    from sketchforge.plugins.testing import make_test_host

    doc = Document(host=make_test_host(entry_points=True, allowlist=["inflate", "assemble"]))
    for k, (P, closed, shift) in enumerate(layers):
        doc.execute({"command": "add_layer", "id": f"l{k}"})
        doc.execute({"command": "set_inflate_params", "layer": f"l{k}", "params": {"resolution": 0.15 * scale}})
        pts = (P + [shift, 0.5 * shift]) * scale
        _outcome("set_contour", lambda: doc.execute(
            {"command": "set_contour", "layer": f"l{k}", "points": pts.tolist(), "closed": closed}))  # noqa: B023 - called in this iteration
    mesh = _outcome("assemble", doc.assembled)
    if mesh is not None:
        assert np.isfinite(mesh.V).all()


def _damaged_pair():
    """Two overlapping inflated layers, a body and an open part whose junction lies on it."""
    from sketchforge_inflate.inflate import inflate_stroke

    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    body = inflate_stroke(np.c_[np.cos(t), 0.7 * np.sin(t)], True, {"resolution": 0.2})
    a = np.linspace(-0.3 * np.pi, 1.3 * np.pi, 30)
    head = inflate_stroke(np.c_[0.4 * np.cos(a), 0.8 + 0.4 * np.sin(a)], False, {"resolution": 0.1})
    return body, head


DAMAGE = ("collapse_face", "merge_vertices", "duplicate_boundary", "huge", "tiny", "nan", "flip_faces",
          "drop_face", "spike_vertex")


def _damage(mesh: Mesh, kind: str, rng) -> Mesh:
    V, F, b, j = np.array(mesh.V), np.array(mesh.F), np.array(mesh.boundary), np.array(mesh.junction)
    i = int(rng.integers(len(V)))
    if kind == "collapse_face":  # one corner moved onto another: a zero-area triangle
        f = F[int(rng.integers(len(F)))]
        V[f[0]] = V[f[1]]
    elif kind == "merge_vertices":  # two vertices at one place (a duplicate Triangle would drop)
        V[i, :2] = V[(i + 1) % len(V), :2]
    elif kind == "duplicate_boundary":  # the outline visits a vertex twice
        b = np.insert(b, 1, b[0])
    elif kind == "huge":
        V[i, :2] *= 1e12
    elif kind == "tiny":
        V *= 1e-150
    elif kind == "nan":
        V[i, int(rng.integers(3))] = np.nan
    elif kind == "flip_faces":
        F = F[:, ::-1].copy()
    elif kind == "drop_face":  # a hole in the mesh, a vertex possibly left unused
        F = np.delete(F, int(rng.integers(len(F))), axis=0)
    elif kind == "spike_vertex":  # an interior vertex pulled across the outline
        V[i, :2] = 3.0 * V[i, :2]
    return Mesh(V, F, b, j)


@settings(max_examples=50, **PROPERTY)
@given(kinds=st.lists(st.tuples(st.sampled_from(DAMAGE), st.integers(0, 1)), min_size=1, max_size=2),
       seed=st.integers(0, 2**16))
def _assembly_of_damaged_meshes(kinds, seed):
    """The assembly hook on hand-edited (snapshot) meshes: geometry no stroke could produce."""
    from sketchforge.document.layer import Layer
    from sketchforge_assemble.plugin import assemble_layers

    global _PAIR
    if "_PAIR" not in globals():
        _PAIR = _damaged_pair()
    rng = np.random.default_rng(seed)
    meshes = list(_PAIR)
    for kind, which in kinds:
        meshes[which] = _damage(meshes[which], kind, rng)
    layers = [Layer("body", "Body", mesh=meshes[0], closed=True), Layer("head", "Head", mesh=meshes[1])]
    mesh = _outcome("damaged", lambda: assemble_layers(layers, {}))
    if mesh is not None:
        assert np.isfinite(mesh.V).all()


def _run_isolated(name: str, timeout: float = 240.0) -> Counter:
    """Run the hypothesis loop ``name`` of this module in a fresh interpreter; fail on a
    non-zero exit (a crash shows as a negative status: -11 is SIGSEGV)."""
    code = (f"import sys; sys.path.insert(0, {str(HERE)!r}); import test_guard as t; "
            f"t.{name}(); print(dict(t.OUTCOMES))")
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
    proc = subprocess.run([sys.executable, "-X", "faulthandler", "-c", code], capture_output=True, text=True,
                          timeout=timeout, cwd=HERE.parent, env=env)
    assert proc.returncode == 0, (
        f"{name} exited with status {proc.returncode} (negative: killed by that signal; -11 = SIGSEGV)\n"
        f"--- stdout ---\n{proc.stdout[-4000:]}\n--- stderr ---\n{proc.stderr[-6000:]}"
    )
    return Counter(ast.literal_eval(proc.stdout.strip().splitlines()[-1]))  # the child's dict of counts


def test_random_graphs_through_the_guard_never_crash_triangle():
    seen = _run_isolated("_pslg_then_triangle")
    assert seen["pslg: GeometryError"] > 20 and seen["pslg: PslgError"] > 20 and seen["triangle: result"] > 20, seen


def test_random_strokes_inflate_or_fail_with_one_sentence():
    seen = _run_isolated("_inflate")
    assert seen["inflate: result"] > 5 and sum(v for k, v in seen.items() if "Error" in k) > 5, seen


def test_random_documents_assemble_or_fail_with_one_sentence():
    # issue 34: every document whose layers inflate assembles (a part that cannot be glued is
    # assembled free), so no assembly is refused at all
    seen = _run_isolated("_assembly")
    refused = sum(v for k, v in seen.items() if k.startswith("assemble: ") and k.endswith("Error"))
    assert seen["assemble: result"] > 3 and refused == 0, seen


def test_damaged_meshes_assemble_or_fail_with_one_sentence():
    seen = _run_isolated("_assembly_of_damaged_meshes")
    assert seen["damaged: GeometryError"] > 3 and seen["damaged: result"] > 3, seen
