"""What the sculpt tool shows a person between gestures: its state when it is made, after a pick
that fails, after a band that cannot be drawn, and after an option change with nothing picked.

The canvas and the status bar read ``tool.overlay``, ``tool.message`` and the pick fields
(sketchforge/qt/); the mutation run leaves the Qt tests out, so these hold the same contract
headlessly. Failures of the isophote search and of the band are forced here (they are rare on
real shapes: a pick inside a shape always finds an isophote), so that what the person is told
when they do happen is pinned down.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_sculpt_tool import PICK, STROKE, ellipse_doc, make_tool
from test_sculpt_tool_preview import _half_lambert_host

from sketchforge.errors import SculptError
from sketchforge_isophote_tool import isophote as isophote_module
from sketchforge_isophote_tool.tool import NOT_ON_A_SHAPE, PICK_FIRST


def _nothing_picked(tool) -> bool:
    return (tool.pick is None and tool.layer_id is None and tool.isovalue is None
            and tool.isophote is None and tool.overlay == {})


def test_a_new_tool_has_nothing_picked_nothing_to_say_and_the_default_band(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc)
    assert _nothing_picked(tool) and tool.message == "" and tool.band == 0.3
    # nothing pressed: a move draws nothing, a release is a click that picks
    tool.move([0.1, 0.1])
    assert "stroke" not in tool.overlay
    assert tool.release(PICK) is None and tool.layer_id == "body" and tool.message == ""


def test_the_band_can_be_set_before_anything_is_picked(real_host):
    tool = make_tool(ellipse_doc(real_host))
    assert tool.set_band(0.5) and tool.band == 0.5
    assert _nothing_picked(tool) and tool.message == ""
    assert tool.pick_at(PICK) and len(tool.overlay["band"]) >= 1  # the pick draws the band set


def test_options_given_to_a_new_tool_are_the_ones_it_uses():
    doc = ellipse_doc(_half_lambert_host())
    tool = make_tool(doc, options={"model": "half_lambert"})
    assert tool.options == {"model": "half_lambert"}
    assert tool.pick_at(PICK) and tool.command_dict(STROKE)["model"] == "half_lambert"
    with pytest.raises(SculptError, match="unknown sculpt tool options"):
        make_tool(doc, options={"modle": "half_lambert"})


def test_changing_the_model_with_nothing_picked_picks_nothing_and_says_nothing():
    doc = ellipse_doc(_half_lambert_host())
    tool = make_tool(doc)
    tool.set_options({"model": "half_lambert"})
    assert _nothing_picked(tool) and tool.message == ""


def test_a_pick_after_a_missed_one_clears_the_message(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc)
    assert not tool.pick_at([5.0, 5.0]) and tool.message == NOT_ON_A_SHAPE
    assert tool.pick_at(PICK) and tool.message == ""
    assert tool.isophote.shape[1] == 2 and tool.isophote.dtype == np.float64


def test_a_pick_whose_isophote_cannot_be_found_drops_the_old_pick_and_says_why(real_host, monkeypatch):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc)
    assert tool.pick_at(PICK)
    steps = doc.undo_stack.count()

    def no_isophote(ld, pick):
        raise SculptError("no isophote through the pick at E = 0.42")

    monkeypatch.setattr(isophote_module, "picked_isophote", no_isophote)
    assert tool.pick_at([0.3, 0.1]) is False
    assert _nothing_picked(tool) and tool.message == "no isophote through the pick at E = 0.42"
    # a stroke now is refused, not applied to the dropped pick
    tool.press(STROKE[0])
    for p in STROKE[1:]:
        tool.move(p)
    assert tool.release(STROKE[-1]) is None and doc.undo_stack.count() == steps
    assert tool.message == PICK_FIRST


def test_a_band_that_cannot_be_drawn_keeps_the_pick_shows_no_band_and_says_why(real_host, monkeypatch):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.3)
    real_band_around = isophote_module.band_around

    def failing(ld, iso, radius):
        if radius > 0.5:
            raise SculptError(f"the band of radius {radius} is empty")
        return real_band_around(ld, iso, radius)

    monkeypatch.setattr(isophote_module, "band_around", failing)
    # a pick whose band fails: the pick holds, the canvas draws no band, the message says why
    tool.band = 0.8
    assert tool.pick_at(PICK)
    assert tool.layer_id == "body" and tool.overlay["band"] == [] and "isophote" in tool.overlay
    assert tool.message == "the band of radius 0.8 is empty"
    # a band change that fails keeps the band there was, and its outline
    assert tool.set_band(0.25)
    rings = tool.overlay["band"]
    assert len(rings) >= 1
    assert tool.set_band(0.9) is False
    assert tool.band == 0.25 and tool.message == "the band of radius 0.9 is empty"
    assert len(tool.overlay["band"]) == len(rings)
    assert all(np.array_equal(a, b) for a, b in zip(tool.overlay["band"], rings))
