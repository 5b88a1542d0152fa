"""Placing a part (sketchforge.geometry.parts) and merging meshes (sketchforge.geometry.merge),
checked against definitions rather than against the code.

These tests come from mutants of parts.py and merge.py that the rest of the suite did not
kill. What they pin down:

- splice_outline, on every pair of outline points of random outlines, equals the redraw built
  from its docstring: of a closed outline the shorter of the two stretches between the stroke's
  ends (lengths summed edge by edge here) gives way to the stroke, of an open one the stretch
  between them; strokes of two points, triangles and a tolerance of zero included. The cases
  that are not a redraw return None.
- overlapped, chord_touches and part_at skip parts without a usable outline and go on looking,
  count a triangle as an outline, answer "positive area" / "more than a point" the same at every
  drawing scale, and keep their documented return types.
- merge_meshes of no meshes is the empty mesh, and of several keeps every mesh's triangles.
"""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge.geometry.merge import merge_meshes
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.parts import chord_touches, overlapped, part_at, splice_outline

SCALES = [1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e6]
# 3 entries but 2 distinct points: no region at all (the guard refuses it), unlike None
NO_REGION = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0]])


def ring(r=0.5, c=(0.0, 0.0), n=60):
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.c_[c[0] + r * np.cos(t), c[1] + r * np.sin(t)]


def box(x0, y0, x1, y1):
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


# --------------------------------------------------------------------------- splice_outline


def star_outline(rng, n):
    """A simple polygon: n points at sorted random angles and random radii, at a random scale
    (0.01 .. 100) and position, so edge lengths differ and no two stretches tie."""
    t = np.sort(rng.uniform(0.0, 2 * np.pi, n))
    r = rng.uniform(0.5, 1.5, n)
    scale = 10.0 ** rng.uniform(-2, 2)
    return scale * np.c_[r * np.cos(t), r * np.sin(t)] + rng.uniform(-5, 5, 2) * scale


def walk(P, a, b):
    """Indices a, a+1, ..., b along a closed outline (wrapping) and the length of that walk."""
    n = len(P)
    idx = [a]
    while idx[-1] != b:
        idx.append((idx[-1] + 1) % n)
    length = sum(float(np.hypot(*(P[q] - P[p]))) for p, q in zip(idx[:-1], idx[1:]))
    return idx, length


def same_ring(A, B):
    """Equal as closed rings: B is A started at another point (same direction)."""
    if A.shape != B.shape:
        return False
    return any(np.array_equal(np.roll(A, -k, axis=0), B) for k in range(len(A)))


def stroke_between(rng, a, b, k):
    """k points from a to b through random points (their position does not matter)."""
    return np.vstack([a, rng.normal(size=(k - 2, 2)), b]) if k > 2 else np.vstack([a, b])


def expected_closed(P, i, j, S):
    fwd, Lf = walk(P, i, j)  # the stretch i -> j along the outline's order
    back, Lb = walk(P, j, i)
    assert abs(Lf - Lb) > 1e-9 * (Lf + Lb), "a tie: both stretches are the shorter one"
    if Lf < Lb:  # i..j gives way; the stroke runs i -> j in the outline's direction
        gone, oriented = set(fwd), S
    else:  # j..i gives way; in the outline's direction the stroke runs j -> i
        gone, oriented = set(back), S[::-1]
    end = (fwd if Lf < Lb else back)[-1]
    kept = [(end + 1 + q) % len(P) for q in range(len(P)) if (end + 1 + q) % len(P) not in gone]
    return np.vstack([oriented, P[kept]])


@pytest.mark.parametrize("seed", range(3))
def test_closed_splice_replaces_the_shorter_stretch_for_every_pair_of_ends(seed):
    rng = np.random.default_rng(seed)
    for n in (3, 4, 5, 8, 11):
        P = star_outline(rng, n)
        for i in range(n):
            for j in range(n):
                if i == j:
                    continue
                S = stroke_between(rng, P[i], P[j], int(rng.choice([2, 3, 5])))
                # ends exactly on outline points: "within tol" holds with tol = 0
                got = splice_outline(P, True, S, 0.0)
                want = expected_closed(P, i, j, S)
                assert got is not None and got.dtype == np.float64
                assert same_ring(got, want), (n, i, j)


