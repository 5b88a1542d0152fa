"""Contracts of the document layer that only the app's gestures used to exercise (found by the
mutation run, `make mutate SCOPE=document`): the light from a drag, macros closed after an undo
or inside another macro, error lines for huge integers, moves and scales about a centre."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document.commands import (
    AddLayer,
    Command,
    MacroCommand,
    RenameLayer,
    TranslateLayer,
    _digits,
    rotate_about,
    scale_about,
)
from sketchforge.document.fileformat import _short
from sketchforge.document.layer import Light
from sketchforge.errors import DocumentFormatError, ParameterError


def exactly(message: str) -> str:
    """A pytest.raises pattern for exactly this message (users read these lines)."""
    return "^" + re.escape(message) + "$"


NO_LENGTH = "the light direction is undefined: drag away from the centre of the drawing"


# --- the light --------------------------------------------------------------------------------
@pytest.mark.parametrize("center, point, angle", [
    ((0.0, 0.0), (2.0, 0.0), 0.0),
    ((1.0, 1.0), (1.0, 4.0), 90.0),
    ((5.0, -2.0), (2.0, -5.0), -135.0),
    ([[3.0], [3.0]], [[2.0], [4.0]], 135.0),  # any array of two numbers (a Qt point's tuple)
])
def test_light_from_drag_points_from_the_centre_to_the_mouse(center, point, angle):
    light = Light.from_drag(center, point)
    assert light.angle == pytest.approx(angle, abs=1e-12)
    assert math.hypot(light.x, light.y) == pytest.approx(1.0, abs=1e-15)
    assert light.direction[2] == 0.0


@pytest.mark.parametrize("center, point, message", [
    ((0.0, 0.0, 0.0), (1.0, 0.0), "a light drag needs a 2D centre and a 2D point"),
    ((0.0, 0.0), (1.0,), "a light drag needs a 2D centre and a 2D point"),
    ((0.0, np.nan), (1.0, 0.0), "a light drag needs finite coordinates"),
    ((0.0, 0.0), (np.inf, 0.0), "a light drag needs finite coordinates"),
    ((0.0, 0.0), (0.0, 0.0), NO_LENGTH),
    # "no length" is relative to the coordinates: 1e-9 is a drag at the origin, not at 1e6
    ((1e6, 1e6), (1e6 + 1e-9, 1e6), NO_LENGTH),
    ((-1e6, 0.0), (-1e6, 1e-9), NO_LENGTH),  # the centre's size counts
    ((0.0, 0.0), (1e-12, 0.0), NO_LENGTH),    # exactly at the limit
])
def test_light_from_a_drag_of_no_length_or_bad_points_is_refused(center, point, message):
    with pytest.raises(ParameterError, match=exactly(message)):
        Light.from_drag(center, point)


def test_light_from_a_tiny_drag_near_the_origin_is_a_direction():
    assert Light.from_drag((0.0, 0.0), (0.0, 1e-9)).angle == pytest.approx(90.0)
    assert Light.from_drag((0.0, 0.0), (0.0, 1.5e-12)).angle == pytest.approx(90.0)  # just above 1e-12
    assert Light.from_drag((0.5, 0.0), (0.5, 1.5e-12)).angle == pytest.approx(90.0)  # scale is at least 1
    # integer coordinates beyond int64 (a script's) are still numbers
    assert Light.from_drag((0, 0), (2**70, 0)).angle == 0.0
    assert Light.from_drag((2**70, 0), (0, 0)).angle == 180.0


@pytest.mark.parametrize("degrees", [0.0, 30.0, 90.0, 200.0, -45.0])
def test_light_from_angle_is_counter_clockwise_from_x(degrees):
    light = Light.from_angle(degrees)
    assert (light.x, light.y) == pytest.approx((math.cos(math.radians(degrees)), math.sin(math.radians(degrees))))
    assert light.angle == pytest.approx((degrees + 180.0) % 360.0 - 180.0)


# --- macros -----------------------------------------------------------------------------------
def _state(doc):
    return (doc.layer_ids(), [doc.layer(i).name for i in doc.layer_ids()], doc.undo_stack.index)


def test_end_macro_without_begin_is_an_error(fan_host):
    doc = Document(host=fan_host)
    with pytest.raises(RuntimeError, match=exactly("end_macro without begin_macro")):
        doc.undo_stack.end_macro()


def test_a_macro_after_an_undo_replaces_the_redo_tail_and_counts_as_one_step(fan_host):
    doc = Document(host=fan_host)
    stack = doc.undo_stack
    doc.push(AddLayer(id="a"))
    doc.push(AddLayer(id="b"))
    doc.push(AddLayer(id="c"))
    stack.undo()
    stack.undo()  # index 1: "b" and "c" can be redone
    stack.begin_macro("Draw two")
    doc.push(AddLayer(id="d"))
    doc.push(RenameLayer(layer="d", new_name="Dee"))
    macro = stack.end_macro()
    assert macro is not None and macro.text() == "Draw two"
    assert stack.count() == 2 and stack.index == 2 and not stack.can_redo()
    assert doc.layer_ids() == ["a", "d"] and doc.layer("d").name == "Dee"
    stack.undo()
    assert doc.layer_ids() == ["a"] and stack.index == 1
    stack.redo()
    assert doc.layer_ids() == ["a", "d"] and doc.layer("d").name == "Dee" and stack.index == 2


def test_a_macro_dropping_the_saved_state_makes_the_document_unsaved_for_good(fan_host):
    doc = Document(host=fan_host)
    stack = doc.undo_stack
    for lid in ("a", "b", "c"):
        doc.push(AddLayer(id=lid))
    stack.set_clean()  # saved with three layers
    stack.undo()
    stack.undo()
    assert not stack.is_clean()
    stack.begin_macro("Other")
    doc.push(AddLayer(id="x"))
    stack.end_macro()
    # the saved state is gone from the history: no undo/redo can get back to "clean"
    assert stack.clean_index == -1
    for _ in range(stack.index):
        stack.undo()
        assert not stack.is_clean()


def test_a_macro_keeps_the_saved_state_when_it_comes_after_it(fan_host):
    doc = Document(host=fan_host)
    stack = doc.undo_stack
    doc.push(AddLayer(id="a"))
    doc.push(AddLayer(id="b"))
    stack.undo()
    stack.set_clean()  # saved with one layer, "b" still redoable
    stack.begin_macro("Other")
    doc.push(AddLayer(id="x"))
    stack.end_macro()
    assert stack.clean_index == 1 and not stack.is_clean()
    stack.undo()
    assert stack.is_clean()


def test_a_macro_inside_a_macro_is_one_child_and_one_step(fan_host):
    doc = Document(host=fan_host)
    stack = doc.undo_stack
    doc.push(AddLayer(id="a"))
    before = _state(doc)
    stack.begin_macro("Outer")
    doc.push(AddLayer(id="b"))
    stack.begin_macro("Inner")
    doc.push(AddLayer(id="c"))
    doc.push(RenameLayer(layer="c", new_name="Cee"))
    inner = stack.end_macro()
    assert stack.in_macro() and stack.count() == 1  # nothing recorded before the outer ends
    doc.push(AddLayer(id="d"))
    outer = stack.end_macro()
    assert [type(c).__name__ for c in outer.children] == ["AddLayer", "MacroCommand", "AddLayer"]
    assert outer.children[1] is inner and len(inner.children) == 2
    assert stack.count() == 2 and stack.index == 2
    after = _state(doc)
    stack.undo()
    assert _state(doc) == before
    stack.redo()
    assert _state(doc) == after and doc.layer("c").name == "Cee"


def test_an_empty_macro_leaves_no_step(fan_host):
    doc = Document(host=fan_host)
    doc.undo_stack.begin_macro("Nothing")
    assert doc.undo_stack.end_macro() is None
    assert doc.undo_stack.count() == 0 and not doc.undo_stack.in_macro()


def test_macro_text_defaults_to_group():
    assert MacroCommand().text() == "Group"
    assert MacroCommand(text="Draw layer").text() == "Draw layer"


def test_macro_that_fails_half_way_changes_nothing(fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    before = _state(doc)
    macro = MacroCommand("Two", [AddLayer(id="b"), AddLayer(id="c"), RenameLayer(layer="zz", new_name="x")])
    with pytest.raises(Exception, match="zz"):
        doc.push(macro)
    assert _state(doc) == before


def test_macro_from_a_journal_needs_a_registry_and_a_bounded_depth(fan_host):
    registry = fan_host.commands
    entry = {"command": "macro", "text": "T", "children": [{"command": "add_layer", "id": "a"}]}
    m = MacroCommand.from_dict(entry, registry)
    assert m.text() == "T" and [c.to_dict()["id"] for c in m.children] == ["a"]
    assert MacroCommand.from_dict({"command": "macro", "children": []}, registry).text() == "Group"
    with pytest.raises(DocumentFormatError, match=exactly("a macro needs a command registry to read its children")):
        MacroCommand.from_dict(entry)
    nested = {"command": "macro", "children": []}
    for _ in range(16):
        nested = {"command": "macro", "children": [nested]}
    with pytest.raises(DocumentFormatError, match="nested more than 16 deep"):
        registry.from_dict(nested)
    ok = {"command": "macro", "children": []}
    for _ in range(15):
        ok = {"command": "macro", "children": [ok]}
    registry.from_dict(ok)  # 16 levels are allowed


# --- error lines ------------------------------------------------------------------------------
@pytest.mark.parametrize("exponent, sign, text", [
    (None, 1, "12345"),
    (19, -1, "-10000000000000000000"),           # 20 digits: shown as is
    (20, 1, "an integer of 21 digits"),
    (20, -1, "an integer of 21 digits"),
    (999, 1, "an integer of 1000 digits"),
    ("10**1000-1", 1, "an integer of 1000 digits"),
    (1000, 1, "an integer of over 1000 digits"),
    (5000, 1, "an integer of over 1000 digits"),      # str() of it would raise
])
def test_huge_integers_are_named_by_their_length(exponent, sign, text):
    if exponent is None:
        value = 12345
    elif exponent == "10**1000-1":
        value = 10**1000 - 1
    else:
        value = sign * 10**exponent
    assert _digits(value) == text


# --- moves, scales, rotations -----------------------------------------------------------------
def _apply(m, p):
    return m[:, :2] @ np.asarray(p, dtype=np.float64) + m[:, 2]


def test_scale_about_keeps_the_centre_and_scales_offsets():
    c = (2.0, -1.0)
    m = scale_about(c, 3.0)
    assert _apply(m, c) == pytest.approx(c)
    assert _apply(m, (3.0, 1.0)) == pytest.approx((2.0 + 3.0, -1.0 + 6.0))
    m2 = scale_about(c, 2.0, 0.5)  # anisotropic
    assert _apply(m2, c) == pytest.approx(c)
    assert _apply(m2, (3.0, 1.0)) == pytest.approx((4.0, 0.0))


def test_rotate_about_keeps_the_centre_and_turns_counter_clockwise():
    c = (1.0, 1.0)
    m = rotate_about(c, math.pi / 2)
    assert _apply(m, c) == pytest.approx(c)
    assert _apply(m, (2.0, 1.0)) == pytest.approx((1.0, 2.0))


@pytest.mark.parametrize("offset", [(1.0,), (1.0, 2.0, 3.0), (np.nan, 0.0), (0.0, np.inf)])
def test_translate_layer_refuses_an_offset_that_is_not_two_finite_numbers(offset):
    with pytest.raises(ParameterError, match=exactly("a move's offset must be two finite numbers")):
        TranslateLayer(layer="a", offset=offset)


def test_translate_layer_reads_and_names_itself(fan_host):
    cmd = fan_host.commands.from_dict({"command": "translate_layer", "layer": "a", "offset": [1, -2]})
    assert isinstance(cmd, TranslateLayer) and cmd.offset == [1.0, -2.0] and cmd.layer == "a"
    assert cmd.text() == "Move layer"
    with pytest.raises(DocumentFormatError, match="'offset' must be 2 numbers"):
        fan_host.commands.from_dict({"command": "translate_layer", "layer": "a", "offset": [1, 2, 3]})


def test_translate_layer_moves_by_an_integer_offset_as_by_floats(fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    from sketchforge.document.commands import SetContour

    doc.push(SetContour(layer="a", points=[[0, 0], [1, 0], [1, 1], [0, 1]], closed=True))
    V0 = doc.layer("a").mesh.V.copy()
    doc.push(TranslateLayer(layer="a", offset=(2, -1)))
    V1 = doc.layer("a").mesh.V
    assert V1.dtype == np.float64
    assert np.array_equal(V1[:, :2], V0[:, :2] + [2.0, -1.0]) and np.array_equal(V1[:, 2], V0[:, 2])
    assert TranslateLayer(layer="a", offset=[[1], [2]]).offset == [1.0, 2.0]
    assert TranslateLayer(layer="a", offset=(2**70, 0)).offset == [float(2**70), 0.0]


def test_scale_about_takes_any_two_number_centre():
    m = scale_about([[1], [2]], 2)
    assert m.dtype == np.float64 and _apply(m, (1.0, 2.0)) == pytest.approx((1.0, 2.0))
    assert _apply(scale_about((1, 1), 3), (2, 2)) == pytest.approx((4.0, 4.0))
    assert _apply(scale_about((2**70, 0), 1.0), (0.0, 0.0)) == pytest.approx((0.0, 0.0))


def test_transform_layer_reads_only_a_2x3_matrix_of_numbers(fan_host):
    reg = fan_host.commands
    ok = reg.from_dict({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 2], [0, 1, 3]]})
    assert ok.layer == "a"
    bad = exactly("command 'transform_layer': 'matrix' must be [[a, b, tx], [c, d, ty]] numbers")
    for m in ([[1, 0, 2]], [[1, 0, 2], [0, 1]], [[1, 0, 2], (0, 1, 3)], [[1, 0, 2], [0, 1, "3"]],
              [[1, 0, 2], [0, 1, True]], [[1, 0, 2], [0, 1, 3], [0, 0, 1]]):
        with pytest.raises(DocumentFormatError, match=bad):
            reg.from_dict({"command": "transform_layer", "layer": "a", "matrix": m})


def test_a_document_takes_an_assembly_done_elsewhere_only_for_its_current_layers(fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    stale = doc.geometry_revision
    doc.push(AddLayer(id="b"))
    doc.offer_assembled(stale, "stale mesh")
    assert doc.assembled() != "stale mesh"
    doc.offer_assembled(doc.geometry_revision, "worker's mesh")
    assert doc.assembled() == "worker's mesh"  # not assembled again


def test_commands_name_themselves_and_do_not_merge_unless_they_say_so():
    class PaintThing(Command):
        name = "paint_thing"

    assert PaintThing().text() == "Paint thing"
    assert PaintThing().merge(PaintThing()) is False
    with pytest.raises(NotImplementedError, match=exactly("command 'paint_thing' cannot be re-applied")):
        PaintThing.reapply(None, None, {})


def test_long_values_in_error_lines_are_cut_to_sixty_characters():
    assert _short("x" * 58) == repr("x" * 58)  # 60 characters with the quotes: kept
    assert _short("x" * 59) == repr("x" * 59)[:57] + "..."
    assert len(_short(list(range(100)))) == 60
    assert _short([1, 2], n=5) == "[1, 2]"[:2] + "..."
    assert _short(None) == "None"


# --- all or nothing: a command that fails part-way --------------------------------------------
class _Mirror:
    """A view: keeps its own copy of the layer list from the document's signals only."""

    def __init__(self, doc):
        self.layers = list(doc.layers)
        self.light = doc.light
        self.plugin_keys_seen = []
        doc.layer_inserted.connect(lambda i, layer: self.layers.insert(i, layer))
        doc.layer_removed.connect(lambda i, layer: self.layers.pop(i))
        doc.layer_changed.connect(self._changed)
        doc.layer_moved.connect(lambda src, dst: self.layers.insert(dst, self.layers.pop(src)))
        doc.light_changed.connect(lambda light: setattr(self, "light", light))
        doc.plugin_data_changed.connect(self.plugin_keys_seen.append)

    def _changed(self, i, new, old):
        assert self.layers[i] is old
        self.layers[i] = new


