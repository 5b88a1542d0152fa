"""One cache helper instead of six (issue 39, point 3): sketchforge.cache.LRUCache, exported to
plugins by sketchforge.plugin_api, bounded by entries and/or bytes, optionally keyed weakly."""

from __future__ import annotations

import gc
import re
import threading
from pathlib import Path

import numpy as np
import pytest

from sketchforge.cache import LRUCache, array_key, held_arrays, nbytes_of

ROOT = Path(__file__).resolve().parents[1]


class Key:
    """A weakly referable key without __eq__ (like a Mesh)."""


def test_the_least_recently_used_entry_goes_first():
    c = LRUCache(2)
    c.put("a", 1)
    c.put("b", 2)
    assert c.get("a") == 1  # "a" is now the most recent
    c.put("c", 3)
    assert "b" not in c and c.get("a") == 1 and c.get("c") == 3 and len(c) == 2
    c.put("a", 10)  # replacing refreshes too
    c.put("d", 4)
    assert c.values() == [10, 4] and c.get("c") is None and c.get("c", "none") == "none"
    assert (c.hits, c.misses) == (3, 2)
    assert c.pop("a") == 10 and c.pop("a", "gone") == "gone" and len(c) == 1
    c.clear()
    assert len(c) == 0 and c.nbytes == 0
    with pytest.raises(ValueError):
        LRUCache(0)
    with pytest.raises(ValueError):
        LRUCache(max_bytes=-1)


def test_a_byte_bound_keeps_the_newest_entries_that_fit_and_always_the_newest():
    c = LRUCache(max_bytes=2500)
    for k in range(5):
        c.put(k, np.zeros(100))  # 800 bytes each
        assert c.nbytes == 800 * len(c) <= 2500
    assert [int(k) for k in range(5) if k in c] == [2, 3, 4]
    c.put("big", np.zeros(1000))  # 8000 bytes: over the bound alone, kept alone
    assert len(c) == 1 and c.nbytes == 8000 and "big" in c
    c.put("small", np.zeros(10))
    assert "big" not in c and c.nbytes == 80
    # a re-put weighs the entry again (a value that grew)
    entry = {"x": np.zeros(10)}
    c.put("e", entry)
    entry["y"] = np.zeros(200)
    c.put("e", entry)
    assert c.nbytes == 80 + 80 + 1600
    # entries and bytes together
    both = LRUCache(3, max_bytes=10**6)
    for k in range(5):
        both.put(k, np.zeros(1))
    assert len(both) == 3


def test_get_or_make_makes_once_per_miss():
    c = LRUCache(4)
    made = []

    def make(k):
        made.append(k)
        return k * 2

    assert [c.get_or_make(k % 3, lambda k=k: make(k % 3)) for k in range(9)] == [0, 2, 4] * 3
    assert made == [0, 1, 2]
    # None is a value like any other
    assert c.get_or_make("n", lambda: None) is None and "n" in c
    assert c.get_or_make("n", lambda: 1 / 0) is None


def test_weak_keys_go_with_their_object_and_never_answer_for_another():
    c = LRUCache(10, weak_keys=True)
    a, b = Key(), Key()
    c.put(a, "for a")
    c.put(b, "for b")
    assert c.get(a) == "for a" and c.get(b) == "for b" and len(c) == 2
    del a
    gc.collect()
    assert len(c) == 1 and c.values() == ["for b"]
    # many short-lived keys: ids are reused, answers never are
    for i in range(200):
        k = Key()
        assert c.get(k) is None, i
        c.put(k, i)
        assert c.get(k) == i
    del k
    gc.collect()
    assert len(c) == 1  # only b is alive
    with pytest.raises(TypeError):
        c.put(1, "an int cannot be held weakly")
    # the value does not keep the key alive, and a value holding another key is fine
    c2 = LRUCache(1, weak_keys=True)
    k1, k2 = Key(), Key()
    c2.put(k1, [k2])
    del k2
    c2.put(k1, "replaced")  # drops the list, which held the last reference to k2: no deadlock
    assert c2.get(k1) == "replaced"


def test_it_is_thread_safe():
    c = LRUCache(8, max_bytes=64 * 8 * 6)
    errors = []

    def work(seed):
        rng = np.random.default_rng(seed)
        try:
            for _ in range(500):
                k = int(rng.integers(0, 20))
                v = c.get_or_make(k, lambda k=k: np.full(64, float(k)))
                assert v[0] == k
                if rng.random() < 0.1:
                    c.pop(k)
        except Exception as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(s,)) for s in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert len(c) <= 6 and c.nbytes == 512 * len(c) == sum(v.nbytes for v in c.values())


def test_array_key_depends_on_values_shape_and_dtype():
    a = np.arange(6, dtype=np.float64)
    assert array_key(a) == array_key(a.copy()) == array_key(np.arange(6.0))
    assert array_key(a) != array_key(a.reshape(2, 3)) != array_key(a.reshape(3, 2))
    assert array_key(a) != array_key(a.view(np.int64))
    assert array_key(a[:3], a[3:]) != array_key(a[:2], a[2:])  # where one ends and the next begins
    strided = np.arange(12.0)[::2]
    assert array_key(strided) == array_key(np.ascontiguousarray(strided))
    assert len(array_key(a)) == 16


