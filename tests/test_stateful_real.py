"""Undo never lies, with the real plugins: random sequences of contours, parameter changes,
sculpt edits, layer operations, light drags, undo, redo, save/open and replay, checking
bit-identical meshes (and assembled models) throughout. A command that fails must leave the
document exactly as it was."""

import json

import numpy as np
from hypothesis import HealthCheck, event, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, precondition, rule
from tests_support import assert_save_open_replay_agree, assert_undo_all_redo_all, examples

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.document.commands import new_gesture_id
from sketchforge.errors import SketchforgeError
from sketchforge.plugins.manager import default_host

COARSE = {"resolution": 0.09, "inflation": 1.0, "smoothing": 0.5}


def blob(cx, cy, rx, ry, n=60):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[cx + rx * np.cos(t), cy + ry * np.sin(t)].tolist()


SHAPES = {
    "body": (blob(0, 0, 1.0, 0.7), True),
    # An open stroke whose ends lie inside the body: attaches as a head.
    "head": ((np.array(blob(0.0, 1.0, 0.45, 0.45, 60))[[*range(50, 60), *range(0, 41)]]).tolist(), False),
    "eye": (blob(1.8, 1.4, 0.25, 0.2, 30), True),
}


class RealDocumentMachine(RuleBasedStateMachine):
    def __init__(self):
        super().__init__()
        self.host = default_host()
        self.doc = Document(host=self.host)
        self.initial = ff.document_to_dict(self.doc)["snapshot"]

    @initialize()
    def start_with_a_body(self):
        # Every run sculpts and assembles something: the body exists from the start, and
        # undoing everything must still give back the empty document.
        self.add_and_draw("body")

    def try_execute(self, entry):
        before = ff.document_to_dict(self.doc)
        try:
            self.doc.execute(entry)
        except SketchforgeError:
            assert ff.document_to_dict(self.doc) == before  # all or nothing

    @rule(lid=st.sampled_from(sorted(SHAPES)))
    def add_and_draw(self, lid):
        if lid in self.doc.layer_ids():
            return
        pts, closed = SHAPES[lid]
        self.try_execute({"command": "add_layer", "id": lid})
        self.try_execute({"command": "set_inflate_params", "layer": lid, "params": COARSE})
        self.try_execute({"command": "set_contour", "layer": lid, "points": pts, "closed": closed})

    @precondition(lambda self: self.doc.layers)
    @rule(data=st.data(), inflation=st.sampled_from([0.7, 1.0, 1.4]))
    def params(self, data, inflation):
        lid = data.draw(st.sampled_from(self.doc.layer_ids()))
        self.try_execute({"command": "set_inflate_params", "layer": lid, "params": {"inflation": inflation}})

    @precondition(lambda self: "body" in self.doc.layer_ids() and self.doc.layer("body").mesh is not None)
    @rule(dx=st.sampled_from([-0.08, 0.0, 0.08]), band=st.sampled_from([0.25, 0.35]))
    def sculpt(self, dx, band):
        event("sculpt")
        stroke = [[0.1 + dx, -0.3], [0.15 + dx, -0.1], [0.22 + dx, 0.1], [0.3 + dx, 0.3]]
        self.try_execute({"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": band, "stroke": stroke})

    @precondition(lambda self: self.doc.layers)
    @rule(data=st.data())
    def reorder(self, data):
        lid = data.draw(st.sampled_from(self.doc.layer_ids()))
        self.try_execute({"command": "move_layer", "layer": lid, "index": data.draw(st.integers(0, len(self.doc.layers) - 1))})

    @precondition(lambda self: self.doc.layers)
    @rule(data=st.data(), visible=st.booleans())
    def visibility(self, data, visible):
        lid = data.draw(st.sampled_from(self.doc.layer_ids()))
        self.try_execute({"command": "set_layer_visible", "layer": lid, "visible": visible})

    @rule(angle=st.sampled_from([0.0, 45.0, 120.0, -60.0]))
    def light(self, angle):
        g = new_gesture_id()
        from sketchforge.document.commands import SetLight

        for a in (angle - 10, angle):
            self.doc.push(SetLight(direction=[np.cos(np.radians(a)), np.sin(np.radians(a))], gesture=g))

    @rule()
    def undo(self):
        self.doc.undo_stack.undo()

    @rule()
    def redo(self):
        self.doc.undo_stack.redo()

    @rule()
    def save_open_replay(self):
        assert_save_open_replay_agree(self.doc, self.host)

    @rule()
    def assembly_is_reproducible(self):
        """After undo-all/redo-all, and in the document reopened from a save, the assembled
        model is recomputed bit for bit."""
        a = self.doc.assembled()
        event(f"assembled {0 if a is None else len(self.doc.layers)} layers")
        st_ = self.doc.undo_stack
        i = st_.index
        st_.set_index(0)
        st_.set_index(i)
        reopened = ff.document_from_dict(json.loads(ff.dumps(self.doc)), "t", host=self.host)
        for b in (self.doc.assembled(), reopened.assembled()):
            assert (a is None and b is None) or a.identical(b)

    @invariant()
    def undo_all_redo_all(self):
        assert_undo_all_redo_all(self.doc, self.initial)


TestRealDocument = RealDocumentMachine.TestCase
TestRealDocument.settings = settings(
    max_examples=examples(20), stateful_step_count=10, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck)
)
