"""Autosave of unsaved work and recovery at the next start (no Qt; the app drives the timer).

Autosaves live in the user's data folder (``$SKETCHFORGE_DATA_DIR``, else
``$XDG_DATA_HOME/sketchforge``, else ``~/.local/share/sketchforge``) under ``autosave/``, one
file per open document, written with the same atomic save as a normal file. A clean save or a
normal close removes the autosave, so what a session that is no longer running left there
is unsaved work from a session that ended abnormally: the app offers to recover it.

Crashes inside native solvers (Triangle, libigl, OSQP, XLA) cannot be caught: they end the
process. So before a solve starts, :meth:`Autosaver.begin_solve` flushes the document as it is
*before* the user's action (only if it changed since the last autosave) and writes a small
side file, ``<autosave>.pending``, naming the action (its journal dict, its text, its layer).
:meth:`Autosaver.end_solve` removes that record once the solver has returned (success, error or
cancel). A ``.pending`` file found at start-up therefore names the step that was running when
the process died; the autosave it names never contains that step (its result had not been
pushed), so recovering it does not replay the crash.

A record lives until its solve really ends, across a save or an open: the document then gets a
new Autosaver (:meth:`Autosaver.hand_over`), which takes over the records of the solves still
running (a cancelled one still in native code, a sculpt preview, an assembly) in the same
record file, now naming the new autosave; ``end_solve`` on the old Autosaver passes them on.

Every Autosaver writes to file names of its own (a random uuid), and only ever removes the
files it wrote itself: an autosave left by an earlier session stays until the user recovers
it, whatever this session does. Both files also record their writer (process id and host
name), and :func:`find_recoverable` skips the files of another process that is still running
on this host (``os.kill(pid, 0)``): a second sketchforge started while the first one runs,
even in the middle of a solve, neither offers nor deletes the first one's files. Limits of
that check: a crashed session's process id may be reused by an unrelated live process; its
files are then kept but not offered until that process has ended (they are offered at a later
start). Files written on another host (a shared home folder) cannot be checked: they are
offered. This process's own files are listed: it knows which of them it still writes (the app
asks once, at start, before it has written any).
"""

from __future__ import annotations

import itertools
import json
import math
import os
import socket
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

from sketchforge.atomic import pid_alive, remove_stale_temps_in, write_bytes_atomic
from sketchforge.document import fileformat as ff
from sketchforge.errors import SketchforgeError

#: Seconds between autosaves of a document with unsaved changes.
DEFAULT_INTERVAL_S = 60.0
#: The app's timer polls at least this often (every interval of 1 s or more is kept to within
#: a second; shorter ones, used by tests, are polled at this rate).
MIN_INTERVAL_S = 1.0
#: The ``format`` of that side file (other files ending in the suffix are left alone).
PENDING_FORMAT = "sketchforge-pending"
#: Suffix of the side file that names the solve running when the autosave was flushed.
PENDING_SUFFIX = ".pending"

#: end_solve tokens, unique in the process: a token stays valid across a hand-over
_tokens = itertools.count(1)


def autosave_interval(setting=None) -> float:
    """Seconds between autosaves: ``$SKETCHFORGE_AUTOSAVE_INTERVAL``, else ``setting`` (the
    app's stored preference), else :data:`DEFAULT_INTERVAL_S`. Invalid values (not a number,
    not finite, <= 0) fall back."""
    for raw in (os.environ.get("SKETCHFORGE_AUTOSAVE_INTERVAL"), setting):
        try:
            value = float(raw)
        except (TypeError, ValueError, OverflowError):
            continue
        if value > 0 and value != float("inf"):
            return value
    return DEFAULT_INTERVAL_S


def poll_interval_ms(interval_s: float) -> int:
    """How often the app's timer calls :meth:`Autosaver.tick`: every 5 s, or the interval when it
    is shorter (but not more often than every :data:`MIN_INTERVAL_S`), so an interval of 1 s
    or more is kept to within a second."""
    return int(round(1000 * min(5.0, max(MIN_INTERVAL_S, float(interval_s)))))


