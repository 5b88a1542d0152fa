"""The move / scale / rotate handles of the selected part, headless: where they are for an
outline at a zoom, which one a point hits, and the 2x3 affine a drag of it means. The canvas
draws :func:`handle_lines` and, at the end of a drag, pushes one ``transform_layer`` with
:func:`drag_matrix` (one undo step per drag)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sketchforge.document.commands import rotate_about, scale_about

#: Screen sizes, in pixels: the half-size of a handle square and its pick radius, and how far
#: above the box the rotate knob sits.
HANDLE_PIXELS = 5.0
PICK_PIXELS = 8.0
ROTATE_PIXELS = 28.0
#: A scale drag is clamped to this range per gesture (a drag through the opposite corner
#: would collapse or mirror the part).
MIN_SCALE, MAX_SCALE = 0.05, 20.0


@dataclass(frozen=True)
class Handles:
    """The handle set of an outline at one zoom.

    lo, hi : (2,) float64, the outline's bounding box (drawing units).
    corners : (4, 2) float64, counter-clockwise from the lower left (scale handles).
    center : (2,) float64, the box centre (move handle; scale and rotate pivot).
    knob : (2,) float64, the rotate handle above the top edge's middle.
    pixel : float, drawing units per screen pixel.
    """

    lo: np.ndarray
    hi: np.ndarray
    corners: np.ndarray
    center: np.ndarray
    knob: np.ndarray
    pixel: float


def handles_for(outline, pixel: float) -> Handles | None:
    """Handles of ``outline`` (n, 2) float64 at ``pixel`` drawing units per screen pixel;
    None when there is no outline."""
    if outline is None or len(outline) < 2:
        return None
    P = np.asarray(outline, dtype=np.float64)
    lo, hi = P.min(axis=0), P.max(axis=0)
    corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    center = 0.5 * (lo + hi)
    knob = np.array([center[0], hi[1] + ROTATE_PIXELS * pixel])
    return Handles(lo, hi, corners, center, knob, float(pixel))


def hit(h: Handles | None, p) -> str | None:
    """Which handle the point ``p`` (2,) grabs: "rotate", "scale0".."scale3" (a corner),
    "move" (the centre marker) or None."""
    if h is None:
        return None
    p = np.asarray(p, dtype=np.float64).reshape(2)
    r = PICK_PIXELS * h.pixel
    if np.linalg.norm(p - h.knob) <= r:
        return "rotate"
    d = np.linalg.norm(h.corners - p, axis=1)
    if d.min() <= r:
        return f"scale{int(np.argmin(d))}"
    # Only the centre marker moves: a drag anywhere else inside the part must still draw (a
    # limb or an eye is drawn over its host, a stretch redrawn from the outline).
    if np.linalg.norm(p - h.center) <= r:
        return "move"
    return None


def drag_matrix(h: Handles, kind: str, start, now) -> np.ndarray:
    """The (2, 3) affine of dragging handle ``kind`` from ``start`` to ``now`` (2,): a move
    by the drag; a uniform scale about the opposite corner by how far the corner moved along
    its diagonal (clamped to [MIN_SCALE, MAX_SCALE]); a rotation about the centre by the angle
    the pointer swept."""
    start = np.asarray(start, dtype=np.float64).reshape(2)
    now = np.asarray(now, dtype=np.float64).reshape(2)
    if kind == "move":
        d = now - start
        return np.array([[1.0, 0.0, d[0]], [0.0, 1.0, d[1]]])
    if kind.startswith("scale"):
        i = int(kind[5:])
        opp = h.corners[(i + 2) % 4]
        diag = h.corners[i] - opp
        n2 = float(diag @ diag)
        s = float((now - opp) @ diag) / n2 if n2 > 0 else 1.0
        return scale_about(opp, float(np.clip(s, MIN_SCALE, MAX_SCALE)))
    if kind == "rotate":
        a0 = np.arctan2(*(start - h.center)[::-1])
        a1 = np.arctan2(*(now - h.center)[::-1])
        return rotate_about(h.center, float(a1 - a0))
    raise ValueError(f"unknown handle {kind!r}")


def is_identity(A) -> bool:
    return bool(np.array_equal(np.asarray(A, dtype=np.float64), np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])))


def apply(A, P) -> np.ndarray:
    """Points P (n, 2) under the affine A (2, 3)."""
    A = np.asarray(A, dtype=np.float64)
    return np.asarray(P, dtype=np.float64) @ A[:, :2].T + A[:, 2]


def handle_lines(h: Handles | None) -> list[np.ndarray]:
    """Polylines (each (k, 2) float64, drawing units) that draw the handle set: the box, a
    square at each corner, the centre cross, the rotate knob on its stem."""
    if h is None:
        return []
    s = HANDLE_PIXELS * h.pixel
    sq = np.array([[-s, -s], [s, -s], [s, s], [-s, s], [-s, -s]])
    t = np.linspace(0.0, 2.0 * np.pi, 17)
    lines = [np.vstack([h.corners, h.corners[:1]])]
    lines += [c + sq for c in h.corners]
    lines += [h.center + 1.6 * sq, h.center + [[-s, 0.0], [s, 0.0]], h.center + [[0.0, -s], [0.0, s]]]
    top = np.array([h.center[0], h.hi[1]])
    lines += [np.vstack([top, h.knob - [0.0, s]]), h.knob + s * np.column_stack([np.cos(t), np.sin(t)])]
    return lines
