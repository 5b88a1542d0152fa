"""Issue 30, point 6: inputs that ran past 60 s or echoed a 5 MB value now get one bounded
line (exit 2) within seconds.

- 3 000 ``duplicate_layer`` entries: the replay itself is linear, but the assembly of 3 001
  layers stacked on each other is not (40 copies took 73 s): a document holds at most
  MAX_LAYERS layers, and an assembly refuses, before any work, more overlapping layers than
  MAX_OVERLAP_WORK allows.
- ``replay --frame 1e21``: frames are computed in order from frame 0; past the loop they wrap
  (frame N is the loop's frame N mod its length, as the app plays it), so any frame is quick.
- a 5 MB id, name or command in an error: quoted at most 80 characters, and every error line
  is cut at MAX_MESSAGE_CHARS.

Time bounds are generous (the machine is shared); the assertions are on the work done and on
the message.
"""

from __future__ import annotations

import numpy as np
import pytest
from attack_helpers import SMALL_DOC, assert_one_line_error, run_cli, write_doc

from sketchforge.document import Document
from sketchforge.document.document import MAX_LAYERS
from sketchforge.errors import MAX_MESSAGE_CHARS, LimitError, SketchforgeError, quote, shorten
from sketchforge.plugins import default_host

BIG = 5_000_000


def _doc_with(entries):
    d = {k: v for k, v in SMALL_DOC.items() if k != "journal"}
    d["journal"] = list(SMALL_DOC["journal"]) + entries
    return d


def test_three_thousand_duplicates_are_refused_at_the_layer_limit(tmp_path):
    doc = write_doc(tmp_path / "dup.json", _doc_with([{"command": "duplicate_layer", "layer": "a", "id": f"c{i}"} for i in range(3000)]))
    res = run_cli("replay", doc, "--export", tmp_path / "out.obj")
    line = assert_one_line_error(res, f"journal entry {len(SMALL_DOC['journal']) + MAX_LAYERS - 1} (duplicate_layer)",
                                 f"at most {MAX_LAYERS} layers")
    assert len(line) < 300 and res.seconds < 20
    assert not (tmp_path / "out.obj").exists()


def test_layer_limit_holds_for_add_and_duplicate_and_changes_nothing(fan_host):
    doc = Document(host=fan_host)
    for i in range(MAX_LAYERS):
        doc.execute({"command": "add_layer", "id": f"l{i}"})
    before = doc.layers
    for entry in ({"command": "add_layer", "id": "one_more"}, {"command": "duplicate_layer", "layer": "l0", "id": "copy"}):
        with pytest.raises(LimitError, match=f"at most {MAX_LAYERS} layers"):
            doc.execute(entry)
        assert doc.layers == before
    doc.undo_stack.undo()  # one fewer: room for a copy again
    doc.execute({"command": "duplicate_layer", "layer": "l0", "id": "copy"})
    assert len(doc.layers) == MAX_LAYERS


def test_a_snapshot_with_too_many_layers_is_refused_before_decoding(tmp_path, saved_doc):
    saved_doc["snapshot"]["layers"] = saved_doc["snapshot"]["layers"] * (MAX_LAYERS + 1)
    res = run_cli("info", write_doc(tmp_path / "many.json", saved_doc))
    assert_one_line_error(res, f"{MAX_LAYERS + 1} layers", f"at most {MAX_LAYERS}")


def test_stacked_layers_are_refused_by_the_assembly_before_any_work(tmp_path):
    from sketchforge_assemble.assemble import MAX_OVERLAP_WORK, overlap_work

    # 200 copies of the 0.03 square in place: under the layer limit, far over the assembly's.
    entries = [{"command": "set_inflate_params", "layer": "a", "params": {"resolution": 0.03}}]
    entries += [{"command": "duplicate_layer", "layer": "a", "id": f"c{i}"} for i in range(200)]
    path = write_doc(tmp_path / "stack.json", _doc_with(entries))
    res = run_cli("replay", path, "--export", tmp_path / "out.obj")
    line = assert_one_line_error(res, "overlapping pairs of layers", f"the limit is {MAX_OVERLAP_WORK:,}")
    assert "20,100 overlapping pairs" in line and res.seconds < 30
    # The estimate: pairs of overlapping bounding boxes, the smaller vertex count of each.
    from sketchforge.document import fileformat as ff

    doc = ff.load(path, default_host())
    meshes = [l.mesh for l in doc.layers]
    pairs, work = overlap_work(meshes)
    assert pairs == 201 * 200 // 2 and work == pairs * meshes[0].n_vertices > MAX_OVERLAP_WORK


