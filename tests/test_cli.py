"""The command line: replay/export/info work headlessly; errors are one line, exit 2."""

import json
import subprocess
import sys

import numpy as np
import pytest
from tests_support import SPEC_DOC


def run(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "sketchforge", *map(str, args)], capture_output=True, text=True, timeout=timeout)


@pytest.fixture
def spec_doc(tmp_path):
    p = tmp_path / "doc.json"
    p.write_text(json.dumps(SPEC_DOC))
    return p


def read_obj(path):
    V, F = [], []
    for line in path.read_text().splitlines():
        if line.startswith("v "):
            V.append([float(x) for x in line.split()[1:]])
        elif line.startswith("f "):
            F.append([int(x) - 1 for x in line.split()[1:]])
    return np.array(V), np.array(F)


def test_replay_exports_one_layer(spec_doc, tmp_path):
    out = tmp_path / "body.obj"
    res = run("replay", spec_doc, "--export", out, "--layer", "body")
    assert res.returncode == 0, res.stderr
    V, F = read_obj(out)
    assert len(V) > 500 and F.max() == len(V) - 1
    assert V[:, 2].min() >= 0 and V[:, 2].max() > 0.2  # an inflated height field
    assert np.abs(V[:, 0]).max() == pytest.approx(1.0, abs=0.02)


@pytest.mark.parametrize("suffix", [".ply", ".stl", ".glb", ".gltf"])
def test_replay_exports_every_format(spec_doc, tmp_path, suffix):
    out = tmp_path / ("m" + suffix)
    res = run("replay", spec_doc, "--export", out, "--layer", "body")
    assert res.returncode == 0, res.stderr
    head = out.read_bytes()[:4]
    assert head == {".ply": b"ply\n", ".stl": b"sket", ".glb": b"glTF", ".gltf": b'{\n "'}[suffix]


def test_info_lists_layers(spec_doc, tmp_path):
    saved = tmp_path / "saved.json"
    assert run("replay", spec_doc, "--save", saved).returncode == 0
    res = run("info", saved)
    assert res.returncode == 0, res.stderr
    assert "body 'Body'" in res.stdout and "vertices" in res.stdout
    check = run("replay", saved, "--check")
    assert check.returncode == 0 and "matches the snapshot" in check.stderr


@pytest.mark.parametrize(
    "args, message",
    [
        (["info", "missing.json"], "no such file"),
        (["replay", "DOC", "--export", "nowhere/x.obj", "--layer", "body"], "does not exist"),
        (["replay", "DOC", "--export", "x.fbx", "--layer", "body"], "cannot export to '.fbx'"),
        (["replay", "DOC", "--export", "x.obj", "--layer", "ghost"], "no layer with id 'ghost'"),
    ],
)
def test_errors_are_one_line_without_traceback(spec_doc, tmp_path, args, message):
    args = [str(spec_doc) if a == "DOC" else (str(tmp_path / a) if a.endswith((".obj", ".fbx")) else a) for a in args]
    res = run(*args)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in res.stderr


def test_bad_contour_in_journal_names_entry(tmp_path):
    doc = json.loads(json.dumps(SPEC_DOC))
    doc["journal"][1]["points"] = [[0, 0], [1, 1], [1, 0], [0, 1]]  # a figure eight
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(doc))
    res = run("replay", p)
    assert res.returncode == 2
    assert "journal entry 1 (set_contour)" in res.stderr and "Traceback" not in res.stderr


def test_replay_exports_the_assembled_model_closed_and_oriented(tmp_path):
    from pathlib import Path

    example = Path(__file__).resolve().parent.parent / "examples" / "toucan.json"
    out = tmp_path / "toucan.obj"
    res = run("replay", example, "--export", out)
    assert res.returncode == 0, res.stderr
    V, F = read_obj(out)
    # Closed 2-manifold: every undirected edge in exactly two triangles, in opposite directions.
    e = np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    assert np.all(counts == 2)
    directed = np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]
    assert len(np.unique(directed, axis=0)) == len(directed)
    volume = np.einsum("ij,ij->i", V[F[:, 0]], np.cross(V[F[:, 1]], V[F[:, 2]])).sum() / 6
    assert volume > 0


def test_info_reports_a_loop_whose_ends_meet_as_closed_as_the_assembly_sees_it(tmp_path, real_host):
    """A closed loop saved with closed=False (an older file, or a script) has no junction: the
    inflation closes it, the assembly treats it as a free part, and info says "closed"."""
    from sketchforge.document import fileformat as ff
    from sketchforge.document.document import Document

    t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    loop = np.c_[0.5 * np.cos(t), 0.5 * np.sin(t)]
    u = loop[:84]  # an arc whose ends are far apart
    doc = Document(host=real_host)
    for lid, pts in (("loop", loop), ("arc", u)):
        doc.execute({"command": "add_layer", "id": lid, "name": lid})
        doc.execute({"command": "set_contour", "layer": lid, "points": pts.tolist()})
    assert len(doc.layer("loop").mesh.junction) == 0 and len(doc.layer("arc").mesh.junction) > 0
    path = tmp_path / "kinds.json"
    ff.save(doc, path)
    res = run("info", path)
    assert res.returncode == 0, res.stderr
    assert "loop 'loop' closed" in res.stdout and "arc 'arc' open" in res.stdout
