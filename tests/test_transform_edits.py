"""Edits follow a moved layer through their own command (issue 29, point 4): the core maps a
layer's outline and mesh, and asks each edit's command (``Command.transform_edit``) how its
entry moves. A command that does not say refuses the transform, naming the layer and itself,
and the document is left as it was."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document.commands import (
    DuplicateLayer,
    TransformLayer,
    TranslateLayer,
    compose_affine,
    rotate_about,
    scale_about,
    transform_points,
)
from sketchforge.errors import EditNotMovableError, PluginError
from sketchforge.plugin_api import ReplaceLayerCommand, hookimpl, parse_field, parse_vector
from sketchforge.plugins.testing import FanInflater, make_test_host

SQUARE = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]


def exactly(message: str) -> str:
    return "^" + re.escape(message) + "$"


# --- the sculpt edit: what the core used to do, now its command's, bit for bit ----------------
def reference_transform(entry: dict, A: np.ndarray) -> dict:
    """The core's edit rewriting before issue 29 (commands._transformed), frozen here."""
    L, t = A[:, :2], A[:, 2]
    moved_only = bool(np.array_equal(L, np.eye(2)))
    s = float(np.sqrt(L[0, 0] * L[1, 1] - L[0, 1] * L[1, 0]))

    def f(P):
        P = np.asarray(P, dtype=np.float64).reshape(-1, 2)
        return P + t if moved_only else P @ L.T + t

    e = dict(entry)
    if isinstance(e.get("pick"), list) and len(e["pick"]) >= 2:
        q = f(np.asarray(e["pick"][:2], dtype=np.float64))[0]
        e["pick"] = [float(q[0]), float(q[1]), *e["pick"][2:]]
    if isinstance(e.get("stroke"), list):
        e["stroke"] = f(e["stroke"]).tolist()
    if not moved_only and isinstance(e.get("band"), (int, float)) and not isinstance(e.get("band"), bool):
        e["band"] = float(e["band"]) * s
    light = e.get("light")
    if not moved_only and isinstance(light, list) and len(light) >= 2:
        v = L @ np.asarray(light[:2], dtype=np.float64)
        v = v / max(float(np.hypot(v[0], v[1])), 1e-300)
        e["light"] = [float(v[0]), float(v[1]), *light[2:]]
    return e


MATRICES = {
    "move": np.array([[1.0, 0.0, 0.1 + 0.2], [0.0, 1.0, -1.0 / 3.0]]),
    "scale-rotate-move": compose_affine(scale_about([0.2, -0.1], 1.5), rotate_about([0.2, -0.1], 0.7),
                                        [[1, 0, 0.3], [0, 1, -0.2]]),
    "shear": np.array([[1.0, 0.35, 0.0], [0.0, 1.0, 0.25]]),
    "half turn": rotate_about([0.0, 0.0], np.pi),
}


@pytest.mark.parametrize("which", sorted(MATRICES))
def test_the_sculpt_command_moves_its_edit_exactly_as_the_core_did(which):
    from sketchforge_isophote_tool.command import SculptIsophote

    A = MATRICES[which]
    s = float(np.sqrt(A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]))  # as the core computes it
    rng = np.random.default_rng(7)
    entries = [
        {"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3,
         "stroke": rng.normal(size=(9, 2)).tolist(), "light": [0.6, 0.8, 0.0], "solver": "gauss_newton"},
        {"command": "sculpt_isophote", "layer": "body", "pick": [1e-17, -3.25, 0.5], "band": 2,
         "stroke": [[0.1, 0.2]], "model": "oren_nayar"},  # an integer band, a 3-number pick, no light
    ]
    for entry in entries:
        got = SculptIsophote.transform_edit(entry, A, s)
        want = reference_transform(entry, A)
        assert got == want and got is not entry
        assert all(type(got[k]) is type(want[k]) for k in want)
        if which == "move":  # a pure move leaves the band and light untouched, bit for bit
            assert got["band"] is entry["band"] and got.get("light") is entry.get("light")