def _ensure_folder(folder: Path) -> None:
    """Create the autosave folder; a clear ExportError when a file is in the way or the disk
    refuses (the app shows it and retries at the next tick)."""
    from sketchforge.errors import ExportError

    try:
        folder.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        raise ExportError(f"cannot autosave: {folder} (or a folder above it) is a file, not a folder") from None
    except OSError as exc:
        raise ExportError(f"cannot autosave to {folder}: {exc.strerror or exc}") from None
    if not folder.is_dir():
        raise ExportError(f"cannot autosave: {folder} is not a folder")


def data_dir() -> Path:
    env = os.environ.get("SKETCHFORGE_DATA_DIR")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_DATA_HOME")
    return (Path(xdg) if xdg else Path.home() / ".local" / "share") / "sketchforge"


def autosave_dir() -> Path:
    return data_dir() / "autosave"


def pending_path_for(autosave_path: Path) -> Path:
    return Path(autosave_path).with_suffix(PENDING_SUFFIX)


def this_writer() -> dict:
    """Who writes a file: recorded in autosaves and records for :func:`writer_alive`."""
    return {"pid": os.getpid(), "host": socket.gethostname()}


def writer_alive(meta) -> bool:
    """True when ``meta`` (a file's ``pid`` and ``host``) names another process that is still
    running on this host: that session's files are not this one's to offer or remove. False
    for this process (it knows its own files), another host (it cannot be checked), files
    without a writer and platforms without ``os.kill(pid, 0)``."""
    if os.name != "posix" or not isinstance(meta, dict):
        return False
    pid = meta.get("pid")
    if type(pid) is not int or pid <= 0 or pid == os.getpid() or meta.get("host") != socket.gethostname():
        return False
    return pid_alive(pid)


@dataclass(frozen=True)
class Recoverable:
    path: Path  # the autosave file (absent when ``has_document`` is False)
    original: str | None  # the document's own path, if it had one
    saved_at: float  # seconds since the epoch
    #: the solves that were running when the session stopped (records written by
    #: :meth:`Autosaver.begin_solve`, oldest first); empty when none was
    running: tuple = ()
    #: False for a crash during a solve on a document without unsaved changes: there is no
    #: work to recover, only the report of which step was running
    has_document: bool = True
    #: the record file of ``running`` (None when there is none)
    pending_path: Path | None = None
    #: SHA-256 of ``original`` as the session last opened or saved it (None: unknown): a save
    #: of the recovered work over it asks first if it changed since
    original_sha256: str | None = None