class _Wreck(Command):
    """A buggy plugin command: changes the document through its private mutators, then raises."""

    name = "wreck"

    def __init__(self, steps):
        self.steps = steps

    def do(self, doc):
        for step in self.steps:
            step(doc)
        raise RuntimeError("plugin bug")

    def undo(self, doc):  # pragma: no cover - never recorded
        raise AssertionError


def _three_layer_doc(fan_host):
    from sketchforge.document.commands import SetContour

    doc = Document(host=fan_host)
    for lid in ("a", "b", "c"):
        doc.push(AddLayer(id=lid))
    doc.push(SetContour(layer="b", points=[[0, 0], [1, 0], [1, 1], [0, 1]], closed=True))
    doc._set_plugin_data("kept", {"x": 1})
    doc._set_plugin_data("changed", [1, 2])
    return doc


@pytest.mark.parametrize("case", ["replace two", "remove", "insert", "remove and insert", "reorder",
                                  "light", "plugin data", "everything"])
def test_a_command_failing_part_way_leaves_the_document_and_its_views_as_before(fan_host, case):
    from dataclasses import replace

    doc = _three_layer_doc(fan_host)
    view = _Mirror(doc)
    before_layers, before_light = doc.layers, doc.light
    before_data = {k: doc.plugin_data(k) for k in doc.plugin_data_keys}
    count, index = doc.undo_stack.count(), doc.undo_stack.index

    def replace_two(d):
        d._replace_layer(replace(d.layer("a"), name="A!"))
        d._replace_layer(replace(d.layer("c"), visible=False))

    def remove(d):
        d._remove_layer(1)

    def insert(d):
        d._insert_layer(0, replace(d.layer("a"), id="new"))

    def reorder(d):
        d._move_layer(0, 2)

    def light(d):
        d._set_light(Light.from_angle(123.0))

    def data(d):
        d._set_plugin_data("changed", [9])
        d._set_plugin_data("kept", None)
        d._set_plugin_data("added", "value")

    steps = {"replace two": [replace_two], "remove": [remove], "insert": [insert],
             "remove and insert": [remove, insert], "reorder": [reorder], "light": [light],
             "plugin data": [data], "everything": [replace_two, remove, insert, light, data]}[case]
    from sketchforge.errors import PluginError

    with pytest.raises(PluginError, match="command 'wreck' failed in do: RuntimeError: plugin bug; the document is unchanged"):
        doc.push(_Wreck(steps))
    # the very same layer objects, in order; the light; the plugin data
    assert len(doc.layers) == len(before_layers)
    assert all(a is b for a, b in zip(doc.layers, before_layers))
    assert doc.light == before_light
    assert {k: doc.plugin_data(k) for k in doc.plugin_data_keys} == before_data
    assert (doc.undo_stack.count(), doc.undo_stack.index) == (count, index)
    # a view that followed the signals shows the same again
    assert len(view.layers) == len(before_layers) and all(a is b for a, b in zip(view.layers, before_layers))
    assert view.light == before_light
    if case in ("plugin data", "everything"):
        assert sorted(set(view.plugin_keys_seen)) == ["added", "changed", "kept"]


