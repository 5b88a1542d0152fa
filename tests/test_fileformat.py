"""The document file: round trips, validation messages that name the problem, atomic saves."""

import json
import os

import pytest

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.errors import DocumentFormatError, ExportError, UnknownCommandError

SPEC_EXAMPLE = {
    "format": "sketchforge",
    "version": 1,
    "light": [0.7071, 0.7071, 0.0],
    "journal": [
        {"command": "add_layer", "id": "body", "name": "Body"},
        {"command": "set_contour", "layer": "body", "points": [[-1.0, -0.6], [1.0, -0.6], [1.0, 0.6], [-1.0, 0.6]]},
        {"command": "set_inflate_params", "layer": "body", "params": {"resolution": 0.03, "inflation": 1.0, "smoothing": 0.0}},
        {"command": "set_light", "direction": [1.0, 0.0, 0.0]},
    ],
}


def test_hand_written_journal_is_a_valid_document(fan_host):
    doc = ff.document_from_dict(SPEC_EXAMPLE, "spec", host=fan_host)
    assert doc.layer_ids() == ["body"] and doc.layer("body").mesh is not None
    assert (doc.light.x, doc.light.y) == (1.0, 0.0)
    assert dict(doc.layer("body").params)["smoothing"] == 0.0
    # The journal survives a save unchanged, and the initial light is kept.
    out = ff.document_to_dict(doc)
    assert out["journal"] == SPEC_EXAMPLE["journal"]
    assert out["light"] == pytest.approx(SPEC_EXAMPLE["light"], abs=1e-4)


def test_save_open_is_bit_identical_and_replay_agrees(tmp_path, fan_host):
    doc = ff.document_from_dict(SPEC_EXAMPLE, "spec", host=fan_host)
    path = tmp_path / "a.sketchforge.json"
    ff.save(doc, path)
    assert doc.undo_stack.is_clean()
    reopened = ff.load(path, host=fan_host)
    assert ff.compare(doc, reopened) == []
    replayed = ff.load(path, host=fan_host, use_snapshot=False)
    assert ff.compare(reopened, replayed) == []


def test_opening_uses_snapshot_not_solver(tmp_path, fan_host):
    """A file reopens exactly as saved even if the solver changed since: the snapshot wins."""
    doc = ff.document_from_dict(SPEC_EXAMPLE, "spec", host=fan_host)
    data = ff.document_to_dict(doc)
    V = ff.decode_array(data["snapshot"]["layers"][0]["mesh"]["V"], "V").copy()
    V[:, 2] *= 2.0
    data["snapshot"]["layers"][0]["mesh"]["V"] = ff.encode_array(V)
    reopened = ff.document_from_dict(data, "x", host=fan_host)
    assert reopened.layer("body").mesh.V[:, 2].max() == pytest.approx(2 * doc.layer("body").mesh.V[:, 2].max())
    assert ff.compare(doc, reopened) == ["layer 'body': mesh differ"]


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda d: d.update(format="blender"), "not a sketchforge document"),
        (lambda d: d.update(version=7), "newer sketchforge"),
        (lambda d: d.update(version="1"), "'version' must be an integer"),
        (lambda d: d.update(light="up"), "'light'"),
        (lambda d: d.update(journal={}), "'journal' must be a list"),
        (lambda d: d["journal"].append({"command": "explode"}), "unknown command 'explode'"),
        (lambda d: d["journal"].append({"command": "rename_layer", "layer": "body"}), "needs the field 'name'"),
        (lambda d: d["journal"].append({"command": "set_contour", "layer": "body", "points": [[1, 2, 3]]}), "'points'"),
        (
            lambda d: d["journal"].append(
                {"command": "set_contour", "layer": "nope", "points": [[0, 0], [1, 0], [0, 1]]}
            ),
            "no layer with id 'nope'",
        ),
        (lambda d: d["journal"].append([1, 2]), "must be an object"),
        (
            lambda d: d["journal"].append(
                {"command": "set_inflate_params", "layer": "body", "params": {"resolution": -1}}
            ),
            "inflater 'fan': 'resolution' must be > 0",
        ),
    ],
)
def test_invalid_documents_are_rejected_with_named_field(mutate, message, fan_host):
    data = json.loads(json.dumps(SPEC_EXAMPLE))
    mutate(data)
    with pytest.raises((DocumentFormatError, UnknownCommandError)) as info:
        ff.document_from_dict(data, "bad.json", host=fan_host)
    assert message in str(info.value)
    assert "bad.json" in str(info.value) or "explode" in str(info.value)


@pytest.mark.parametrize(
    "content, message",
    [
        (b'{"format": "sketchforge", "vers', "invalid JSON at line 1"),
        (b"\xff\xfe\x00garbage", "not UTF-8"),
        (b"[]", "not a sketchforge document"),
    ],
)
def test_broken_files(tmp_path, content, message, fan_host):
    p = tmp_path / "broken.json"
    p.write_bytes(content)
    with pytest.raises(DocumentFormatError, match=message):
        ff.load(p, host=fan_host)


def test_directory_and_missing_file(tmp_path, fan_host):
    with pytest.raises(DocumentFormatError, match="is a directory"):
        ff.load(tmp_path, host=fan_host)
    with pytest.raises(DocumentFormatError, match="no such file"):
        ff.load(tmp_path / "none.json", host=fan_host)


def test_save_into_missing_folder_is_a_clear_error(tmp_path, fan_host):
    doc = Document(host=fan_host)
    with pytest.raises(ExportError, match="does not exist"):
        ff.save(doc, tmp_path / "no" / "such" / "x.json")


def test_interrupted_save_leaves_the_old_file_intact(tmp_path, fan_host, monkeypatch):
    doc = ff.document_from_dict(SPEC_EXAMPLE, "spec", host=fan_host)
    path = tmp_path / "doc.json"
    ff.save(doc, path)
    original = path.read_bytes()
    doc.execute({"command": "rename_layer", "layer": "body", "name": "Changed"})

    import sketchforge.atomic as atomic

    calls = {"n": 0}
    real_fsync = os.fsync

    def failing_fsync(fd):
        calls["n"] += 1
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", failing_fsync)
    with pytest.raises(ExportError, match="No space left"):
        ff.save(doc, path)
    monkeypatch.setattr(atomic.os, "fsync", real_fsync)
    assert path.read_bytes() == original
    assert [p.name for p in tmp_path.iterdir()] == ["doc.json"]  # no temp file left behind
    assert not doc.undo_stack.is_clean()


def test_mid_write_failure_keeps_old_file(tmp_path, fan_host, monkeypatch):
    """Fail after part of the bytes went out: the target still holds the old content."""
    doc = ff.document_from_dict(SPEC_EXAMPLE, "spec", host=fan_host)
    path = tmp_path / "doc.json"
    ff.save(doc, path)
    original = path.read_bytes()

    import sketchforge.atomic as atomic

    def half_write(fh, data):
        fh.write(data[: len(data) // 2])
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(atomic, "_write_all", half_write)
    doc.execute({"command": "rename_layer", "layer": "body", "name": "Changed"})
    with pytest.raises(ExportError):
        ff.save(doc, path)
    assert path.read_bytes() == original
    assert len(list(tmp_path.iterdir())) == 1
