"""The ``sculpt_isophote`` journal entry as a file holds it: what a broken entry is told, the
largest band a file may ask for, the undo menu's label, and an edit on a layer with no surface.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_sculpt_tool import PICK, STROKE, ellipse_doc

from sketchforge.errors import DocumentFormatError, SculptError
from sketchforge_isophote_tool.command import SculptIsophote

GOOD = {"command": "sculpt_isophote", "layer": "body", "pick": PICK, "band": 0.3, "stroke": STROKE}


@pytest.mark.parametrize("change, message", [
    ({"layer": 7}, "command 'sculpt_isophote': field 'layer' has the wrong type (int)"),
    ({"pick": [0.1, 0.2, 0.3]}, "command 'sculpt_isophote': 'pick' must be 2 numbers [x, y]"),
    ({"pick": "here"}, "command 'sculpt_isophote': field 'pick' has the wrong type (str)"),
    ({"pick": [0.1]}, "command 'sculpt_isophote': 'pick' must be 2 or 3 numbers"),
    ({"band": "wide"}, "command 'sculpt_isophote': field 'band' has the wrong type (str)"),
    ({"band": 2e9}, "command 'sculpt_isophote': 'band' is 2e+09; it must be at most 1e+09 drawing units"),
    ({"stroke": [[0.0, 0.0], [1.0]]}, "command 'sculpt_isophote': 'stroke' must be a list of [x, y] number pairs"),
    ({"model": 3}, "command 'sculpt_isophote': field 'model' has the wrong type (int)"),
])
def test_a_broken_entry_is_refused_naming_the_command_and_the_field(change, message):
    with pytest.raises(DocumentFormatError) as info:
        SculptIsophote.from_dict({**GOOD, **change})
    assert str(info.value) == message


def test_the_largest_band_a_file_may_ask_for_is_accepted():
    # 1e9 drawing units, the tool's own limit: what the tool writes, the file reads back.
    cmd = SculptIsophote.from_dict({**GOOD, "band": 1e9})
    assert cmd.band == 1e9 and cmd.to_dict()["band"] == 1e9


def test_the_entry_round_trips_and_names_itself_in_the_undo_menu(real_host):
    cmd = SculptIsophote.from_dict(GOOD)
    assert cmd.to_dict() == GOOD
    assert SculptIsophote.from_dict({**GOOD, "model": "half_lambert"}).to_dict()["model"] == "half_lambert"
    doc = ellipse_doc(real_host)
    doc.execute(GOOD)
    assert cmd.text() == "Sculpt isophote"
    assert doc.undo_stack.undo_text() == "Sculpt isophote"


def test_sculpting_a_layer_that_has_no_surface_yet_says_to_draw_first(real_host):
    doc = ellipse_doc(real_host)
    doc.execute({"command": "add_layer", "id": "blank"})
    count = doc.undo_stack.count()
    with pytest.raises(SculptError) as info:
        doc.execute({**GOOD, "layer": "blank"})
    assert str(info.value) == "layer 'blank' has no surface to sculpt yet (draw its contour first)"
    assert doc.undo_stack.count() == count


@pytest.mark.parametrize("key", ["ring", "rim_margin"])
def test_ring_and_rim_margin_take_a_length_or_none_and_refuse_the_rest(key):
    from sketchforge.errors import ParameterError
    from sketchforge_isophote_tool.gauss_newton import check_params

    for good in (0, 0.25, 3, None):
        assert check_params({key: good})[key] == good
    for bad, why in ((-0.1, "must be >= 0, got -0.1"), (float("inf"), "must be a finite number, got inf"),
                     (float("nan"), "must be a finite number, got nan"), ("wide", "must be a number or null, got 'wide'"),
                     ([1], "must be a number or null, got [1]")):
        with pytest.raises(ParameterError) as info:
            check_params({key: bad})
        assert str(info.value) == f"{key!r} {why}"


def test_a_stroke_drawn_as_a_closed_loop_stays_a_smooth_closed_loop():
    # Redrawing a whole isophote: the loop is smoothed all the way round, with no end pinned,
    # so a drawn circle stays a circle about its own centre (the (1/4, 1/2, 1/4) filter only
    # shrinks it by a hair at the h/2 spacing).
    from sketchforge_isophote_tool.stroke import prepare_stroke

    t = np.linspace(0.0, 2.0 * np.pi, 89, endpoint=False)
    r, h = 0.6, 0.05
    circle = np.c_[0.3 + r * np.cos(t), -0.2 + r * np.sin(t)]
    circle = np.vstack([circle, circle[:1]])  # closed: the first point repeated
    P = prepare_stroke(circle, h)
    assert np.array_equal(P[0], P[-1]) and len(P) > 60
    ring = P[:-1]
    assert np.abs(ring.mean(axis=0) - [0.3, -0.2]).max() < 1e-3
    radius = np.hypot(ring[:, 0] - 0.3, ring[:, 1] + 0.2)
    assert radius.max() - radius.min() < 2e-3 and abs(radius.mean() - r) < 2e-3
    step = np.linalg.norm(np.diff(P, axis=0), axis=1)
    assert step.max() < 0.51 * h and step.min() > 0.4 * h  # still about h/2 apart, the seam too