def test_adopting_another_document_takes_its_first_light_journal_and_plugin_data(fan_host):
    src = _three_layer_doc(fan_host)
    src.initial_light = Light.from_angle(10.0)
    src.base_journal = [{"command": "add_layer", "id": "z"}]
    dst = Document(host=fan_host)
    dst._set_plugin_data("old", 1)
    dst.adopt(src)
    assert dst.layer_ids() == ["a", "b", "c"] and dst.light == src.light
    assert dst.initial_light == Light.from_angle(10.0)
    assert dst.base_journal == [{"command": "add_layer", "id": "z"}]
    assert dst.plugin_data("changed") == [1, 2] and dst.plugin_data("old") is None
    assert dst.same_state(src) and not dst.same_state(Document(host=fan_host))
    assert dst.undo_stack.count() == 0 and dst.undo_stack.is_clean()


def test_layers_are_the_same_state_only_when_every_field_is_equal():
    from dataclasses import replace

    from sketchforge.document.layer import Layer

    base = Layer(id="a", name="A", points=np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
                 holes=(np.array([[0.1, 0.1], [0.2, 0.1], [0.1, 0.2]]),))
    assert base.same_state(replace(base)) and not base.same_state("not a layer")
    assert not base.same_state(replace(base, points=None))
    assert not replace(base, points=None).same_state(base)
    assert replace(base, points=None).same_state(replace(base, points=None))
    assert not base.same_state(replace(base, points=base.points[:2]))
    assert not base.same_state(replace(base, points=base.points + 1e-15))
    assert not base.same_state(replace(base, holes=()))
    assert not base.same_state(replace(base, holes=(base.holes[0] * 1.01,)))
    assert not base.same_state(replace(base, holes=(base.holes[0][:, ::-1].copy(),)))
    assert not base.same_state(replace(base, name="B"))
    assert not base.same_state(replace(base, visible=False))


