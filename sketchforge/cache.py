"""One least-recently-used cache for the memos of the core and the plugins (issue 39).

Six hand-made LRU caches (an ``OrderedDict``, a lock, ``move_to_end`` and ``popitem``, each
with its own bound) kept derived data: the gradient operators of a planar mesh, the strips'
grid rasters, the isophote tool's planar data, layer data and picks, and the canvas's
fragments of each mesh. They differed only in their bugs: the canvas's was keyed weakly by
mesh and bounded per mesh, never in all, so an undo history of 200 moves kept 200 meshes'
fragments (19 MB a step on a 36k-vertex layer). :class:`LRUCache` is the one implementation,
bounded by entries, by bytes, or both. Plugins get it from :mod:`sketchforge.plugin_api`.

No numerics and no imports beyond the standard library and numpy: the geometry core uses it.
"""

from __future__ import annotations

import hashlib
import threading
import types
import weakref
from collections import OrderedDict
from collections.abc import Callable, Hashable, Mapping
from typing import Any, TypeVar

import numpy as np

T = TypeVar("T")

__all__ = ["LRUCache", "array_key", "held_arrays", "nbytes_of"]

_MISSING = object()


def array_key(*arrays) -> bytes:
    """A 16-byte digest of ``arrays`` (their dtypes, shapes and contents), for keying a cache on
    array values rather than on the arrays' identity. Two arrays with the same bytes but
    another shape or dtype get another key."""
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.digest()


def nbytes_of(value: Any) -> int:
    """Bytes of the numpy arrays in ``value`` (see :func:`held_arrays`), each counted once:
    what a byte-bounded cache weighs its entries with."""
    return sum(held_arrays(value).values())


#: How deep :func:`held_arrays` looks (a command -> its layer -> its mesh -> an array is 4).
MAX_DEPTH = 10


def held_arrays(value: Any, out: dict | None = None) -> dict:
    """{id of the array that owns the memory: its bytes} for every numpy array ``value``
    reaches: through tuples, lists, dicts (and read-only mappings), objects' attributes
    (dataclasses, commands, scipy sparse matrices) and :class:`LRUCache` s. A view counts as
    the array it views, so arrays shared by two values count once when their dicts are
    merged. Documents are not entered (an object with an ``undo_stack``), nor classes,
    functions or modules; long lists of plain numbers (JSON data) are passed over.

    The ids are only meaningful while ``value`` holds the arrays."""
    out = {} if out is None else out
    _walk(value, set(), 0, out)
    return out


_ATOMS = (str, bytes, int, float, bool, complex, type(None))


def _walk(value, seen: set, depth: int, out: dict) -> None:
    if isinstance(value, _ATOMS) or depth > MAX_DEPTH or id(value) in seen:
        return
    seen.add(id(value))
    if isinstance(value, np.ndarray):
        base = value
        while isinstance(base.base, np.ndarray):
            base = base.base
        if base.dtype != object:
            out[id(base)] = int(base.nbytes)
        return
    if isinstance(value, LRUCache):
        for v in value.values():
            _walk(v, seen, depth + 1, out)
        return
    if isinstance(value, (list, tuple)):
        if len(value) > 16 and isinstance(value[0], (int, float, list, tuple)) and not _holds_arrays(value[0]):
            return  # JSON numbers
        for v in value:
            _walk(v, seen, depth + 1, out)
        return
    if isinstance(value, Mapping):
        for v in value.values():
            _walk(v, seen, depth + 1, out)
        return
    if isinstance(value, (type, types.ModuleType, types.FunctionType, types.MethodType)) or hasattr(value, "undo_stack"):
        return
    fields = getattr(value, "__dict__", None)
    if isinstance(fields, dict):
        for v in fields.values():
            _walk(v, seen, depth + 1, out)


def _holds_arrays(v) -> bool:
    return isinstance(v, (list, tuple)) and bool(v) and isinstance(v[0], np.ndarray)