class Autosaver:
    """Call :meth:`tick` periodically (or :meth:`save_now`); it writes only when the document
    has unsaved changes it has not autosaved yet. Wrap every solve that runs native code in
    :meth:`begin_solve` / :meth:`end_solve`. When the document is saved or replaced, use the
    Autosaver that :meth:`hand_over` returns; at a normal close, :meth:`discard`."""

    def __init__(self, doc, original_path=None, interval_s: float = DEFAULT_INTERVAL_S, folder: Path | None = None,
                 original_sha256: str | None = None) -> None:
        self.doc = doc
        self.original_path = None if original_path is None else str(Path(original_path).resolve())
        self.original_sha256 = original_sha256 if self.original_path is not None else None
        self.interval_s = float(interval_s)
        self.folder = Path(folder) if folder is not None else autosave_dir()
        self._last_revision = -1
        self._last_time = time.monotonic()
        self._running: dict[int, dict] = {}
        self._successor: Autosaver | None = None
        # A name of its own: two sessions (or a crashed one and this one) editing the same file
        # never write to, or remove, each other's autosave.
        self.path = self.folder / f"{uuid.uuid4().hex}.json"
        self.pending_path = pending_path_for(self.path)

    def tick(self) -> bool:
        now = time.monotonic()
        # While a solve runs (e.g. one cancelled in the GUI whose native code is still going),
        # a crash can come at any moment: keep the autosave current at every tick.
        if now - self._last_time < self.interval_s and not self._running:
            return False
        self._last_time = now
        return self.save_now()

    def save_now(self) -> bool:
        if self._successor is not None:
            return False  # handed over: the new Autosaver writes
        stack = self.doc.undo_stack
        if stack.in_macro():
            # Half a macro (e.g. "Draw layer": its new layer is in, its contour is being
            # inflated) is no state the user ever had, and the journal would not match the
            # snapshot. The state before the macro was flushed by begin_solve.
            return False
        if stack.is_clean():
            self._remove_document()
            return False
        if self.doc.revision == self._last_revision:
            return False
        _ensure_folder(self.folder)
        data = ff.document_to_dict(self.doc)
        data["autosave"] = {"original": self.original_path, "saved_at": time.time(), **this_writer()}
        if self.original_sha256 is not None:
            data["autosave"]["original_sha256"] = self.original_sha256
        write_bytes_atomic(self.path, json.dumps(data, separators=(",", ":")).encode("utf-8"))
        self._last_revision = self.doc.revision
        return True

    # --- solves -----------------------------------------------------------------------------------
    def begin_solve(self, cmd=None, *, text: str | None = None, macro: str | None = None, before=()) -> int:
        """Call on the GUI thread just before native code starts (before a macro opens, so that
        ``before``, the macro's cheap first commands, are not in the document yet). Makes sure
        the autosave holds the document as it is now (a clean document has none: the saved
        file is the state) and writes the pending record, both fsynced. Returns a token for
        :meth:`end_solve`. Raises ExportError (nothing recorded) when the disk refuses."""
        record = self._describe(cmd, text, macro, before)
        self.save_now()
        token = next(_tokens)
        self._running[token] = record
        try:
            self._write_pending()
        except BaseException:
            del self._running[token]
            raise
        return token

    def end_solve(self, token) -> None:
        """The solve's native code has returned (whatever the outcome): forget its record. A
        token of a solve handed over (:meth:`hand_over`) is passed on to the new Autosaver."""
        if self._successor is not None:
            self._successor.end_solve(token)
            return
        if self._running.pop(token, None) is None:
            return
        if self._running:
            self._write_pending()
        else:
            self.pending_path.unlink(missing_ok=True)
        if self.doc.undo_stack.is_clean():
            self._remove_document()  # the usual rule: a clean document has no autosave

    @staticmethod
    def _entry(cmd) -> dict | None:
        """A command's journal dict, or None when a plugin's odd command has none (that must
        not block the solve)."""
        try:
            entry = cmd.to_dict()
            json.dumps(entry)
        except Exception:  # noqa: BLE001
            return None
        return entry if isinstance(entry, dict) else None

    def _describe(self, cmd, text, macro, before) -> dict:
        entry = self._entry(cmd) if cmd is not None else None
        before_entries = [d for d in map(self._entry, before) if d is not None]
        layer = entry.get("layer") if entry is not None and isinstance(entry.get("layer"), str) else None
        layer_name = None
        new_layer = layer is not None and layer not in self.doc.layer_ids()
        if layer is not None:
            if not new_layer:
                layer_name = self.doc.layer(layer).name
            else:  # a layer the macro is about to add
                for d in before_entries:
                    if d.get("command") == "add_layer" and d.get("id") == layer and isinstance(d.get("name"), str):
                        layer_name = d["name"]
        return {
            "text": macro or text or (cmd.text() if cmd is not None else "a computation"),
            "command": entry,
            "macro": macro,
            "before": before_entries,
            "layer": layer,
            "layer_name": layer_name,
            "new_layer": new_layer,
            # False: the saved file was the state (no autosave is needed to recover it)
            "unsaved": not self.doc.undo_stack.is_clean(),
        }

    def _write_pending(self) -> None:
        _ensure_folder(self.folder)
        data = {
            "format": PENDING_FORMAT,
            "original": self.original_path,
            "autosave": self.path.name,  # the autosave these solves started from
            "saved_at": time.time(),
            **this_writer(),
            "running": list(self._running.values()),
        }
        write_bytes_atomic(self.pending_path, json.dumps(data, separators=(",", ":")).encode("utf-8"))

    # --- saved, replaced, closed ------------------------------------------------------------------
    def hand_over(self, original_path=None, original_sha256: str | None = None) -> Autosaver:
        """The document was saved (to ``original_path``) or replaced (opened, new, recovered):
        returns its new Autosaver (a new file name) and removes this one's autosave. The solves
        still running keep their record until they end: the new Autosaver takes them over, in
        the same record file, and :meth:`end_solve` on this one passes their tokens on. If that
        file cannot be rewritten (the disk), it keeps naming them beside the old autosave's
        name, and still goes when the last of them ends."""
        new = Autosaver(self.doc, original_path, self.interval_s, self.folder, original_sha256)
        new.pending_path = self.pending_path
        clean = self.doc.undo_stack.is_clean()
        # Saved, or replaced at the person's choice: no unsaved changes of theirs are at stake.
        new._running = {t: dict(r, unsaved=bool(r.get("unsaved")) and not clean) for t, r in self._running.items()}
        self._running = {}
        self._successor = new
        if new._running:
            try:
                new._write_pending()
            except OSError:
                pass
        self._remove_document()
        return new

    def _remove_document(self) -> None:
        self.path.unlink(missing_ok=True)
        self._last_revision = -1

    def discard(self) -> None:
        """A normal close: remove this autosaver's files (never anyone else's), the records of
        solves still running included (nothing will end them: the window is gone and the
        session is ending normally). A save or an open uses :meth:`hand_over` instead."""
        if self._successor is None:
            self._running.clear()
            self.pending_path.unlink(missing_ok=True)
        self._remove_document()


