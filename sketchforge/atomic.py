"""Atomic file writes: a reader sees the old file or the new one, never a torn one.

The temp file lives in the target's folder (so the final rename is atomic) under a short name,
``.<first 40 characters of the name>.<hash of the name>.<pid>.<random>.tmp``, so a legal
255-byte target name never makes an illegal temp name. A save killed half-way leaves its temp
file behind; the next save of the same file removes those whose writer is no longer running
(and the ``.NAME.XXXXXXXX.tmp`` files of the previous release once they are a minute old).

An existing target keeps its permission bits (rwx, not setuid, setgid or sticky); a new one
gets the user's umask (the temp file is created with mode 0666 and the kernel applies the
umask). A target without any write bit is read-only: it is refused, even for root, who could
otherwise overwrite it.
"""

from __future__ import annotations

import errno
import hashlib
import os
import re
import secrets
import stat
import time
from pathlib import Path

from sketchforge.errors import ExportError

#: Characters (and at most bytes) of the target's name kept in its temp name (plus a hash).
_NAME_CHARS = 40
_NAME_BYTES = 80
#: Previous-release temp files (no writer recorded) older than this are stale.
_LEGACY_STALE_S = 60.0


def _name_key(name: str) -> str:
    return hashlib.sha1(name.encode("utf-8", "surrogatepass")).hexdigest()[:10]


