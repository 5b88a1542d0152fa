"""The independent checks of ``tests/mesh_checks.py`` measure what they say, on shapes whose
answer is known."""

from __future__ import annotations

import mesh_checks as mc
import numpy as np

from sketchforge_inflate import inflate_stroke


def _beak(tip_x: float = 0.3):
    """An open stroke drawn as a beak: its junction the closing segment at x = 0, a sharp tip."""
    top = np.c_[np.linspace(0.0, tip_x, 30), np.linspace(0.06, 0.0, 30)]
    bottom = np.c_[np.linspace(tip_x, 0.0, 30)[1:], np.linspace(0.0, -0.06, 30)[1:]]
    return np.vstack([top, bottom])


def test_drawn_tips_are_the_sharp_corners_of_the_outline_not_the_junction_ends():
    beak = inflate_stroke(_beak(), closed=False, params={"resolution": 0.03})
    tips = mc.drawn_tips(beak)
    assert len(beak.junction) >= 2
    # the tip, resampled finer where the outline nears itself, may count several points; all there
    assert len(tips) >= 1 and np.all(np.linalg.norm(tips - [0.3, 0.0], axis=1) < 0.02)
    t = np.linspace(0.0, 2.0 * np.pi, 80, endpoint=False)
    blob = inflate_stroke(np.c_[0.4 * np.cos(t), 0.25 * np.sin(t)], closed=True, params={"resolution": 0.03})
    assert len(mc.drawn_tips(blob)) == 0


def test_edges_at_a_drawn_tip_are_those_of_its_own_layer_within_the_radius():
    beak = inflate_stroke(_beak(), closed=False, params={"resolution": 0.03})
    face_layer = np.zeros(len(beak.F), np.int64)
    key, _ = mc.dihedral(beak.V, beak.F)
    near = mc.at_drawn_tips(beak.V, beak.F, face_layer, [mc.drawn_tips(beak)], 0.05)
    mid = beak.V[key].mean(axis=1)[:, :2]
    d = np.linalg.norm(mid - [0.3, 0.0], axis=1)
    assert near.any() and np.all(d[near] < 0.05 + 0.02) and not near[d > 0.08].any()
    # on another layer's faces, none
    assert not mc.at_drawn_tips(beak.V, beak.F, face_layer + 1, [mc.drawn_tips(beak), np.zeros((0, 2))], 0.05).any()


def test_the_layers_edge_length_is_weighed_by_area_so_a_finer_small_part_does_not_shrink_it():
    t = np.linspace(0.0, 2.0 * np.pi, 80, endpoint=False)
    body = inflate_stroke(np.c_[0.6 * np.cos(t), 0.4 * np.sin(t)], closed=True, params={"resolution": 0.03})
    eyes = [inflate_stroke(np.c_[0.04 * np.cos(t) + x, 0.04 * np.sin(t)], closed=True, params={"resolution": 0.03})
            for x in (-0.2, 0.0, 0.2)]
    alone = mc.layers_edge_length([body])
    assert abs(mc.layers_edge_length([body, *eyes]) - alone) < 0.02 * alone
    # the median of each layer's own would be an eye's, several times finer
    assert np.median([mc.edge_length(m.V, m.F) for m in [body, *eyes]]) < 0.5 * alone
