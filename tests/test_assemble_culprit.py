"""The sentence the assembly says when a junction cut cannot be made (``remesh._culprit``): who is
at fault (the part's junction, two parts, the layer below) and what to do, for every kind of
conflict Triangle cannot take."""

from __future__ import annotations

import pytest

from sketchforge_assemble.remesh import _culprit

NAMES = ["Arm", "Leg"]
AT = (0.5, -0.25)


@pytest.mark.parametrize("kind, a, b, want", [
    ("cross", 0, 0, "The junction of layer 'Arm' crosses itself near (0.5, -0.25); redraw the part."),
    ("touch", 1, 1, "The junction of layer 'Leg' touches itself near (0.5, -0.25); redraw the part."),
    ("merge", 0, 0, "The junction of layer 'Arm' has two points closer than 0.001 near (0.5, -0.25); redraw the part."),
    ("cross", 0, 1, "The junctions of layers 'Arm' and 'Leg' cross on layer 'Body' near (0.5, -0.25); "
                    "move one of them apart."),
    ("touch", 1, 0, "The junctions of layers 'Leg' and 'Arm' touch on layer 'Body' near (0.5, -0.25); "
                    "move one of them apart."),
    ("merge", -2, -1, "Two vertices of layer 'Body' are closer than 0.001 near (0.5, -0.25); redraw the layer."),
    ("cross", -1, -1, "The outline of layer 'Body' crosses itself near (0.5, -0.25); redraw the layer."),
    ("touch", -1, -1, "The outline of layer 'Body' touches itself near (0.5, -0.25); redraw the layer."),
    ("touch", -2, -1, "A vertex of layer 'Body' lies on its outline near (0.5, -0.25); redraw the layer."),
    ("cross", 1, -1, "The junction of layer 'Leg' crosses the outline of layer 'Body' near (0.5, -0.25); "
                     "redraw the part so its ends lie inside the layer."),
    ("touch", -1, 0, "The junction of layer 'Arm' touches the outline of layer 'Body' near (0.5, -0.25); "
                     "redraw the part so its ends lie inside the layer."),
    ("touch", 0, -2, "The junction of layer 'Arm' touches a vertex of layer 'Body' near (0.5, -0.25); "
                     "redraw the part so its ends lie inside the layer."),
])
def test_each_conflict_names_who_is_at_fault_and_what_to_do(kind, a, b, want):
    assert _culprit(kind, a, b, AT, "Body", NAMES, 1e-3) == want