def temp_prefix(path) -> str:
    """The temp-name prefix of saves to ``path``: ``.<name[:40]>.<hash>.`` (at most 93 bytes,
    whatever the target's length)."""
    name = Path(path).name
    short = name[:_NAME_CHARS]
    while len(short.encode("utf-8", "surrogatepass")) > _NAME_BYTES:  # multibyte characters
        short = short[:-1]
    return f".{short}.{_name_key(name)}."


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this host (``os.kill(pid, 0)``). An answer other than
    "no such process" counts as alive (another user's process, an unexpected error): a live
    writer's files are never removed on a guess."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)  # signal 0: only asks whether the process exists
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def remove_stale_temps(path) -> list[Path]:
    """Remove the temp files that crashed saves to ``path`` left behind (their writer process
    is gone), and previous-release ``.NAME.XXXXXXXX.tmp`` files older than a minute. Returns
    what was removed. Never raises."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    prefix = temp_prefix(path)
    legacy = re.compile(re.escape(f".{path.name}.") + r"[A-Za-z0-9_]{8}\.tmp\Z")
    removed: list[Path] = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    now = time.time()
    for e in entries:
        name = e.name
        if not name.endswith(".tmp"):
            continue
        stale = False
        if name.startswith(prefix):
            pid_text = name[len(prefix) :].split(".", 1)[0]
            stale = pid_text.isdigit() and not pid_alive(int(pid_text))
        elif legacy.match(name):
            try:
                stale = now - e.stat(follow_symlinks=False).st_mtime > _LEGACY_STALE_S
            except OSError:
                stale = False
        if stale:
            _remove_file(e, removed)
    return removed


def _remove_file(e: os.DirEntry, removed: list[Path]) -> None:
    """Unlink the plain file ``e`` (never a link or folder) and note it; a file that cannot
    be removed is left as it is (the next start tries again)."""
    try:
        if e.is_file(follow_symlinks=False):
            os.unlink(e.path)
            removed.append(Path(e.path))
    except OSError:
        pass


#: Any temp name this module makes: ``.<name>.<10 hex>.<pid>.<8 hex>.tmp``.
_TEMP_NAME = re.compile(r"\A\..*\.[0-9a-f]{10}\.(\d+)\.[0-9a-f]{8}\.tmp\Z", re.DOTALL)


def remove_stale_temps_in(folder) -> list[Path]:
    """Remove every temp file in ``folder`` that a killed save left (its writer process is
    gone), whatever file it was for. For folders whose targets change name at each session
    (the autosaves: a fresh name each time, so "the next save of the same file" never
    comes). A live writer's temp is left alone. Returns what was removed; never raises."""
    removed: list[Path] = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for e in entries:
        m = _TEMP_NAME.match(e.name)
        if m is not None and not pid_alive(int(m.group(1))):
            _remove_file(e, removed)
    return removed


def check_writable(path) -> os.stat_result | None:
    """Refuse a target that is a directory, a non-regular file or read-only (no write bit at
    all, checked on the mode so root is refused too). Returns the target's stat, or None when
    it does not exist."""
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise ExportError(f"cannot write {path}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise ExportError(f"cannot write {path}: it is a directory")
    if not stat.S_ISREG(st.st_mode):
        raise ExportError(f"cannot write {path}: it is not a regular file")
    if st.st_mode & 0o222 == 0 or not os.access(path, os.W_OK):
        raise ExportError(f"cannot write {path}: the file is read-only")
    return st


def check_target(path) -> None:
    """Raise ExportError now if ``path`` cannot be written (no folder, a directory, a read-only
    file): a command line checks its outputs before the work, so a refusal is its only line."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise ExportError(f"cannot write {path}: the folder {folder} does not exist")
    check_writable(path)


def same_file(a, b) -> bool:
    """True when paths ``a`` and ``b`` name the same file (links and ``..`` resolved), or would."""
    a, b = Path(a), Path(b)
    try:
        if os.path.samefile(a, b):
            return True
    except OSError:
        pass
    try:
        return a.resolve() == b.resolve()
    except (OSError, RuntimeError):
        return os.path.abspath(a) == os.path.abspath(b)


def refuse_input_as_output(out, inputs, what: str = "output") -> None:
    """Raise ExportError when ``out`` is one of ``inputs`` (documents open or named on the
    command line): writing it would destroy the input."""
    for src in inputs:
        if src is not None and same_file(out, src):
            raise ExportError(f"cannot write {out}: it is the input document {src}; choose another {what} file")


def write_bytes_atomic(path, data: bytes) -> os.stat_result:
    """Write ``data`` to ``path`` via a temp file in the same folder, fsync, then rename.
    Returns the written file's ``fstat`` (the rename keeps its inode and times), so a caller
    can tell later whether someone else replaced it (no window for a race in between).

    Raises ExportError (an OSError) with a readable message when the folder does not exist or
    refuses new files, the path is a directory or read-only, or the write fails; the old file,
    if any, is left untouched and no temp file is left behind.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise ExportError(f"cannot write {path}: the folder {folder} does not exist")
    old = check_writable(path)
    remove_stale_temps(path)
    tmp = folder / f"{temp_prefix(path)}{os.getpid()}.{secrets.token_hex(4)}.tmp"
    fd = None
    try:
        # 0o666: the kernel applies the umask, as for any new file the user makes.
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
        if old is not None:
            # The permission bits only: setuid, setgid and sticky do not pass to new contents
            # (a write to a file clears setuid too); an export over a setuid file kept the bit.
            os.fchmod(fd, stat.S_IMODE(old.st_mode) & 0o777)
        with os.fdopen(fd, "wb") as fh:
            fd = None  # the file object owns it now
            _write_all(fh, data)
            fh.flush()
            os.fsync(fh.fileno())
            written = os.fstat(fh.fileno())
        os.replace(tmp, path)
    except BaseException as exc:
        if fd is not None:
            os.close(fd)
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError) and not isinstance(exc, ExportError):
            reason = exc.strerror or str(exc)
            if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
                reason = f"the folder {folder} does not allow new files ({reason})"
            raise ExportError(f"cannot write {path}: {reason}") from None
        raise
    try:  # make the rename itself durable
        dfd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except OSError:
        pass
    return written


def _write_all(fh, data: bytes) -> None:
    # Written in chunks so a test can fail the write part-way through (see tests).
    view = memoryview(data)
    step = 1 << 20
    for i in range(0, len(view), step):
        fh.write(view[i : i + step])