def _read_json_dict(path: Path) -> dict:
    """A JSON object through the document reader's guards: a FIFO or device named ``*.json``
    in the folder is refused instead of blocking the start-up scan (a plain ``read_text`` did),
    and an oversized file is refused before it is read."""
    try:
        data = ff.read_json(path)
    except SketchforgeError as exc:
        raise ValueError(str(exc)) from None
    if not isinstance(data, dict):
        raise ValueError("not an object")
    return data


#: Where :func:`find_recoverable` moves an autosave it cannot use (inside the autosave folder,
#: so the user still has it; never offered again).
SET_ASIDE_FOLDER = "set-aside"
#: The longest ``original`` path an autosave may name (Linux's PATH_MAX).
MAX_PATH_CHARS = 4096


def _autosave_meta(data: dict) -> tuple[str | None, float | None, str | None]:
    """The ``original`` path, ``saved_at`` time and ``original_sha256`` an autosave records,
    checked: ``original`` None or a path (a string without NUL, at most MAX_PATH_CHARS),
    ``saved_at`` absent or a finite number of seconds, the digest absent or 64 hex digits.
    Raises ValueError naming the bad field (issue 38: an ``original`` of 5 made the app exit
    with a TypeError once the user chose to recover)."""
    meta = data.get("autosave", {})
    if not isinstance(meta, dict):
        raise ValueError("its 'autosave' record is not an object")
    original = meta.get("original")
    if original is not None and not (isinstance(original, str) and original and "\0" not in original
                                     and len(original) <= MAX_PATH_CHARS):
        raise ValueError("its 'original' is not a file path")
    saved_at = meta.get("saved_at")
    if saved_at is not None:
        if isinstance(saved_at, bool) or not isinstance(saved_at, (int, float)) or not math.isfinite(saved_at):
            raise ValueError("its 'saved_at' is not a time")
        saved_at = float(saved_at)
    for key, kind in (("pid", int), ("host", str)):
        if key in meta and (not isinstance(meta[key], kind) or isinstance(meta[key], bool)):
            raise ValueError(f"its '{key}' is malformed")
    digest = meta.get("original_sha256")
    if digest is not None and not (isinstance(digest, str) and len(digest) == 64
                                   and all(c in "0123456789abcdef" for c in digest)):
        raise ValueError("its 'original_sha256' is malformed")
    return original, saved_at, digest


def set_aside(path: Path, why: str) -> str:
    """Move an autosave (and its record) that cannot be used into :data:`SET_ASIDE_FOLDER`,
    kept for the user but never offered again; returns one line saying so."""
    dest_dir = path.parent / SET_ASIDE_FOLDER
    try:
        dest_dir.mkdir(exist_ok=True)
        dest = dest_dir / path.name
        os.replace(path, dest)
        record = pending_path_for(path)
        if record.exists():
            os.replace(record, dest_dir / record.name)
    except OSError as exc:
        return f"the autosave {path} cannot be used ({why}) and could not be moved aside ({exc.strerror or exc})"
    return f"the autosave {path.name} cannot be used ({why}); it was moved to {dest}"


def _running_records(raw) -> tuple:
    if not isinstance(raw, list):
        return ()
    return tuple(r for r in raw if isinstance(r, dict) and isinstance(r.get("text"), str))


