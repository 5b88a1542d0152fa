"""Autosave of unsaved work and recovery at the next start (no Qt; the app drives the timer).

Autosaves live in the user's data folder (``$SKETCHFORGE_DATA_DIR``, else
``$XDG_DATA_HOME/sketchforge``, else ``~/.local/share/sketchforge``) under ``autosave/``, one
file per open document, written with the same atomic save as a normal file. A clean save or a
normal close removes the autosave, so whatever is left there at start-up is unsaved work from
a session that ended abnormally: the app offers to recover it.

Crashes inside native solvers (Triangle, libigl, OSQP, XLA) cannot be caught: they end the
process. So before a solve starts, :meth:`Autosaver.begin_solve` flushes the document as it is
*before* the user's action (only if it changed since the last autosave) and writes a small
side file, ``<autosave>.pending``, naming the action (its journal dict, its text, its layer).
:meth:`Autosaver.end_solve` removes that record once the solver has returned (success, error or
cancel). A ``.pending`` file found at start-up therefore names the step that was running when
the process died; the autosave next to it never contains that step (its result had not been
pushed), so recovering it does not replay the crash.

Every Autosaver writes to a file name of its own (the original path, the process and a
counter are hashed), and only ever removes the files it wrote itself: an autosave left by an
earlier session stays until the user recovers it, whatever this session does.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

from sketchforge.atomic import write_bytes_atomic
from sketchforge.document import fileformat as ff

#: Seconds between autosaves of a document with unsaved changes.
DEFAULT_INTERVAL_S = 60.0
#: Suffix of the side file that names the solve running when the autosave was flushed.
PENDING_SUFFIX = ".pending"

_instances = itertools.count(1)


def autosave_interval(setting=None) -> float:
    """Seconds between autosaves: ``$SKETCHFORGE_AUTOSAVE_INTERVAL``, else ``setting`` (the
    app's stored preference), else :data:`DEFAULT_INTERVAL_S`. Invalid values fall back."""
    for raw in (os.environ.get("SKETCHFORGE_AUTOSAVE_INTERVAL"), setting):
        try:
            value = float(raw)
        except (TypeError, ValueError):
            continue
        if value > 0:
            return value
    return DEFAULT_INTERVAL_S


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

    @property
    def pending(self) -> dict | None:
        """The solve that was running when the session stopped (the newest, if several)."""
        return self.running[-1] if self.running else None

    @property
    def pending_path(self) -> Path:
        return pending_path_for(self.path)


class Autosaver:
    """Call :meth:`tick` periodically (or :meth:`save_now`); it writes only when the document
    has unsaved changes it has not autosaved yet. Wrap every solve that runs native code in
    :meth:`begin_solve` / :meth:`end_solve`."""

    def __init__(self, doc, original_path=None, interval_s: float = DEFAULT_INTERVAL_S, folder: Path | None = None) -> None:
        self.doc = doc
        self.original_path = None if original_path is None else str(Path(original_path).resolve())
        self.interval_s = float(interval_s)
        self.folder = Path(folder) if folder is not None else autosave_dir()
        self._last_revision = -1
        self._last_time = time.monotonic()
        self._running: dict[int, dict] = {}
        self._tokens = itertools.count(1)
        #: seconds the last :meth:`begin_solve` spent writing (for the app's diagnostics/tests)
        self.last_flush_s = 0.0
        # A name of its own: two sessions (or a crashed one and this one) editing the same file
        # never write to, or remove, each other's autosave.
        key = f"{self.original_path or 'untitled'}\0{os.getpid()}\0{time.time_ns()}\0{next(_instances)}"
        self.path = self.folder / f"{hashlib.sha1(key.encode()).hexdigest()[:16]}.json"
        self.pending_path = pending_path_for(self.path)

    @property
    def running(self) -> list[dict]:
        """Records of the solves started with :meth:`begin_solve` and not yet ended."""
        return list(self._running.values())

    def tick(self) -> bool:
        now = time.monotonic()
        # While a solve runs (e.g. one cancelled in the GUI whose native code is still going),
        # a crash can come at any moment: keep the autosave current at every tick.
        if now - self._last_time < self.interval_s and not self._running:
            return False
        self._last_time = now
        return self.save_now()

    def save_now(self) -> bool:
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
        self.folder.mkdir(parents=True, exist_ok=True)
        data = ff.document_to_dict(self.doc)
        data["autosave"] = {"original": self.original_path, "saved_at": time.time()}
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
        t0 = time.perf_counter()
        record = self._describe(cmd, text, macro, before)
        self.save_now()
        token = next(self._tokens)
        self._running[token] = record
        try:
            self._write_pending()
        except BaseException:
            del self._running[token]
            raise
        self.last_flush_s = time.perf_counter() - t0
        return token

    def end_solve(self, token) -> None:
        """The solve's native code has returned (whatever the outcome): forget its record."""
        if self._running.pop(token, None) is None:
            return
        if self._running:
            self._write_pending()
        else:
            self._remove(self.pending_path)
        if self.doc.undo_stack.is_clean():
            self._remove_document()  # the usual rule: a clean document has no autosave

    def _describe(self, cmd, text, macro, before) -> dict:
        entry = None
        if cmd is not None:
            try:
                entry = cmd.to_dict()
                json.dumps(entry)
            except Exception:  # noqa: BLE001 - a plugin's odd command must not block the solve
                entry = None
        layer = entry.get("layer") if isinstance(entry, dict) and isinstance(entry.get("layer"), str) else None
        layer_name = None
        new_layer = layer is not None and layer not in self.doc.layer_ids()
        if layer is not None:
            if not new_layer:
                layer_name = self.doc.layer(layer).name
            else:  # a layer the macro is about to add
                for c in before:
                    try:
                        d = c.to_dict()
                    except Exception:  # noqa: BLE001
                        continue
                    if d.get("command") == "add_layer" and d.get("id") == layer and isinstance(d.get("name"), str):
                        layer_name = d["name"]
        before_entries = []
        for c in before:
            try:
                before_entries.append(c.to_dict())
            except Exception:  # noqa: BLE001
                pass
        return {
            "text": macro or text or (cmd.text() if cmd is not None else "a computation"),
            "command_text": cmd.text() if cmd is not None else None,
            "command": entry,
            "macro": macro,
            "before": before_entries,
            "layer": layer,
            "layer_name": layer_name,
            "new_layer": new_layer,
            # False: the saved file was the state (no autosave is needed to recover it)
            "unsaved": not self.doc.undo_stack.is_clean(),
            "started_at": time.time(),
        }

    def _write_pending(self) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)
        data = {
            "format": "sketchforge-pending",
            "original": self.original_path,
            "autosave": self.path.name,
            "saved_at": time.time(),
            "running": list(self._running.values()),
        }
        write_bytes_atomic(self.pending_path, json.dumps(data, separators=(",", ":")).encode("utf-8"))

    # --- removing ---------------------------------------------------------------------------------
    @staticmethod
    def _remove(path: Path) -> None:
        try:
            path.unlink()
        except FileNotFoundError:
            pass

    def _remove_document(self) -> None:
        self._remove(self.path)
        self._last_revision = -1

    def discard(self) -> None:
        """The document was saved, closed or replaced: remove this autosaver's files (never
        anyone else's) and forget running solves."""
        self._running.clear()
        self._remove(self.pending_path)
        self._remove_document()


