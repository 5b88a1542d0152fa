"""The assembly's memo (sketchforge_assemble.cache): least recently used entries go first, by
count and by bytes; hits and misses are counted per call; a failed computation stores nothing.
The app's repeated assemblies (a drag, an undo) rest on it; the speed tests measure what it
saves, these pin down what it keeps."""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge_assemble.cache import AssemblyCache, memo


def _fill(cache, keys, kind="sheet"):
    made = []
    for k in keys:
        cache.get(kind, k, lambda k=k: made.append(k) or np.full(4, len(made), np.float64))
    return made


def test_the_least_recently_used_entries_go_first():
    cache = AssemblyCache(max_entries=3)
    assert _fill(cache, [b"a", b"b", b"c"]) == [b"a", b"b", b"c"]
    assert len(cache) == 3 and (cache.hits, cache.misses) == (0, 3)
    _fill(cache, [b"a"])  # a hit: "a" is now the most recent
    assert (cache.hits, cache.misses) == (1, 3)
    assert _fill(cache, [b"d"]) == [b"d"]  # "b", the least recently used, goes
    assert len(cache) == 3
    assert _fill(cache, [b"a", b"c", b"d"]) == []  # kept
    assert _fill(cache, [b"b"]) == [b"b"]  # recomputed
    assert (cache.hits, cache.misses) == (4, 5)
    assert cache.counts["sheet", "hit"] == 4 and cache.counts["sheet", "miss"] == 5


def test_entries_go_when_their_bytes_pass_the_budget_but_the_newest_stays():
    cache = AssemblyCache(max_bytes=3 * 800 + 100)
    for k in range(5):
        cache.get("rows", bytes([k]), lambda: np.zeros(100))  # 800 bytes of data each
    assert len(cache) == 3 and cache.bytes <= 3 * 800 + 100
    big = cache.get("rows", b"big", lambda: np.zeros(10_000))  # larger than the whole budget
    assert len(cache) == 1 and big.shape == (10_000,)  # kept alone: the caller gets it next time
    assert cache.get("rows", b"big", lambda: pytest.fail("recomputed")) is big


def test_a_failed_computation_stores_nothing_and_counts_nothing():
    cache = AssemblyCache()

    def boom():
        raise RuntimeError("no")

    with pytest.raises(RuntimeError):
        cache.get("pair", b"k", boom)
    assert len(cache) == 0 and (cache.hits, cache.misses) == (0, 0) and cache.bytes == 0
    assert cache.get("pair", b"k", lambda: 7) == 7 and cache.misses == 1


def test_clearing_forgets_entries_and_counts_and_memo_without_a_cache_computes():
    cache = AssemblyCache(max_entries=4)
    _fill(cache, [b"a", b"b", b"a"])
    cache.clear()
    assert len(cache) == 0 and cache.bytes == 0 and (cache.hits, cache.misses) == (0, 0) and not cache.counts
    calls = []
    assert memo(None, "sheet", (1, 2), lambda: calls.append(1) or "v") == "v"
    assert memo(None, "sheet", (1, 2), lambda: calls.append(1) or "v") == "v" and len(calls) == 2
    assert memo(cache, "sheet", (1, 2), lambda: calls.append(1) or "v") == "v"
    assert memo(cache, "sheet", (1, 2), lambda: calls.append(1) or "w") == "v" and len(calls) == 3
    assert memo(cache, "sheet", (1, 3), lambda: "other") == "other"  # another key


def test_a_slotted_dataclass_counts_the_arrays_it_holds():
    # a frozen dataclass with __slots__ has no __dict__: its arrays are found through its fields
    from dataclasses import dataclass

    from sketchforge_assemble.cache import nbytes

    @dataclass(frozen=True, slots=True)
    class Held:
        a: np.ndarray
        b: tuple

    v = Held(np.zeros(1000), (np.zeros(10, np.int32), None))
    assert nbytes(v) == 64 + 8000 + 40 + 64
