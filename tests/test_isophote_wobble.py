"""Isophotes drawn from the display's normals stay on the exact ones (issue 11, point 2).

Figures on more meshes and at a finer resolution: ``benchmarks/bench_isophotes.py``.
"""

import numpy as np
import pytest

from sketchforge.geometry import gbuffer as gb
from sketchforge.geometry.heightfield import layer_normals
from sketchforge.geometry.isophote_error import InflatedEllipse, line_wobble, polyline_wobble
from sketchforge.geometry.normals import vertex_normals

LIGHT = np.array([np.cos(0.5), np.sin(0.5), 0.0])  # in the plane: the lit rim is where lines broke
SURFACE = InflatedEllipse(1.5, 1.0)


@pytest.fixture(scope="module", params=[120, 2000], ids=["120-point outline", "2000-point outline"])
def mesh(request):
    return SURFACE.mesh(request.param, 0.03)  # the default resolution


def test_drawn_lines_run_on_the_exact_isophotes_in_one_piece(mesh):
    view = gb.View.framing([mesh], 600, 600, 0.05)
    w = line_wobble(SURFACE, mesh, view, LIGHT, 8)
    assert w.centre_pixels > 2500
    # a perfect 1.2 px line has its centre pixels within 0.6 px of the level
    assert w.median < 0.4 and w.p95 < 0.9 and w.max < 3.0, w
    assert w.pieces == w.exact_pieces == (1,) * 8, w
    # the area-weighted vertex normals drew the same levels zig-zagging and in pieces
    old = line_wobble(SURFACE, mesh, view, LIGHT, 8, normals=vertex_normals(mesh.V, mesh.F))
    assert old.p95 > 1.5 and old.extra_pieces >= 5, old


def test_picked_isophotes_follow_the_exact_ones(mesh):
    E = layer_normals(mesh) @ LIGHT
    for c in (0.3, 0.6, 0.89):
        p95, worst, pieces = polyline_wobble(SURFACE, mesh, E, c, LIGHT)
        assert p95 < 0.08 and worst < 0.15 and pieces == 1, (c, p95, worst, pieces)