def test_overlap_work_counts_only_overlapping_boxes():
    from sketchforge.geometry.mesh import Mesh
    from sketchforge_assemble.assemble import overlap_work

    def square(x0, n):
        V = np.zeros((n, 3))
        V[:, 0] = x0 + np.linspace(0, 1, n)
        V[:, 1] = np.linspace(0, 1, n) ** 2
        return Mesh(V, np.array([[0, 1, 2]]), np.array([0, 1, 2]))

    assert overlap_work([square(0, 10), square(0.5, 4), square(5, 100)]) == (1, 4)
    assert overlap_work([square(0, 10)]) == (0, 0)


@pytest.mark.parametrize("frame", ["1e21", str(10**21), "999999999999999999999999999999"])
def test_a_huge_frame_wraps_round_the_loop(tmp_path, frame):
    from pathlib import Path

    src = Path(__file__).resolve().parents[2] / "examples" / "animated.json"
    res = run_cli("replay", src, "--export", tmp_path / "f.obj", "--frame", frame)
    assert res.rc == 0, res.err[-500:]
    assert res.seconds < 60
    # The same vertices as the frame it wraps to, computed from frame 0.
    from sketchforge.document import fileformat as ff
    from sketchforge_animate.state import Animation

    loop = Animation.of(ff.load(src, default_host())).loop
    assert loop > 1
    want = int(float(frame)) % loop if "e" in frame else int(frame) % loop
    res2 = run_cli("replay", src, "--export", tmp_path / "g.obj", "--frame", str(want))
    assert res2.rc == 0
    assert (tmp_path / "f.obj").read_bytes() == (tmp_path / "g.obj").read_bytes()


def test_loop_frame_wraps_and_refuses_negative_frames():
    from sketchforge.errors import ParameterError
    from sketchforge_animate.export import loop_frame
    from sketchforge_animate.state import Animation, Pin

    still = Animation((Pin("p", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),), 0)
    assert loop_frame(still, 10**21) == 0
    moving = Animation((Pin("p", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), np.zeros((48, 3))),), 48)
    assert [loop_frame(moving, f) for f in (0, 47, 48, 10**21)] == [0, 47, 0, 10**21 % 48]
    with pytest.raises(ParameterError, match="0 or more"):
        loop_frame(moving, -1)


@pytest.mark.parametrize("arg", ["1.5", "nan", "inf", "x" * 5000, "7" * 5000])
def test_a_bad_frame_is_one_bounded_usage_line(tmp_path, arg):
    res = run_cli("replay", write_doc(tmp_path / "d.json", SMALL_DOC), "--export", tmp_path / "f.obj", "--frame", arg)
    assert res.rc == 2
    assert "--frame: expected a whole number" in res.err and max(len(l) for l in res.err.splitlines()) < 500


@pytest.mark.parametrize("entry, fragment", [
    ({"command": "rename_layer", "layer": "x" * BIG, "name": "n"}, "there is no layer with id 'xxx"),
    ({"command": "rename_layer", "layer": "a", "name": "n", "extra": 1, "id": "y"}, None),
    ({"command": "x" * BIG}, "unknown command 'xxx"),
    ({"command": "add_layer", "id": "a"}, "a layer with id 'a' already exists"),
    ({"command": "duplicate_layer", "layer": "a", "id": "a" + "z" * BIG}, None),
    ({"command": "duplicate_layer", "layer": "a", "id": "a"}, "a layer with id 'a' already exists"),
])
def test_a_five_megabyte_value_is_quoted_short(tmp_path, entry, fragment):
    res = run_cli("replay", write_doc(tmp_path / "d.json", _doc_with([entry])))
    if fragment is None:  # valid entries: no error at all
        assert res.rc == 0, res.err[-500:]
        return
    line = assert_one_line_error(res, fragment)
    assert len(line) < 500, len(line)
    if len(str(entry)) > BIG:
        assert f"({BIG:,} characters)" in line


def test_every_error_message_is_bounded():
    err = SketchforgeError("y" * BIG)
    assert len(str(err)) == MAX_MESSAGE_CHARS and str(err).endswith(f"({BIG - MAX_MESSAGE_CHARS:,} more characters)")
    assert str(SketchforgeError("short")) == "short" and shorten("abc", 2000) == "abc"
    assert quote("a" * 10) == "'aaaaaaaaaa'" and quote("a" * 200) == repr("a" * 80) + "… (200 characters)"
    assert len(quote(list(range(10**4)))) <= 81
    from sketchforge.errors import LayerNotFoundError

    assert len(str(LayerNotFoundError("z" * BIG))) == MAX_MESSAGE_CHARS


def test_a_missing_layer_lists_a_few_ids_not_thousands(fan_host):
    doc = Document(host=fan_host)
    for i in range(100):
        doc.execute({"command": "add_layer", "id": f"layer_{i}"})
    with pytest.raises(SketchforgeError) as info:
        doc.layer("nope")
    msg = str(info.value)
    assert "layers: layer_0, layer_1" in msg and "and 88 more" in msg and len(msg) < 400