def test_reset_clean_means_no_state_in_the_history_is_the_saved_file(fan_host):
    doc = Document(host=fan_host)
    stack = doc.undo_stack
    assert stack.is_clean() and stack.clean_index == 0
    doc.push(AddLayer(id="a"))
    doc.push(AddLayer(id="b"))
    stack.set_clean()
    stack.reset_clean()
    assert stack.clean_index == -1
    for _ in range(2):
        assert not stack.is_clean()
        stack.undo()
    assert not stack.is_clean()
    for _ in range(2):
        stack.redo()
        assert not stack.is_clean()


def test_a_disconnected_slot_is_no_longer_called_and_disconnecting_twice_is_harmless():
    from sketchforge.document.events import Signal

    sig = Signal(int, name="s")
    got = []

    def slot(v):
        got.append(v)

    other = []
    sig.connect(slot)
    sig.connect(other.append)
    sig.emit(1)
    sig.disconnect(slot)
    sig.disconnect(slot)
    sig.emit(2)
    assert got == [1] and other == [1, 2]


def test_plugin_data_is_set_removed_and_announced_and_every_change_is_a_new_revision(fan_host):
    doc = Document(host=fan_host)
    seen = []
    doc.plugin_data_changed.connect(seen.append)
    assert doc.plugin_data("anim") is None and doc.plugin_data("anim", default=7) == 7
    revisions = [doc.revision]
    doc._set_plugin_data("anim", {"pins": []})
    revisions.append(doc.revision)
    doc._set_plugin_data("other", 1)
    revisions.append(doc.revision)
    assert doc.plugin_data("anim", default=7) == {"pins": []} and sorted(doc.plugin_data_keys) == ["anim", "other"]
    doc._set_plugin_data("anim", None)  # None removes
    revisions.append(doc.revision)
    doc._set_plugin_data("never set", None)  # removing what is not there is harmless
    revisions.append(doc.revision)
    assert doc.plugin_data_keys == ["other"] and doc.plugin_data("anim", default=7) == 7
    assert seen == ["anim", "other", "anim", "never set"]
    # autosave and views compare revisions: each change must give one never seen before
    assert all(b > a for a, b in zip(revisions, revisions[1:]))
    doc.push(AddLayer(id="a"))
    assert doc.revision > revisions[-1]