def find_recoverable(folder: Path | None = None, set_aside_notes: list | None = None) -> list[Recoverable]:
    """Autosaves left by sessions that did not end normally, newest first, each with the solves
    that were running when it stopped (``running``; see :meth:`Autosaver.begin_solve`). A
    ``.pending`` record without an autosave (the document had no unsaved changes) is listed
    with ``has_document=False``. The files of another sketchforge still running on this host
    are left out (:func:`writer_alive`).

    An autosave that cannot be used (not JSON, malformed metadata) is skipped, and, when
    ``set_aside_notes`` is a list (the app at start), moved to :data:`SET_ASIDE_FOLDER` (never
    deleted: the user may want it) with one line appended there saying so. Temp files of
    autosaves killed mid-write (their writer process is gone) are removed: their names are
    new at each session, so no later save of the same name would ever remove them."""
    folder = Path(folder) if folder is not None else autosave_dir()
    if not folder.is_dir():
        return []
    if set_aside_notes is not None:
        remove_stale_temps_in(folder)
    records: dict[str, tuple[Path, dict]] = {}  # autosave name -> (record file, its contents)
    for q in sorted(folder.glob("*" + PENDING_SUFFIX)):
        try:
            data = _read_json_dict(q)
        except (OSError, ValueError):
            continue
        if data.get("format") != PENDING_FORMAT or writer_alive(data):
            continue  # not our record (any file may end in .pending), or its writer still runs
        name = data.get("autosave")
        if not (isinstance(name, str) and name.endswith(".json") and Path(name).name == name):
            name = q.with_suffix(".json").name
        records[name] = (q, data)
    out = []
    for p in sorted(folder.glob("*.json")):
        try:
            data = _read_json_dict(p)
            if writer_alive(data.get("autosave")):
                continue
            original, saved_at, digest = _autosave_meta(data)
            saved_at = p.stat().st_mtime if saved_at is None else saved_at
        except ValueError as exc:
            if set_aside_notes is not None:
                set_aside_notes.append(set_aside(p, str(exc)))
            continue
        except OSError:
            continue
        q, data = records.pop(p.name, (None, {}))
        out.append(Recoverable(p, original, saved_at, _running_records(data.get("running")), pending_path=q,
                               original_sha256=digest))
    for name, (q, data) in records.items():
        doc_path = folder / name
        if doc_path.exists():
            continue  # an autosave that is unreadable or still being written: leave both alone
        running = _running_records(data.get("running"))
        original = data.get("original")
        try:
            saved_at = float(data.get("saved_at", q.stat().st_mtime))
        except (OSError, ValueError, TypeError):
            continue
        if running:
            out.append(
                Recoverable(doc_path, original if isinstance(original, str) else None, saved_at, running,
                            has_document=False, pending_path=q)
            )
    return sorted(out, key=lambda r: -r.saved_at)


def describe_stop(item: Recoverable) -> str:
    """One sentence naming the step that was running when the session stopped ("" if none):
    "sketchforge stopped while computing 'Sculpt isophote' on layer 'body'." """
    if not item.running:
        return ""
    parts = []
    for r in item.running:
        s = f"'{r.get('text')}'"
        if r.get("layer_name"):
            s += f" on layer '{r['layer_name']}'"
        elif r.get("new_layer"):
            s += " on a new layer"
        elif r.get("layer"):
            s += f" on layer '{r['layer']}'"
        parts.append(s)
    if len(parts) > 1:  # an older, cancelled solve whose native code was still running
        return f"sketchforge stopped while computing {parts[-1]} (and {', '.join(parts[:-1])}, cancelled but still running)."
    return f"sketchforge stopped while computing {parts[0]}."


def recover(item: Recoverable, host):
    """Open an autosave as a document with unsaved changes. The file itself is left alone;
    the caller removes it (:func:`forget`) once a new autosaver has taken over. A step that
    was running when the session stopped is not in it: its result was never pushed."""
    doc = ff.load(item.path, host=host)
    doc.undo_stack.reset_clean()  # the recovered state is not the saved file
    return doc


def forget(item: Recoverable) -> None:
    """Remove a recovered (or reported) autosave and its pending record."""
    item.path.unlink(missing_ok=True)
    if item.pending_path is not None:
        item.pending_path.unlink(missing_ok=True)
