"""Picking an isophote with the sculpt tool, headlessly: through stacked and empty layers, on a
tool bound to one layer, with bad input, and the band outline the canvas draws.

The Qt tests click through the same calls (tests/qt/test_qt_sculpt.py); these pin down which
layer a pick lands on and what the person is told when it lands on none.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from test_sculpt_tool import PICK, RING, ellipse_doc, make_tool

from sketchforge_isophote_tool.tool import NOT_ON_A_SHAPE, _rings

SMALL = [[0.5 + 0.2 * x, 0.2 * y] for x, y in RING]  # a small ellipse inside the body, at x = 0.5


def _two_layers(host):
    """The body (1 x 0.7) with a small "patch" layer drawn in front of it around (0.5, 0)."""
    doc = ellipse_doc(host)
    doc.execute({"command": "add_layer", "id": "patch"})
    doc.execute({"command": "set_contour", "layer": "patch", "points": SMALL, "closed": True})
    return doc


def test_a_pick_lands_on_the_front_most_layer_under_it_and_falls_through_elsewhere(real_host):
    doc = _two_layers(real_host)
    tool = make_tool(doc)
    assert tool.pick_at([0.5, 0.0]) and tool.layer_id == "patch"
    assert tool.pick_at(PICK) and tool.layer_id == "body"  # outside the patch: the body
    # A front layer without a surface yet (added, nothing drawn) is passed over.
    doc.execute({"command": "add_layer", "id": "empty"})
    assert tool.pick_at([0.5, 0.0]) and tool.layer_id == "patch"
    doc.execute({"command": "set_layer_visible", "layer": "patch", "visible": False})
    assert tool.pick_at([0.5, 0.0]) and tool.layer_id == "body"


def test_a_tool_bound_to_one_layer_picks_only_there(real_host):
    doc = _two_layers(real_host)
    tool = make_tool(doc, layer="body")
    assert tool.pick_at([0.5, 0.0]) and tool.layer_id == "body"  # under the patch, but bound
    patch_only = make_tool(doc, layer="patch")
    assert not patch_only.pick_at(PICK) and patch_only.message == NOT_ON_A_SHAPE
    gone = make_tool(doc, layer="no_such_layer")
    assert not gone.pick_at(PICK) and gone.pick is None and gone.message == NOT_ON_A_SHAPE


def test_every_triangle_can_be_picked_on(real_host):
    doc = ellipse_doc(real_host)
    mesh = doc.layer("body").mesh
    tool = make_tool(doc)
    interior = np.setdiff1d(np.arange(mesh.n_faces), np.flatnonzero(np.isin(mesh.F, mesh.boundary).any(axis=1)))
    for f in (0, int(interior[0]), int(interior[len(interior) // 2])):
        c = mesh.V[mesh.F[f], :2].mean(axis=0)
        # triangle 0 may lie on the rim, in shadow (no isophote there): never "not on a shape"
        ok = tool.pick_at(c)
        assert ok or (f == 0 and tool.message != NOT_ON_A_SHAPE), (f, tool.message)
        assert not ok or (tool.layer_id == "body" and np.array_equal(tool.pick, c))


@pytest.mark.parametrize("point, shown", [
    ([np.nan, 0.0], "[nan, 0.0]"),
    ([0.1, np.inf], "[0.1, inf]"),
    ([1.0, 2.0, 3.0], "[1.0, 2.0, 3.0]"),
    ("here", "['here']"),
])
def test_a_pick_that_is_not_a_finite_point_is_refused_with_a_message(real_host, point, shown):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc)
    assert tool.pick_at(PICK)
    assert tool.pick_at(point) is False
    assert tool.message == f"the pick must be one finite point [x, y], got {shown}"
    assert tool.pick is None and tool.overlay == {}


def test_after_a_reset_the_band_can_be_set_before_the_next_pick(real_host):
    doc = ellipse_doc(real_host)
    tool = make_tool(doc, band=0.2)
    assert tool.pick_at(PICK)
    tool.reset()
    assert tool.set_band(0.35) and tool.band == 0.35 and tool.overlay == {}
    assert tool.pick_at(PICK)
    assert shapely.Polygon(tool.overlay["band"][0]).area > 0


# --- the band outline the canvas draws ------------------------------------------------------


def test_band_rings_are_every_outer_and_inner_ring_as_closed_2d_polylines():
    outer = shapely.box(0, 0, 4, 4)
    holed = outer.difference(shapely.box(1, 1, 2, 2))
    far = shapely.box(10, 0, 11, 1)
    cases = {
        "polygon with a hole": (holed, [holed.exterior, holed.interiors[0]]),
        "two parts": (shapely.MultiPolygon([holed, far]), [holed.exterior, holed.interiors[0], far.exterior]),
        "nested collection": (shapely.GeometryCollection([shapely.MultiPolygon([far]), shapely.Point(0, 0)]),
                              [far.exterior]),
    }
    for name, (geom, rings) in cases.items():
        got = _rings(geom)
        assert len(got) == len(rings), name
        for a, ring in zip(got, rings):
            assert a.dtype == np.float64 and a.shape[1] == 2, name
            assert np.array_equal(a[0], a[-1]) and np.allclose(a, np.asarray(ring.coords)[:, :2]), name
    z = shapely.Polygon([(0, 0, 5), (1, 0, 5), (0, 1, 5)], holes=[[(0.1, 0.1, 5), (0.3, 0.1, 5), (0.1, 0.3, 5)]])
    assert all(a.shape[1] == 2 for a in _rings(z))  # drawn in the plane: z dropped
    assert _rings(None) == [] and _rings(shapely.Polygon()) == []


# --- the local half-width behind the rim margin ------------------------------------------------


def _half_width(outline, h, reach, P):
    from sketchforge_isophote_tool.layerdata import RIM_WIDTH_FRACTION, _width_grid, local_margin

    grid = _width_grid(outline, h, reach)
    return local_margin(grid, np.inf, np.asarray(P, np.float64)) / RIM_WIDTH_FRACTION, grid


def test_a_thin_limb_reads_its_own_half_width_along_it_and_next_to_its_rim():
    # A limb 0.2 wide and 3 long, off the origin and much longer than wide (so a grid read
    # with x and y swapped, or shifted, reads the wrong place).
    limb = shapely.box(1.0, 5.0, 4.0, 5.2)
    h = 0.02
    xs = np.linspace(1.05, 3.95, 30)
    P = np.concatenate([np.column_stack([xs, np.full_like(xs, y)]) for y in (5.1, 5.01, 5.19)])
    rho, (origin, spacing, W) = _half_width(limb, h, 0.5, P)
    assert spacing == pytest.approx(0.5 * h)
    assert np.allclose(rho, 0.1, atol=spacing), (rho.min(), rho.max())
    # The grid holds the whole layer with room around it: its outer nodes lie outside.
    assert origin[0] < 1.0 - h and origin[1] < 5.0 - h
    far = origin + spacing * (np.array(W.shape) - 1)
    assert far[0] > 4.0 + h and far[1] > 5.2 + h
    assert W.shape[0] > 10 * W.shape[1] // 2  # long in x, as the limb


def test_a_wide_body_reads_at_least_the_reach_even_next_to_its_rim():
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    disk = shapely.Polygon(np.column_stack([np.cos(t), np.sin(t)]))
    h, reach = 0.03, 0.4
    P = np.array([[0.0, 0.0], [0.9, 0.0], [0.0, -0.95], [0.6, 0.6]])
    rho, (_, spacing, _) = _half_width(disk, h, reach, P)
    assert rho[0] == pytest.approx(1.0, abs=2 * spacing)  # the centre: the radius
    assert (rho[1:] >= reach - spacing).all()  # within reach of a deep interior


def test_the_width_grid_reads_the_deepest_point_exactly_reach_away():
    # A square whose sides lie on grid nodes: there the distance transform is exact (a node k
    # nodes in from a side is k spacings from it), so the half-width read at the nodes next
    # to a side is the distance of the node r = ceil(reach / spacing) nodes further in: r + 1
    # spacings, on the left, right, bottom and top side alike.
    from sketchforge_isophote_tool.layerdata import _width_grid

    h = 0.04
    s = 0.5 * h
    L = 200 * s
    square = shapely.box(0.0, 0.0, L, L)
    for reach, r in ((10 * s, 10), (9.5 * s, 10), (0.5 * s, 1)):
        origin, spacing, W = _width_grid(square, h, reach)
        assert spacing == s and origin.tolist() == [-2 * h, -2 * h]
        # nodes from 2h before the square to the first node at least 2h beyond it
        assert W.shape == (L / s + 9, L / s + 9)
        i0 = int(round(-origin[0] / s))  # the node on the square's left (and bottom) side
        mid = i0 + 100
        want = (r + 1) * s
        for node in ((i0 + 1, mid), (i0 + 199, mid), (mid, i0 + 1), (mid, i0 + 199)):
            assert W[node] == pytest.approx(want, abs=1e-12), (reach, node)
        # deep inside: the distance of the node itself, when the centre is out of reach
        assert W[i0 + 50, mid] == pytest.approx((50 + r) * s, abs=1e-12)
        if r == 1:  # outside, the side's own node and beyond read nothing unless in reach
            assert W[i0 - 1, mid] == 0.0 and W[i0, mid] == s


def test_a_huge_layer_gets_a_grid_of_about_600_nodes_a_side():
    from sketchforge_isophote_tool.layerdata import _width_grid

    h = 0.02
    origin, spacing, W = _width_grid(shapely.box(0.0, 0.0, 1000.0, 400.0), h, 1.0)
    assert spacing == pytest.approx((1000.0 + 4 * h) / 600.0, rel=1e-12)
    assert 601 <= W.shape[0] <= 602 and W.shape[1] == np.ceil((400 + 4 * h) / spacing) + 1


def test_the_rim_margin_is_read_bilinearly_from_the_width_grid():
    from sketchforge_isophote_tool.layerdata import RIM_WIDTH_FRACTION, _width_grid, local_margin

    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    blob = shapely.Polygon(np.column_stack([np.cos(t) * (1 + 0.3 * np.cos(3 * t)), 0.6 * np.sin(t)]))
    grid = _width_grid(blob, 0.05, 0.3)
    origin, spacing, W = grid
    rng = np.random.default_rng(5)
    P = rng.uniform(origin, origin + spacing * (np.array(W.shape) - 1.0001), (300, 2))  # over the grid
    u = (P - origin) / spacing
    i, f = np.floor(u).astype(int), u - np.floor(u)
    want = (W[i[:, 0], i[:, 1]] * (1 - f[:, 0]) * (1 - f[:, 1]) + W[i[:, 0] + 1, i[:, 1]] * f[:, 0] * (1 - f[:, 1])
            + W[i[:, 0], i[:, 1] + 1] * (1 - f[:, 0]) * f[:, 1] + W[i[:, 0] + 1, i[:, 1] + 1] * f[:, 0] * f[:, 1])
    assert np.ptp(want) > 0.1  # thin lobes and a wide middle
    got = local_margin(grid, np.inf, P)
    assert got == pytest.approx(RIM_WIDTH_FRACTION * want, abs=1e-12)
    capped = local_margin(grid, 0.01, P)
    assert np.array_equal(capped, np.minimum(0.01, got))


def test_a_hole_with_a_broken_point_is_named_as_the_layer_s_outline():
    from sketchforge.errors import GeometryError

    square = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)]
    with pytest.raises(GeometryError) as err:
        _outline_of(square, holes=[[(0.5, 0.5), (1.0, np.inf), (1.0, 1.0)]])
    assert str(err.value) == "the layer's outline has a point that is not a finite number (point 6: [1.0, inf])"


# --- the layer's planar data: edge length and rim margin -----------------------------------


def test_the_layer_s_edge_length_and_rim_margin_are_what_the_docs_say():
    from sketchforge_isophote_tool.layerdata import planar_data
    from sketchforge_isophote_tool.testing import inflated

    branches = set()
    for shape, resolution in (("ellipse", 0.04), ("ellipse", 0.015), ("m", 0.04)):
        mesh = inflated(shape, resolution)
        pd = planar_data(mesh)
        V, F = mesh.V[:, :2], mesh.F
        # h: the mean length over every face's three edges (interior edges counted twice)
        e = np.linalg.norm(V[F] - V[np.roll(F, -1, axis=1)], axis=2)
        assert pd.h == pytest.approx(e.mean(), rel=1e-12)
        # margin: max(3h, 0.12 size), size = 2·area/perimeter of the outline
        ring = shapely.Polygon(V[mesh.boundary])
        size = 2.0 * ring.area / ring.length
        assert pd.margin == pytest.approx(max(3.0 * pd.h, 0.12 * size), rel=1e-9)
        branches.add(3.0 * pd.h > 0.12 * size)
        assert pd.mass.dtype == np.float64 and pd.mass.sum() == pytest.approx(ring.area, rel=1e-9)
    assert branches == {True, False}  # both terms of the max were the margin somewhere


def _outline_of(ring, holes=()):
    from types import SimpleNamespace

    from sketchforge_isophote_tool.layerdata import outline_polygon

    pts = [np.asarray(ring, np.float64)] + [np.asarray(h, np.float64) for h in holes]
    V = np.column_stack([np.concatenate(pts), np.zeros(sum(len(p) for p in pts))])
    start = np.cumsum([0] + [len(p) for p in pts])
    idx = [np.arange(start[i], start[i + 1]) for i in range(len(pts))]
    return outline_polygon(SimpleNamespace(V=V, boundary=idx[0], holes=tuple(idx[1:])))


def test_the_outline_is_a_counter_clockwise_polygon_whatever_the_drawing_order():
    square = [(0.0, 0.0), (0.0, 2.0), (2.0, 2.0), (2.0, 0.0)]  # clockwise
    for ring in (square, square[::-1]):
        poly = _outline_of(ring)
        assert poly.geom_type == "Polygon" and poly.exterior.is_ccw and poly.area == pytest.approx(4.0)
    holed = _outline_of(square, holes=[[(0.5, 0.5), (1.0, 0.5), (1.0, 1.0)]])
    assert holed.exterior.is_ccw and len(holed.interiors) == 1
    assert holed.area == pytest.approx(4.0 - 0.125)


def test_a_self_crossing_outline_keeps_its_largest_part():
    # Lobes of area 0.5 and 4.5 meeting where the outline crosses itself at (1, 0.75).
    poly = _outline_of([(0.0, 0.0), (4.0, 3.0), (4.0, 0.0), (0.0, 1.0)])
    assert poly.geom_type == "Polygon" and poly.is_valid and poly.exterior.is_ccw
    assert poly.area == pytest.approx(4.5) and poly.contains(shapely.Point(3.5, 1.0))
    # a hole across the shell's edge: the shell less the hole, its largest part
    cut = _outline_of([(0.0, 0.0), (4.0, 0.0), (4.0, 1.0), (0.0, 1.0)],
                      holes=[[(1.4, -1.0), (1.6, -1.0), (1.6, 2.0), (1.4, 2.0)]])
    assert cut.geom_type == "Polygon" and cut.is_valid and cut.area == pytest.approx(2.4)


def test_an_outline_with_a_point_that_is_not_finite_is_named_in_the_error():
    from sketchforge.errors import GeometryError

    with pytest.raises(GeometryError, match=r"^the layer's outline has a point that is not a finite number"):
        _outline_of([(0.0, 0.0), (np.nan, 1.0), (1.0, 0.0)])


def test_the_planar_data_is_shared_by_height_changes_only():
    from sketchforge.geometry.mesh import Mesh
    from sketchforge_isophote_tool.layerdata import planar_data
    from sketchforge_isophote_tool.testing import inflated

    mesh = inflated("ellipse")
    V2 = mesh.V.copy()
    V2[:, 2] *= 1.5
    raised = Mesh(V2, mesh.F, boundary=mesh.boundary)
    assert planar_data(raised) is planar_data(mesh)  # the same drawing: computed once
    # The same triangles listed in another order: per-face data follows the new order.
    F = mesh.F[::-1].copy()
    reordered = Mesh(mesh.V, F, boundary=mesh.boundary)
    assert planar_data(reordered) is not planar_data(mesh)
    assert np.array_equal(planar_data(reordered).F, F)
    # The same surface with another outline listed (a rotated start): its own outline data.
    rolled = Mesh(mesh.V, mesh.F, boundary=np.roll(mesh.boundary, 5))
    assert planar_data(rolled) is not planar_data(mesh)