def test_new_layer_ids_skip_every_taken_one(fan_host):
    doc = Document(host=fan_host)
    for lid in ("layer1", "layer2", "layer4"):
        doc.push(AddLayer(id=lid))
    assert doc.new_layer_id() == "layer3"
    doc.push(AddLayer(id="layer3"))
    assert doc.new_layer_id() == "layer5" and doc.new_layer_id("leg") == "leg1"
    doc.push(AddLayer())  # an id chosen by the document
    assert doc.layer_ids()[-1] == "layer5" and doc.new_layer_id() == "layer6"


def test_a_light_change_is_a_new_revision_but_not_new_geometry(fan_host):
    doc = Document(host=fan_host)
    rev, geo = doc.revision, doc.geometry_revision
    doc._set_light(Light.from_angle(30.0))
    assert doc.revision > rev and doc.geometry_revision == geo


def _two_layer_doc(fan_host):
    from sketchforge.document.commands import SetContour, SetLayerVisible

    doc = Document(host=fan_host)
    for lid in ("a", "b", "c"):
        doc.push(AddLayer(id=lid))
    doc.push(SetContour(layer="a", points=[[0, 0], [1, 0], [1, 1], [0, 1]], closed=True))
    doc.push(SetContour(layer="b", points=[[2, 0], [3, 0], [3, 1], [2, 1]], closed=True))
    doc.push(SetContour(layer="c", points=[[4, 0], [5, 0], [5, 1], [4, 1]], closed=True))
    doc.push(SetLayerVisible(layer="c", visible=False))
    return doc


