"""The height solve behind a sculpt (thesis 4.5-4.6 in this product's least-squares form), on its
own: what it does with no free vertex, with a shading already met, and with a vertex asked to
be brighter (with its one ring free, and alone)."""

from __future__ import annotations

import numpy as np

from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge_isophote_tool.heights import solve_heights
from sketchforge_isophote_tool.layerdata import layer_data
from sketchforge_isophote_tool.testing import LIGHT, inflated


def _layer():
    return layer_data(inflated("ellipse", 0.04), LIGHT, LAMBERTIAN)


def _brighter(ld, at, ring=True):
    """(v, U, target): the vertex nearest ``at`` asked to be 0.05 brighter, everything else as
    it is; free: that vertex, with its one ring when ``ring``."""
    v = int(np.argmin(np.linalg.norm(ld.planar.V2 - at, axis=1)))
    F = ld.mesh.F
    U = np.zeros(len(ld.z), bool)
    U[np.unique(F[(F == v).any(axis=1)]) if ring else v] = True
    target = ld.E.copy()
    target[v] += 0.05
    return v, U, target


def _shading_after(ld, dz):
    return layer_data(ld.mesh.with_heights(ld.z + dz), LIGHT, LAMBERTIAN).E


def test_no_free_vertex_changes_nothing():
    ld = _layer()
    n = len(ld.z)
    dz = solve_heights(ld, ld.E + 0.1, np.zeros(n, bool), np.ones(n), 1.0)
    assert dz.shape == (n,) and not dz.any()


def test_a_shading_already_met_changes_nothing():
    ld = _layer()
    n = len(ld.z)
    U = np.zeros(n, bool)
    U[np.setdiff1d(np.arange(n), ld.mesh.boundary)[::3]] = True
    dz = solve_heights(ld, ld.E.copy(), U, np.ones(n), 1.0)
    assert np.abs(dz).max() <= 1e-12


def test_a_vertex_asked_to_be_brighter_gets_closer_and_only_its_region_moves():
    # the vertex nearest (0.2, -0.1), asked to be 0.05 brighter; free: it and its one ring (a
    # vertex's shading reads its neighbours' heights). Only they move, and the misfit over them
    # drops by more than half (to 0.33 of it, measured).
    ld = _layer()
    v, U, target = _brighter(ld, [0.2, -0.1])
    dz = solve_heights(ld, target, U, np.ones(len(U)), 0.01)
    assert set(np.flatnonzero(dz)) <= set(np.flatnonzero(U)) and np.abs(dz).max() > 1e-4
    after = _shading_after(ld, dz)
    misfit = lambda E: float(np.sum((E[U] - target[U]) ** 2))  # noqa: E731
    assert misfit(after) < 0.5 * misfit(ld.E)
    assert after[v] > ld.E[v] + 0.02  # 0.027 measured


def test_a_single_free_vertex_is_solved_too():
    # one free vertex can do little (its shading reads mostly its neighbours' heights), but what
    # it can do it does: it moves, and its shading rises towards the brighter target
    ld = _layer()
    v, U, target = _brighter(ld, [0.5, 0.2], ring=False)
    dz = solve_heights(ld, target, U, np.ones(len(U)), 0.01)
    assert np.flatnonzero(dz).tolist() == [v]
    after = _shading_after(ld, dz)
    assert after[v] - ld.E[v] > 5e-5  # 1.4e-4 measured


def test_one_gauss_newton_step_already_goes_downhill():
    # the first step is the direct solve of the linearised problem: alone, it must lower the
    # misfit (later steps refine from where it leaves the surface)
    ld = _layer()
    _, U, target = _brighter(ld, [0.2, -0.1])
    misfit = lambda E: float(np.sum((E[U] - target[U]) ** 2))  # noqa: E731
    for steps in (1, 2):
        dz = solve_heights(ld, target, U, np.ones(len(U)), 0.01, steps=steps)
        assert misfit(_shading_after(ld, dz)) < 0.6 * misfit(ld.E), steps
