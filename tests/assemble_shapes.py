"""Shapes the assembly tests draw (ellipses and arcs as stroke points, inflated by the real
inflate plugin), and an assembly whose depth problem and settled answer are caught on their
way through it."""

from __future__ import annotations

import numpy as np


def ellipse(cx, cy, a, b, n=48):
    """(n, 2) float64 points of an ellipse, counter-clockwise."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[cx + a * np.cos(t), cy + b * np.sin(t)]


def arc(cx, cy, r, a0, a1, n=40):
    """(n, 2) float64 points of a circular arc from a0 to a1 degrees."""
    t = np.radians(np.linspace(a0, a1, n))
    return np.c_[cx + r * np.cos(t), cy + r * np.sin(t)]


def inflate(points, closed, res=0.05):
    """The layer mesh of a stroke: ``sketchforge_inflate.inflate_stroke`` at resolution ``res``."""
    from sketchforge_inflate import inflate_stroke

    return inflate_stroke(points, closed=closed, params={"resolution": res, "inflation": 1.0, "smoothing": 0.5})


def assemble_caught(meshes, closed=None, params=None):
    """(result, got): ``assemble_detailed`` with spies on ``build_problem`` (its arguments in
    ``got["args"]``/``got["kw"]``, its answer in ``got["out"]``) and ``settle_free_parts`` (its
    answer in ``got["settled"]``); ``got["wall"]``: the assembly's wall time (s)."""
    import time

    import sketchforge_assemble.assemble as asm

    got = {}
    build, settle = asm.build_problem, asm.settle_free_parts

    def spy_build(*args, **kw):
        got["args"], got["kw"] = args, kw
        got["out"] = build(*args, **kw)
        return got["out"]

    def spy_settle(*args, **kw):
        got["settled"] = settle(*args, **kw)
        return got["settled"]

    asm.build_problem, asm.settle_free_parts = spy_build, spy_settle
    try:
        t0 = time.perf_counter()
        res = asm.assemble_detailed(list(meshes), None if closed is None else list(closed), params=params)
        got["wall"] = time.perf_counter() - t0
    finally:
        asm.build_problem, asm.settle_free_parts = build, settle
    return res, got
