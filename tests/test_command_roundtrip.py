"""Every registered command round-trips through to_dict/from_dict (the journal contract)."""

from sketchforge.plugins.manager import default_host

EXAMPLES = [
    {"command": "add_layer", "id": "body", "name": "Body"},
    {"command": "add_layer", "id": "x", "name": "X", "index": 0},
    {"command": "remove_layer", "layer": "body"},
    {"command": "rename_layer", "layer": "body", "name": "Torso"},
    {"command": "set_layer_visible", "layer": "body", "visible": False},
    {"command": "move_layer", "layer": "body", "index": 2},
    {"command": "duplicate_layer", "layer": "body", "id": "body2", "name": "Body copy"},
    {"command": "duplicate_layer", "layer": "body", "id": "body3", "name": "Body copy", "index": 0, "offset": [0.25, -0.5]},
    {"command": "mirror_layer", "layer": "body"},
    {"command": "mirror_layer", "layer": "body", "axis": "host"},
    {"command": "mirror_layer", "layer": "body", "axis": 0.25},
    {"command": "transform_layer", "layer": "body", "matrix": [[0.0, -2.0, 0.5], [2.0, 0.0, -0.25]]},
    {"command": "translate_layer", "layer": "body", "offset": [0.125, -0.5]},
    {"command": "set_contour", "layer": "body", "points": [[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]]},
    {"command": "set_contour", "layer": "body", "points": [[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]], "closed": True},
    {"command": "set_contour", "layer": "body", "points": [[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]], "keep_edits": True},
    {"command": "set_contour", "layer": "body", "points": [[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]],
     "holes": [[[0.4, 0.2], [0.6, 0.2], [0.5, 0.4]]]},
    {"command": "set_inflate_params", "layer": "body", "params": {"resolution": 0.05, "inflation": 1.2, "smoothing": 0.0}},
    {"command": "set_inflate_params", "layer": "body", "params": {"inflation": 0.8}, "solver": "fan"},
    {"command": "set_assembly", "params": {"fillet": 0}},
    {"command": "set_assembly", "solver": "depth_qp", "params": {}},
    {"command": "set_light", "direction": [0.6, 0.8, 0.0]},
    {"command": "sculpt_isophote", "layer": "body", "pick": [0.2, 0.1], "band": 0.3, "stroke": [[0.1, -0.3], [0.3, 0.3]]},
    {"command": "set_light", "direction": [0.0, 0.0, 1.0]},
    {"command": "sculpt_isophotes", "layer": "body", "edits": [
        {"pick": [0.2, 0.1], "band": 0.3, "stroke": [[0.1, -0.3], [0.3, 0.3]]},
        {"pick": [-0.2, 0.0], "band": 0.2, "stroke": [[-0.3, -0.3], [-0.25, 0.3]]}],
     "solver": "gauss_newton", "params": {"joint_stroke_weight": 50.0}},
    {"command": "add_pin", "id": "pin1", "at": [0.5, 0.25, 0.75]},
    {"command": "move_pin", "pin": "pin1", "to": [0.5, 0.5, 1.0]},
    {"command": "remove_pin", "pin": "pin1"},
    {"command": "hold_pin", "pin": "pin1"},
    {"command": "record_motion", "pin": "pin1", "start": 3, "samples": [[0.0, 0.0, 1.0], [0.125, 0.0, 1.0]]},
    {"command": "copy_motion", "source": "pin1", "pin": "pin2"},
    # examples/plugins/bump_brush (installed by `make`, as a third-party brush would be)
    {"command": "bump_brush", "layer": "body", "center": [0.25, -0.5], "radius": 0.3, "height": 0.125},
    {"command": "macro", "text": "Draw layer", "children": [
        {"command": "add_layer", "id": "a", "name": "A"},
        {"command": "set_contour", "layer": "a", "points": [[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]]}]},
]


def test_every_command_round_trips():
    registry = default_host().commands
    for entry in EXAMPLES:
        assert registry.from_dict(entry).to_dict() == entry, entry["command"]
    # A new command without an example here fails this test until one is added.
    assert set(registry.names()) == {e["command"] for e in EXAMPLES}


def _other_type(v):
    """A value of a type the field cannot hold."""
    return [1] if isinstance(v, dict) else {"not": "this"}


def test_a_bad_or_missing_field_names_the_command_and_the_field():
    """A damaged journal entry is refused with a line naming the command and the field, for
    every command (a user finds the entry in the file from that line)."""
    from sketchforge.errors import SketchforgeError

    registry = default_host().commands
    checked = 0
    for entry in EXAMPLES:
        name = entry["command"]
        for key in [k for k in entry if k != "command"]:
            bad = dict(entry, **{key: _other_type(entry[key])})
            try:
                registry.from_dict(bad)
            except SketchforgeError as e:
                msg = str(e)
                assert f"'{name}'" in msg, (name, key, msg)
                checked += 1
            else:
                raise AssertionError(f"{name}: {key}={bad[key]!r} was accepted")
            missing = {k: v for k, v in entry.items() if k != key}
            try:
                registry.from_dict(missing)  # accepted when the field is optional
            except SketchforgeError as e:
                assert f"'{name}'" in str(e) and key in str(e), (name, key, str(e))
    assert checked > 60
