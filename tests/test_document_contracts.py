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
    MacroCommand,
    RenameLayer,
    TranslateLayer,
    _digits,
    rotate_about,
    scale_about,
)
from sketchforge.document.layer import Light
from sketchforge.document.commands import Command
from sketchforge.document.fileformat import _short
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
