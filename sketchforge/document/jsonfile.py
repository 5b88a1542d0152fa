"""Reading a document file's JSON within bounds: a regular file of at most MAX_FILE_BYTES,
read without ever holding more, then its items counted, its text's memory bounded and its
nesting checked before and after the parse, each refusal one line naming the file. Used for
documents, autosaves and batch inputs (:mod:`sketchforge.document.fileformat` re-exports
every name)."""

from __future__ import annotations

import hashlib
import json
import os
import re
import stat
from pathlib import Path
from typing import Any

import numpy as np

from sketchforge.errors import DocumentFormatError, LimitError, SketchforgeError

#: Files larger than this are refused before parsing.
MAX_FILE_BYTES = 512 * 1024 * 1024
#: Nesting of JSON arrays and objects: a real document needs about 40 (macros of macros).
MAX_JSON_DEPTH = 100
#: JSON items (values and object keys) one file may hold. The byte cap alone does not bound
#: memory: each item costs the parser 40-80 bytes however short its text, so 60 MB of
#: ``[],`` grew past 3 GB (issue 38). With this many, the worst kind of item and a file at the
#: byte cap, opening stays under 2 GB; a real document needs far fewer (examples/creature.json,
#: whose meshes are base64 strings: 1 600; 100 strokes of 20 000 points: 6 million).
MAX_JSON_ITEMS = 8_000_000
#: Item boundaries outside strings: every value or key but the top-level one follows one of
#: these, so their count (plus one) bounds the items a parse builds.
_ITEM_MARKS = (b",", b":", b"[", b"{")
#: A string (skipped whole, escapes included; an unterminated one runs to the end), or a run
#: of item marks.
_SCAN = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*(?:"|\Z)|[,:\[{]+', re.DOTALL)
#: Digits of a JSON integer: no field of a document needs more (coordinates above 1e308
#: cannot even be a float).
MAX_INT_DIGITS = 308


def _parse_int(text: str) -> int:
    digits = len(text.lstrip("-"))
    if digits > MAX_INT_DIGITS:
        raise DocumentFormatError(f"an integer of {digits} digits is too large (at most {MAX_INT_DIGITS} digits)")
    return int(text)


def _parse_constant(name: str):
    raise DocumentFormatError(f"{name} is not a number a document may contain (numbers must be finite)")


def _check_depth(data: Any, limit: int = MAX_JSON_DEPTH) -> None:
    # Iterative, one level at a time: a recursive walk would hit the very recursion limit this
    # check is for, and a stack of (value, depth) pairs cost 70 bytes per container.
    level, depth = [data], 1
    while level:
        nested: list = []
        for v in level:
            if isinstance(v, dict):
                nested.extend(x for x in v.values() if isinstance(x, (dict, list)))
            elif isinstance(v, list):
                nested.extend(x for x in v if isinstance(x, (dict, list)))
        if nested and depth >= limit:
            raise LimitError(f"JSON nested more than {limit} levels deep")
        level, depth = nested, depth + 1


#: Python stores a whole string 1, 2 or 4 bytes a character, by its widest one: a UTF-8 lead
#: byte C4-EF or a ``\\uXXXX`` escape above 00FF makes 2, F0 and up or an escaped surrogate
#: makes 4. One emoji in 500 MB of ASCII made the text 2 GB, and the string parsed from it
#: 2 GB more (issue 38). (An escaped backslash before "u" is counted too: an overestimate.)
_ESCAPE_4 = re.compile(rb"\\u[dD][89abAB]")
_ESCAPE_2 = re.compile(rb"\\u(?:0[1-9a-fA-F]|[1-9a-fA-F][0-9a-fA-F])")
_BLOCK = 1 << 24


def text_memory(raw: bytes) -> int:
    """An upper bound of the bytes Python needs for the text of ``raw`` (UTF-8), and so for
    all the strings parsed from it: its characters times the widest one's storage size (1, 2
    or 4 bytes). Scans in 16 MB blocks with numpy and two regexes with a literal prefix: about
    a second for 512 MB."""
    width = 1
    view = np.frombuffer(raw, dtype=np.uint8)
    if not raw.isascii():
        top = max(int(view[i : i + _BLOCK].max()) for i in range(0, len(view), _BLOCK))
        width = 4 if top >= 0xF0 else 2 if top >= 0xC4 else 1
    if width < 4 and _ESCAPE_4.search(raw):
        width = 4
    elif width < 2 and _ESCAPE_2.search(raw):
        width = 2
    if width == 1:
        return len(raw)
    follow = sum(int(np.count_nonzero((view[i : i + _BLOCK] & 0xC0) == 0x80)) for i in range(0, len(view), _BLOCK))
    return width * (len(raw) - follow)


def count_json_items(raw: bytes, limit: int | None = None) -> int:
    """How many items (values and object keys) parsing ``raw`` can build: one plus the commas,
    colons, ``[`` and ``{`` outside strings; counting stops once it passes ``limit``.

    First a bound from ``bytes.count`` (a fraction of a second for 512 MB); only when that
    passes ``limit`` (a bomb, or marks inside strings) are strings skipped, item by item, until
    the count passes ``limit``, so the scan costs at most about ``limit`` steps. Two strings
    with no mark between them cannot be JSON: the scan stops there, since the parser fails at
    or before that point, having built no more than what was counted. Never builds an item.

    Parameters
    ----------
    raw : bytes
        The file's UTF-8 text (multi-byte characters never contain an ASCII byte).
    limit : int or None
        Default :data:`MAX_JSON_ITEMS`.

    Returns
    -------
    int
        The count, exact up to ``limit + 1`` when the quick bound passed ``limit``.
    """
    limit = MAX_JSON_ITEMS if limit is None else limit
    bound = 1 + sum(raw.count(m) for m in _ITEM_MARKS)
    return bound if bound <= limit else scan_items(raw, limit)


def scan_items(raw: bytes, limit: int) -> int:
    """:func:`count_json_items`' exact count, strings skipped; it stops once past ``limit``."""
    count, strings = 1, 0
    for m in _SCAN.finditer(raw):
        if raw[m.start()] == 0x22:  # '"'
            strings += 1
            if strings > count:
                break  # not JSON from here on (see above)
        else:
            count += m.end() - m.start()
            if count > limit:
                break
    return count


def read_regular_file(path, limit: int | None = None, info: dict | None = None) -> bytearray:
    """The bytes of ``path`` (a bytearray), a regular file of at most ``limit`` bytes. A FIFO, a
    device (``/dev/zero``), a socket or a directory is refused before reading (opening a FIFO does not
    block: O_NONBLOCK), and at most ``limit + 1`` bytes are ever read, so a file that grows
    while being read cannot exhaust memory. With ``info`` (a dict), ``info["stat"]`` is the
    file's ``fstat`` as it was opened. Raises DocumentFormatError or LimitError."""
    path = Path(path)
    limit = MAX_FILE_BYTES if limit is None else limit
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise DocumentFormatError(f"cannot open {path}: no such file") from None
    except PermissionError:
        raise DocumentFormatError(f"cannot open {path}: permission denied") from None
    except IsADirectoryError:
        raise DocumentFormatError(f"cannot open {path}: it is a directory") from None
    except OSError as exc:
        raise DocumentFormatError(f"cannot open {path}: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        if info is not None:
            info["stat"] = st
        if stat.S_ISDIR(st.st_mode):
            raise DocumentFormatError(f"cannot open {path}: it is a directory")
        if not stat.S_ISREG(st.st_mode):
            raise DocumentFormatError(f"cannot open {path}: not a regular file (a pipe, device or socket)")
        if st.st_size > limit:
            raise LimitError(f"cannot open {path}: {st.st_size} bytes is over the limit of {limit}")
        # One buffer of the announced size (and a byte more, to notice growth), filled in
        # place: a list of chunks joined at the end held the file twice.
        buf, total = bytearray(min(st.st_size, limit) + 1), 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 22, limit + 1 - total))
            if not chunk:
                break
            if total + len(chunk) > len(buf):  # the file grew while being read
                buf.extend(bytes(total + len(chunk) - len(buf)))  # still at most limit + 1
            buf[total : total + len(chunk)] = chunk
            total += len(chunk)
        if total > limit:
            raise LimitError(f"cannot open {path}: more than {limit} bytes, the limit")
        del buf[total:]
        return buf
    except OSError as exc:
        raise DocumentFormatError(f"cannot open {path}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


def read_json(path, info: dict | None = None) -> Any:
    """The JSON value of the document file ``path``, through every bound (size, items, text
    memory, nesting). With ``info`` (a dict): ``info["stat"]``, the file's fstat, and
    ``info["sha256"]``, the digest of the very bytes parsed (the app tells later whether the
    file changed on disk since, :func:`changed_on_disk`)."""
    path = Path(path)
    raw = read_regular_file(path, info=info)
    if info is not None:
        info["sha256"] = hashlib.sha256(raw).hexdigest()
    box = [raw]
    del raw  # _parse holds the only reference, and drops it before the parse
    return _parse(box, path)


def parse_json(raw: bytes, path) -> Any:
    """A document file's bytes as JSON, with the checks and one-line errors of :func:`read_json`
    (``path`` names the file in them): for bytes read elsewhere (a batch worker on another
    machine gets the document's bytes, not its path)."""
    return _parse([raw], path)


def _parse(box: list, path) -> Any:
    """The JSON of the bytes ``box[0]`` (taken out of the list, so that they can be freed
    before the parse builds its objects), through every bound."""
    raw = box.pop()
    if len(raw) > MAX_FILE_BYTES:
        raise LimitError(f"cannot open {path}: {len(raw)} bytes is over the limit of {MAX_FILE_BYTES}")
    items = count_json_items(raw)
    if items > MAX_JSON_ITEMS:
        raise LimitError(
            f"cannot open {path}: it holds more than {MAX_JSON_ITEMS:,} JSON items (values and keys); the limit is "
            f"{MAX_JSON_ITEMS:,}"
        )
    need = text_memory(raw)
    if need > MAX_FILE_BYTES:
        raise LimitError(
            f"cannot open {path}: its text would take {need / 2**20:,.1f} MiB in memory (characters outside Latin-1, "
            f"even as \\u escapes, take 2 or 4 bytes each); the limit is {MAX_FILE_BYTES / 2**20:g} MiB"
        )
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DocumentFormatError(f"cannot open {path}: not UTF-8 text (byte {exc.start})") from None
    del raw  # the parse needs the text only: never both copies and the parsed items at once
    try:
        data = json.loads(text, parse_int=_parse_int, parse_constant=_parse_constant)
    except json.JSONDecodeError as exc:
        raise DocumentFormatError(f"cannot open {path}: invalid JSON at line {exc.lineno}, column {exc.colno} ({exc.msg})") from None
    except RecursionError:
        raise DocumentFormatError(f"cannot open {path}: JSON nested too deeply") from None
    except SketchforgeError as exc:
        raise DocumentFormatError(f"cannot open {path}: {exc}") from None
    try:
        _check_depth(data)
    except LimitError as exc:
        raise LimitError(f"cannot open {path}: {exc}") from None
    return data
