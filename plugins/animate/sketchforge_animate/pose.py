"""Posing the assembled model: pins -> handle vertices -> ARAP frames.

A frame sequence is computed in order: frame 0 from the rest shape with
``INITIAL_ITERATIONS`` local/global steps, each later frame warm-started from the one before
with ``FRAME_ITERATIONS`` step (frames are 1/24 s apart, so the previous frame is a close
start; one step is what fits the 16 ms budget at 16k vertices, see benchmarks/bench_animate.py,
and playback in the app shows exactly the exported frames). So frame N is a deterministic function of the model and the
animation (what ``replay --frame N`` and the glTF exporter compute), bit for bit.
"""

from __future__ import annotations

import atexit
import dataclasses

import numpy as np
from scipy.spatial import cKDTree

from sketchforge.plugin_api import AssembledMesh, Mesh, ParameterError

from .arap import ArapSolver
from .state import Animation

INITIAL_ITERATIONS = 60
FRAME_ITERATIONS = 1


def attach_pins(V: np.ndarray, rests: np.ndarray, ids=None) -> np.ndarray:
    """Nearest vertex of V (n,3) to each pin's rest point (k,3) -> (k,) int64. Two pins on one
    vertex are refused (the model changed under them, or they were put too close)."""
    if len(rests) == 0:
        return np.zeros(0, dtype=np.int64)
    _, idx = cKDTree(V).query(np.asarray(rests, dtype=np.float64).reshape(-1, 3))
    idx = np.asarray(idx, dtype=np.int64)
    uniq, counts = np.unique(idx, return_counts=True)
    if np.any(counts > 1):
        v = uniq[counts > 1][0]
        who = [ids[i] if ids else str(i) for i in np.flatnonzero(idx == v)]
        raise ParameterError(f"pins {', '.join(who)} fall on the same vertex of the model; remove one of them")
    return idx


class Animator:
    """ARAP posing of one mesh for one pin set (one factorisation, reused for every frame)."""

    def __init__(self, mesh: Mesh, anim: Animation) -> None:
        self.mesh = mesh
        self.ids = tuple(p.id for p in anim.pins)
        self.rests = np.array([p.rest for p in anim.pins], dtype=np.float64).reshape(-1, 3)
        self.handles = attach_pins(mesh.V, self.rests, list(self.ids))
        self.solver = ArapSolver(mesh.V, mesh.F, self.handles) if len(self.handles) else None

    def fits(self, mesh: Mesh, anim: Animation) -> bool:
        """True when this animator's factorisation serves ``anim`` on ``mesh`` (same pins)."""
        if mesh is not self.mesh or tuple(p.id for p in anim.pins) != self.ids:
            return False
        rests = np.array([p.rest for p in anim.pins], dtype=np.float64).reshape(-1, 3)
        if np.array_equal(rests, self.rests):
            return True  # asked on every frame: no nearest-vertex search when nothing moved
        return np.array_equal(attach_pins(mesh.V, rests, list(self.ids)), self.handles)

    def frames(self, anim: Animation, count: int):
        """Yield ``count`` frames (n,3) float64 from frame 0, in order."""
        if self.solver is None:
            for _ in range(count):
                yield np.array(self.mesh.V)
            return
        self.solver.reset()
        P = np.array(self.mesh.V)
        for f in range(count):
            P = self.solver.solve(anim.targets(f), P, INITIAL_ITERATIONS if f == 0 else FRAME_ITERATIONS)
            yield P

    def frame(self, anim: Animation, frame: int) -> np.ndarray:
        """Frame ``frame`` (n,3) float64 (computes the frames before it, in order)."""
        if frame < 0:
            raise ParameterError(f"a frame number must be 0 or more, got {frame}")
        P = None
        for P in self.frames(anim, frame + 1):  # noqa: B007 - run to the last frame, keep it
            pass
        return P

    def drag(self, targets: np.ndarray, previous: np.ndarray, iterations: int = FRAME_ITERATIONS) -> np.ndarray:
        """Interactive step: ``iterations`` steps towards ``targets`` (k,3) from ``previous`` (n,3)."""
        if self.solver is None:
            return np.array(self.mesh.V)
        return self.solver.solve(targets, previous, iterations)


_last: Animator | None = None


@atexit.register
def _forget() -> None:
    # libigl's factorisation object must go before the interpreter tears its bindings down
    # (nanobind reports a leak otherwise)
    global _last
    _last = None


def animator_for(mesh: Mesh, anim: Animation) -> Animator:
    """An animator for ``anim`` on ``mesh``, reusing the last factorisation when it fits."""
    global _last
    if _last is None or not _last.fits(mesh, anim):
        _last = Animator(mesh, anim)
    return _last


def posed_mesh(mesh: Mesh, anim: Animation, frame: int) -> Mesh:
    """The model posed at ``frame``: same triangles (and rim pairs, for an assembled model),
    moved vertices."""
    P = animator_for(mesh, anim).frame(anim, frame)
    # a posed surface keeps no outline (it is no height field); an assembled model keeps its
    # rim pairs, whose normals the renderers share
    return dataclasses.replace(mesh, V=P) if isinstance(mesh, AssembledMesh) else Mesh(P, mesh.F)