def _read_json_dict(path: Path) -> dict:
    data = json.loads(path.read_text("utf-8"))
    if not isinstance(data, dict):
        raise ValueError("not an object")
    return data


def _running_records(raw) -> tuple:
    if not isinstance(raw, list):
        return ()
    return tuple(r for r in raw if isinstance(r, dict) and isinstance(r.get("text"), str))


def find_recoverable(folder: Path | None = None) -> list[Recoverable]:
    """Autosaves left by sessions that did not end normally, newest first, each with the solves
    that were running when it stopped (``running``; see :meth:`Autosaver.begin_solve`). A
    ``.pending`` record without an autosave (the document had no unsaved changes) is listed
    with ``has_document=False``. Unreadable files are skipped (never deleted: the user may
    want them)."""
    folder = Path(folder) if folder is not None else autosave_dir()
    if not folder.is_dir():
        return []
    out = []
    for p in sorted(folder.glob("*.json")):
        try:
            meta = _read_json_dict(p).get("autosave", {})
            original, saved_at = meta.get("original"), float(meta.get("saved_at", p.stat().st_mtime))
        except (OSError, ValueError, AttributeError, TypeError):
            continue
        running: tuple = ()
        pending = pending_path_for(p)
        if pending.exists():
            try:
                running = _running_records(_read_json_dict(pending).get("running"))
            except (OSError, ValueError):
                running = ()
        out.append(Recoverable(p, original, saved_at, running))
    for q in sorted(folder.glob("*" + PENDING_SUFFIX)):
        doc_path = q.with_suffix(".json")
        if doc_path.exists():
            continue  # listed above with its autosave
        try:
            data = _read_json_dict(q)
            running = _running_records(data.get("running"))
            original = data.get("original")
            saved_at = float(data.get("saved_at", q.stat().st_mtime))
        except (OSError, ValueError, AttributeError, TypeError):
            continue
        if running:
            out.append(Recoverable(doc_path, original if isinstance(original, str) else None, saved_at, running, has_document=False))
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


def recover(item: Recoverable, host=None):
    """Open an autosave as a document with unsaved changes. The file itself is left alone;
    the caller removes it (:func:`forget`) once a new autosaver has taken over. A step that
    was running when the session stopped is not in it: its result was never pushed."""
    doc = ff.load(item.path, host=host)
    doc.undo_stack.reset_clean()  # the recovered state is not the saved file
    return doc


def forget(item: Recoverable) -> None:
    """Remove a recovered (or reported) autosave and its pending record."""
    for p in (item.path, item.pending_path):
        try:
            p.unlink()
        except FileNotFoundError:
            pass
