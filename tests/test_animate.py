"""Animation plugin: ARAP keeps a bent bar's edges, motions loop in sync, every change is an
undoable journaled command whose replay gives bit-identical frames, the .glb reads back."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sketchforge.document import fileformat as ff
from sketchforge.document.document import Document
from sketchforge.errors import DocumentFormatError, SketchforgeError
from sketchforge.plugins import default_host
from sketchforge_animate import Animation, ArapSolver, animated_glb_bytes
from sketchforge_animate.arap import edge_weights
from sketchforge_animate.gltf import accessor_array, read_glb
from sketchforge_animate.state import fit_recording, smooth_loop


def bar(nx=40, nr=12, length=4.0, radius=0.3):
    """A closed tube along x (capped), (V, F) with outward triangles."""
    xs = np.linspace(0.0, length, nx)
    th = 2 * np.pi * np.arange(nr) / nr
    V = [[x, radius * np.cos(t), radius * np.sin(t)] for x in xs for t in th]
    F = []
    for a in range(nx - 1):
        for b in range(nr):
            i, j = a * nr + b, a * nr + (b + 1) % nr
            F += [[i, i + nr, j], [j, i + nr, j + nr]]
    c0, c1 = len(V), len(V) + 1
    V += [[0.0, 0, 0], [length, 0, 0]]
    for b in range(nr):
        F += [[c0, b, (b + 1) % nr], [c1, (nx - 1) * nr + (b + 1) % nr, (nx - 1) * nr + b]]
    return np.array(V), np.array(F, dtype=np.int64)


def rel_edge_change(V0, V1, F):
    i, j, _ = edge_weights(V0, F)
    return np.abs(np.linalg.norm(V1[i] - V1[j], axis=1) / np.linalg.norm(V0[i] - V0[j], axis=1) - 1.0)


def test_arap_bend_keeps_edge_lengths():
    V, F = bar()
    nr = 12
    left = np.arange(2 * nr)  # two rings at x = 0 held
    right = np.arange(len(V) - 2 - 2 * nr, len(V) - 2)
    handles = np.concatenate([left, right])
    # both ends go where a quarter-circle bend of the bar would put them (lengths kept)
    rho = 4.0 / (np.pi / 2)

    def bend(p):
        th = p[:, 0] / rho
        return np.c_[rho * np.sin(th) - p[:, 1] * np.sin(th), rho * (1 - np.cos(th)) + p[:, 1] * np.cos(th), p[:, 2]]

    tgt = bend(V[handles])
    s = ArapSolver(V, F, handles)
    P = s.solve(tgt, V, 60)
    assert np.allclose(P[handles], tgt)
    ch = rel_edge_change(V, P, F)
    assert np.median(ch) < 0.03, np.median(ch)
    # the bar really bent: its far end points up
    assert P[right, 1].mean() > 1.0
    # a plain Laplacian solve (no rotations fitted) from the same targets stretches far more
    s2 = ArapSolver(V, F, handles)
    ch0 = rel_edge_change(V, s2.solve(tgt, V, 1), F)
    assert np.median(ch) < 0.5 * np.median(ch0)


def test_arap_deterministic_and_rigid_motion_is_exact():
    V, F = bar(nx=12, nr=8)
    h = np.random.default_rng(0).choice(len(V), 12, replace=False)
    R = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])  # a quarter turn, then a shift
    a = ArapSolver(V, F, h).solve(V[h] @ R.T + 1.0, V, 120)
    b = ArapSolver(V, F, h).solve(V[h] @ R.T + 1.0, V, 120)
    assert a.tobytes() == b.tobytes()
    # the pins move the bar rigidly: ARAP finds that rigid motion (bar length 4)
    assert np.abs(a - (V @ R.T + 1.0)).max() < 5e-3


def test_arap_refuses_bad_input():
    V, F = bar(nx=5, nr=6)
    for h in ([], [0, 0], [len(V)]):
        with pytest.raises(SketchforgeError):
            ArapSolver(V, F, h)
    with pytest.raises(SketchforgeError):
        ArapSolver(V, F, [0]).solve(np.full((1, 3), np.nan), V, 1)


def test_recording_sync_and_smoothing():
    first = np.c_[np.arange(10.0), np.zeros(10), np.zeros(10)]
    traj, loop = fit_recording(first, 7, 0)
    assert loop == 10 and traj.shape == (10, 3)  # the first recording defines the loop, from 0
    # a later, shorter recording started at loop frame 6 lands on frames 6, 7, 8 (in sync)
    later = np.array([[1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0]])
    traj2, loop2 = fit_recording(later, 6, 10)
    assert loop2 == 10
    raw = traj2  # smoothed: frame 7 (the middle sample) stays near 2
    assert abs(raw[7, 0] - 2.0) < 0.3
    # the gap 9..5 blends from 3 back to 1, so the loop closes without a jump
    assert np.all(np.abs(np.diff(np.r_[raw[:, 0], raw[:1, 0]])) < 1.0)
    # smoothing removes jitter but keeps a constant
    noisy = np.c_[np.sin(np.arange(48) / 48 * 2 * np.pi) + 0.05 * (-1.0) ** np.arange(48), np.zeros((48, 2))]
    sm = smooth_loop(noisy)
    assert np.abs(np.diff(sm[:, 0], 2)).max() < 0.3 * np.abs(np.diff(noisy[:, 0], 2)).max()
    assert np.allclose(smooth_loop(np.ones((20, 3))), 1.0)
    with pytest.raises(SketchforgeError):
        fit_recording(first[:1], 0, 0)


# --- documents --------------------------------------------------------------------------------

BLOB = [[np.cos(t) * 1.0, np.sin(t) * 0.5] for t in np.linspace(0, 2 * np.pi, 40, endpoint=False)]


def animated_doc(host):
    doc = Document(host=host)
    doc.execute({"command": "add_layer", "id": "body", "name": "Body"})
    doc.execute({"command": "set_contour", "layer": "body", "points": BLOB, "closed": True})
    doc.execute({"command": "set_inflate_params", "layer": "body", "params": {"resolution": 0.08}})
    V = doc.export_mesh().V
    left, right = V[np.argmin(V[:, 0])], V[np.argmax(V[:, 0])]
    doc.execute({"command": "add_pin", "id": "a", "at": left.tolist()})
    doc.execute({"command": "add_pin", "id": "b", "at": right.tolist()})
    doc.execute({"command": "add_pin", "id": "c", "at": V[np.argmax(V[:, 2])].tolist()})
    wave = [(right + [0.0, 0.3 * np.sin(2 * np.pi * k / 24), 0.1]).tolist() for k in range(24)]
    doc.execute({"command": "record_motion", "pin": "b", "start": 0, "samples": wave})
    doc.execute({"command": "copy_motion", "source": "b", "pin": "a"})
    return doc


def frames(doc, n):
    from sketchforge_animate.pose import Animator

    anim = Animation.of(doc)
    return [P.copy() for P in Animator(doc.export_mesh(), anim).frames(anim, n)]


def test_commands_undo_and_replay_bit_identical(real_host, tmp_path):
    doc = animated_doc(real_host)
    anim = Animation.of(doc)
    assert [p.id for p in anim.pins] == ["a", "b", "c"] and anim.loop == 24
    assert anim.pin("a").motion.shape == (24, 3)
    fa = frames(doc, 30)
    # replay the journal from scratch: same frames bit for bit
    path = tmp_path / "anim.json"
    ff.save(doc, path)
    data = json.loads(path.read_text())
    replayed = ff.replay_journal(ff.validate_header(data, "x")[0], data["journal"], host=real_host)
    assert replayed.same_state(doc)
    fb = frames(replayed, 30)
    assert all(x.tobytes() == y.tobytes() for x, y in zip(fa, fb))
    # the snapshot reopens with the same animation
    assert ff.load(path, host=real_host).same_state(doc)
    # every frame is a closed 2-manifold with the static connectivity, pins where they go
    from sketchforge_animate.pose import Animator

    rest = doc.export_mesh()
    an = Animator(rest, anim)
    E = np.unique(np.sort(np.r_[rest.F[:, [0, 1]], rest.F[:, [1, 2]], rest.F[:, [2, 0]]], axis=1), axis=0)
    length0 = np.linalg.norm(rest.V[E[:, 0]] - rest.V[E[:, 1]], axis=1)
    for f in (0, 7, 23):
        assert np.allclose(fa[f][an.handles], anim.targets(f), atol=1e-12)
        # as rigid as possible: the pose moves the pins, the surface keeps its edge lengths
        length = np.linalg.norm(fa[f][E[:, 0]] - fa[f][E[:, 1]], axis=1)
        assert np.median(np.abs(length / length0 - 1.0)) < 0.03
    # undo walks back one command at a time
    doc.undo_stack.undo()
    assert Animation.of(doc).pin("a").motion is None
    doc.undo_stack.undo()
    assert Animation.of(doc).loop == 0
    doc.undo_stack.redo()
    assert Animation.of(doc).loop == 24


def test_move_drag_is_one_undo_step_and_pins_refuse_bad_edits(real_host):
    from sketchforge.document.commands import new_gesture_id
    from sketchforge_animate.commands import MovePin

    doc = animated_doc(real_host)
    c0 = Animation.of(doc).pin("c").target
    depth = len(doc.journal())
    g = new_gesture_id()
    for k in range(5):
        doc.push(MovePin(pin="c", to=(c0[0], c0[1] + 0.05 * k, c0[2]), gesture=g))
    assert len(doc.journal()) == depth + 1
    assert Animation.of(doc).pin("c").target[1] == pytest.approx(c0[1] + 0.2)
    doc.undo_stack.undo()
    assert Animation.of(doc).pin("c").target == c0
    before = doc.plugin_data("animate")
    for entry in (
        {"command": "add_pin", "id": "d", "at": list(Animation.of(doc).pin("c").rest)},  # same vertex
        {"command": "remove_pin", "pin": "nope"},
        {"command": "hold_pin", "pin": "c"},  # has no motion
        {"command": "copy_motion", "source": "c", "pin": "a"},
        {"command": "add_pin", "id": "a", "at": [0, 0, 0]},
    ):
        with pytest.raises(SketchforgeError):
            doc.execute(entry)
    assert doc.plugin_data("animate") is before
    with pytest.raises(DocumentFormatError):
        real_host.commands.from_dict({"command": "move_pin", "pin": "a", "to": [1, "x", 2]})
    doc.execute({"command": "hold_pin", "pin": "a"})
    doc.execute({"command": "hold_pin", "pin": "b"})
    assert Animation.of(doc).loop == 0  # no motion left: the next recording defines a new loop
    doc.execute({"command": "remove_pin", "pin": "c"})
    assert [p.id for p in Animation.of(doc).pins] == ["a", "b"]


def test_glb_reads_back(real_host, tmp_path):
    doc = animated_doc(real_host)
    exp = real_host.exporter_for(tmp_path / "a.glb", doc)
    assert exp.name == "gltf-animation"
    exp.write_document(tmp_path / "a.glb", doc)
    gltf, blob = read_glb((tmp_path / "a.glb").read_bytes())
    mesh = doc.export_mesh()
    prim = gltf["meshes"][0]["primitives"][0]
    assert gltf["accessors"][prim["attributes"]["POSITION"]]["count"] == mesh.n_vertices
    idx = accessor_array(gltf, blob, prim["indices"]).reshape(-1, 3)
    assert np.array_equal(idx, mesh.F)
    assert len(prim["targets"]) == 23  # frames 1..23 of a 24-frame loop
    anim = gltf["animations"][0]
    assert anim["channels"] == [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]
    times = accessor_array(gltf, blob, anim["samplers"][0]["input"])
    weights = accessor_array(gltf, blob, anim["samplers"][0]["output"]).reshape(len(times), -1)
    assert np.allclose(np.diff(times), 1 / 24) and times[-1] == pytest.approx(1.0)
    assert np.array_equal(weights[0], weights[-1]) and not weights[0].any()  # the loop closes
    # base + target 7 = frame 8
    fr = frames(doc, 9)
    base = accessor_array(gltf, blob, prim["attributes"]["POSITION"])
    d8 = accessor_array(gltf, blob, prim["targets"][7]["POSITION"])
    assert np.abs(base + d8 - fr[8]).max() < 1e-5
    # without pins the plain exporter is used
    assert real_host.exporter_for(tmp_path / "a.glb", Document(host=real_host)).name == "gltf"


def test_glb_uses_32_bit_indices_past_65535_vertices():
    n = 70000
    V = np.random.default_rng(1).random((n, 3))
    F = np.stack([np.arange(n - 2), np.arange(1, n - 1), np.arange(2, n)], axis=1)
    gltf, blob = read_glb(animated_glb_bytes(F, [V, V + 1.0]))
    acc = gltf["accessors"][gltf["meshes"][0]["primitives"][0]["indices"]]
    assert acc["componentType"] == 5125 and acc["count"] == F.size
    assert accessor_array(gltf, blob, gltf["meshes"][0]["primitives"][0]["indices"]).max() == n - 1


# --- command line and example ----------------------------------------------------------------


def test_cli_exports_animation_and_a_posed_frame(real_host, tmp_path):
    import subprocess
    import sys

    from sketchforge.exporters import obj_bytes
    from sketchforge_animate.pose import posed_mesh

    doc = animated_doc(real_host)
    path = tmp_path / "doc.json"
    ff.save(doc, path)

    def run(*args):
        return subprocess.run(
            [sys.executable, "-m", "sketchforge", "replay", str(path), *args],
            capture_output=True,
            text=True,
            timeout=300,
        )

    r = run("--export", str(tmp_path / "a.glb"))
    assert r.returncode == 0, r.stderr
    assert "24 frames" in r.stderr
    gltf, _ = read_glb((tmp_path / "a.glb").read_bytes())
    assert len(gltf["animations"][0]["channels"]) == 1
    r = run("--export", str(tmp_path / "f5.obj"), "--frame", "5")
    assert r.returncode == 0, r.stderr
    want = posed_mesh(doc.export_mesh(), Animation.of(doc), 5)
    assert (tmp_path / "f5.obj").read_bytes() == obj_bytes(want)  # the replayed frame, bit for bit
    r = run("--frame", "5")
    assert r.returncode == 2 and "needs --export" in r.stderr and "Traceback" not in r.stderr
    r = run("--export", str(tmp_path / "x.obj"), "--frame", "-1")
    assert r.returncode == 2 and "0 or more" in r.stderr


def test_example_is_rebuilt_deterministically_and_is_closed(tmp_path):
    import importlib.util
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    spec = importlib.util.spec_from_file_location("make_animated", root / "examples" / "make_animated.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.main(tmp_path / "animated.json")
    assert (tmp_path / "animated.json").read_bytes() == (root / "examples" / "animated.json").read_bytes()
    doc = ff.load(root / "examples" / "animated.json", default_host())
    anim = Animation.of(doc)
    assert len(anim.pins) >= 2 and anim.loop >= 48  # >= 2 s at 24 fps
    mesh = doc.export_mesh()
    P = frames(doc, 13)[12]
    # a closed 2-manifold: every undirected edge in exactly two triangles, used once each way
    F = mesh.F
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)
    und = np.sort(directed, axis=1)
    _, counts = np.unique(und, axis=0, return_counts=True)
    assert np.all(counts == 2)
    assert np.all(np.isfinite(P)) and np.abs(P - mesh.V).max() > 0.05  # it moved
    assert np.median(rel_edge_change(mesh.V, P, F)) < 0.03


def test_a_posed_model_and_its_glb_keep_the_rim_shared(real_host, tmp_path):
    """The assembled model's rim pairs (issue 34) live on through a pose: the posed model still
    names them, so the renderers share its rim normals in every frame, and the animated .glb's
    normals (base and every morph target) are the shared ones."""
    from sketchforge.geometry.normals import vertex_normals
    from sketchforge_animate.export import pose_document

    doc = animated_doc(real_host)
    model = doc.export_mesh()
    assert len(model.rim_pairs) > 20
    posed = pose_document(doc, 8)
    np.testing.assert_array_equal(posed.rim_pairs, model.rim_pairs)
    assert np.abs(posed.V - model.V).max() > 0.05
    doc_path = tmp_path / "a.glb"
    real_host.exporter_for(doc_path, doc).write_document(doc_path, doc)
    gltf, blob = read_glb(doc_path.read_bytes())
    prim = gltf["meshes"][0]["primitives"][0]
    base_n = accessor_array(gltf, blob, prim["attributes"]["NORMAL"]).reshape(-1, 3)
    first = pose_document(doc, 0)  # the .glb's base is frame 0
    np.testing.assert_allclose(base_n, vertex_normals(first.V, first.F, first.rim_pairs), atol=1e-6)
    own = vertex_normals(first.V, first.F)
    rim = model.rim_pairs.ravel()
    assert np.abs(base_n[rim, 2]).max() < 0.5 * np.abs(own[rim, 2]).min()  # not the unshared ones
    d8 = accessor_array(gltf, blob, prim["targets"][7]["NORMAL"]).reshape(-1, 3)
    np.testing.assert_allclose(base_n + d8, vertex_normals(posed.V, posed.F, posed.rim_pairs), atol=2e-6)
