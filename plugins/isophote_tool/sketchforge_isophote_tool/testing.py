"""Test and benchmark support: the thesis' test outlines, inflated through the inflate plugin.

Deterministic; shared by tests/test_sculpt*.py and benchmarks/bench_sculpt.py.
"""

from __future__ import annotations

import functools

import numpy as np

from sketchforge.plugin_api import Mesh

LIGHT = np.array([1.0 / np.sqrt(2.0), 1.0 / np.sqrt(2.0), 0.0])


def ellipse_outline(a: float = 1.0, b: float = 0.7, n: int = 400) -> np.ndarray:
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([a * np.cos(t), b * np.sin(t)])


def pillow_outline(n: int = 400) -> np.ndarray:
    """A convex "pillow": a superellipse |x|^4 + |y|^4 = 1 with rounded corners (fig. 5.1)."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    c, s = np.cos(t), np.sin(t)
    return 0.9 * np.column_stack([np.sign(c) * np.abs(c) ** 0.5, np.sign(s) * np.abs(s) ** 0.5])


def m_outline(per_unit: int = 60) -> np.ndarray:
    """A concave "m" (fig. 5.1): three legs joined at the top, two notches from below,
    centred on the origin."""
    C = np.array([[0, 0], [0.3, 0], [0.3, 0.55], [0.5, 0.55], [0.5, 0], [0.8, 0], [0.8, 0.55], [1.0, 0.55],
                  [1.0, 0], [1.3, 0], [1.3, 0.85], [1.15, 1.0], [0.15, 1.0], [0, 0.85]], float)
    C = (C - [0.65, 0.5]) * 1.4
    out = []
    for i in range(len(C)):
        a, b = C[i], C[(i + 1) % len(C)]
        k = max(int(np.linalg.norm(b - a) * per_unit), 2)
        out.append(a + (b - a) * np.linspace(0, 1, k, endpoint=False)[:, None])
    return np.concatenate(out)


OUTLINES = {"ellipse": ellipse_outline, "pillow": pillow_outline, "m": m_outline}


@functools.lru_cache(maxsize=16)
def inflated(shape: str = "ellipse", resolution: float = 0.04, smoothing: float = 0.5) -> Mesh:
    """An inflated layer of a named outline (cached; meshes are immutable)."""
    from sketchforge_inflate.inflate import inflate_stroke

    return inflate_stroke(OUTLINES[shape](), True, {"resolution": resolution, "inflation": 1.0, "smoothing": smoothing})
