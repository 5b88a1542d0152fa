"""Animation (Monster Mash style): control pins on the assembled model, as-rigid-as-possible
posing, recorded looping motions, animated glTF export.

Public API
----------
ArapSolver            one factorisation per pin set, local/global frames (:mod:`.arap`)
Animation, Pin        the document's animation value (:mod:`.state`)
Animator, posed_mesh  frames of an animation on a model (:mod:`.pose`)
animated_glb_bytes    the .glb writer (:mod:`.gltf`)
commands              add_pin, move_pin, remove_pin, hold_pin, record_motion, copy_motion
"""

from __future__ import annotations

from .arap import ArapSolver
from .gltf import animated_glb_bytes
from .pose import Animator, posed_mesh
from .state import FPS, Animation, Pin

__all__ = ["ArapSolver", "Animation", "Pin", "Animator", "posed_mesh", "animated_glb_bytes", "FPS"]