@pytest.mark.parametrize("seed", range(2))
def test_open_splice_replaces_the_stretch_between_the_ends_for_every_pair(seed):
    rng = np.random.default_rng(10 + seed)
    for n in (3, 4, 7, 10):
        P = star_outline(rng, n)
        for i in range(n):
            for j in range(n):
                if i == j:
                    continue
                S = stroke_between(rng, P[i], P[j], int(rng.choice([2, 3, 5])))
                got = splice_outline(P, False, S, 0.0)
                a, b = min(i, j), max(i, j)
                oriented = S if i < j else S[::-1]  # follows the outline from its start
                want = np.vstack([P[:a], oriented, P[b + 1 :]])
                assert got is not None and np.array_equal(got, want), (n, i, j)


def test_splice_takes_the_stroke_as_drawn_when_its_ends_are_only_near_the_outline():
    rng = np.random.default_rng(5)
    P = star_outline(rng, 9)
    spacing = min(np.linalg.norm(P - np.roll(P, 1, axis=0), axis=1))
    tol = 0.1 * spacing
    for i, j in [(1, 3), (6, 2), (0, 5), (8, 4)]:
        S = stroke_between(rng, P[i] + [0.05 * spacing, 0.0], P[j] - [0.0, 0.05 * spacing], 4)
        got = splice_outline(P, True, S, tol)
        assert same_ring(got, expected_closed(P, i, j, S))


def test_splice_is_not_a_redraw_unless_both_ends_are_on_the_outline_at_two_points():
    P = ring(0.5, n=24)
    tol = 0.01
    mid = [0.9, 0.1]
    for closed in (True, False):
        assert splice_outline(P, closed, np.array([P[2], mid, P[7]]), tol) is not None
        assert splice_outline(P, closed, np.array([P[2], mid, [0.9, 0.9]]), tol) is None  # end off
        assert splice_outline(P, closed, np.array([[0.9, 0.9], mid, P[7]]), tol) is None  # start off
        assert splice_outline(P, closed, np.array([P[2], mid, P[2]]), tol) is None  # one point
        # two points are not an outline, whatever the stroke
        assert splice_outline(P[:2], closed, np.array([P[0], mid, P[1]]), tol) is None


# --------------------------------------------------------------------------- overlapped


def test_overlapped_is_a_bool_per_outline_even_for_a_stroke_that_is_no_region():
    outlines = [ring(0.5), None, ring(0.2, (3.0, 0.0))]
    got = overlapped(ring(0.2, (0.3, 0.0)), outlines)
    assert got.dtype == np.bool_ and got.tolist() == [True, False, False]
    for stroke in ([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0]], [[np.nan, 0.0], [1.0, 0.0], [0.0, 1.0]]):
        got = overlapped(stroke, outlines)
        assert got.dtype == np.bool_ and got.shape == (3,) and not got.any()
    assert overlapped(ring(0.2), []).shape == (0,)


def test_overlapped_skips_unusable_outlines_and_counts_triangles():
    tri = np.array([[0.0, -0.2], [0.6, -0.2], [0.0, 0.4]])
    stroke = ring(0.2, (0.1, 0.0))
    assert overlapped(stroke, [NO_REGION, None, tri]).tolist() == [False, False, True]
    assert overlapped(stroke, [None, NO_REGION, box(-1, -1, 1, 1)]).tolist() == [False, False, True]


def test_zero_area_overlaps_nothing_not_even_zero_area():
    line = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]  # three distinct points on a line: no area
    assert overlapped(line, [[[0.5, 0.0], [1.5, 0.0], [3.0, 0.0]], ring(0.5)]).tolist() == [False, False]


@pytest.mark.parametrize("s", SCALES)
def test_overlap_is_the_same_at_every_drawing_scale(s):
    stroke = ring(0.3, (0.5, 0.0))
    outlines = [ring(0.5), ring(0.3, (3.0, 0.0)), box(0.8, -0.5, 1.8, 0.5), box(-1.5, -1, -0.5, 1)]
    # the first box touches the stroke at the one point (0.8, 0): no area in common
    want = [True, False, False, False]
    assert overlapped(stroke, outlines).tolist() == want
    assert overlapped(s * stroke, [s * P for P in outlines]).tolist() == want
    # two squares sharing an edge meet in a segment, with zero area
    assert overlapped(s * box(0, 0, 1, 1), [s * box(1, 0, 2, 1), s * box(0.5, 0.5, 2, 2)]).tolist() == [False, True]


