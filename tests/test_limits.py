"""Deliberate limits: huge inputs give a working result in bounded memory or a clear error,
never a freeze or an out-of-memory kill."""

import json
import resource
import time

import numpy as np
import pytest

from sketchforge.document import Document
from sketchforge.document import fileformat as ff
from sketchforge.errors import LimitError
from sketchforge.plugins.testing import make_test_host


@pytest.fixture(scope="module")
def inflate_host():
    return make_test_host(entry_points=True, allowlist=["inflate"])


def test_contour_with_100k_points_inflates(inflate_host):
    t = np.linspace(0, 2 * np.pi, 100_000, endpoint=False)
    pts = np.c_[np.cos(t), 0.6 * np.sin(t)]
    doc = Document(host=inflate_host)
    doc.execute({"command": "add_layer", "id": "a"})
    t0 = time.perf_counter()
    doc.execute({"command": "set_contour", "layer": "a", "points": pts.tolist(), "closed": True})
    elapsed = time.perf_counter() - t0
    mesh = doc.layer("a").mesh
    # The stroke is resampled at the resolution, not kept point for point.
    assert 1_000 < mesh.n_vertices < 20_000
    assert elapsed < 60  # generous: a freeze would be minutes


def test_resolution_that_would_make_millions_of_triangles_is_refused(inflate_host):
    doc = Document(host=inflate_host)
    doc.execute({"command": "add_layer", "id": "a"})
    doc.execute({"command": "set_contour", "layer": "a", "points": [[-1, -1], [1, -1], [1, 1], [-1, 1]], "closed": True})
    before = doc.layer("a")
    t0 = time.perf_counter()
    with pytest.raises(LimitError, match="vertices") as info:
        doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"resolution": 1e-4}})
    assert time.perf_counter() - t0 < 5  # refused before any triangulation
    assert "maximum" in str(info.value) or "limit" in str(info.value)
    assert doc.layer("a") is before and doc.undo_stack.count() == 2


def test_journal_of_10k_commands_replays_in_bounded_memory(inflate_host, tmp_path):
    journal = [{"command": "add_layer", "id": "a"},
               {"command": "set_contour", "layer": "a", "points": [[0, 0], [1, 0], [1, 1], [0, 1]], "closed": True}]
    for i in range(10_000):
        if i % 2:
            journal.append({"command": "rename_layer", "layer": "a", "name": f"n{i}"})
        else:
            a = np.radians(i % 360)
            journal.append({"command": "set_light", "direction": [float(np.cos(a)), float(np.sin(a)), 0.0]})
    data = {"format": "sketchforge", "version": 1, "light": [1, 0, 0], "journal": journal}
    p = tmp_path / "long.json"
    p.write_text(json.dumps(data))
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    doc = ff.load(p, host=inflate_host)
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    assert doc.layer("a").name == "n9999"
    assert len(doc.journal()) == 10_002
    assert (rss1 - rss0) < 500_000  # KiB: well under 0.5 GiB extra
    # Saving and reopening the long document works too.
    ff.save(doc, tmp_path / "again.json")
    assert len(ff.load(tmp_path / "again.json", host=inflate_host).journal()) == 10_002


def test_journal_over_the_limit_is_refused(monkeypatch, fan_host):
    monkeypatch.setattr(ff, "MAX_JOURNAL_ENTRIES", 5)
    data = {"format": "sketchforge", "version": 1, "light": [1, 0, 0], "journal": [{"command": "add_layer"}] * 6}
    with pytest.raises(LimitError, match="limit is 5"):
        ff.document_from_dict(data, "big.json", host=fan_host)


def test_huge_coordinates_are_a_clear_error(inflate_host):
    from sketchforge.errors import ContourError

    doc = Document(host=inflate_host)
    doc.execute({"command": "add_layer", "id": "a"})
    with pytest.raises((ContourError, LimitError)):
        doc.execute({"command": "set_contour", "layer": "a", "points": [[0, 0], [1e200, 0], [0, 1e200]]})
    assert doc.layer("a").mesh is None
