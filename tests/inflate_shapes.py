"""Test strokes for the contour and inflate tests (deterministic)."""

from __future__ import annotations

import numpy as np


def _polygon(corners, per_edge: int) -> np.ndarray:
    C = np.asarray(corners, dtype=np.float64)
    t = np.linspace(0.0, 1.0, per_edge, endpoint=False)[:, None]
    return np.vstack([C[i] + (C[(i + 1) % len(C)] - C[i]) * t for i in range(len(C))])


def circle(n=400, radius=1.0, turns=1.0, start=0.0, center=(0.0, 0.0), clockwise=False):
    t = start + np.linspace(0.0, 2 * np.pi * turns, n, endpoint=turns != 1.0)
    if clockwise:
        t = -t
    return np.column_stack([center[0] + radius * np.cos(t), center[1] + radius * np.sin(t)])


def ellipse(n=600, a=1.5, b=1.0):
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([a * np.cos(t), b * np.sin(t)])


def star(n=5, r_out=1.0, r_in=0.45, per_edge=20):
    """A star outline and its 2n corners (tips first at even indices)."""
    ang = np.pi / 2 + np.arange(2 * n) * np.pi / n
    rad = np.where(np.arange(2 * n) % 2 == 0, r_out, r_in)
    C = np.column_stack([rad * np.cos(ang), rad * np.sin(ang)])
    return _polygon(C, per_edge), C


def letter_m():
    """A thick letter "m": an outline with two deep notches from below."""
    C = [[0, 0], [0.25, 0], [0.25, 0.6], [0.5, 0.6], [0.5, 0], [0.75, 0], [0.75, 0.6], [1.0, 0.6],
         [1.0, 0], [1.25, 0], [1.25, 0.85], [1.1, 1.0], [0.15, 1.0], [0, 0.85]]
    return _polygon(C, 15)


def figure_eight(n=400):
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([np.sin(t), np.sin(t) * np.cos(t)])


def min_angles(V, F):
    """Smallest angle (degrees) of each triangle, from the x, y columns of V."""
    P = np.asarray(V)[:, :2]
    out = np.full(len(F), 180.0)
    for k in range(3):
        a, b, c = P[F[:, k]], P[F[:, (k + 1) % 3]], P[F[:, (k + 2) % 3]]
        u, v = b - a, c - a
        cos = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        out = np.minimum(out, np.degrees(np.arccos(np.clip(cos, -1, 1))))
    return out


def signed_face_areas(V, F):
    P = np.asarray(V)[:, :2]
    a, b, c = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
