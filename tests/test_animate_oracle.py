"""The animation's frames against oracles that do not use the code under test (issue 39, point 1).

tests/test_animate.py compared each posed frame's pins with ``Animation.targets(frame)``, the
function that decides them: shifting every pin's target by one frame passed. Here the pins of
frame f are read from the stored JSON (``motion[f mod loop]``, or ``target`` for a held pin)
and their vertices found by brute force; the loop's smoothing is recomputed from its
definition (a circular Gaussian of SMOOTHING_FRAMES, cut at 3 sigma); a later recording's
placement from Monster Mash's rule (frames in sync with the loop, the last pass wins, the gap
closed by a straight blend).
"""

from __future__ import annotations

import copy
import math
import re

import numpy as np
import pytest
from test_animate import bar

from sketchforge.errors import DocumentFormatError, ParameterError
from sketchforge.geometry.mesh import Mesh
from sketchforge_animate.pose import Animator, posed_mesh
from sketchforge_animate.state import (
    FPS,
    MAX_LOOP_FRAMES,
    MAX_PINS,
    SMOOTHING_FRAMES,
    Animation,
    Pin,
    fit_recording,
    smooth_loop,
)

RNG = np.random.default_rng(3901)


# --- oracles -------------------------------------------------------------------------------------


def smooth_oracle(traj: np.ndarray, sigma: float = SMOOTHING_FRAMES) -> np.ndarray:
    """out[i] = sum_o w(o) traj[(i - o) mod L] / sum_o w(o), o in -r..r, w(o) = exp(-o²/2σ²),
    r = 3σ rounded up, but never so wide that the window meets itself around the loop."""
    L = len(traj)
    if L < 3 or sigma <= 0:
        return np.array(traj, dtype=np.float64)
    r = min(math.ceil(3 * sigma), (L - 1) // 2)
    out = np.zeros((L, traj.shape[1]))
    for i in range(L):
        total = 0.0
        for o in range(-r, r + 1):
            w = math.exp(-o * o / (2 * sigma * sigma))
            out[i] += w * traj[(i - o) % L]
            total += w
        out[i] /= total
    return out


def placed_oracle(samples: np.ndarray, start: int, loop: int) -> np.ndarray:
    """A later recording on a loop of ``loop`` frames, before smoothing: sample j lands on
    frame (start + j) mod loop (a later pass overwrites), frames no sample reached are a
    straight blend from the last sample back to the first sample of the last pass."""
    k = len(samples)
    raw = [None] * loop
    for j in range(k):
        raw[(start + j) % loop] = samples[j]
    first = samples[max(0, k - loop)]
    last = samples[-1]
    gap = []
    f = (start + k) % loop
    while raw[f] is None:
        gap.append(f)
        f = (f + 1) % loop
        if len(gap) > loop:
            break
    for i, f in enumerate(gap):
        t = (i + 1) / (len(gap) + 1)
        raw[f] = (1 - t) * last + t * first
    return np.array(raw, dtype=np.float64)


def stored_targets(data: dict, frame: int) -> np.ndarray:
    """Every pin's position at ``frame``, read from the stored JSON value."""
    out = []
    for p in data["pins"]:
        if "motion" in p:
            out.append(p["motion"][frame % data["loop"]])
        else:
            out.append(p["target"])
    return np.array(out, dtype=np.float64)


def nearest_vertices(V: np.ndarray, points: np.ndarray) -> np.ndarray:
    return np.array([int(np.argmin(((V - p) ** 2).sum(axis=1))) for p in points])


# --- the stored value --------------------------------------------------------------------------


def bar_animation(loop=9):
    """Three pins on the bar's ends and middle: two with (different) motions, one held."""
    V, F = bar(nx=16, nr=8)
    ends = [int(np.argmin(V[:, 0])), int(np.argmax(V[:, 0])), int(np.argmin(np.abs(V[:, 0] - 2.0) + np.abs(V[:, 1] - 0.3)))]
    frames = np.arange(loop)
    pins = []
    for n, v in enumerate(ends):
        p = {"id": f"p{n}", "rest": V[v].tolist(), "target": (V[v] + [0.0, 0.0, 0.05 * n]).tolist()}
        if n < 2:
            wave = np.c_[0.1 * np.sin(2 * np.pi * (frames + 2 * n) / loop), 0.2 * np.cos(2 * np.pi * frames / loop) * (n + 1),
                         0.03 * frames]
            p["motion"] = (V[v] + wave).tolist()
        pins.append(p)
    return Mesh(V, F), {"loop": loop, "pins": pins}


def test_targets_are_the_stored_motion_of_that_frame_wrapping_around_the_loop():
    _, data = bar_animation(loop=9)
    anim = Animation.from_json(data)
    for frame in (0, 1, 4, 8, 9, 10, 17, 18, 9 * 7 + 5, 1000):
        assert anim.targets(frame).tolist() == stored_targets(data, frame).tolist(), frame
    assert anim.targets(3).shape == (3, 3)
    assert anim.to_json() == data  # and it is stored back exactly as it was read


def test_each_posed_frame_holds_every_pin_where_the_file_says_for_that_frame():
    mesh, data = bar_animation(loop=9)
    anim = Animation.from_json(data)
    handles = nearest_vertices(mesh.V, np.array([p["rest"] for p in data["pins"]]))
    frames = list(Animator(mesh, anim).frames(anim, 20))
    for f, P in enumerate(frames):
        assert np.abs(P[handles] - stored_targets(data, f)).max() < 1e-10, f
    # frames differ from one another: the motion is not one frame's pose repeated
    assert np.abs(frames[1] - frames[0]).max() > 0.01
    # one frame alone is the same computation (frames in order from 0), and posed_mesh keeps
    # the model's triangles
    for f in (0, 5, 13):
        alone = posed_mesh(mesh, anim, f)
        assert alone.V.tobytes() == frames[f].tobytes() and alone.F.tobytes() == mesh.F.tobytes()
        assert np.abs(alone.V[handles] - stored_targets(data, f)).max() < 1e-10
    with pytest.raises(ParameterError, match="a frame number must be 0 or more, got -1"):
        Animator(mesh, anim).frame(anim, -1)


def test_a_pose_without_motion_holds_each_pin_at_its_target():
    mesh, data = bar_animation()
    for p in data["pins"]:
        p.pop("motion", None)
    data["loop"] = 0
    anim = Animation.from_json(data)
    assert not anim.has_motion()
    handles = nearest_vertices(mesh.V, np.array([p["rest"] for p in data["pins"]]))
    P = posed_mesh(mesh, anim, 3).V
    assert np.abs(P[handles] - np.array([p["target"] for p in data["pins"]])).max() < 1e-10
    # no pins: the model as it is
    assert posed_mesh(mesh, Animation(), 2).V.tobytes() == mesh.V.tobytes()


def test_the_animated_document_poses_its_frames_from_its_stored_motion(real_host):
    from test_animate import animated_doc

    doc = animated_doc(real_host)
    data = doc.plugin_data("animate")
    rest = doc.export_mesh()
    handles = nearest_vertices(rest.V, np.array([p["rest"] for p in data["pins"]]))
    for frame in (0, 5, data["loop"] + 5):
        posed = real_host.pose(doc, frame)
        assert np.abs(posed.V[handles] - stored_targets(data, frame)).max() < 1e-9, frame
    # the recorded wave is pin b's motion, smoothed around the loop; pin a's is a copy of it,
    # moved from b's rest point to a's, and a starts where its motion starts
    b = next(p for p in data["pins"] if p["id"] == "b")
    a = next(p for p in data["pins"] if p["id"] == "a")
    shift = np.array(a["rest"]) - np.array(b["rest"])
    assert np.abs(np.array(a["motion"]) - (np.array(b["motion"]) + shift)).max() < 1e-12
    assert a["target"] == a["motion"][0]
    right = np.array(b["rest"])
    wave = np.array([right + [0.0, 0.3 * np.sin(2 * np.pi * k / 24), 0.1] for k in range(24)])
    assert np.abs(np.array(b["motion"]) - smooth_oracle(wave)).max() < 1e-12


# --- recordings ----------------------------------------------------------------------------------


@pytest.mark.parametrize("L", [3, 4, 5, 7, 8, 9, 24, 50])
def test_smoothing_is_the_circular_gaussian_of_the_loop(L):
    traj = RNG.normal(size=(L, 3))
    assert np.abs(smooth_loop(traj) - smooth_oracle(traj)).max() < 1e-12
    assert np.abs(smooth_loop(traj, 0.7) - smooth_oracle(traj, 0.7)).max() < 1e-12
    # it is circular: turning the loop and smoothing is smoothing and turning
    assert np.abs(smooth_loop(np.roll(traj, 2, axis=0)) - np.roll(smooth_loop(traj), 2, axis=0)).max() < 1e-12
    assert np.abs(smooth_loop(traj).mean(axis=0) - traj.mean(axis=0)).max() < 1e-12


def test_smoothing_leaves_very_short_loops_and_no_smoothing_alone():
    for traj in (RNG.normal(size=(1, 3)), RNG.normal(size=(2, 3))):
        out = smooth_loop(traj)
        assert out.tolist() == traj.tolist() and out is not traj
    traj = RNG.normal(size=(10, 3))
    assert smooth_loop(traj, 0.0).tolist() == traj.tolist()
    assert smooth_loop(traj, -1.0).tolist() == traj.tolist()


def test_the_first_recording_defines_the_loop_and_starts_at_frame_zero():
    samples = RNG.normal(size=(13, 3))
    traj, loop = fit_recording(samples, 7, 0)
    assert loop == 13 and np.abs(traj - smooth_oracle(samples)).max() < 1e-12
    traj, loop = fit_recording(samples[:2], 0, 0)
    assert loop == 2 and traj.tolist() == samples[:2].tolist()
    with pytest.raises(ParameterError, match="at least 2 frames"):
        fit_recording(samples[:1], 0, 0)
    long = np.zeros((MAX_LOOP_FRAMES + 1, 3))
    with pytest.raises(ParameterError, match=f"at most {MAX_LOOP_FRAMES} frames \\({MAX_LOOP_FRAMES // FPS} s\\)"):
        fit_recording(long, 0, 0)
    assert fit_recording(long[:-1], 0, 0)[1] == MAX_LOOP_FRAMES
    # a later one longer than the maximum is fine: it keeps its last pass of the loop
    assert fit_recording(long, 0, 10)[1] == 10


@pytest.mark.parametrize("k, start, loop", [(3, 6, 10), (4, 0, 10), (9, 8, 10), (10, 3, 10), (14, 5, 10), (23, 2, 10),
                                            (2, 9, 3), (5, 1, 4), (12, 0, 24)])
def test_a_later_recording_runs_in_sync_with_the_loop(k, start, loop):
    samples = RNG.normal(size=(k, 3))
    traj, got_loop = fit_recording(samples, start, loop)
    assert got_loop == loop
    assert np.abs(traj - smooth_oracle(placed_oracle(samples, start, loop))).max() < 1e-12


# --- the stored value's limits -------------------------------------------------------------------


def test_the_loop_and_pin_limits_are_inclusive():
    _, data = bar_animation(loop=4)
    ok = copy.deepcopy(data)
    ok["loop"] = MAX_LOOP_FRAMES
    for p in ok["pins"]:
        p.pop("motion", None)
    assert Animation.from_json(ok).loop == MAX_LOOP_FRAMES
    ok["loop"] = MAX_LOOP_FRAMES + 1
    with pytest.raises(DocumentFormatError, match=f"the loop length must be 0..{MAX_LOOP_FRAMES} frames"):
        Animation.from_json(ok)
    many = {"loop": 0, "pins": [{"id": f"q{i}", "rest": [i, 0, 0], "target": [i, 0, 0]} for i in range(MAX_PINS)]}
    anim = Animation.from_json(many)
    assert len(anim.pins) == MAX_PINS
    with pytest.raises(ParameterError, match=f"at most {MAX_PINS} pins"):
        anim.with_pin(Pin("new", (0, 0, 0), (0, 0, 0)))
    assert anim.with_pin(Pin("q3", (1, 1, 1), (2, 2, 2))).pin("q3").target == (2, 2, 2)  # replacing is fine when full
    many["pins"].append({"id": "extra", "rest": [0, 1, 0], "target": [0, 1, 0]})
    with pytest.raises(DocumentFormatError, match=f"at most {MAX_PINS} pins, this one has {MAX_PINS + 1}"):
        Animation.from_json(many)


def test_a_motion_needs_a_loop_of_two_frames_and_one_position_per_frame():
    def one(loop, motion):
        return {"loop": loop, "pins": [{"id": "a", "rest": [0, 0, 0], "target": [0, 0, 0], "motion": motion}]}

    two = Animation.from_json(one(2, [[0, 0, 0], [1, 0, 0]]))
    assert two.has_motion() and not two.pin("a").motion.flags.writeable
    for loop in (0, 1):
        with pytest.raises(DocumentFormatError, match=f"has a motion but the loop has {loop} frames"):
            Animation.from_json(one(loop, [[0, 0, 0]] * loop))
    for bad in ([[0, 0, 0]] * 3, "xx"):  # not one position per frame
        with pytest.raises(DocumentFormatError, match=re.escape("its motion must have one [x, y, z] per loop frame (2)")):
            Animation.from_json(one(2, bad))
    for bad in ([[0, 0]] * 2, [[0, 0, 0], [0, 0, float("nan")]]):  # a position that is no finite triple
        with pytest.raises(DocumentFormatError, match=re.escape("its motion (one [x, y, z] per loop frame (2)) must be "
                                                                "[x, y, z] triples of finite numbers")):
            Animation.from_json(one(2, bad))
    assert not Animation.from_json({"loop": 2, "pins": [{"id": "a", "rest": [0, 0, 0], "target": [0, 0, 0]}]}).has_motion()
    assert Animation.from_json(None) == Animation() and Animation().to_json() is None


def test_pin_values_and_edits():
    anim = Animation.from_json({"loop": 0, "pins": [{"id": "pin1", "rest": [1, 2, 3], "target": [4, 5, 6]},
                                                     {"id": "pin3", "rest": [0, 0, 0], "target": [0, 0, 0]}]})
    p = anim.pin("pin1")
    assert p.rest == (1.0, 2.0, 3.0) and p.target == (4.0, 5.0, 6.0) and all(type(x) is float for x in p.rest)
    assert anim.new_pin_id() == "pin2"
    assert Animation().new_pin_id() == "pin1"
    with pytest.raises(ParameterError) as info:
        anim.pin("pin9")
    assert str(info.value) == "there is no pin 'pin9' (pins: pin1, pin3)"
    with pytest.raises(ParameterError, match=r"\(pins: none\)"):
        Animation().pin("x")
    # replacing keeps the order; adding appends
    moved = anim.with_pin(Pin("pin1", p.rest, (0.0, 0.0, 0.0)))
    assert [q.id for q in moved.pins] == ["pin1", "pin3"] and moved.pin("pin1").target == (0.0, 0.0, 0.0)
    assert [q.id for q in anim.with_pin(Pin("pin2", (0, 0, 0), (0, 0, 0))).pins] == ["pin1", "pin3", "pin2"]
    assert anim.pin("pin1").target == (4.0, 5.0, 6.0)  # values: the old one is unchanged
    # removing the last pin with a motion ends the loop; one without leaves it
    rec = Animation.from_json({"loop": 3, "pins": [
        {"id": "m", "rest": [0, 0, 0], "target": [0, 0, 0], "motion": [[0, 0, 0]] * 3},
        {"id": "s", "rest": [1, 0, 0], "target": [1, 0, 0]}]})
    assert rec.without_pin("s").loop == 3 and [q.id for q in rec.without_pin("s").pins] == ["m"]
    assert rec.without_pin("m").loop == 0 and not rec.without_pin("m").has_motion()
    with pytest.raises(ParameterError, match="there is no pin 'zz'"):
        rec.without_pin("zz")
    for bad in ([1, 2], [1, 2, 3, 4], [1, float("inf"), 3], "abc", None):
        with pytest.raises(DocumentFormatError, match="the rest of pin 'a' must be 3"):
            Animation.from_json({"loop": 0, "pins": [{"id": "a", "rest": bad, "target": [0, 0, 0]}]})
