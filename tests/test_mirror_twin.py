"""Issue 30, point 8: Ctrl+D then Ctrl+M gives the symmetric twin at the mirrored place.

Ctrl+D puts the copy 1.25 part widths aside; mirroring that copy about its host's axis used to
mirror it from where it was put aside, so the "right leg" landed 1.25 widths left of where the
left leg's mirror image is (or, when the moved junction left the body, was mirrored about its
own axis). A copy moved aside and otherwise unchanged now becomes its original's mirror image.
"""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document import commands as C
from sketchforge.document import fileformat as ff


def _body_and_leg(host):
    doc = Document(host=host)
    t = np.linspace(0.0, 2 * np.pi, 120, endpoint=False)
    body = np.column_stack([0.3 + 1.2 * np.cos(t), 0.2 + 0.6 * np.sin(t)])  # axis at x = 0.3
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": body.tolist(), "closed": True,
                 "keep_edits": False})
    doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"resolution": 0.06}})
    # A left leg: an open stroke hanging down, whose closing segment (the junction) lies on the body.
    s = np.linspace(0.0, 1.0, 40)
    leg = np.vstack([np.column_stack([-0.5 + 0.0 * s, 0.0 - 0.9 * s]), np.column_stack([-0.5 + 0.25 * s, -0.9 + 0.0 * s]),
                     np.column_stack([-0.25 + 0.0 * s, -0.9 + 0.9 * s])])
    doc.execute({"command": "add_layer", "id": "leg", "name": "Leg"})
    doc.execute({"command": "set_contour", "layer": "leg", "points": leg.tolist()})
    doc.execute({"command": "set_inflate_params", "layer": "leg", "params": {"resolution": 0.06}})
    assert C.host_of(doc, doc.layer("leg")).id == "body"
    return doc


def _mirror_of(points, cx):
    P = np.array(points)
    P[:, 0] = 2.0 * cx - P[:, 0]
    return P


@pytest.mark.parametrize("offset", [[1.25 * 0.25, 0.0], [0.9, -0.05], [2.5, 0.3]])
def test_duplicate_aside_then_mirror_gives_the_exact_twin(real_host, offset):
    doc = _body_and_leg(real_host)
    leg = doc.layer("leg")
    doc.push(C.DuplicateLayer(layer="leg", new_id="leg2", offset=offset))
    cmd = C.MirrorLayer(layer="leg2", axis="host")
    doc.push(cmd)
    body = np.asarray(doc.layer("body").points)
    cx = 0.5 * (body[:, 0].min() + body[:, 0].max())
    twin = doc.layer("leg2")
    assert np.abs(np.asarray(twin.points) - _mirror_of(leg.points, cx)).max() < 1e-12
    assert cmd.of == "leg" and cmd.used_axis == "host" and doc.journal()[-1]["of"] == "leg"
    # The twin hangs on the body, at the mirrored place.
    assert C.host_of(doc, twin).id == "body"
    J = twin.mesh.V[twin.mesh.junction, :2].mean(axis=0)
    J0 = leg.mesh.V[leg.mesh.junction, :2].mean(axis=0)
    assert abs(J[0] - (2 * cx - J0[0])) < 0.02 and abs(J[1] - J0[1]) < 0.02
    # One undo step each; undo gives the copy back where it was put aside.
    doc.undo_stack.undo()
    assert np.abs(np.asarray(doc.layer("leg2").points) - (np.asarray(leg.points) + offset)).max() < 1e-12
    doc.undo_stack.redo()
    # The journal replays to the same twin.
    replayed = ff.replay_journal(doc.initial_light, doc.journal(), host=real_host)
    assert replayed.layer("leg2").mesh.identical(twin.mesh)


