"""The 3D view's display style follows the panel (issue 11, point 4)."""


def test_the_3d_isophote_count_follows_the_spin_box_live(make_window):
    """Issue 11: the 3D view's isophote lines follow the "Isophote lines" box (it was read
    only when the style was switched)."""
    w = make_window()
    w.view3d.set_style("isophotes", 8)
    w.creation_panel.isolines.setValue(5)
    assert w.view3d.isophote_count == 5 and w.view3d.shading_style == "isophotes"
    w.creation_panel.isolines.setValue(0)  # lines off on the canvas: the 3D style keeps its count
    assert w.view3d.isophote_count == 5
    w.creation_panel.isolines.setValue(12)
    assert w.view3d.isophote_count == 12


def test_the_3d_model_shades_a_parts_rim_as_one_point_rest_and_posed(qtbot):
    """Issue 34: the 3D view's model item takes the assembled model's rim pairs, so a part's
    outline seen edge-on shows no line there either: each rim vertex is one shading vertex
    whose normal is the headless renderer's (vertex_normals with the pairs), at rest and in a
    posed frame."""
    import numpy as np
    from rim_lens import lens  # tests/ is on the path (tests/conftest.py)

    from sketchforge.geometry.normals import vertex_normals
    from sketchforge.qt.view3d import _mesh_item_class

    V, F, P = lens(0.01)
    item = _mesh_item_class()(V, F, P, glOptions="opaque")
    rim = np.isin(item._src, P.ravel())
    assert np.bincount(item._src[rim]).max() == 1
    np.testing.assert_allclose(item.normals[rim], vertex_normals(V, F, P)[item._src[rim]], atol=1e-6)
    assert np.abs(item.normals[rim, 2]).max() < 1e-6
    posed = V * np.array([1.0, 1.3, 0.8])
    item.set_positions(posed)
    np.testing.assert_allclose(item.normals[rim], vertex_normals(posed, F, P)[item._src[rim]], atol=1e-6)
    # without the pairs the rim shades as two points, tilted apart (the line)
    plain = _mesh_item_class()(V, F, glOptions="opaque")
    assert np.abs(plain.normals[np.isin(plain._src, P.ravel()), 2]).min() > 0.2
