"""Raster cost is capped before rendering (once: 2000 overlapping snapshot triangles took
9.5 GB, ``--size 8192`` ran past 60 s), and render's own arguments are checked first."""

from __future__ import annotations

import base64

import numpy as np
import pytest
from attack_helpers import MAX_RSS_GROWTH, assert_one_line_error, peak_rss_bytes, run_cli, write_doc


def _overlapping_triangles_doc(n=2000):
    """A 70 KB-class document whose one layer is n copies of the same large triangle."""
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] * n)
    F = np.arange(3 * n, dtype=np.int64).reshape(n, 3)

    def arr(a, dt):
        a = np.ascontiguousarray(a, dtype="<f8" if dt == "float64" else "<i8")
        return {"dtype": dt, "shape": list(a.shape), "data": base64.b64encode(a.tobytes()).decode()}

    mesh = {"V": arr(V, "float64"), "F": arr(F, "int64"), "boundary": arr(np.zeros(0), "int64"), "junction": arr(np.zeros(0), "int64")}
    layer = {"id": "a", "name": "A", "visible": True, "closed": True, "points": None, "params": {}, "edits": [], "mesh": mesh}
    return {"format": "sketchforge", "version": 1, "light": [1.0, 0.0, 0.0], "journal": [],
            "snapshot": {"light": [1.0, 0.0, 0.0], "layers": [layer]}}


def test_overdraw_is_refused_before_rendering(tmp_path):
    path = write_doc(tmp_path / "doc.json", _overlapping_triangles_doc())
    before = peak_rss_bytes()
    res = run_cli("render", path, "--png", tmp_path / "out.png")
    assert_one_line_error(res, "would test", "use a smaller size")
    assert res.seconds < 30.0  # a hang; the memory bound shows the refusal came first
    assert peak_rss_bytes() - before < MAX_RSS_GROWTH
    assert not (tmp_path / "out.png").exists()
    # A few copies are a fine image.
    path = write_doc(tmp_path / "few.json", _overlapping_triangles_doc(3))
    assert run_cli("render", path, "--png", tmp_path / "few.png").rc == 0
    assert (tmp_path / "few.png").read_bytes()[:4] == b"\x89PNG"


def test_huge_size_is_refused_quickly(tmp_path, saved_doc):
    path = write_doc(tmp_path / "doc.json", saved_doc)
    res = run_cli("render", path, "--png", tmp_path / "out.png", "--size", "8192")
    assert_one_line_error(res, "rendering limit")
    assert res.seconds < 30.0  # a hang; the memory bound shows the refusal came first
    assert_one_line_error(run_cli("render", path, "--png", tmp_path / "out.png", "--size", "9000"), "--size must be between 16 and 8192")


@pytest.mark.parametrize("k", ["-5", "1000000"])
def test_isophote_count_out_of_range(tmp_path, saved_doc, k):
    path = write_doc(tmp_path / "doc.json", saved_doc)
    assert_one_line_error(run_cli("render", path, "--png", tmp_path / "out.png", "--isophotes", k), "--isophotes must be between 0 and 255")


def test_render_top_cost_accounts_for_overlap():
    """The cap counts overdraw: the same triangles once fit, 2000 times over they do not."""
    from sketchforge.errors import LimitError
    from sketchforge.geometry.mesh import Mesh
    from sketchforge.geometry.raster import render_top

    one = Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float), np.array([[0, 1, 2]]))
    img = render_top([one], [1.0, 0.0, 0.0], size=256, max_cost=2 * 256 * 256 + 60_000)
    assert (img != img[0, 0]).any(axis=2).sum() > 20_000  # the triangle covers about half
    with pytest.raises(LimitError):
        render_top([one] * 20, [1.0, 0.0, 0.0], size=256, max_cost=2 * 256 * 256 + 60_000 * 10)