def test_a_journal_entry_without_of_mirrors_the_layer_itself(real_host):
    # Files written before the twin rule replay as they always did: the copy mirrored from
    # where it was put aside.
    doc = _body_and_leg(real_host)
    doc.execute({"command": "duplicate_layer", "layer": "leg", "id": "leg2", "offset": [0.4, 0.0]})
    aside = np.asarray(doc.layer("leg2").points)
    cx, _ = C.mirror_axis_x(doc, doc.layer("leg2"), "host")
    doc.execute({"command": "mirror_layer", "layer": "leg2", "axis": "host"})
    assert np.abs(np.asarray(doc.layer("leg2").points) - _mirror_of(aside, cx)).max() < 1e-12
    assert "of" not in doc.journal()[-1]


def test_a_copy_in_place_or_a_changed_copy_mirrors_itself(real_host):
    doc = _body_and_leg(real_host)
    leg = np.asarray(doc.layer("leg").points)
    body = np.asarray(doc.layer("body").points)
    cx = 0.5 * (body[:, 0].min() + body[:, 0].max())
    # In place: the mirror of itself is the mirror of the original (host_of looks past the sibling).
    doc.push(C.DuplicateLayer(layer="leg", new_id="inplace"))
    cmd = C.MirrorLayer(layer="inplace", axis="host")
    doc.push(cmd)
    assert cmd.of is None and np.abs(np.asarray(doc.layer("inplace").points) - _mirror_of(leg, cx)).max() < 1e-12
    # A copy whose outline was scaled after the duplicate is not an unchanged copy.
    doc.push(C.DuplicateLayer(layer="leg", new_id="scaled", offset=[0.4, 0.0]))
    doc.push(C.TransformLayer(layer="scaled", matrix=C.scale_about([0.0, -0.5], 0.9).tolist()))
    cmd = C.MirrorLayer(layer="scaled", axis="host")
    doc.push(cmd)
    assert cmd.of is None
    # "own" never looks for a twin.
    doc.push(C.DuplicateLayer(layer="leg", new_id="own", offset=[0.4, 0.0]))
    cmd = C.MirrorLayer(layer="own", axis="own")
    doc.push(cmd)
    assert cmd.of is None


def test_twin_source_needs_an_attached_original(fan_host):
    doc = Document(host=fan_host)
    sq = [[0, 0], [1, 0], [1, 1], [0, 1]]
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": sq, "closed": True})
    doc.execute({"command": "duplicate_layer", "layer": "a", "id": "b", "offset": [2.0, 0.0]})
    assert C.twin_source(doc, doc.layer("b")) is None  # a free part: mirrored about its own axis


def test_a_copy_whose_hole_moved_on_its_own_is_no_twin(real_host):
    """A twin is an unchanged copy moved aside: its holes moved by the same offset as its
    stroke. A copy whose hole was redrawn elsewhere, or with another number of points, is
    mirrored about its own place like any changed part (and the check never fails on it)."""
    doc = _body_and_leg(real_host)
    t = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    hole = np.column_stack([-0.375 + 0.06 * np.cos(t), -0.6 + 0.1 * np.sin(t)])
    leg = np.asarray(doc.layer("leg").points)
    doc.execute({"command": "set_contour", "layer": "leg", "points": leg.tolist(), "holes": [hole.tolist()]})
    assert len(doc.layer("leg").holes) == 1 and C.host_of(doc, doc.layer("leg")).id == "body"
    d = np.array([0.9, -0.05])
    coarse = np.column_stack([-0.375 + 0.06 * np.cos(t[::2]), -0.6 + 0.1 * np.sin(t[::2])])
    for name, copy_hole, twin in (("same", hole + d, "leg"), ("moved", hole + d + [0.0, -0.1], None),
                                  ("redrawn", coarse + d, None)):
        doc.execute({"command": "add_layer", "id": name})
        doc.execute({"command": "set_inflate_params", "layer": name, "params": {"resolution": 0.06}})
        doc.execute({"command": "set_contour", "layer": name, "points": (leg + d).tolist(), "holes": [copy_hole.tolist()]})
        found = C.twin_source(doc, doc.layer(name))
        assert (None if found is None else found.id) == twin, name
        doc.execute({"command": "remove_layer", "layer": name})
