"""The inflate plugin's hook implementation (registered by the ``sketchforge`` entry point)."""

from __future__ import annotations

from sketchforge.plugins.hookspecs import hookimpl

from sketchforge_inflate.inflate import inflate_stroke


@hookimpl
def sketchforge_inflate(points, closed, params, holes):
    return inflate_stroke(points, closed, params, holes=holes)
