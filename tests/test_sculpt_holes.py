"""The isophote sculpt treats every ring of a holed layer as rim (issue 12, point 2): the rim
distance, the rim margin and the fixed z = 0 vertices include the holes."""

import numpy as np
import shapely
from sculpt_helpers import isophote_stroke

from sketchforge_inflate import inflate_stroke
from sketchforge_isophote_tool.layerdata import planar_data
from sketchforge_isophote_tool.pipeline import sculpt
from sketchforge_isophote_tool.testing import LIGHT


def ring(r, n):
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def test_rim_distance_and_sculpt_respect_the_hole():
    a, b = 0.4, 1.2
    mesh = inflate_stroke(ring(b, 300), True, {"resolution": 0.04, "smoothing": 0.5}, holes=[ring(a, 120)])
    pd = planar_data(mesh)
    r = np.hypot(mesh.V[:, 0], mesh.V[:, 1])
    # Distance to the nearest ring, the hole's included (0.0006 measured; the outer ring
    # alone would be off by up to 0.8 next to the hole).
    assert np.abs(pd.d_rim - np.minimum(b - r, r - a)).max() < 0.005
    assert np.all(pd.is_contour[mesh.holes[0]])
    pick = [-0.1, 0.8]
    stroke, _, _ = isophote_stroke(mesh, pick, offset=0.05, half=0.2)
    res = sculpt(mesh, LIGHT, pick, 0.25, stroke)
    dz = np.abs(res.mesh.V[:, 2] - mesh.V[:, 2])
    assert dz.max() > 0.005
    assert np.all(res.mesh.V[mesh.holes[0], 2] == 0.0)
    assert len(res.mesh.holes) == 1 and np.array_equal(res.mesh.holes[0], mesh.holes[0])
    # Within half the rim margin of the hole the surface barely moves (0.001 vs 0.016 measured).
    assert dz[r < a + 0.5 * pd.margin].max() < 0.15 * dz.max()
    # The band shown around an isophote that passes the hole stops at the hole's rim.
    from sketchforge.geometry.reflectance import LAMBERTIAN
    from sketchforge_isophote_tool.isophote import band_around, picked_isophote
    from sketchforge_isophote_tool.layerdata import layer_data

    ld = layer_data(mesh, LIGHT, LAMBERTIAN)
    _, iso = picked_isophote(ld, [0.0, 0.55])
    region = band_around(ld, iso, 0.3)
    assert region.area > 0.1 and region.intersection(shapely.Polygon(ring(a - 1e-3, 120))).area == 0.0
