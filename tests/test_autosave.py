"""Autosave writes unsaved work to the data folder and offers it back at the next start."""

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.document.autosave import Autosaver, find_recoverable, recover


def test_autosave_and_recover(tmp_path, fan_host):
    doc = Document(host=fan_host)
    saver = Autosaver(doc, original_path=tmp_path / "mine.json", interval_s=0, folder=tmp_path / "auto")
    assert saver.save_now() is False  # nothing unsaved: nothing written
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": [[0, 0], [2, 0], [1, 1]]})
    assert saver.tick() is True
    assert saver.tick() is False  # no new change since
    found = find_recoverable(tmp_path / "auto")
    assert len(found) == 1 and found[0].original == str((tmp_path / "mine.json").resolve())
    back = recover(found[0], host=fan_host)
    assert ff.compare(doc, back) == [] and not back.undo_stack.is_clean()
    # Saving normally makes the document clean; the next tick removes the autosave.
    ff.save(doc, tmp_path / "mine.json")
    saver.tick()
    assert find_recoverable(tmp_path / "auto") == []


def test_unreadable_autosave_is_skipped(tmp_path):
    folder = tmp_path / "auto"
    folder.mkdir()
    (folder / "x.json").write_bytes(b"\xff not json")
    assert find_recoverable(folder) == []
    assert (folder / "x.json").exists()
