"""A third-party plugin as a solver author would write it from the plugin guide: an inflater and
a sculpt solver with their own parameters, importing only ``sketchforge.plugin_api``
(tests/test_solver_registries.py registers it through the shipped fixtures).

``rings``  inflater: concentric copies of a star-shaped outline shrunk towards its centroid,
           heights ``height`` · sqrt(1 - s²) (a dome); ``rings`` copies.
``probe``  sculpt solver: a Gaussian ridge along the stroke, of width ``radius`` edge lengths,
           whose signed height is the best of ``amplitudes`` tries by the host's own measure
           (``problem.distance_after``): crude, but it uses the contract end to end.
"""

from __future__ import annotations

import numpy as np

from sketchforge.plugin_api import (
    ContourError,
    Inflater,
    Mesh,
    SculptSolution,
    SculptSolver,
    hookimpl,
    number,
    validate_params,
)

RINGS_DEFAULTS = {"height": 1.0, "rings": 12}
RINGS_CHECKS = {"height": number("height", 0.0, 100.0), "rings": number("rings", 2, 200, integer=True)}


def rings_params(params) -> dict:
    return validate_params(params, RINGS_DEFAULTS, RINGS_CHECKS)


def rings_inflate(points, closed, params, holes):
    P = np.asarray(points, dtype=np.float64)
    # A point repeated (the closing one, a mouse resting) would give flat rings: drop them.
    keep = np.r_[True, np.linalg.norm(np.diff(P, axis=0), axis=1) > 1e-9]
    P = P[keep]
    if len(P) > 1 and np.linalg.norm(P[0] - P[-1]) <= 1e-9:
        P = P[:-1]
    if len(P) < 3:
        raise ContourError("rings: an outline needs at least 3 points")
    area = 0.5 * float(np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1]))
    if area < 0:
        P = P[::-1]
    n, k = len(P), int(params["rings"])
    c = P.mean(axis=0)
    s = np.linspace(1.0, 0.0, k + 1)[:-1]  # ring scale: 1 is the outline
    V = [np.c_[c + si * (P - c), np.full(n, params["height"] * np.sqrt(max(1.0 - si * si, 0.0)))] for si in s]
    V.append([[c[0], c[1], params["height"]]])
    V = np.vstack(V)
    F = []
    for r in range(k - 1):
        a, b = r * n, (r + 1) * n
        for i in range(n):
            j = (i + 1) % n
            F += [[a + i, a + j, b + j], [a + i, b + j, b + i]]
    centre, last = k * n, (k - 1) * n
    F += [[last + i, last + (i + 1) % n, centre] for i in range(n)]
    return Mesh(V, np.array(F, dtype=np.int64), np.arange(n))


PROBE_DEFAULTS = {"radius": 3.0, "amplitudes": 8}
PROBE_CHECKS = {"radius": number("radius", 0.5, 50.0), "amplitudes": number("amplitudes", 1, 32, integer=True)}


def probe_params(params) -> dict:
    return validate_params(params, PROBE_DEFAULTS, PROBE_CHECKS)


def probe_solve(problem, params) -> SculptSolution:
    w = params["radius"] * problem.h
    d = problem.distance_to_stroke(problem.V[:, :2], 4.0 * w)
    ridge = np.exp(-((d / w) ** 2)) * ~problem.is_rim
    best, best_after = np.zeros(len(d)), problem.before
    for k in range(params["amplitudes"]):
        for sign in (1.0, -1.0):
            dz = sign * problem.h * 0.5 * 2.0 ** (k / 2) * ridge
            after = problem.distance_after(np.maximum(problem.z + dz, 0.0))
            if after < best_after:
                best, best_after = dz, after
    return SculptSolution(best, info={"tried": 2 * params["amplitudes"]})


class ThirdPartySolvers:
    """The plugin object (a package would register its module through an entry point)."""

    @hookimpl
    def sketchforge_inflaters(self):
        return [Inflater("rings", rings_inflate, check_params=rings_params, version="2", holes=False,
                         description="concentric rings (a test plugin)")]

    @hookimpl
    def sketchforge_sculpt_solvers(self):
        return [SculptSolver("probe", probe_solve, check_params=probe_params, version="3", label="Probe ridge")]
