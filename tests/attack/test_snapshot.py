"""Snapshots are checked as strictly as the journal: dtypes, shapes, index ranges, degenerate
faces and edit schemas are refused at load (once accepted, then a numpy error, an
OSQPException or a ZeroDivisionError later, or silently reinterpreted faces)."""

from __future__ import annotations

import base64

import numpy as np
import pytest
from attack_helpers import assert_one_line_error, run_cli, write_doc

from sketchforge.plugins import default_host


def _mesh(doc):
    return doc["snapshot"]["layers"][0]["mesh"]


def _arr(a, dtype):
    a = np.ascontiguousarray(a, dtype="<f8" if dtype == "float64" else "<i8")
    return {"dtype": dtype, "shape": list(a.shape), "data": base64.b64encode(a.tobytes()).decode()}


def _set_shape(shape):
    def f(doc):
        nbytes = 8 * int(np.prod(shape) if max(shape) < 10**6 else 0)
        _mesh(doc)["V"] = {"dtype": "float64", "shape": shape, "data": base64.b64encode(b"\0" * nbytes).decode()}
    return f


def _faces_as_float(doc):
    F = np.frombuffer(base64.b64decode(_mesh(doc)["F"]["data"]), "<i8").reshape(-1, 3)
    _mesh(doc)["F"] = _arr(F.astype(float), "float64")


def _degenerate(doc):
    F = np.frombuffer(base64.b64decode(_mesh(doc)["F"]["data"]), "<i8").reshape(-1, 3).copy()
    F[5] = [F[5, 0], F[5, 0], F[5, 1]]  # a triangle with a repeated corner: zero area
    _mesh(doc)["F"] = _arr(F, "int64")


def _collinear(doc):
    V = np.frombuffer(base64.b64decode(_mesh(doc)["V"]["data"]), "<f8").reshape(-1, 3).copy()
    F = np.frombuffer(base64.b64decode(_mesh(doc)["F"]["data"]), "<i8").reshape(-1, 3)
    a, b, c = F[3]
    V[c, :2] = 0.5 * (V[a, :2] + V[b, :2])  # flat in the drawing plane: infinite cotangents
    _mesh(doc)["V"] = _arr(V, "float64")


def _index_out_of_range(doc):
    F = np.frombuffer(base64.b64decode(_mesh(doc)["F"]["data"]), "<i8").reshape(-1, 3).copy()
    F[0, 0] = 10**9
    _mesh(doc)["F"] = _arr(F, "int64")


def _boundary_repeat(doc):
    B = np.frombuffer(base64.b64decode(_mesh(doc)["boundary"]["data"]), "<i8").copy()
    B[1] = B[0]
    _mesh(doc)["boundary"] = _arr(B, "int64")


CASES = {
    "shape [0, 1e20]": (_set_shape([0, 10**20]), "bad shape"),
    "100 dimensions": (_set_shape([1] * 100), "bad shape"),
    "V of shape (k, 2)": (lambda d: _mesh(d).__setitem__("V", _arr(np.zeros((3, 2)), "float64")), "shape must be [k, 3]"),
    "faces stored as float64": (_faces_as_float, "dtype must be int64, got float64"),
    "degenerate triangle": (_degenerate, "triangle of zero area"),
    "triangle flat in the plane": (_collinear, "triangle of zero area"),
    "index out of range": (_index_out_of_range, "outside 0.."),
    "boundary lists a vertex twice": (_boundary_repeat, "lists a vertex twice"),
    "base64 longer than the shape": (lambda d: _mesh(d)["junction"].__setitem__("data", "A" * 4000), "base64 characters"),
    "garbage edit": (lambda d: d["snapshot"]["layers"][0].__setitem__("edits", [{"command": "sculpt_isophote", "junk": 1}]), "edits[0]"),
    "edit that is not a sculpt edit": (lambda d: d["snapshot"]["layers"][0].__setitem__("edits", [{"command": "add_layer"}]),
                                       "is not a sculpt edit"),
    "edit with a bad light": (
        lambda d: d["snapshot"]["layers"][0].__setitem__(
            "edits", [{"command": "sculpt_isophote", "layer": "a", "pick": [0.5, 0.5], "band": 0.3,
                       "stroke": [[0.2, 0.5], [0.8, 0.5]], "light": [0.0, 0.0, "x"]}]
        ),
        "light: must be a unit direction",
    ),
    "points too large": (lambda d: d["snapshot"]["layers"][0].__setitem__("points", [[1.5e308, 0]] * 3), None),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_snapshot_is_refused_at_load(tmp_path, saved_doc, case):
    mutate, fragment = CASES[case]
    mutate(saved_doc)
    path = write_doc(tmp_path / "doc.json", saved_doc)
    for cmd in (("info", path), ("render", path, "--png", tmp_path / "out.png")):
        res = run_cli(*cmd)
        if fragment is None:  # finite, in float range: accepted as the stroke it is
            assert res.rc == 0 and res.err.count("\n") <= 1, res.err
            continue
        line = assert_one_line_error(res, fragment)
        assert "snapshot.layers[0]" in line
    assert not (tmp_path / "out.png").exists() or fragment is None


def test_the_library_s_own_snapshots_still_load(examples_dir, tmp_path):
    """The strict checks accept every example, and a save by this version reopens exactly."""
    from sketchforge.document import fileformat as ff

    for example in sorted(examples_dir.glob("*.json")):
        res = run_cli("replay", example, "--save", tmp_path / example.name)
        assert res.rc == 0, res.err
        doc = ff.load(tmp_path / example.name, default_host())
        assert doc.layers and all(l.mesh is not None for l in doc.layers if l.points is not None)