def test_the_assembled_model_takes_the_visible_layers_with_meshes_once_per_change(fan_host, monkeypatch):
    from sketchforge.document.commands import SetLayerVisible

    doc = _two_layer_doc(fan_host)
    doc.push(AddLayer(id="empty"))  # visible, no mesh
    calls = []
    monkeypatch.setattr(
        doc.host,
        "assemble",
        lambda layers, params=None, solver=None: calls.append(([l.id for l in layers], params)) or "model",
    )
    monkeypatch.setattr(doc.host, "has_assembler", lambda: True)
    assert doc.assembled() == "model" and doc.assembled() == "model"
    assert calls == [(["a", "b"], {})]  # once, the hidden and the empty layer left out
    assert doc.export_mesh() == "model" and len(calls) == 1
    doc.push(SetLayerVisible(layer="a", visible=False))
    doc.push(SetLayerVisible(layer="b", visible=False))
    assert doc.assembled() is None and len(calls) == 1  # nothing to assemble: no call
    with pytest.raises(Exception, match=exactly("there is nothing to export: no visible layer has a mesh")):
        doc.export_mesh()


def test_export_without_an_assembler_merges_the_visible_layers(fan_host):
    doc = _two_layer_doc(fan_host)
    a, b = doc.layer("a").mesh, doc.layer("b").mesh
    merged = doc.export_mesh()
    assert merged.V.shape[0] == a.V.shape[0] + b.V.shape[0] and merged.F.shape[0] == a.F.shape[0] + b.F.shape[0]
    assert doc.export_mesh("c") is doc.layer("c").mesh  # one layer: hidden or not
    with pytest.raises(Exception, match=exactly("layer 'empty' has no mesh (no contour was drawn)")):
        doc.push(AddLayer(id="empty"))
        doc.export_mesh("empty")


