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
