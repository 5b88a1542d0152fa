"""Isophote sculpt tool (thesis 4.3-4.6): redraw an isophote, recompute the heights it affects.

Public API
----------
sculpt(mesh, light, pick, band, stroke, model=LAMBERTIAN, solver=None, params=None) -> SculptResult
    The numerical edit as a pure function (see :mod:`.pipeline`); ``solver`` a SculptSolver
    (default :data:`GAUSS_NEWTON`, the built-in), ``params`` its parameters.
SculptResult, DEFAULT_OPTIONS (``gauss_newton``'s default parameters), GAUSS_NEWTON
warm_up()
    Compile the JAX solvers ahead of the first edit (background thread).
SculptIsophote, SculptIsophoteTool
    The ``sculpt_isophote`` command and the gesture tool (registered by :mod:`.plugin`).

Submodules import JAX lazily where possible: importing this package does not import JAX.
"""

from __future__ import annotations


def __getattr__(name):
    if name in ("sculpt", "SculptResult"):
        from . import pipeline as _s

        return getattr(_s, name)
    if name in ("DEFAULT_OPTIONS", "GAUSS_NEWTON"):
        from . import gauss_newton as _g

        return _g.DEFAULT_PARAMS if name == "DEFAULT_OPTIONS" else _g.GAUSS_NEWTON
    if name == "warm_up":
        from .warmup import warm_up

        return warm_up
    if name == "SculptIsophote":
        from .command import SculptIsophote

        return SculptIsophote
    if name == "SculptIsophoteTool":
        from .tool import SculptIsophoteTool

        return SculptIsophoteTool
    raise AttributeError(name)


__all__ = ["sculpt", "SculptResult", "DEFAULT_OPTIONS", "GAUSS_NEWTON", "warm_up", "SculptIsophote", "SculptIsophoteTool"]
