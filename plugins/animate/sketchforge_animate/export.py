"""The animation exporter (``.glb``) and the ``sketchforge_pose`` hook's work."""

from __future__ import annotations

from sketchforge.plugin_api import ParameterError, write_bytes_atomic, write_gltf

from .gltf import animated_glb_bytes
from .pose import animator_for, posed_mesh
from .state import FPS, Animation


def has_animation(doc) -> bool:
    """True when the document has pins (a pose or a motion) to export."""
    return bool(Animation.of(doc).pins)


def loop_frame(anim: Animation, frame: int) -> int:
    """The frame of the loop that frame ``frame`` of playback shows: ``frame`` modulo the
    loop, 0 without a motion (as the app's timeline and the exported glTF have it). Frames are
    computed in order from frame 0, so without this ``--frame 10**21`` would run for ever."""
    frame = int(frame)
    if frame < 0:
        raise ParameterError(f"a frame number must be 0 or more, got {frame}")
    return frame % anim.loop if anim.has_motion() else 0


def pose_document(doc, frame: int):
    """The assembled model posed at ``frame`` (the static model when there are no pins);
    frames past the loop wrap (:func:`loop_frame`)."""
    anim = Animation.of(doc)
    return posed_mesh(doc.export_mesh(), anim, loop_frame(anim, frame))


def write_animation(path, doc, progress=None) -> str:
    """Write the document's animation (every loop frame; one posed frame without a motion)
    as an animated .glb. Returns a one-line summary."""
    anim = Animation.of(doc)
    mesh = doc.export_mesh()
    count = anim.loop if anim.has_motion() else 1
    frames = []
    for f, P in enumerate(animator_for(mesh, anim).frames(anim, count)):
        frames.append(P.copy())
        if progress is not None:
            progress(f + 1, count)
    write_bytes_atomic(path, animated_glb_bytes(mesh.F, frames, rim_pairs=getattr(mesh, "rim_pairs", None),
                                                rim_weights=getattr(mesh, "rim_weights", None)))
    secs = count / FPS
    return f"{count} frames, {secs:.2f} s at {FPS} fps, {mesh.n_vertices} vertices, {mesh.n_faces} triangles"


def exporter():
    from sketchforge.plugin_api import Exporter

    return Exporter(
        "gltf-animation",
        (".glb",),
        write_gltf,
        "Animated glTF 2.0 (.glb, morph targets, 24 fps)",
        write_document=write_animation,
        handles=has_animation,
    )