# --------------------------------------------------------------------------- chord_touches

# an arch from (0.2, 0) up and over to (0.8, 0): its chord is y = 0, 0.2 <= x <= 0.8
ARCH = np.array([[0.2, 0.0], [0.0, 1.0], [1.0, 1.0], [0.8, 0.0]])
STRIP = box(0.4, -1.0, 0.6, 0.05)  # crosses the chord's middle, clear of the arch's sides
TRIANGLE = np.array([[0.5, -1.0], [0.7, 0.05], [0.3, 0.05]])
DIAMOND = np.array([[0.5, 0.0], [0.3, -0.2], [0.5, -0.4], [0.7, -0.2]])  # its top corner on the chord
UNDER = box(0.4, -1.0, 0.6, 0.0)  # its top edge lies on the chord


def test_only_the_chord_from_the_last_point_to_the_first_counts():
    assert chord_touches(ARCH, [STRIP])
    assert chord_touches(ARCH[::-1], [STRIP])
    # the strip lies across nothing but the chord: the stroke's own first and last legs miss it
    assert not chord_touches(ARCH[:3], [STRIP])  # chord (1, 1) -> (0.2, 0)
    assert not chord_touches(ARCH[1:], [STRIP])  # chord (0.8, 0) -> (0, 1)


def test_chord_skips_unusable_outlines_and_counts_triangles():
    assert chord_touches(ARCH, [None, NO_REGION, TRIANGLE])
    assert chord_touches(ARCH, [NO_REGION, None, TRIANGLE])
    assert not chord_touches(ARCH, [None, NO_REGION, box(5, 5, 6, 6)])


@pytest.mark.parametrize("s", SCALES)
def test_more_than_a_point_is_the_same_at_every_drawing_scale(s):
    for outline, want in [(STRIP, True), (UNDER, True), (DIAMOND, False), (box(2, 2, 3, 3), False)]:
        assert chord_touches(s * ARCH, [s * outline]) is want, (outline.tolist(), s)


# --------------------------------------------------------------------------- part_at


def test_part_at_with_no_parts_and_the_frontmost_part():
    assert part_at((0.0, 0.0), []) == -1
    outlines = [ring(0.8), ring(0.2, (0.3, 0.0))]  # the small one is in front
    assert part_at((0.3, 0.0), outlines) == 1
    assert part_at((-0.5, 0.0), outlines) == 0


def test_part_at_skips_unusable_outlines_and_counts_triangles():
    tri = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert part_at((0.2, 0.2), [ring(2.0), tri]) == 1
    assert part_at((0.2, 0.2), [tri, None]) == 0
    assert part_at((0.2, 0.2), [ring(2.0), NO_REGION]) == 0
    assert part_at((0.2, 0.2), [ring(2.0), tri, NO_REGION, None]) == 1


# --------------------------------------------------------------------------- merge_meshes


def test_merging_no_meshes_is_the_empty_mesh():
    m = merge_meshes([])
    assert m.n_vertices == 0 and m.n_faces == 0
    assert m.V.shape == (0, 3) and m.F.shape == (0, 3) and m.F.dtype == np.int64


def fan(c, n, z):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    V = np.c_[np.r_[c[0], c[0] + np.cos(t)], np.r_[c[1], c[1] + np.sin(t)], np.full(n + 1, z)]
    F = np.c_[np.zeros(n, int), 1 + np.arange(n), 1 + (np.arange(n) + 1) % n]
    return Mesh(V, F)


def test_merging_keeps_every_triangle_of_every_mesh():
    meshes = [fan((0, 0), 5, 0.0), fan((3, 0), 7, 1.0), fan((0, 3), 4, 2.0), fan((3, 3), 6, 3.0)]
    m = merge_meshes(meshes)
    assert m.n_vertices == sum(x.n_vertices for x in meshes)
    # every triangle, as its three corner positions in order, is one of a source mesh's
    assert corners(m) == sorted(sum((corners(x) for x in meshes), []))


def corners(mesh):
    return sorted(map(tuple, mesh.V[mesh.F].reshape(-1, 9).tolist()))
