"""Build examples/animated.json from examples/creature.json: pins on both feet, the tail and
the head, then recorded motions (a 2 s tail wag, the head nodding in sync, the feet walking).

Deterministic: the "recordings" are sampled at 24 fps from closed-form curves, as if dragged
by hand along them. Run: .venv/bin/python examples/make_animated.py [--strip PNG]
(``--strip`` also renders the README's strip of frames).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from sketchforge.atomic import write_bytes_atomic
from sketchforge.document import fileformat as ff
from sketchforge.geometry.mesh import Mesh
from sketchforge.plugins import default_host

HERE = Path(__file__).resolve().parent
FPS = 24
LOOP = 2 * FPS  # 2 s


def surface_point(V: np.ndarray, x: float, y: float) -> list[float]:
    """The front-most model vertex near (x, y) in the drawing plane (where a click lands)."""
    d = np.hypot(V[:, 0] - x, V[:, 1] - y)
    near = np.argsort(d, kind="stable")[:30]
    return [round(float(c), 6) for c in V[near[np.argmax(V[near, 2])]]]


def main(out: Path = HERE / "animated.json") -> None:
    doc = ff.load(HERE / "creature.json", default_host(), use_snapshot=False)
    V = doc.export_mesh().V
    pins = {"foot_l": (-0.47, -1.18), "foot_r": (0.43, -1.18), "tail": (-1.42, 0.93), "head": (1.05, 0.55)}
    at = {}
    for pid, (x, y) in pins.items():
        at[pid] = np.array(surface_point(V, x, y))
        doc.execute({"command": "add_pin", "id": pid, "at": at[pid].tolist()})
    t = np.arange(LOOP) / LOOP * 2 * np.pi
    # the first recording defines the 2 s loop: the tail wags
    wag = at["tail"] + np.c_[0.30 * np.sin(t), 0.15 * np.sin(2 * t), 0.05 * np.cos(t)]
    doc.execute({"command": "record_motion", "pin": "tail", "start": 0, "samples": np.round(wag, 6).tolist()})
    # a later recording, started at frame 12 and a little longer than the loop: it runs in sync
    k = np.arange(LOOP + 6)
    tt = (12 + k) / LOOP * 2 * np.pi
    nod = at["head"] + np.c_[0.06 * np.sin(tt), 0.12 * np.sin(tt + 0.6), np.zeros(len(k))]
    doc.execute({"command": "record_motion", "pin": "head", "start": 12, "samples": np.round(nod, 6).tolist()})
    # a walk: the left foot steps (swings, lifting on the way forward) ...
    step = np.c_[0.22 * np.sin(t), 0.16 * np.clip(np.cos(t), 0, None), np.zeros(LOOP)]
    doc.execute({"command": "record_motion", "pin": "foot_l", "start": 0, "samples": np.round(at["foot_l"] + step, 6).tolist()})
    # ... and the right foot, the same step recorded from mid-loop, lands half a cycle later
    doc.execute({"command": "record_motion", "pin": "foot_r", "start": LOOP // 2, "samples": np.round(at["foot_r"] + step, 6).tolist()})
    # journal only, like the other examples: opening replays it
    write_bytes_atomic(out, json.dumps(ff.document_to_dict(doc, snapshot=False), separators=(",", ":")).encode())
    print(f"wrote {out}: {len(pins)} pins, {LOOP} frames ({LOOP / FPS:.1f} s at {FPS} fps)")


def strip(doc_path: Path, png: Path, frames=(0, 8, 16, 24, 32, 40), size: int = 240) -> None:
    """Render the given frames of the animation side by side (front view, no OpenGL)."""
    from sketchforge.geometry.raster import render_top, write_png
    from sketchforge_animate import Animation, Animator, posed_mesh

    doc = ff.load(doc_path, default_host())
    mesh = doc.export_mesh()
    anim = Animation.of(doc)
    posed = list(Animator(mesh, anim).frames(anim, max(frames) + 1))
    # one frame box for all images, so the motion is visible against a fixed background
    lo = np.min([posed[f][:, :2].min(0) for f in frames], axis=0)
    hi = np.max([posed[f][:, :2].max(0) for f in frames], axis=0)
    # two specks at the box's corners frame every image alike (one triangle across the box drew
    # its outline as a diagonal line through the pictures)
    e = 1e-9 * float(np.max(hi - lo))
    corners = np.array([[lo[0], lo[1], 0.0], [lo[0] + e, lo[1], 0.0], [lo[0], lo[1] + e, 0.0],
                        [hi[0], hi[1], 0.0], [hi[0] - e, hi[1], 0.0], [hi[0], hi[1] - e, 0.0]])
    frame_mesh = Mesh(corners, np.array([[0, 1, 2], [3, 5, 4]]))
    images = []
    for f in frames:
        img = render_top([frame_mesh, posed_mesh(mesh, anim, f)], doc.light.direction, size=size, cel=False)
        images.append(img)
    write_png(png, np.concatenate(images, axis=1))
    print(f"wrote {png}: frames {', '.join(map(str, frames))}")


if __name__ == "__main__":
    import sys

    main()
    if "--strip" in sys.argv:
        strip(HERE / "animated.json", Path(sys.argv[sys.argv.index("--strip") + 1]))
