"""Issue 30, point 7: a snapshot's plugin data is validated when the file is opened, with the
limits of the commands that make it; a bad value is one DocumentFormatError line naming the
key, and the file is left as it was."""

from __future__ import annotations

import copy
import json

import pytest

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.errors import DocumentFormatError, PluginError, SketchforgeError
from sketchforge.plugins.hookspecs import hookimpl
from sketchforge_animate.state import MAX_LOOP_FRAMES, MAX_PINS


@pytest.fixture(scope="module")
def animated(tmp_path_factory, real_host):
    """A saved document with two pins and a 4-frame motion (its snapshot as a dict)."""
    doc = Document(host=real_host)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    doc.execute({"command": "set_contour", "layer": "a", "points": [[0, 0], [1, 0], [1, 1], [0, 1]], "closed": True})
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"resolution": 0.1}})
    doc._plugin_data["animate"] = {
        "loop": 4,
        "pins": [
            {"id": "p1", "rest": [0.5, 0.5, 0.1], "target": [0.5, 0.6, 0.1], "motion": [[0.5, 0.5 + 0.01 * i, 0.1] for i in range(4)]},
            {"id": "p2", "rest": [0.2, 0.2, 0.05], "target": [0.2, 0.2, 0.05]},
        ],
    }
    path = tmp_path_factory.mktemp("anim") / "a.json"
    ff.save(doc, path)
    return json.loads(path.read_text())


def _bad(animated, change):
    d = copy.deepcopy(animated)
    change(d["snapshot"]["plugin_data"]["animate"])
    return d


def _many_pins(a):
    a["pins"] = [dict(a["pins"][1], id=f"q{i}") for i in range(MAX_PINS + 1)]


CASES = [
    (_many_pins, f"at most {MAX_PINS} pins, this one has {MAX_PINS + 1}"),
    (lambda a: a.update(loop=MAX_LOOP_FRAMES + 1), f"the loop length must be 0..{MAX_LOOP_FRAMES} frames"),
    (lambda a: a.update(loop=True), "the loop length must be"),
    (lambda a: a["pins"][0].update(motion=a["pins"][0]["motion"][:3]), "its motion must have one [x, y, z] per loop frame (4)"),
    (lambda a: a["pins"][0].update(motion=[[0, 0]] * 4), "per loop frame"),
    (lambda a: a["pins"][1].update(id="p1"), "two pins have the id 'p1'"),
    (lambda a: a["pins"][1].update(id=7), "a pin's id must be a non-empty string, got 7"),
    (lambda a: a["pins"][1].update(rest=[1, 2]), "the rest of pin 'p2' must be 3"),
    (lambda a: a["pins"][1].pop("target"), "lacks the field 'target'"),
    (lambda a: a.update(pins={"p1": 1}), "'pins' must be a list, got dict"),
    (lambda a: a.update(loop=0), "has a motion but the loop has 0 frames"),
]


@pytest.mark.parametrize("change, message", CASES)
def test_a_bad_animation_is_refused_on_open_naming_the_key(tmp_path, animated, real_host, change, message):
    path = tmp_path / "bad.json"
    text = json.dumps(_bad(animated, change))
    path.write_text(text)
    with pytest.raises(DocumentFormatError) as info:
        ff.load(path, host=real_host)
    msg = str(info.value)
    assert "snapshot.plugin_data['animate']: the animation data is malformed" in msg and message in msg, msg
    assert "\n" not in msg and len(msg) < 400
    assert path.read_text() == text  # nothing written


def test_the_cli_says_it_in_one_line(tmp_path, animated):
    from sketchforge.cli import main

    path = tmp_path / "bad.json"
    path.write_text(json.dumps(_bad(animated, _many_pins)))
    import contextlib
    import io

    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        assert main(["info", str(path)]) == 2
    lines = err.getvalue().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sketchforge: error: ") and "plugin_data['animate']" in lines[0]


def test_a_good_animation_still_opens_bit_identical(tmp_path, animated, real_host):
    path = tmp_path / "good.json"
    path.write_text(json.dumps(animated))
    doc = ff.load(path, host=real_host)
    assert doc.plugin_data("animate") == animated["snapshot"]["plugin_data"]["animate"]


class DemoValidator:
    """A third-party plugin keeping document data under "demo": a list of at most 3 ints."""

    calls: list = []

    @hookimpl
    def sketchforge_plugin_data_validators(self):
        def validate(value):
            DemoValidator.calls.append(value)
            if not (isinstance(value, list) and len(value) <= 3):
                raise SketchforgeError("demo data is a list of at most 3 numbers")

        return {"demo": validate}


class BrokenValidator:
    @hookimpl
    def sketchforge_plugin_data_validators(self):
        return {"broken": lambda value: 1 / 0}


def _with(animated, **extra):
    d = copy.deepcopy(animated)
    d["snapshot"]["plugin_data"].update(extra)
    return d


def test_a_plugin_registers_a_validator_for_its_key(make_sketchforge_host, animated):
    host = make_sketchforge_host(DemoValidator(), installed=("inflate", "animate"))
    DemoValidator.calls.clear()
    doc = ff.document_from_dict(_with(animated, demo=[1, 2]), "x.json", host=host)
    assert doc.plugin_data("demo") == [1, 2] and DemoValidator.calls == [[1, 2]]
    with pytest.raises(DocumentFormatError, match=r"^x.json: snapshot.plugin_data\['demo'\]: demo data is a list of at most 3"):
        ff.document_from_dict(_with(animated, demo=[1, 2, 3, 4]), "x.json", host=host)
    # A key no installed plugin validates is kept as it is.
    doc = ff.document_from_dict(_with(animated, other={"anything": 1}), "x.json", host=host)
    assert doc.plugin_data("other") == {"anything": 1}


def test_a_validator_that_breaks_is_a_plugin_error_naming_it(make_sketchforge_host, animated):
    host = make_sketchforge_host(BrokenValidator(), installed=("inflate",), strict=False)
    with pytest.raises(PluginError, match="validator for 'broken' .*ZeroDivisionError"):
        ff.document_from_dict(_with(animated, broken=1), "x.json", host=host)
    # Without that key the validator is never called.
    ff.document_from_dict(animated, "x.json", host=host)
