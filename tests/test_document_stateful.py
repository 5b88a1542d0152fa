"""Random sequences of commands, undo, redo, save and open keep the document honest:
every single undo gives back exactly the state before that command and every redo the state
after it (the machine keeps the state at each index of the stack: a bug in one command's undo,
such as re-inserting a removed layer at the end, shows at that step, not only in the sum),
undo of everything restores the initial document exactly, redo restores the final one,
save -> open gives bit-identical meshes, and replaying the journal agrees with the snapshot."""


import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, precondition, rule
from tests_support import IN_MUTATION_RUN, assert_save_open_replay_agree, assert_undo_all_redo_all, examples

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.document.commands import (
    AddLayer,
    DuplicateLayer,
    MirrorLayer,
    MoveLayer,
    RemoveLayer,
    RenameLayer,
    SetContour,
    SetInflateParams,
    SetLayerVisible,
    SetLight,
    TransformLayer,
    new_gesture_id,
)
from sketchforge.plugins.testing import FanInflater, make_test_host

HOST = make_test_host(FanInflater())


def star(n: int, seed: int) -> list:
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 1.0 + 0.3 * rng.random(n)
    return np.c_[r * np.cos(t), r * np.sin(t)].tolist()


def snapshot(doc):
    return [(l.id, l.name, l.visible, l.closed, dict(l.params), l.edits, l.points, l.mesh) for l in doc.layers], doc.light


class DocumentMachine(RuleBasedStateMachine):
    def __init__(self):
        super().__init__()
        self.doc = Document(host=HOST)
        self.initial = ff.document_to_dict(self.doc)
        self.states = [self.initial["snapshot"]]  # states[i]: the document at stack index i

    def state(self):
        return ff.document_to_dict(self.doc)["snapshot"]

    def push(self, command):
        self.doc.push(command)
        i = self.doc.undo_stack.index
        # a merged command (light drag) replaces the state at the same index; a push after undo
        # drops the redo tail's states with its commands
        self.states = self.states[:i] + [self.state()]
        # each command's undo checked right after it ran (a random later undo may never come)
        stack = self.doc.undo_stack
        stack.undo()
        assert self.state() == self.states[i - 1]
        stack.redo()
        assert self.state() == self.states[i]

    def ids(self):
        return self.doc.layer_ids()

    @initialize()
    def start_with_layers(self):
        # three layers make reordering bugs visible (with two, every move is a swap and an
        # undo that moves the wrong way still restores the order); rules remove them too
        for lid in ["a", "b", "c"]:
            self.push(AddLayer(id=lid))

    @rule(name=st.sampled_from(["a", "d", "e", None]))
    def add(self, name):
        if name is None or name not in self.ids():
            self.push(AddLayer(id=name))

    @precondition(lambda self: self.doc.layers)
    @rule(data=st.data())
    def remove(self, data):
        self.push(RemoveLayer(layer=data.draw(st.sampled_from(self.ids()))))

    @precondition(lambda self: self.doc.layers)
    @rule(data=st.data(), text=st.text(min_size=1, max_size=8).filter(str.strip))
    def rename(self, data, text):
        self.push(RenameLayer(layer=data.draw(st.sampled_from(self.ids())), new_name=text))

    @precondition(lambda self: self.doc.layers)
    @rule(data=st.data(), visible=st.booleans())
    def visible(self, data, visible):
        self.push(SetLayerVisible(layer=data.draw(st.sampled_from(self.ids())), visible=visible))

    @precondition(lambda self: len(self.doc.layers) >= 2)
    @rule(data=st.data())
    def move(self, data):
        ids = self.ids()
        src = data.draw(st.integers(0, len(ids) - 1))
        # a real move (a no-op move would hide an undo that moves the wrong way)
        dst = data.draw(st.integers(0, len(ids) - 1).filter(lambda i: i != src))
        self.push(MoveLayer(layer=ids[src], index=dst))

    @precondition(lambda self: self.doc.layers and len(self.doc.layers) < 6)
    @rule(data=st.data())
    def duplicate(self, data):
        self.push(DuplicateLayer(layer=data.draw(st.sampled_from(self.ids()))))

    @precondition(lambda self: self.doc.layers)
    @rule(data=st.data(), n=st.integers(5, 12), seed=st.integers(0, 50), closed=st.booleans())
    def contour(self, data, n, seed, closed):
        self.push(SetContour(layer=data.draw(st.sampled_from(self.ids())), points=star(n, seed), closed=closed))

    @precondition(lambda self: any(l.points is not None for l in self.doc.layers))
    @rule(data=st.data(), inflation=st.floats(0.1, 3.0), smoothing=st.sampled_from([0.0, 0.3, 0.9]))
    def params(self, data, inflation, smoothing):
        lid = data.draw(st.sampled_from([l.id for l in self.doc.layers if l.points is not None]))
        self.push(SetInflateParams(layer=lid, params={"inflation": inflation, "smoothing": smoothing}))

    @precondition(lambda self: any(l.points is not None for l in self.doc.layers))
    @rule(data=st.data())
    def mirror(self, data):
        lid = data.draw(st.sampled_from([l.id for l in self.doc.layers if l.points is not None]))
        self.push(MirrorLayer(layer=lid))

    @precondition(lambda self: any(l.points is not None for l in self.doc.layers))
    @rule(data=st.data(), angle=st.floats(-180, 180), scale=st.floats(0.5, 2.0), dx=st.floats(-1, 1))
    def transform(self, data, angle, scale, dx):
        lid = data.draw(st.sampled_from([l.id for l in self.doc.layers if l.points is not None]))
        a = np.radians(angle)
        L = scale * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        self.push(TransformLayer(layer=lid, matrix=np.column_stack([L, [dx, 0.25]])))

    @rule(angles=st.lists(st.floats(-180, 180), min_size=1, max_size=4))
    def light_drag(self, angles):
        g = new_gesture_id()
        for a in angles:
            self.push(SetLight(direction=[np.cos(np.radians(a)), np.sin(np.radians(a))], gesture=g))

    @rule()
    def undo(self):
        stack = self.doc.undo_stack
        if stack.can_undo():
            stack.undo()
            assert self.state() == self.states[stack.index]

    @rule()
    def redo(self):
        stack = self.doc.undo_stack
        if stack.can_redo():
            stack.redo()
            assert self.state() == self.states[stack.index]

    @rule()
    def save_and_open(self):
        assert_save_open_replay_agree(self.doc, HOST)

    @invariant()
    def undo_all_then_redo_all(self):
        final_state = snapshot(self.doc)
        assert_undo_all_redo_all(self.doc, self.initial["snapshot"])
        # Identity, not only equality: redo reuses the very same mesh objects.
        for (a, b) in zip(snapshot(self.doc)[0], final_state[0]):
            assert a[7] is b[7]


TestDocumentMachine = DocumentMachine.TestCase
TestDocumentMachine.settings = settings(
    max_examples=examples(40), stateful_step_count=15, deadline=None, derandomize=IN_MUTATION_RUN,
    suppress_health_check=[HealthCheck.too_slow],
)
