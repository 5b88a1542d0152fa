"""Issue 30, point 5: a sculpt stroke that runs outside the band says how much of it was
ignored (length and share), after the edit is applied; one wholly inside says nothing of it."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from sculpt_helpers import isophote_stroke

from sketchforge_isophote_tool import sculpt
from sketchforge_isophote_tool.stroke import prepare_stroke
from sketchforge_isophote_tool.testing import LIGHT, inflated

PICK = [0.2, 0.1]
BAND = 0.15


@pytest.fixture(scope="module")
def mesh():
    return inflated("ellipse", 0.04)


def _stroke_with_tail(mesh, tail):
    """The isophote moved a little, then a straight run of ``tail`` drawing units going away
    from it (out of the band) at its end."""
    stroke, _, _ = isophote_stroke(mesh, PICK, offset=0.03)
    d = stroke[-1] - stroke[-2]
    d /= np.linalg.norm(d)
    away = np.array([-d[1], d[0]])  # square to the isophote: out of the band quickly
    run = stroke[-1] + np.linspace(0.0, tail, 40)[1:, None] * away
    return np.vstack([stroke, run])


def test_a_stroke_wholly_inside_the_band_ignores_nothing(mesh):
    stroke, _, _ = isophote_stroke(mesh, PICK, offset=0.03)
    r = sculpt(mesh, LIGHT, PICK, BAND, stroke)
    assert r.ignored_length < 0.5 * r.h and r.ignored_fraction < 0.05
    assert "ignored" not in r.describe()


@pytest.mark.parametrize("tail", [0.3, 0.6])
def test_the_part_outside_the_band_is_measured_and_said(mesh, tail):
    stroke = _stroke_with_tail(mesh, tail)
    r = sculpt(mesh, LIGHT, PICK, BAND, stroke)
    # What lay outside: the cleaned stroke minus its part inside the band (exact, by GEOS).
    cleaned = shapely.LineString(prepare_stroke(stroke, r.h))
    outside = cleaned.length - cleaned.intersection(r.band).length
    assert outside > tail - BAND - 0.05
    assert r.ignored_length == pytest.approx(outside, abs=0.5 * r.h)
    assert r.ignored_fraction == pytest.approx(r.ignored_length / cleaned.length, rel=1e-9)
    text = r.describe()
    assert f"{r.ignored_fraction:.0%} of the stroke" in text and "outside the band and was ignored" in text
    assert f"{r.ignored_length:.3g} drawing units" in text
