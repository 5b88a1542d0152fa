"""The redrawn isophote stroke on its way in: its length limit and its clipping to the band
around the picked isophote (the parts outside are not the person's intent)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from sketchforge.errors import GeometryError, SculptError
from sketchforge_isophote_tool.stroke import MAX_STROKE_SAMPLES, clip_to_band, guard_length


def test_a_stroke_leaving_and_re_entering_the_band_keeps_both_parts_inside():
    # a ring band of radii 0.9..1.1; a horizontal stroke through it crosses it twice
    band = shapely.Point(0, 0).buffer(1.1, 256).difference(shapely.Point(0, 0).buffer(0.9, 256))
    P = np.c_[np.linspace(-1.5, 1.5, 61), np.full(61, 0.05)]
    h = 0.04
    pieces = clip_to_band(P, band, h)
    assert len(pieces) == 2
    for piece in sorted(pieces, key=lambda q: q[0, 0]):
        assert shapely.contains_xy(band.buffer(1e-9), piece[:, 0], piece[:, 1]).all()
        assert np.abs(piece[:, 1] - 0.05).max() <= 1e-12  # on the stroke
        steps = np.linalg.norm(np.diff(piece, axis=0), axis=1)
        assert steps.max() <= 0.5 * h + 1e-12 and np.ptp(steps) <= 1e-9  # evenly, h/2 at most
    # together they are the stroke's whole length inside the band
    inside = shapely.LineString(P).intersection(band).length
    got = sum(np.linalg.norm(np.diff(q, axis=0), axis=1).sum() for q in pieces)
    assert got == pytest.approx(inside, rel=1e-9)


def test_a_stroke_outside_the_band_is_refused_with_what_to_do():
    band = shapely.box(0, 0, 1, 0.2)
    with pytest.raises(SculptError) as err:
        clip_to_band(np.array([[0.0, 0.5], [1.0, 0.6]]), band, 0.05)
    assert str(err.value) == ("the stroke has no part inside the band around the picked isophote: "
                              "draw it inside the dashed band")
    with pytest.raises(GeometryError) as err:
        clip_to_band(np.array([[0.0, 0.1], [np.nan, 0.1]]), band, 0.05)
    assert str(err.value).startswith("the stroke has a point that is not a finite number")


def test_a_long_stroke_is_measured_along_its_length():
    # 1000 steps of 0.06 zig-zagging: 60 drawing units, over the limit of 50 at h = 0.001
    # (a stroke that would need over MAX_STROKE_SAMPLES samples of h/2)
    h = 1e-3
    limit = MAX_STROKE_SAMPLES * 0.5 * h
    t = np.arange(1001)
    zig = np.c_[t * 0.06 * np.cos(np.radians(30)), (t % 2) * 0.06 * np.sin(np.radians(30))]
    with pytest.raises(SculptError) as err:
        guard_length(zig, h)
    assert str(err.value) == (f"the stroke is 60 drawing units long, too long for a layer of edge length "
                              f"0.001 (at most {limit:.3g}): draw it over the layer")
    assert np.array_equal(guard_length(zig[:800], h), zig[:800])  # 48 units: taken as drawn
