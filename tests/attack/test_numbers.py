"""Numbers out of range: each refused at parse time with one line (once OverflowError,
ValueError for a 4300+ digit integer, ZeroDivisionError, a GEOS exception)."""

from __future__ import annotations

import pytest
from attack_helpers import assert_one_line_error, run_cli, write_doc

HUGE = 10**400  # JSON integer too large for any float
DIGITS_5000 = "7" * 5000  # beyond Python's 4300-digit int parsing limit (kept as text)


def _journal(small_doc, entry):
    small_doc["journal"].append(entry)
    return small_doc


def _raw(data, token, number_text):
    """The document's JSON with the placeholder string replaced by a bare number literal."""
    import json

    return json.dumps(data).replace(f'"{token}"', number_text)


CASES = {
    "light": (lambda d: d.__setitem__("light", [1, "@N", 0]), "integer of 401 digits"),
    "set_light": (lambda d: d["journal"].append({"command": "set_light", "direction": ["@N", 1, 0]}), "integer of 401 digits"),
    "contour point": (lambda d: d["journal"][1]["points"][0].__setitem__(0, "@N"), "integer of 401 digits"),
    "resolution": (lambda d: d["journal"][2]["params"].__setitem__("resolution", "@N"), "integer of 401 digits"),
    "band": (lambda d: d["journal"].append({"command": "sculpt_isophote", "layer": "a", "pick": [0.5, 0.5], "band": "@N",
                                            "stroke": [[0.2, 0.5], [0.8, 0.5]]}), "integer of 401 digits"),
    "pick": (lambda d: d["journal"].append({"command": "sculpt_isophote", "layer": "a", "pick": [0.5, "@N"], "band": 0.3,
                                            "stroke": [[0.2, 0.5], [0.8, 0.5]]}), "integer of 401 digits"),
}


@pytest.mark.parametrize("field", sorted(CASES))
def test_integer_too_large_for_a_float(tmp_path, small_doc, field):
    mutate, message = CASES[field]
    mutate(small_doc)
    path = write_doc(tmp_path / "doc.json", _raw(small_doc, "@N", str(HUGE)))
    for cmd in ("replay", "info"):
        assert_one_line_error(run_cli(cmd, path), message)


def test_integer_over_4300_digits(tmp_path, small_doc):
    small_doc["light"] = [1, "@N", 0]
    path = write_doc(tmp_path / "doc.json", _raw(small_doc, "@N", DIGITS_5000))
    assert_one_line_error(run_cli("info", path), "integer of 5000 digits is too large")


@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_literals(tmp_path, small_doc, literal):
    small_doc["journal"][1]["points"][0][0] = "@N"
    path = write_doc(tmp_path / "doc.json", _raw(small_doc, "@N", literal))
    assert_one_line_error(run_cli("replay", path), f"{literal} is not a number a document may contain")


def test_huge_integers_in_process_journal(fan_host):
    """The same numbers arriving as Python ints (a plugin, the app, a script) are refused by
    command parsing, not only by the JSON reader."""
    from sketchforge.document.document import Document
    from sketchforge.errors import SketchforgeError

    doc = Document(host=fan_host)
    doc.execute({"command": "add_layer", "id": "a"})
    for entry in (
        {"command": "set_light", "direction": [HUGE, 1, 0]},
        {"command": "set_contour", "layer": "a", "points": [[HUGE, 0], [1, 0], [1, 1]]},
        {"command": "set_inflate_params", "layer": "a", "params": {"resolution": HUGE}},
        {"command": "move_layer", "layer": "a", "index": HUGE},
    ):
        with pytest.raises(SketchforgeError):
            doc.execute(entry)
    assert doc.layer_ids() == ["a"] and doc.layer("a").mesh is None


@pytest.mark.parametrize(
    "params, message",
    [({"resolution": 1e-300}, "would make about"), ({"resolution": 1e300}, "at most 1e+09"), ({"inflation": 1e300}, "at most 1e+09")],
)
def test_resolution_and_inflation_out_of_range(tmp_path, small_doc, params, message):
    small_doc["journal"][2]["params"].update(params)
    assert_one_line_error(run_cli("replay", write_doc(tmp_path / "doc.json", small_doc)), message)


def test_band_1e308(tmp_path, small_doc):
    small_doc["journal"].append(
        {"command": "sculpt_isophote", "layer": "a", "pick": [0.5, 0.5], "band": 1e308, "stroke": [[0.2, 0.5], [0.8, 0.5]]}
    )
    assert_one_line_error(run_cli("replay", write_doc(tmp_path / "doc.json", small_doc)), "it must be at most 1e+09")