class LRUCache:
    """A thread-safe least-recently-used cache.

    Parameters
    ----------
    max_entries : int or None
        Most entries kept (None: no bound on the count).
    max_bytes : int or None
        Most bytes kept, weighed by ``size_of`` (None: no bound on the size). The newest entry
        is kept even when it alone weighs more: a cache that cannot hold one answer would
        recompute it on every call.
    weak_keys : bool
        Keys are objects held weakly and compared by identity (like a ``WeakKeyDictionary``
        of objects without ``__eq__``): an entry goes when its key is collected, so a cache of
        derived data never keeps a value alive (a mesh in the undo history).
    size_of : callable, optional
        ``size_of(value) -> int`` bytes; default :func:`nbytes_of`.
    name : str
        For ``repr`` and messages.

    Lookups and inserts hold one lock; :meth:`get_or_make` computes outside it, so a slow
    computation never blocks other threads (two threads may then compute the same value; the
    later one is kept, both return their own).
    """

    def __init__(self, max_entries: int | None = None, max_bytes: int | None = None, *, weak_keys: bool = False,
                 size_of: Callable[[Any], int] | None = None, name: str = "") -> None:
        if max_entries is not None and int(max_entries) < 1:
            raise ValueError(f"an LRU cache holds at least one entry, got max_entries={max_entries!r}")
        if max_bytes is not None and max_bytes < 0:
            raise ValueError(f"max_bytes must be 0 or more, got {max_bytes!r}")
        self.max_entries = None if max_entries is None else int(max_entries)
        self.max_bytes = max_bytes
        self.weak_keys = weak_keys
        self.size_of = size_of or nbytes_of
        self.name = name
        # Re-entrant: dropping a value inside the lock may collect another weak key of this
        # cache, whose callback takes the lock again on the same thread.
        self._lock = threading.RLock()
        # internal key -> (value, bytes, weak reference to the key or None); oldest first
        self._data: OrderedDict[Hashable, tuple] = OrderedDict()
        self._bytes = 0
        self.hits = 0
        self.misses = 0

    def __repr__(self) -> str:
        return (f"LRUCache({self.name or 'unnamed'}: {len(self)} entries, {self._bytes} bytes, "
                f"max_entries={self.max_entries}, max_bytes={self.max_bytes})")

    # --- keys -------------------------------------------------------------------------------
    def _internal(self, key) -> Hashable:
        return id(key) if self.weak_keys else key

    def _alive(self, key, entry) -> bool:
        return entry[2] is None or entry[2]() is key

    # --- reading ----------------------------------------------------------------------------
    def get(self, key, default=None):
        """The value for ``key`` (now the most recently used), or ``default``."""
        k = self._internal(key)
        with self._lock:
            entry = self._data.get(k)
            if entry is None or not self._alive(key, entry):
                self.misses += 1
                return default
            self._data.move_to_end(k)
            self.hits += 1
            return entry[0]

    def __contains__(self, key) -> bool:
        with self._lock:
            entry = self._data.get(self._internal(key))
            return entry is not None and self._alive(key, entry)

    def __len__(self) -> int:
        return len(self._data)

    @property
    def nbytes(self) -> int:
        """Bytes held, as weighed when each entry was put (0 without ``max_bytes``)."""
        return self._bytes

    def values(self) -> list:
        """The values, least recently used first."""
        with self._lock:
            return [entry[0] for entry in self._data.values()]

    # --- writing ----------------------------------------------------------------------------
    def put(self, key, value):
        """Store ``value`` as the most recently used (replacing, and re-weighing, an entry of
        the same key), then drop the least recently used entries beyond the bounds. Returns
        ``value``."""
        size = int(self.size_of(value)) if self.max_bytes is not None else 0
        k = self._internal(key)
        ref = None
        if self.weak_keys:
            ref = weakref.ref(key, self._forget_callback(k))
        with self._lock:
            old = self._data.pop(k, None)
            if old is not None:
                self._bytes -= old[1]
            self._data[k] = (value, size, ref)
            self._bytes += size
            self._evict()
        return value

    def _evict(self) -> None:
        while len(self._data) > 1 and (
            (self.max_entries is not None and len(self._data) > self.max_entries)
            or (self.max_bytes is not None and self._bytes > self.max_bytes)
        ):
            _, entry = self._data.popitem(last=False)
            self._bytes -= entry[1]

    def _forget_callback(self, k):
        me = weakref.ref(self)

        def forget(ref) -> None:  # the key was collected: its entry goes (unless replaced since)
            cache = me()
            if cache is None:
                return
            with cache._lock:
                entry = cache._data.get(k)
                if entry is not None and entry[2] is ref:
                    del cache._data[k]
                    cache._bytes -= entry[1]

        return forget

    def get_or_make(self, key, make: Callable[[], T]) -> T:
        """The value for ``key``, made by ``make()`` (and stored) on a miss."""
        value = self.get(key, _MISSING)
        if value is not _MISSING:
            return value
        return self.put(key, make())

    def pop(self, key, default=None):
        """Remove ``key``'s entry; its value, or ``default``."""
        with self._lock:
            entry = self._data.get(self._internal(key))
            if entry is None or not self._alive(key, entry):
                return default
            del self._data[self._internal(key)]
            self._bytes -= entry[1]
            return entry[0]

    def clear(self) -> None:
        with self._lock:
            self._data.clear()
            self._bytes = 0
