"""Nesting: macros 450 deep once gave a 3000-line RecursionError traceback."""

from __future__ import annotations

import pytest
from attack_helpers import assert_one_line_error, run_cli, write_doc


def _macro(depth, leaf):
    m = leaf
    for _ in range(depth):
        m = {"command": "macro", "text": "group", "children": [m]}
    return m


@pytest.mark.parametrize("depth", [20, 45, 450, 5000])
def test_deeply_nested_macros(tmp_path, small_doc, depth):
    import json

    small_doc["journal"].append("@M")
    # Written as text: json.dumps itself cannot encode 5000 levels.
    macro = '{"command": "macro", "children": [' * depth + '{"command": "add_layer", "id": "deep"}' + "]}" * depth
    path = write_doc(tmp_path / "doc.json", json.dumps(small_doc).replace('"@M"', macro))
    line = assert_one_line_error(run_cli("replay", path))
    assert "nested" in line


def test_nested_arrays(tmp_path):
    path = write_doc(tmp_path / "doc.json", "[" * 100_000 + "]" * 100_000)
    assert_one_line_error(run_cli("info", path), "nested")


def test_macro_depth_in_process(fan_host):
    """The cap is in command parsing too (a journal built in memory)."""
    from sketchforge.document.commands import MAX_MACRO_DEPTH
    from sketchforge.document.document import Document
    from sketchforge.errors import DocumentFormatError

    doc = Document(host=fan_host)
    doc.execute(_macro(MAX_MACRO_DEPTH, {"command": "add_layer", "id": "ok"}))  # the cap itself works
    with pytest.raises(DocumentFormatError, match=f"nested more than {MAX_MACRO_DEPTH} deep"):
        doc.execute(_macro(MAX_MACRO_DEPTH + 1, {"command": "add_layer", "id": "deep"}))
    assert doc.layer_ids() == ["ok"]
