"""Contracts of the document layer that the mutation run over ``sketchforge/document/`` showed no
test held (`make mutate SCOPE=document`): where an autosave is written, what recovery lists and in
which order, the files it pairs and the junk it steps over, the sentences and undo texts a person
reads, journal entries read back, macros read from a journal, transforms composed from a drag,
the light from a drag at the limit of "no length", and what views are told when a command fails.
"""

from __future__ import annotations

import errno
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from test_crash_recovery import contour, dirty_doc
from test_document_contracts import NO_LENGTH, _apply, _three_layer_doc, _Wreck, exactly

from sketchforge.document import Document, autosave
from sketchforge.document import fileformat as ff
from sketchforge.document.autosave import (
    Autosaver,
    autosave_dir,
    autosave_interval,
    data_dir,
    describe_stop,
    find_recoverable,
    forget,
    recover,
)
from sketchforge.document.commands import (
    AddLayer,
    Command,
    MacroCommand,
    RemoveLayer,
    RenameLayer,
    SetLayerVisible,
    TransformLayer,
    compose_affine,
    rotate_about,
    scale_about,
)
from sketchforge.document.layer import Light
from sketchforge.errors import DocumentFormatError, ExportError, ParameterError, PluginError


# --- undo texts and journal entries of the layer commands -------------------------------------
def test_removing_hiding_and_showing_a_layer_are_named_in_the_undo_menu(fan_host):
    doc = Document(host=fan_host)
    stack = doc.undo_stack
    doc.push(AddLayer(id="a"))
    doc.push(AddLayer(id="b"))
    doc.push(SetLayerVisible(layer="a", visible=False))
    assert stack.undo_text() == "Hide layer"
    doc.push(SetLayerVisible(layer="a", visible=True))
    assert stack.undo_text() == "Show layer"
    doc.push(RemoveLayer(layer="b"))
    assert stack.undo_text() == "Remove layer"
    stack.undo()
    assert stack.redo_text() == "Remove layer" and stack.undo_text() == "Show layer"
    stack.undo()
    assert stack.redo_text() == "Show layer" and stack.undo_text() == "Hide layer"