def test_nbytes_counts_each_memory_once():
    a = np.zeros(1000)
    assert nbytes_of([a, a[:10], {"k": (a, a.T)}]) == 8000
    assert nbytes_of({"x": np.zeros(3), "y": [np.zeros(2, np.int32)]}) == 24 + 8
    import scipy.sparse as sp

    m = sp.csr_matrix(np.eye(50))
    assert nbytes_of(m) == m.data.nbytes + m.indices.nbytes + m.indptr.nbytes
    assert nbytes_of([0.5] * 1000) == 0 and nbytes_of("text") == 0
    held = held_arrays([a[:5]])
    assert list(held.values()) == [8000]


def test_the_six_caches_are_lru_caches_and_no_hand_made_one_is_left():
    from sketchforge.geometry import gbuffer, heightfield
    from sketchforge_isophote_tool import layerdata, pipeline
    from sketchforge_strips import solver

    for cache in (gbuffer._mesh_cache, heightfield._OPERATORS, layerdata._PLANAR, layerdata._CACHE, pipeline._PICKS,
                  solver._RASTERS):
        assert isinstance(cache, LRUCache), cache
    assert gbuffer._mesh_cache.weak_keys and gbuffer._mesh_cache.max_bytes == gbuffer.MESH_CACHE_BYTES
    # (plugins/assemble keeps its own: issue 34 rewrites that plugin)
    found = []
    for path in [*ROOT.glob("sketchforge/**/*.py"), *ROOT.glob("plugins/*/sketchforge_*/**/*.py")]:
        rel = path.relative_to(ROOT).as_posix()
        if rel == "sketchforge/cache.py" or rel.startswith("plugins/assemble/"):
            continue
        if re.search(r"move_to_end|popitem\(last=False\)|del \w+\[next\(iter\(", path.read_text()):
            found.append(rel)
    assert found == []


def test_plugins_get_it_from_the_plugin_api():
    import sketchforge.plugin_api as api

    assert api.LRUCache is LRUCache and api.array_key is array_key
    assert "LRUCache" in api.__all__ and "array_key" in api.__all__


def test_the_canvas_cache_forgets_meshes_nobody_holds_and_stays_within_its_bytes(monkeypatch):
    from sketchforge.geometry import gbuffer as gb
    from sketchforge.geometry.mesh import Mesh

    def disc(shift, n=40):
        t = np.linspace(0, 2 * np.pi, n, endpoint=False)
        V = np.r_[np.c_[np.cos(t) + shift, np.sin(t), np.zeros(n)], [[shift, 0.0, 0.5]]]
        F = np.array([[i, (i + 1) % n, n] for i in range(n)])
        return Mesh(V, F, np.arange(n))

    cache = LRUCache(max_bytes=gb.MESH_CACHE_BYTES, weak_keys=True)
    monkeypatch.setattr(gb, "_mesh_cache", cache)
    view = gb.View.framing([disc(0.0)], 120, 100)
    m = disc(0.0)
    first = gb.rasterise([m], view)
    assert len(cache) == 1 and cache.nbytes > 0
    again = gb.rasterise([m], view)
    assert again.normal.tobytes() == first.normal.tobytes()
    frag = gb._layer_fragments(m, view, True)
    assert gb._layer_fragments(m, view, True) is frag  # a hit: the very same arrays
    del m
    gc.collect()
    assert len(cache) == 0  # the mesh went: its fragments went with it
    # meshes kept alive (an undo history) do not keep their fragments past the bound
    kept = [disc(0.01 * i) for i in range(12)]
    for mesh in kept:
        gb.rasterise([mesh], view)
    one = cache.nbytes / len(cache)
    cache.max_bytes = int(3.5 * one)
    gb.rasterise([kept[-1]], gb.View.framing([kept[-1]], 121, 100))  # a new view: weighed again
    assert len(cache) <= 4 and cache.nbytes <= cache.max_bytes + one
    assert kept[-1] in cache and kept[0] not in cache


def test_what_the_byte_count_looks_into_and_what_it_leaves_alone():
    a, b = np.zeros(10), np.zeros(20)

    def nested(v, k):
        for _ in range(k):
            v = [v]
        return v

    from sketchforge.cache import MAX_DEPTH

    assert nbytes_of(nested(a, MAX_DEPTH)) == 80  # within reach
    assert nbytes_of(nested(a, MAX_DEPTH + 2)) == 0  # beyond it: not looked at
    # a long list of records holding arrays is walked; a long list of plain numbers is not
    assert nbytes_of([(np.zeros(1),) for _ in range(20)]) == 20 * 8
    assert nbytes_of([[1.0, 2.0]] * 40 + [a]) == 0

    class Doc:  # a document is never entered (commands may hold one)
        def __init__(self):
            self.undo_stack = None
            self.big = np.zeros(1000)

    class Holder:
        def __init__(self):
            self.arr = b

    assert nbytes_of([Doc(), Holder()]) == 160
    loop = [a]
    loop.append(loop)  # a cycle ends
    assert nbytes_of(loop) == 80
    # without a byte bound, nothing is weighed
    c = LRUCache(2)
    c.put(1, np.zeros(10))
    assert c.nbytes == 0
