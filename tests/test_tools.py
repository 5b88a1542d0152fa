"""The core gesture tools, driven headlessly in document coordinates."""

import math

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.errors import ContourError
from sketchforge.tools import DrawContourTool, LightTool


def drag(tool, points):
    tool.press(points[0])
    for p in points[1:-1]:
        tool.move(p)
    return tool.release(points[-1])


def circle(cx=0.0, cy=0.0, r=1.0, n=24):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[cx + r * np.cos(t), cy + r * np.sin(t)]


def test_drawing_makes_a_layer_in_one_undo_step_and_redraw_replaces(fan_host):
    doc = Document(host=fan_host)
    drag(DrawContourTool(doc), circle())
    assert doc.layer_ids() == ["layer1"] and doc.undo_stack.count() == 1
    assert doc.undo_stack.undo_text() == "Draw layer"
    first = doc.layer("layer1").mesh
    np.testing.assert_allclose(first.V[first.boundary, :2].mean(axis=0), (0, 0), atol=1e-9)
    drag(DrawContourTool(doc, target_layer="layer1", closed=True), circle(2.0, 0.0))
    moved = doc.layer("layer1").mesh
    assert doc.layer("layer1").closed and moved.V[moved.boundary, 0].mean() == pytest.approx(2.0)
    doc.undo_stack.undo()
    assert doc.layer("layer1").mesh is first
    doc.undo_stack.undo()
    assert doc.layers == ()


def test_a_bad_stroke_leaves_nothing_behind(fan_host):
    doc = Document(host=fan_host)
    with pytest.raises(ContourError):
        drag(DrawContourTool(doc), [[0, 0], [1, 1]])
    assert doc.layers == () and doc.undo_stack.count() == 0 and not doc.undo_stack.in_macro()


def test_light_drag_follows_the_mouse_within_a_degree_in_one_undo_step(fan_host):
    doc = Document(host=fan_host)
    before = doc.light
    tool = LightTool(doc, center=(0.5, 0.5))
    path = [(0.5 + 0.3 * math.cos(a), 0.5 + 0.3 * math.sin(a)) for a in np.radians([10, 60, 120, 200])]
    drag(tool, path)
    assert abs((doc.light.angle - 200.0 + 180.0) % 360.0 - 180.0) < 1.0  # the last mouse position
    assert doc.light.direction[2] == 0.0
    assert doc.undo_stack.count() == 1
    doc.undo_stack.undo()
    assert doc.light == before
    # A drag that never leaves the centre changes nothing.
    drag(LightTool(doc, center=(0.5, 0.5)), [(0.5, 0.5), (0.5, 0.5)])
    assert doc.undo_stack.count() == 1 and doc.light == before
