"""Memo of the assembly's per-layer and per-pair work, keyed by digests of its inputs.

Why. Changing one layer (a sculpt stroke, a redrawn limb) used to rebuild every layer's sheet,
junction cut, Laplacian, locator and every overlapping pair's depth rows. Each of those is a
pure function of a few arrays, so the cache keeps its result under a digest of exactly those
arrays (dtype, shape and bytes) and hands back the same object next time: a re-assembly
computes only what the changed layer touches, and its result is bit-identical to a
re-assembly from scratch (same inputs, same deterministic code, the same outputs; the tests
compare the arrays). Nothing is keyed by layer id or position, so reordering, renaming or
undoing also hits.

Cached values are shared between assemblies and must never be modified in place; everything
that reads them in this package only reads.
"""

from __future__ import annotations

import hashlib
import threading
from collections import Counter, OrderedDict
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

T = TypeVar("T")


def digest(*parts) -> bytes:
    """A 16-byte digest of arrays, scalars, strings, None and (nested) tuples/lists of them;
    arrays count by dtype, shape and bytes, so equal digests mean bit-identical inputs."""
    h = hashlib.blake2b(digest_size=16)

    def feed(p):
        if isinstance(p, np.ndarray):
            a = np.ascontiguousarray(p)
            h.update(f"a{a.dtype.str}{a.shape}".encode())
            h.update(a.view(np.uint8).reshape(-1).data if a.size else b"")
        elif isinstance(p, (tuple, list)):
            h.update(f"t{len(p)}(".encode())
            for q in p:
                feed(q)
            h.update(b")")
        elif isinstance(p, bytes):
            h.update(b"b" + len(p).to_bytes(8, "little") + p)
        elif p is None or isinstance(p, (bool, int, float, str, np.integer, np.floating)):
            h.update(f"s{type(p).__name__}:{p!r};".encode())
        else:
            raise TypeError(f"cannot digest {type(p).__name__}")

    for p in parts:
        feed(p)
    return h.digest()


def nbytes(value, _depth: int = 0) -> int:
    """Approximate memory held by a cached value: the bytes of the numpy arrays (sparse
    matrices' too) reachable through tuples, lists, dicts and object attributes, a few levels
    deep; other objects count 64 bytes."""
    if _depth > 4:
        return 0
    if isinstance(value, np.ndarray):
        return int(value.nbytes)
    if isinstance(value, (tuple, list)):
        return sum(nbytes(v, _depth + 1) for v in value)
    if isinstance(value, dict):
        return sum(nbytes(v, _depth + 1) for v in value.values())
    attrs = getattr(value, "__dict__", None)
    if attrs is None and hasattr(value, "__dataclass_fields__"):
        attrs = {k: getattr(value, k) for k in value.__dataclass_fields__}
    if attrs:
        return 64 + sum(nbytes(v, _depth + 1) for v in attrs.values())
    return 64


class AssemblyCache:
    """Least-recently-used memo of assembly results (see the module docstring).

    Parameters
    ----------
    max_entries : int
        Entries kept (a sheet, a Laplacian, a pair's rows... each count one). The creature
        uses 50 entries (~4.6 MB) per version of its layers.
    max_bytes : int
        Memory the entries may hold (:func:`nbytes`); the least recently used go first. The
        default keeps a few versions of every layer of a 100k-vertex document.
    """

    def __init__(self, max_entries: int = 512, max_bytes: int = 256 << 20):
        self.max_entries = int(max_entries)
        self.max_bytes = int(max_bytes)
        self.bytes = 0
        self._size: dict[tuple, int] = {}
        self._memo: OrderedDict[tuple, Any] = OrderedDict()
        self._lock = threading.Lock()  # the app assembles on a worker thread
        self.hits = 0
        self.misses = 0
        self.counts: Counter = Counter()  # (kind, "hit" | "miss") -> calls

    def __len__(self) -> int:
        return len(self._memo)

    def get(self, kind: str, key: bytes, make: Callable[[], T]) -> T:
        """The value stored under (kind, key), or ``make()`` stored there (an exception in
        ``make`` stores nothing)."""
        k = (kind, key)
        with self._lock:
            if k in self._memo:
                self._memo.move_to_end(k)
                self.hits += 1
                self.counts[kind, "hit"] += 1
                return self._memo[k]
        value = make()  # outside the lock: two threads may both compute it, both get equal values
        size = nbytes(value)
        with self._lock:
            self.misses += 1
            self.counts[kind, "miss"] += 1
            if k not in self._memo:
                self._memo[k] = value
                self._size[k] = size
                self.bytes += size
            while len(self._memo) > 1 and (len(self._memo) > self.max_entries or self.bytes > self.max_bytes):
                old, _ = self._memo.popitem(last=False)
                self.bytes -= self._size.pop(old)
        return value

    def clear(self) -> None:
        with self._lock:
            self._memo.clear()
            self._size.clear()
            self.bytes = 0
            self.hits = self.misses = 0
            self.counts.clear()


def memo(cache: AssemblyCache | None, kind: str, key_parts: tuple, make: Callable[[], T]) -> T:
    """``make()`` through ``cache`` (keyed by the digest of ``key_parts``), or directly without one."""
    if cache is None:
        return make()
    return cache.get(kind, digest(*key_parts), make)