def test_differences_name_what_differs(fan_host):
    from dataclasses import replace

    one, two = _two_layer_doc(fan_host), _two_layer_doc(fan_host)
    assert one.differences(two) == []
    two._set_light(Light.from_angle(10.0))
    assert one.differences(two) == [f"light differs: {one.light} vs {two.light}"]
    two._set_light(one.light)
    two._replace_layer(replace(two.layer("a"), name="Other"))
    assert one.differences(two) == ["layer 'a': fields differ"]
    two._replace_layer(replace(two.layer("a"), name=one.layer("a").name, mesh=None))
    assert one.differences(two) == ["layer 'a': mesh differ"]
    assert two.differences(one) == ["layer 'a': mesh differ"]
    two._replace_layer(one.layer("a"))
    m = one.layer("b").mesh
    from sketchforge.geometry.mesh import Mesh

    V = m.V.copy()
    V[0, 2] += 1e-12
    two._replace_layer(replace(one.layer("b"), mesh=Mesh(V, m.F, m.boundary, m.junction, m.holes)))
    assert one.differences(two) == ["layer 'b': mesh differ"]
    two._replace_layer(one.layer("b"))
    two._set_plugin_data("only here", 1)
    assert one.differences(two) == ["plugin data 'only here' differs"]
    assert two.differences(one) == ["plugin data 'only here' differs"]
    three = _two_layer_doc(fan_host)
    three.push(AddLayer(id="d"))
    assert one.differences(three) == ["layers differ: ['a', 'b', 'c'] vs ['a', 'b', 'c', 'd']"]