def test_showing_a_hidden_layer_shows_it_and_the_journal_replays_it(fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    doc.push(SetLayerVisible(layer="a", visible=False))
    assert doc.layer("a").visible is False
    doc.push(SetLayerVisible(layer="a", visible=True))
    assert doc.layer("a").visible is True
    assert doc.journal()[1:] == [
        {"command": "set_layer_visible", "layer": "a", "visible": False},
        {"command": "set_layer_visible", "layer": "a", "visible": True},
    ]
    replay = Document(host=fan_host)
    for entry in json.loads(json.dumps(doc.journal())):
        replay.execute(entry)
    assert replay.layer("a").visible is True and replay.same_state(doc)
    doc.undo_stack.undo()
    assert doc.layer("a").visible is False


# --- journal entries read back ----------------------------------------------------------------
@pytest.mark.parametrize("axis", ["left", "HOST", True, None, [1.0]])
def test_a_mirror_axis_that_is_no_axis_is_refused_when_the_journal_is_read(fan_host, axis):
    with pytest.raises(DocumentFormatError,
                       match=exactly("command 'mirror_layer': 'axis' must be 'host', 'own' or a number")):
        fan_host.commands.from_dict({"command": "mirror_layer", "layer": "a", "axis": axis})


def test_a_numeric_mirror_axis_is_read_as_an_x_and_one_beyond_float_range_is_refused(fan_host):
    cmd = fan_host.commands.from_dict({"command": "mirror_layer", "layer": "a", "axis": 2})
    assert type(cmd.axis) is float and cmd.axis == 2.0 and cmd.to_dict()["axis"] == 2.0
    assert fan_host.commands.from_dict({"command": "mirror_layer", "layer": "a", "axis": "host"}).axis == "host"
    # a corrupt number is refused when the file is read, not half-way through a replay
    with pytest.raises(DocumentFormatError, match="^command 'mirror_layer': "):
        fan_host.commands.from_dict({"command": "mirror_layer", "layer": "a", "axis": 10**400})


def test_duplicate_layer_from_a_journal_chooses_the_id_when_none_is_given(fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a", layer_name="Arm"))
    cmd = doc.execute({"command": "duplicate_layer", "layer": "a"})
    assert doc.layer_ids() == ["a", "a_copy1"] and doc.layer("a_copy1").name == "Arm copy"
    assert cmd.to_dict() == {"command": "duplicate_layer", "layer": "a", "id": "a_copy1", "name": "Arm copy"}
    with pytest.raises(DocumentFormatError, match=exactly("command 'duplicate_layer': 'offset' must be 2 numbers")):
        fan_host.commands.from_dict({"command": "duplicate_layer", "layer": "a", "offset": [1, 2, 3]})


# --- macros read from a journal ---------------------------------------------------------------
def _nested(levels: int) -> dict:
    entry = {"command": "macro", "children": []}
    for _ in range(levels - 1):
        entry = {"command": "macro", "children": [entry]}
    return entry


def test_a_macro_read_directly_has_the_same_depth_bound_as_through_the_registry(fan_host):
    registry = fan_host.commands
    MacroCommand.from_dict(_nested(16), registry)  # 16 levels are allowed either way
    registry.from_dict(_nested(16))
    for read in (lambda d: MacroCommand.from_dict(d, registry), registry.from_dict):
        with pytest.raises(DocumentFormatError, match=exactly("macros are nested more than 16 deep")):
            read(_nested(17))


def test_a_macro_without_a_text_is_written_back_with_an_empty_one_and_reads_again(fan_host):
    registry = fan_host.commands
    m = registry.from_dict({"command": "macro", "children": [{"command": "add_layer", "id": "a", "name": "A"}]})
    assert m.text() == "Group"
    written = json.loads(json.dumps(m.to_dict()))
    assert written["text"] == ""
    again = registry.from_dict(written)
    assert again.text() == "Group" and again.to_dict() == written


# --- transforms from a drag -------------------------------------------------------------------
def test_composed_transforms_apply_in_order():
    scale = scale_about((0.0, 0.0), 2.0)
    move = [[1.0, 0.0, 3.0], [0.0, 1.0, -1.0]]
    turn = rotate_about((0.0, 0.0), math.pi / 2)
    m = compose_affine(scale, move)  # scale first, then move
    assert m.tolist() == [[2.0, 0.0, 3.0], [0.0, 2.0, -1.0]]
    assert _apply(m, (1.0, 1.0)) == pytest.approx((5.0, 1.0))
    assert compose_affine(move, scale).tolist() == [[2.0, 0.0, 6.0], [0.0, 2.0, -2.0]]
    three = compose_affine(move, move, turn)
    assert _apply(three, (0.0, 0.0)) == pytest.approx((2.0, 6.0), abs=1e-15)


def test_composed_transforms_take_any_numbers_and_are_float64():
    m = compose_affine([[1, 0, 2**70], [0, 1, 0]], [[2, 0, 0], [0, 2, 0]])
    assert m.dtype == np.float64 and m.tolist() == [[2.0, 0.0, 2.0 * 2**70], [0.0, 2.0, 0.0]]


def test_a_scale_about_a_float32_centre_keeps_the_centre_to_float64_rounding():
    c = np.array([0.1, 0.7], dtype=np.float32)  # e.g. a vertex of a GPU buffer
    m = scale_about(c, 3.0)
    assert m.dtype == np.float64
    assert _apply(m, c) == pytest.approx(c.astype(np.float64), rel=0, abs=1e-15)


def test_rotate_about_takes_any_two_number_centre():
    m = rotate_about([[1.0, 1.0]], math.pi / 2)  # a (1, 2) point, e.g. V[[k], :2]
    assert _apply(m, (1.0, 1.0)) == pytest.approx((1.0, 1.0)) and _apply(m, (2.0, 1.0)) == pytest.approx((1.0, 2.0))
    big = rotate_about((2**70, 0), math.pi)
    assert big.dtype == np.float64
    assert _apply(big, (0.0, 0.0))[0] == pytest.approx(2.0 * 2**70)


# --- the light from a drag at the limit of "no length" ------------------------------------------
# A drag of exactly 1.00000761449337e-06 (8590 units of the last place at 1e6) near x = 1e6:
# no length relative to the larger of the two ends, 1000007.6144939, but more than 1e-12 of the
# smaller one.
FAR, NEAR = 1000007.6144939, 1000007.6144929
ONE_STEP_NEARER = 1000007.6144928999


def test_a_drag_at_the_limit_is_refused_whichever_end_is_the_centre():
    assert FAR - NEAR == 8590 * 2.0**-33
    for center, point in [((FAR, 0.0), (NEAR, 0.0)), ((NEAR, 0.0), (FAR, 0.0)),
                          ((0.0, FAR), (0.0, NEAR)), ((0.0, NEAR), (0.0, FAR))]:
        with pytest.raises(ParameterError, match=exactly(NO_LENGTH)):
            Light.from_drag(center, point)


def test_a_drag_one_step_longer_from_a_large_centre_gives_the_right_light():
    assert Light.from_drag((FAR, 0.0), (ONE_STEP_NEARER, 0.0)).angle == 180.0
    assert Light.from_drag((ONE_STEP_NEARER, 0.0), (FAR, 0.0)).angle == 0.0
    assert Light.from_drag((0.0, FAR), (0.0, ONE_STEP_NEARER)).angle == -90.0


# --- a command that fails part-way: what views are told ---------------------------------------
class _Rows:
    """A list view (a Qt model): every index it is told must be a row it has."""

    def __init__(self, doc):
        self.rows = doc.layer_ids()
        self.log = []
        self.bad = []
        doc.layer_inserted.connect(self._inserted)
        doc.layer_removed.connect(self._removed)
        doc.layer_changed.connect(self._changed)

    def _inserted(self, i, layer):
        if not 0 <= i <= len(self.rows):
            self.bad.append(("inserted", i))
        self.rows.insert(i, layer.id)
        self.log.append(("inserted", i, layer.id))

    def _removed(self, i, layer):
        if not (0 <= i < len(self.rows) and self.rows[i] == layer.id):
            self.bad.append(("removed", i, layer.id))
        self.rows.pop(i)
        self.log.append(("removed", i, layer.id))

    def _changed(self, i, new, old):
        if not (0 <= i < len(self.rows) and self.rows[i] == new.id):
            self.bad.append(("changed", i, new.id))
        self.log.append(("changed", i, new.id))


def test_a_failed_change_of_one_layer_re_announces_only_that_layer(fan_host):
    """Views keep per-layer state (a selection, GPU buffers): putting one layer back must not
    remove and re-insert every layer."""
    from dataclasses import replace

    doc = _three_layer_doc(fan_host)
    view = _Rows(doc)
    with pytest.raises(PluginError):
        doc.push(_Wreck([lambda d: d._replace_layer(replace(d.layer("b"), name="B!"))]))
    assert view.log == [("changed", 1, "b"), ("changed", 1, "b")] and view.bad == []
    assert doc.layer("b").name == "B" and doc.layer_ids() == ["a", "b", "c"]


def test_a_failed_removal_is_put_back_with_rows_the_views_have(fan_host):
    doc = _three_layer_doc(fan_host)
    view = _Rows(doc)
    with pytest.raises(PluginError):
        doc.push(_Wreck([lambda d: d._remove_layer(0)]))
    assert view.bad == [] and view.rows == ["a", "b", "c"] == doc.layer_ids()
    assert [e[2] for e in view.log if e[0] == "removed"][0] == "a"  # the command's own removal


# --- where autosaves go -----------------------------------------------------------------------
def test_autosaves_go_to_the_xdg_data_folder_else_to_local_share_in_home(tmp_path, monkeypatch, fan_host):
    monkeypatch.delenv("SKETCHFORGE_DATA_DIR", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert data_dir() == tmp_path / "xdg" / "sketchforge"
    assert autosave_dir() == tmp_path / "xdg" / "sketchforge" / "autosave"
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    saver = Autosaver(doc)
    assert saver.save_now() is True
    assert saver.path.parent == tmp_path / "xdg" / "sketchforge" / "autosave" and saver.path.exists()
    assert [i.path for i in find_recoverable()] == [saver.path]
    for xdg in ("", None):  # empty or unset: the home folder's .local/share
        if xdg is None:
            monkeypatch.delenv("XDG_DATA_HOME")
        else:
            monkeypatch.setenv("XDG_DATA_HOME", xdg)
        assert data_dir() == tmp_path / "home" / ".local" / "share" / "sketchforge"
        assert autosave_dir() == tmp_path / "home" / ".local" / "share" / "sketchforge" / "autosave"
    assert find_recoverable() == []
    monkeypatch.setenv("SKETCHFORGE_DATA_DIR", str(tmp_path / "own"))
    assert autosave_dir() == tmp_path / "own" / "autosave"


@pytest.mark.parametrize("env, setting, expected", [
    ("0", 30, 30.0),      # 0 s is no interval: the setting
    (None, 0, 60.0),      # and then the default
    ("-5", "0.0", 60.0),
    ("inf", 12.5, 12.5),
    ("2.5", 30, 2.5),
    (None, "45", 45.0),
])
def test_an_autosave_interval_must_be_a_positive_finite_number(monkeypatch, env, setting, expected):
    if env is None:
        monkeypatch.delenv("SKETCHFORGE_AUTOSAVE_INTERVAL", raising=False)
    else:
        monkeypatch.setenv("SKETCHFORGE_AUTOSAVE_INTERVAL", env)
    assert autosave_interval(setting) == expected


def test_a_disk_that_refuses_the_folder_is_named_in_the_message(tmp_path, monkeypatch):
    folder = tmp_path / "auto"
    saver = Autosaver(dirty_doc(), folder=folder)

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "mkdir", full)
    with pytest.raises(ExportError, match=exactly(f"cannot autosave to {folder}: No space left on device")):
        saver.save_now()
    # a folder that is gone again as soon as it was made (another program's cleanup)
    monkeypatch.setattr(Path, "mkdir", lambda self, *a, **k: None)
    with pytest.raises(ExportError, match=exactly(f"cannot autosave: {folder} is not a folder")):
        saver.save_now()
    assert not folder.exists()


# --- what an autosave holds -------------------------------------------------------------------
def test_the_files_of_a_session_still_running_are_not_offered(tmp_path, monkeypatch):
    """Each file names its writer (process id and host): the files of another sketchforge still
    running on this host are left alone (pid 1, init, always runs)."""
    doc = dirty_doc()
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    clean = dirty_doc()
    clean.undo_stack.set_clean()
    other = Autosaver(clean, interval_s=0, folder=tmp_path)
    with monkeypatch.context() as m:
        m.setattr(autosave.os, "getpid", lambda: 1)
        saver.begin_solve(contour("a"))  # an autosave and its record
        other.begin_solve(contour("a"))  # a record only
    assert sorted(p.suffix for p in tmp_path.iterdir()) == [".json", ".pending", ".pending"]
    assert find_recoverable(tmp_path) == []


def test_recovery_lists_by_when_the_work_was_saved_not_by_the_files_dates(tmp_path, monkeypatch):
    """A backup tool or a copy changes the files' dates; the newest work is still offered first."""
    older, newer = dirty_doc(), dirty_doc()
    first = Autosaver(older, interval_s=0, folder=tmp_path)
    second = Autosaver(newer, interval_s=0, folder=tmp_path)
    for saver, t in ((first, 1_700_000_000.5), (second, 1_700_000_100.25)):
        with monkeypatch.context() as m:
            m.setattr(autosave.time, "time", lambda t=t: t)
            assert saver.save_now() is True
    os.utime(first.path, (1_800_000_000, 1_800_000_000))
    os.utime(second.path, (1_600_000_000, 1_600_000_000))
    found = find_recoverable(tmp_path)
    assert [(i.path, i.saved_at) for i in found] == [(second.path, 1_700_000_100.25), (first.path, 1_700_000_000.5)]


def _circle_doc(fan_host, n=200):
    doc = Document(host=fan_host)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    doc.execute({"command": "add_layer", "id": "a", "name": "Alpha"})
    doc.execute({"command": "set_contour", "layer": "a", "points": np.c_[np.cos(t), np.sin(t)].tolist(), "closed": True})
    return doc


def _compact(raw: bytes) -> bytes:
    return json.dumps(json.loads(raw), separators=(",", ":")).encode("utf-8")


def test_the_autosave_and_its_record_are_as_compact_as_a_saved_file(tmp_path, fan_host):
    """They are rewritten (and fsynced) before solves: their size is what they cost."""
    doc = _circle_doc(fan_host)
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    token = saver.begin_solve(contour("a", np.c_[np.arange(100.0), np.arange(100.0) % 7].tolist()))
    raw, record = saver.path.read_bytes(), saver.pending_path.read_bytes()
    assert raw == _compact(raw) and record == _compact(record)
    assert len(raw) - len(ff.dumps(doc)) < 300  # the document as a save writes it, plus a short header
    saver.end_solve(token)


def test_recovery_opens_the_autosave_with_the_app_s_plugins(tmp_path, fan_host):
    doc = dirty_doc()
    Autosaver(doc, interval_s=0, folder=tmp_path).save_now()
    [item] = find_recoverable(tmp_path)
    back = recover(item, host=fan_host)
    assert back.host is fan_host and not back.undo_stack.is_clean()


def test_a_document_marked_unsaved_after_its_autosave_went_is_autosaved_again(tmp_path, fan_host):
    """Recovered work is marked unsaved without changing (reset_clean): the autosave follows."""
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    doc.undo_stack.set_clean()
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    assert saver.tick() is False and not saver.path.exists()
    doc.undo_stack.reset_clean()
    assert saver.tick() is True and saver.path.exists()
    [item] = find_recoverable(tmp_path)
    assert recover(item, host=fan_host).layer_ids() == ["a"]


# --- solves -------------------------------------------------------------------------------------
def test_a_solve_ends_quietly_when_its_record_was_already_removed(tmp_path):
    """This process's own files are listed too, and a person may empty the folder: the end of
    a solve whose record is gone is no error."""
    doc = dirty_doc()
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    token = saver.begin_solve(contour("a"))
    saver.pending_path.unlink()
    saver.end_solve(token)
    assert not saver.pending_path.exists() and saver.path.exists()
    [item] = find_recoverable(tmp_path)
    assert item.running == () and item.pending_path is None


def test_a_plugin_command_whose_journal_entry_is_not_an_object_does_not_block_the_solve(tmp_path):
    class ListEntry(Command):
        name = "list_entry"

        def text(self):
            return "Paint"

        def to_dict(self):
            return ["list_entry", "a"]  # JSON, but no journal entry

    doc = dirty_doc()
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    token = saver.begin_solve(ListEntry(), before=[ListEntry()])
    [record] = json.loads(saver.pending_path.read_text())["running"]
    assert record["text"] == "Paint" and record["command"] is None and record["before"] == []
    assert record["layer"] is None
    saver.end_solve(token)
    assert not saver.pending_path.exists()


def test_a_hand_over_with_changes_still_unsaved_keeps_them_reported_as_unsaved(tmp_path):
    """Only a save (or replacing the document at the person's choice) makes the running step's
    work "saved"; a crash right after a hand-over that left changes unsaved says so."""
    doc = dirty_doc()
    saver = Autosaver(doc, interval_s=3600, folder=tmp_path)
    token = saver.begin_solve(contour("a"))
    new = saver.hand_over()  # the document still has its unsaved changes
    [item] = find_recoverable(tmp_path)
    assert item.has_document is False and item.running[-1]["unsaved"] is True
    saver.end_solve(token)
    assert find_recoverable(tmp_path) == []
    new.discard()


# --- what recovery lists ------------------------------------------------------------------------
def _real_files(folder):
    """A session with unsaved work that stopped in a solve, and one with none that did too."""
    work = Autosaver(dirty_doc(), original_path=folder / "mine.json", interval_s=0, folder=folder)
    work.begin_solve(contour("a"))
    clean = dirty_doc()
    clean.undo_stack.set_clean()
    report = Autosaver(clean, original_path=folder / "other.json", interval_s=0, folder=folder)
    report.begin_solve(contour("a"))
    return work, report


def _record_of(saver) -> dict:
    return json.loads(saver.pending_path.read_text())


@pytest.mark.parametrize("junk", ["unreadable record", "foreign record", "live session's record",
                                  "unreadable autosave", "live session's autosave",
                                  "record of an autosave being written", "record with a bad time"])
def test_junk_listed_first_in_the_folder_hides_no_real_work(tmp_path, junk):
    work, report = _real_files(tmp_path)
    record = _record_of(report)
    jp, jj = tmp_path / "!junk.pending", tmp_path / "!junk.json"  # sorted before every real name
    if junk == "unreadable record":
        jp.write_bytes(b"\xff{")
    elif junk == "foreign record":
        jp.write_text(json.dumps(dict(record, format="notes")))
    elif junk == "live session's record":
        jp.write_text(json.dumps(dict(record, pid=1, autosave="!junk.json")))
    elif junk == "unreadable autosave":
        jj.write_bytes(b"{")
    elif junk == "live session's autosave":
        data = json.loads(work.path.read_text())
        data["autosave"]["pid"] = 1
        jj.write_text(json.dumps(data))
    elif junk == "record of an autosave being written":
        jp.write_text(json.dumps(dict(record, autosave="!junk.json")))
        jj.write_bytes(b'{"format": "sketchf')
    elif junk == "record with a bad time":
        jp.write_text(json.dumps(dict(record, autosave="!junk.json", saved_at="yesterday")))
    before = {p: p.read_bytes() for p in tmp_path.iterdir()}
    found = find_recoverable(tmp_path)
    assert sorted((i.path.name, i.has_document) for i in found) == sorted(
        [(work.path.name, True), (report.path.name, False)])
    assert all(i.running[-1]["layer_name"] == "Alpha" for i in found)
    assert {p: p.read_bytes() for p in tmp_path.iterdir()} == before  # nothing is removed


@pytest.mark.parametrize("name", ["notes.txt", "../elsewhere.json", "sub/x.json", 5, None])
def test_a_record_naming_no_autosave_of_this_folder_goes_with_its_own_autosave(tmp_path, name):
    (tmp_path / "elsewhere.json").write_text("{}")
    folder = tmp_path / "auto"
    saver = Autosaver(dirty_doc(), interval_s=0, folder=folder)
    saver.begin_solve(contour("a"))
    data = _record_of(saver)
    data["autosave"] = name
    saver.pending_path.write_text(json.dumps(data))
    [item] = find_recoverable(folder)
    assert (item.path, item.pending_path, item.has_document) == (saver.path, saver.pending_path, True)
    assert item.running[-1]["text"] == "Draw contour"
    forget(item)
    assert list(folder.iterdir()) == [] and (tmp_path / "elsewhere.json").exists()


def test_forgetting_recovered_work_removes_its_autosave_and_its_record(tmp_path):
    work, report = _real_files(tmp_path)
    items = find_recoverable(tmp_path)
    assert sorted(i.pending_path for i in items) == sorted([work.pending_path, report.pending_path])
    for item in items:
        forget(item)
    assert list(tmp_path.iterdir()) == []


def test_forgetting_work_whose_record_is_already_gone_is_no_error(tmp_path):
    work, _ = _real_files(tmp_path)
    items = find_recoverable(tmp_path)
    work.pending_path.unlink()  # the solve of this very process ended meanwhile
    for item in items:
        forget(item)
        forget(item)  # twice is harmless
    assert list(tmp_path.iterdir()) == []


def test_an_autosave_without_its_header_or_time_is_listed_at_the_file_s_date(tmp_path, fan_host):
    """An autosave by an older sketchforge (no time in its header) or a document without the
    header is still offered, dated by the file."""
    doc = dirty_doc()
    old = Autosaver(doc, original_path=tmp_path / "mine.json", interval_s=0, folder=tmp_path / "auto")
    old.save_now()
    data = json.loads(old.path.read_text())
    del data["autosave"]["saved_at"]
    old.path.write_text(json.dumps(data))
    os.utime(old.path, (1_600_000_000, 1_600_000_000))
    bare = tmp_path / "auto" / "bare.json"
    ff.save(doc, bare, mark_clean=False)
    os.utime(bare, (1_650_000_000, 1_650_000_000))
    found = find_recoverable(tmp_path / "auto")
    assert [(i.path, i.original, i.saved_at) for i in found] == [
        (bare, None, 1_650_000_000.0),
        (old.path, str((tmp_path / "mine.json").resolve()), 1_600_000_000.0),
    ]
    assert ff.compare(recover(found[0], host=fan_host), doc) == []


def test_a_report_without_work_is_dated_by_its_record_else_by_the_file(tmp_path):
    _, report = _real_files(tmp_path)
    record = _record_of(report)
    report.pending_path.write_text(json.dumps(dict(record, saved_at=1_700_000_000.75, original=42)))
    os.utime(report.pending_path, (1_600_000_000, 1_600_000_000))
    [item] = [i for i in find_recoverable(tmp_path) if i.pending_path == report.pending_path]
    assert (item.has_document, item.original, item.saved_at) == (False, None, 1_700_000_000.75)
    del record["saved_at"]
    report.pending_path.write_text(json.dumps(record))
    os.utime(report.pending_path, (1_600_000_000, 1_600_000_000))
    [item] = [i for i in find_recoverable(tmp_path) if i.pending_path == report.pending_path]
    assert (item.has_document, item.original, item.saved_at) == (False, str((tmp_path / "other.json").resolve()),
                                                                  1_600_000_000.0)


def test_only_records_with_a_text_are_reported(tmp_path):
    _, report = _real_files(tmp_path)
    record = _record_of(report)
    real = record["running"][0]
    record["running"] = ["junk", 7, None, {"text": 5}, {"layer": "a"}, real]
    report.pending_path.write_text(json.dumps(record))
    [item] = [i for i in find_recoverable(tmp_path) if not i.has_document]
    assert item.running == (real,)
    assert describe_stop(item) == "sketchforge stopped while computing 'Draw contour' on layer 'Alpha'."


# --- the sentence a person reads after a crash ---------------------------------------------------
def test_work_without_a_running_step_has_no_stop_sentence(tmp_path):
    Autosaver(dirty_doc(), interval_s=0, folder=tmp_path).save_now()
    [item] = find_recoverable(tmp_path)
    assert item.running == () and describe_stop(item) == ""


def test_a_layer_without_a_name_is_named_by_its_id(tmp_path, fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="body", layer_name=""))
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    token = saver.begin_solve(contour("body"))
    [item] = find_recoverable(tmp_path)
    assert describe_stop(item) == "sketchforge stopped while computing 'Draw contour' on layer 'body'."
    saver.end_solve(token)


def test_the_stop_sentence_names_the_last_step_and_every_earlier_one_still_running(tmp_path):
    doc = dirty_doc()
    doc.execute({"command": "add_layer", "id": "b", "name": "Beta"})
    saver = Autosaver(doc, interval_s=0, folder=tmp_path)
    saver.begin_solve(contour("a"))  # cancelled, still in native code
    saver.begin_solve(text="Assemble")  # cancelled too
    saver.begin_solve(RenameLayer(layer="b", new_name="x"))
    [item] = find_recoverable(tmp_path)
    assert describe_stop(item) == (
        "sketchforge stopped while computing 'Rename layer' on layer 'Beta' "
        "(and 'Draw contour' on layer 'Alpha', 'Assemble', cancelled but still running)."
    )


def test_mirroring_and_duplicating_a_layer_are_named_in_the_undo_menu(fan_host):
    doc = Document(host=fan_host)
    stack = doc.undo_stack
    doc.push(AddLayer(id="a"))
    doc.push(contour("a", ((0, 0), (2, 0), (1, 1))))
    doc.execute({"command": "mirror_layer", "layer": "a", "axis": "own"})
    assert stack.undo_text() == "Mirror layer"
    doc.execute({"command": "duplicate_layer", "layer": "a", "id": "b"})
    assert stack.undo_text() == "Duplicate layer"
    stack.undo()
    assert stack.redo_text() == "Duplicate layer" and stack.undo_text() == "Mirror layer"


def test_a_duplicate_offset_given_as_a_one_by_two_row_is_journalled_as_two_numbers(fan_host):
    # numpy code often holds a 2D offset as a (1, 2) row; the command takes it (it flattens the
    # offset before checking it), so its journal entry must be two plain numbers that replay.
    from sketchforge.document.commands import DuplicateLayer

    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    doc.push(contour("a", ((0, 0), (2, 0), (1, 1))))
    cmd = DuplicateLayer(layer="a", new_id="b", offset=np.array([[0.5, -0.25]]))
    doc.push(cmd)
    entry = json.loads(json.dumps(cmd.to_dict()))
    assert entry["offset"] == [0.5, -0.25]
    moved = np.asarray(doc.layer("b").points) - np.asarray(doc.layer("a").points)
    assert np.allclose(moved, [0.5, -0.25], atol=0)
    replay = Document(host=fan_host)
    replay.push(AddLayer(id="a"))
    replay.push(contour("a", ((0, 0), (2, 0), (1, 1))))
    replay.execute(entry)
    assert np.array_equal(replay.layer("b").points, doc.layer("b").points)


@pytest.mark.parametrize("L, text", [
    (((1, 0), (0, 1)), "Move layer"),
    (((2.5, 0), (0, 2.5)), "Scale layer"),
    (((math.cos(0.3), -math.sin(0.3)), (math.sin(0.3), math.cos(0.3))), "Rotate layer"),
    (((-1, 0), (0, -1)), "Rotate layer"),          # a half turn
    (((1, 1), (0, 1)), "Transform layer"),          # a shear: det 1, but no rotation
    (((2, 0), (0, 0.5)), "Transform layer"),        # det 1, stretched
    (((0, -2), (2, 0)), "Transform layer"),         # a rotation and a scale
    (((-2, 0), (0, -2)), "Transform layer"),
    (((1, 0.1), (0.1, 1)), "Transform layer"),
])
def test_a_transform_is_named_in_the_undo_menu_by_what_it_does(fan_host, L, text):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    doc.push(contour("a", ((0, 0), (2, 0), (1, 1))))
    matrix = [[*map(float, L[0]), 0.25], [*map(float, L[1]), -0.5]]
    doc.push(TransformLayer(layer="a", matrix=matrix))
    assert doc.undo_stack.undo_text() == text
    # the journal's copy names the same step
    assert doc.undo_stack.undo_text() == TransformLayer.from_dict(TransformLayer(layer="a", matrix=matrix).to_dict()).text()


def test_a_rotation_from_a_drag_is_named_a_rotation(fan_host):
    doc = Document(host=fan_host)
    doc.push(AddLayer(id="a"))
    doc.push(contour("a", ((0, 0), (2, 0), (1, 1))))
    doc.push(TransformLayer(layer="a", matrix=rotate_about((1.0, 0.3), 2.0)))
    assert doc.undo_stack.undo_text() == "Rotate layer"


# --- files: what is read back, and what a bad file is told -----------------------------------


def _lit_doc(host):
    """A saved layer under a light that was changed after the file's first step."""
    doc = Document(host=host)
    doc.push(AddLayer(id="a"))
    doc.push(contour("a", ((0, 0), (2, 0), (1, 1))))
    doc.execute({"command": "set_light", "direction": [0.0, 1.0, 0.0]})
    return json.loads(ff.dumps(doc))


def test_a_reopened_file_keeps_the_light_its_journal_starts_from(fan_host):
    data = _lit_doc(fan_host)
    first = data["light"]
    assert first != [0.0, 1.0, 0.0] and data["snapshot"]["light"] == [0.0, 1.0, 0.0]
    doc = ff.document_from_dict(data, "t", host=fan_host)
    assert doc.light.direction.tolist() == [0.0, 1.0, 0.0]
    again = json.loads(ff.dumps(doc))
    assert again["light"] == first and again["snapshot"]["light"] == [0.0, 1.0, 0.0]
    # the journal replayed from that light ends where the snapshot is
    replayed = ff.document_from_dict(again, "t", host=fan_host, use_snapshot=False)
    assert ff.compare(doc, replayed) == []


def test_a_file_with_no_light_anywhere_is_lit_from_plus_x(fan_host):
    data = _lit_doc(fan_host)
    del data["light"], data["snapshot"]["light"]
    doc = ff.document_from_dict(data, "t", host=fan_host)
    assert doc.light.direction.tolist() == [1.0, 0.0, 0.0]
    assert json.loads(ff.dumps(doc))["light"] == [1.0, 0.0, 0.0]


def test_a_snapshot_layer_without_closed_is_an_open_stroke(fan_host):
    data = _lit_doc(fan_host)
    layer = data["snapshot"]["layers"][0]
    assert layer.pop("closed") is False
    assert ff.document_from_dict(data, "t", host=fan_host).layer("a").closed is False
    layer["closed"] = None
    with pytest.raises(DocumentFormatError):
        ff.document_from_dict(data, "t", host=fan_host)


@pytest.mark.parametrize("snapshot", [[], "layers", {"light": [1, 0, 0]}, {"layers": {}}])
def test_a_snapshot_that_is_no_object_with_layers_is_refused_by_name(fan_host, snapshot):
    data = _lit_doc(fan_host)
    data["snapshot"] = snapshot
    with pytest.raises(DocumentFormatError, match=exactly("t: field 'snapshot' must be an object with a 'layers' list")):
        ff.document_from_dict(data, "t", host=fan_host)


@pytest.mark.parametrize("plugin_data", [[], "x", 3])
def test_plugin_data_that_is_no_object_is_refused_by_name(fan_host, plugin_data):
    data = _lit_doc(fan_host)
    data["snapshot"]["plugin_data"] = plugin_data
    with pytest.raises(DocumentFormatError, match=exactly("t: snapshot.plugin_data must be an object")):
        ff.document_from_dict(data, "t", host=fan_host)


def test_a_file_of_another_format_is_named_by_its_format_field(fan_host):
    data = _lit_doc(fan_host)
    data["format"] = "blender"
    with pytest.raises(DocumentFormatError,
                       match=exactly("t: not a sketchforge document (field 'format' is 'blender')")):
        ff.document_from_dict(data, "t", host=fan_host)


def test_a_bad_light_in_a_journal_entry_is_named_with_its_command(fan_host):
    with pytest.raises(DocumentFormatError) as info:
        fan_host.commands.from_dict({"command": "set_light", "direction": [0.0, 0.0, 0.0]})
    assert str(info.value).startswith("command 'set_light': 'direction': ")


def test_a_journal_may_add_a_layer_without_an_id(fan_host):
    doc = ff.replay_journal(Light(1.0, 0.0),
                            [{"command": "add_layer"}, {"command": "add_layer", "name": "Leg"}], "t", fan_host)
    ids = doc.layer_ids()
    assert len(ids) == 2 and len(set(ids)) == 2 and all(isinstance(i, str) and i for i in ids)
    assert doc.layer(ids[1]).name == "Leg"


def test_a_saved_file_is_compact_json(fan_host):
    doc = ff.document_from_dict(_lit_doc(fan_host), "t", host=fan_host)
    raw = ff.dumps(doc)
    assert json.loads(raw) == ff.document_to_dict(doc)
    assert b", " not in raw and b": " not in raw and b"\n" not in raw


def test_a_file_the_user_may_not_read_is_named_in_the_message(tmp_path, monkeypatch):
    path = tmp_path / "locked.sketch"
    path.write_text("{}")

    def denied(*a, **k):
        raise PermissionError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(ff.os, "open", denied)
    with pytest.raises(DocumentFormatError, match=exactly(f"cannot open {path}: permission denied")):
        ff.read_regular_file(path)
