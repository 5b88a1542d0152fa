"""Autosave of unsaved work and recovery at the next start (no Qt; the app drives the timer).

Autosaves live in the user's data folder (``$SKETCHFORGE_DATA_DIR``, else
``$XDG_DATA_HOME/sketchforge``, else ``~/.local/share/sketchforge``) under ``autosave/``, one
file per open document, written with the same atomic save as a normal file. A clean save or a
normal close removes the autosave, so whatever is left there at start-up is unsaved work from
a session that ended abnormally: the app offers to recover it.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

from sketchforge.atomic import write_bytes_atomic
from sketchforge.document import fileformat as ff

#: Seconds between autosaves of a document with unsaved changes.
DEFAULT_INTERVAL_S = 60.0


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


@dataclass(frozen=True)
class Recoverable:
    path: Path  # the autosave file
    original: str | None  # the document's own path, if it had one
    saved_at: float  # seconds since the epoch


class Autosaver:
    """Call :meth:`tick` periodically (or :meth:`save_now`); it writes only when the document
    has unsaved changes it has not autosaved yet."""

    def __init__(self, doc, original_path=None, interval_s: float = DEFAULT_INTERVAL_S, folder: Path | None = None) -> None:
        self.doc = doc
        self.original_path = None if original_path is None else str(Path(original_path).resolve())
        self.interval_s = float(interval_s)
        self.folder = Path(folder) if folder is not None else autosave_dir()
        self._last_revision = -1
        self._last_time = time.monotonic()
        key = self.original_path or f"untitled-{os.getpid()}-{id(doc)}"
        self.path = self.folder / f"{hashlib.sha1(key.encode()).hexdigest()[:16]}.json"

    def tick(self) -> bool:
        now = time.monotonic()
        if now - self._last_time < self.interval_s:
            return False
        self._last_time = now
        return self.save_now()

    def save_now(self) -> bool:
        if self.doc.undo_stack.is_clean():
            self.discard()
            return False
        if self.doc.revision == self._last_revision:
            return False
        self.folder.mkdir(parents=True, exist_ok=True)
        data = ff.document_to_dict(self.doc)
        data["autosave"] = {"original": self.original_path, "saved_at": time.time()}
        write_bytes_atomic(self.path, json.dumps(data, separators=(",", ":")).encode("utf-8"))
        self._last_revision = self.doc.revision
        return True

    def discard(self) -> None:
        try:
            self.path.unlink()
        except FileNotFoundError:
            pass
        self._last_revision = -1


def find_recoverable(folder: Path | None = None) -> list[Recoverable]:
    """Autosaves left by sessions that did not end normally, newest first. Unreadable files
    are skipped (never deleted: the user may want them)."""
    folder = Path(folder) if folder is not None else autosave_dir()
    out = []
    for p in sorted(folder.glob("*.json")) if folder.is_dir() else []:
        try:
            meta = json.loads(p.read_text("utf-8")).get("autosave", {})
            out.append(Recoverable(p, meta.get("original"), float(meta.get("saved_at", p.stat().st_mtime))))
        except (OSError, ValueError, AttributeError, TypeError):
            continue
    return sorted(out, key=lambda r: -r.saved_at)


def recover(item: Recoverable, host=None):
    """Open an autosave as a document with unsaved changes. The file itself is left alone;
    the caller removes it once a new autosaver has taken over."""
    doc = ff.load(item.path, host=host)
    doc.undo_stack.reset_clean()  # the recovered state is not the saved file
    return doc