def test_a_sculpted_layer_moved_in_the_document_carries_the_commands_result(real_host):
    doc = Document(host=real_host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    doc.execute({"command": "set_contour", "layer": "body", "points": np.c_[np.cos(t), 0.7 * np.sin(t)].tolist(),
                 "closed": True})
    doc.execute({"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3,
                 "stroke": [[0.1, -0.3], [0.15, -0.1], [0.22, 0.1], [0.3, 0.3]]})
    before = doc.layer("body").edits
    A = MATRICES["scale-rotate-move"]
    doc.push(TransformLayer(layer="body", matrix=A))
    assert doc.layer("body").edits == tuple(reference_transform(e, A) for e in before)


# --- a plugin edit with and without transform_edit --------------------------------------------
@dataclass
class Stamp(ReplaceLayerCommand):
    """A plugin edit: marks the layer at ``at``; recorded in the layer's edits and re-applied
    after re-inflation (lifts the vertex nearest to ``at``). Says nothing about moving."""

    name: ClassVar[str] = "stamp"
    at: list = None

    def compute(self, doc, old):
        return self.reapply(doc, old, self.to_dict())

    @classmethod
    def reapply(cls, doc, layer, entry):
        V = np.array(layer.mesh.V)
        k = int(np.argmin(np.hypot(*(V[:, :2] - entry["at"]).T)))
        V[k, 2] += 0.25
        from dataclasses import replace

        return layer.evolve(mesh=replace(layer.mesh, V=V), edits=tuple(layer.edits) + (dict(entry),))

    def to_dict(self):
        return {"command": self.name, "layer": self.layer, "at": [float(v) for v in self.at]}

    @classmethod
    def from_dict(cls, d):
        return cls(layer=parse_field(d, "layer", str, cls.name), at=parse_vector(d, "at", cls.name))


@dataclass
class MovableStamp(Stamp):
    name: ClassVar[str] = "movable_stamp"

    @classmethod
    def transform_edit(cls, entry, matrix, scale):
        e = dict(entry)
        e["at"] = transform_points(matrix, e["at"])[0].tolist()
        return e


@dataclass
class BuggyStamp(Stamp):
    name: ClassVar[str] = "buggy_stamp"

    @classmethod
    def transform_edit(cls, entry, matrix, scale):
        return entry["where"]  # a bug: KeyError


@dataclass
class ListStamp(Stamp):
    name: ClassVar[str] = "list_stamp"

    @classmethod
    def transform_edit(cls, entry, matrix, scale):
        return [entry]


class StampPlugin:
    @hookimpl
    def sketchforge_commands(self):
        return [Stamp, MovableStamp, BuggyStamp, ListStamp]


def stamped(command: str):
    host = make_test_host(FanInflater(), StampPlugin())
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "a", "name": "Arm"})
    doc.execute({"command": "set_contour", "layer": "a", "points": SQUARE, "closed": True})
    doc.execute({"command": command, "layer": "a", "at": [0.5, 0.25]})
    return doc


MOVES = {
    "transform_layer": lambda: TransformLayer(layer="a", matrix=rotate_about([0.0, 0.0], 0.5)),
    "translate_layer": lambda: TranslateLayer(layer="a", offset=[2.0, 0.0]),
    "duplicate_layer offset": lambda: DuplicateLayer(layer="a", offset=[2.5, 0.0]),
}


@pytest.mark.parametrize("move", sorted(MOVES))
def test_an_edit_whose_plugin_does_not_say_how_to_move_it_refuses_the_transform(move):
    doc = stamped("stamp")
    layer, layers, count = doc.layer("a"), doc.layers, doc.undo_stack.count()
    with pytest.raises(EditNotMovableError, match=exactly(
        "layer 'a' cannot be moved: its edit 'stamp' (plugin 'plugin-1-StampPlugin') cannot follow it: "
        "its plugin does not say how to move its edits (Command.transform_edit)"
    )):
        doc.push(MOVES[move]())
    assert doc.layer("a") is layer and doc.layers == layers and doc.undo_stack.count() == count


def test_a_duplicate_in_place_needs_no_move():
    doc = stamped("stamp")
    doc.push(DuplicateLayer(layer="a", new_id="b"))
    assert doc.layer("b").edits == doc.layer("a").edits and len(doc.layers) == 2


def test_an_edit_that_says_how_follows_the_layer_and_is_reapplied_there():
    doc = stamped("movable_stamp")
    A = compose_affine(rotate_about([0.0, 0.0], np.pi / 2), [[1.0, 0.0, 3.0], [0.0, 1.0, 0.0]])
    doc.push(TransformLayer(layer="a", matrix=A))
    at = np.array(doc.layer("a").edits[0]["at"])
    assert np.abs(at - (A[:, :2] @ [0.5, 0.25] + A[:, 2])).max() < 1e-15  # (2.75, 0.5)
    # The re-inflated layer gets the stamp where the edit now lies: on the moved part, at the
    # vertex nearest to the moved point (not at the original (0.5, 0.25), off the part).
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"inflation": 1.0}})
    layer = doc.layer("a")
    plain = doc.host.inflate(layer.points, True, layer.params, solver=layer.solver)
    V = layer.mesh.V
    dz = V[:, 2] - plain.V[:, 2]
    lifted = np.flatnonzero(dz)
    assert len(lifted) == 1 and dz[lifted[0]] == 0.25
    assert lifted[0] == np.argmin(np.hypot(*(V[:, :2] - at).T))
    assert V[:, 0].min() > 1.9  # the whole part moved right of x = 2
    doc.undo_stack.undo()
    doc.undo_stack.undo()
    assert doc.layer("a").edits[0]["at"] == [0.5, 0.25]


def test_a_transform_edit_bug_or_wrong_value_names_the_plugin_and_changes_nothing():
    for command, tail in (("buggy_stamp", "failed: KeyError: 'where'"),
                          ("list_stamp", "must return the edit's dict with \"command\": 'list_stamp', got list")):
        doc = stamped(command)
        layer = doc.layer("a")
        with pytest.raises(PluginError, match=exactly(
            f"layer 'a' cannot be moved: transform_edit of command {command!r} (plugin 'plugin-1-StampPlugin') {tail}"
        )):
            doc.push(TranslateLayer(layer="a", offset=[1.0, 0.0]))
        assert doc.layer("a") is layer


def test_transform_points_adds_the_offset_only_for_a_pure_move():
    P = np.array([[0.1, 0.2], [-3.0, 1e-300]])
    move = [[1.0, 0.0, 0.7], [0.0, 1.0, -0.3]]
    assert transform_points(move, P).tobytes() == (P + [0.7, -0.3]).tobytes()
    A = [[0.0, -2.0, 1.0], [2.0, 0.0, 0.0]]
    assert np.array_equal(transform_points(A, [1.0, 0.5]), [[0.0, 2.0]])