def test_undo_and_redo_texts_name_the_step_they_would_undo_or_redo(fan_host):
    doc = Document(host=fan_host)
    stack = doc.undo_stack
    assert stack.undo_text() == "" and stack.redo_text() == ""
    doc.push(AddLayer(id="a"))
    doc.push(RenameLayer(layer="a", new_name="A"))
    assert stack.undo_text() == "Rename layer" and stack.redo_text() == ""
    stack.undo()
    assert stack.undo_text() == "Add layer" and stack.redo_text() == "Rename layer"
    stack.undo()
    assert stack.undo_text() == "" and stack.redo_text() == "Add layer"


def test_history_changes_are_announced_only_when_something_changed(fan_host):
    doc = Document(host=fan_host)
    seen = []
    doc.history_changed.connect(lambda: seen.append(doc.undo_stack.index))
    doc.push(AddLayer(id="a"))
    assert seen == [1]
    doc.undo_stack.redo()  # nothing to redo: no announcement
    assert seen == [1]
    doc.undo_stack.undo()
    assert seen == [1, 0]


def test_mesh_changed_is_announced_only_when_the_mesh_changes(fan_host):
    from sketchforge.document.commands import SetContour

    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    seen = []
    doc.mesh_changed.connect(seen.append)
    doc.push(SetContour(layer="a", points=[[0, 0], [1, 0], [1, 1], [0, 1]], closed=True))
    assert seen == ["a"]
    doc.push(RenameLayer(layer="a", new_name="A"))
    assert seen == ["a"]


def test_clearing_the_history_inside_a_macro_is_refused(fan_host):
    doc = Document(host=fan_host)
    doc.undo_stack.begin_macro("Draw")
    with pytest.raises(RuntimeError, match=exactly("cannot clear the undo stack inside a macro")):
        doc.undo_stack.clear()
    doc.undo_stack.abort_macro()


def test_an_unknown_layer_error_lists_the_known_ones(fan_host):
    from sketchforge.errors import LayerNotFoundError

    doc = Document(host=fan_host)
    with pytest.raises(LayerNotFoundError, match=exactly("there is no layer with id 'zz' (layers: none)")):
        doc.index_of("zz")
    doc.push(AddLayer(id="a"))
    doc.push(AddLayer(id="b"))
    with pytest.raises(LayerNotFoundError, match=exactly("there is no layer with id 'zz' (layers: a, b)")):
        doc.index_of("zz")


def test_a_command_mutating_plugin_data_in_place_is_undone_too(fan_host):
    doc = Document(host=fan_host)
    doc._set_plugin_data("anim", {"pins": [1, 2]})

    def mutate_in_place(d):
        d.plugin_data("anim")["pins"].append(3)

    from sketchforge.errors import PluginError

    with pytest.raises(PluginError):
        doc.push(_Wreck([mutate_in_place]))
    assert doc.plugin_data("anim") == {"pins": [1, 2]}


def test_a_signal_called_with_the_wrong_number_of_arguments_says_so():
    from sketchforge.document.events import Signal

    sig = Signal(int, str, name="pair")
    with pytest.raises(TypeError, match=exactly("signal 'pair' takes 2 arguments, got 1")):
        sig.emit(1)
