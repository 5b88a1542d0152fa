"""The redrawn isophote stroke on its way in: its length limit, its clipping to the band
around the picked isophote (the parts outside are not the person's intent), and the shading
change it asks for, checked against its definition, and the characteristics traced from it."""

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


# --- the shading change the stroke asks for (thesis 4.4) ----------------------------------------


def _shading_problem():
    from sketchforge_isophote_tool.layerdata import planar_data
    from sketchforge_isophote_tool.shading import bary_rows
    from sketchforge_isophote_tool.testing import inflated

    mesh = inflated("ellipse", 0.04)
    pd = planar_data(mesh)
    x, y = pd.V2[:, 0], pd.V2[:, 1]
    E = 0.5 + 0.3 * x - 0.2 * y**2  # any shading: the definition holds for every one
    free = np.abs(x - 0.1) < 0.25
    P = np.c_[np.full(40, 0.1), np.linspace(-0.3, 0.3, 40)]
    B = bary_rows(pd, P)
    ws = np.full(40, 0.6 / 40)
    return pd, E, free, B, ws


def test_the_shading_change_is_the_minimiser_it_is_defined_as():
    # δE = 0 off the free vertices; on them, the gradient of
    # δEᵀ Q δE + β Σ w_k (E(P_k) + δE(P_k) − c)² vanishes, and the stroke's points move towards c
    from sketchforge_isophote_tool.shading import STROKE_WEIGHT, shading_change

    pd, E, free, B, ws = _shading_problem()
    c = 0.7
    dE = shading_change(pd, E, free, B, ws, c)
    assert np.all(dE[~free] == 0.0) and np.abs(dE[free]).max() > 0.01
    idx = np.flatnonzero(free)
    beta = STROKE_WEIGHT / pd.h**3
    Bf = B[:, idx]
    grad = pd.Q[idx][:, idx] @ dE[idx] + beta * (Bf.T @ (ws * (B @ (E + dE) - c)))
    scale = beta * np.abs(Bf.T @ (ws * (B @ E - c))).max()
    assert np.abs(grad).max() <= 1e-9 * scale
    assert np.abs(B @ (E + dE) - c).max() < np.abs(B @ E - c).min()
    assert not shading_change(pd, E, np.zeros(len(E), bool), B, ws, c).any()  # nothing free


def test_a_broken_shading_is_refused_by_name():
    from sketchforge_isophote_tool.shading import shading_change

    pd, E, free, B, ws = _shading_problem()
    E = E.copy()
    E[B.indices[0]] = np.nan  # under the stroke
    with pytest.raises(GeometryError) as err:
        shading_change(pd, E, free, B, ws, 0.7)
    assert str(err.value).startswith("the right-hand side of the shading interpolation has a value that is not "
                                     "a finite number"), str(err.value)


def test_characteristics_are_traced_only_from_stroke_points_on_the_layer():
    # a stroke over the layer gives one characteristic per seed, each a polyline through its
    # seed; seeds off the layer (the stroke drawn past the outline) can take no step: none
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.characteristics import base_characteristics
    from sketchforge_isophote_tool.layerdata import layer_data
    from sketchforge_isophote_tool.testing import LIGHT, inflated

    ld = layer_data(inflated("ellipse", 0.04), LIGHT, LAMBERTIAN)
    on = [np.c_[np.full(20, 0.1), np.linspace(-0.3, 0.3, 20)]]
    lines = base_characteristics(ld, on, 0.2, n=6)
    assert len(lines) == 6 and all(len(q) >= 3 for q in lines)
    off = [np.c_[np.full(20, 3.0), np.linspace(-0.3, 0.3, 20)]]
    assert base_characteristics(ld, off, 0.2, n=6) == []
