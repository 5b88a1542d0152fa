"""Shapes the assembly tests draw: ellipses and arcs as stroke points, inflated by the real
inflate plugin."""

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
