"""Test support shipped with the package: hosts built from an explicit plugin list.

Tests register plugins explicitly (entry points off) so they never depend on what happens to
be installed; :class:`FanInflater` is a tiny deterministic stand-in for the inflate plugin
for tests about the document machinery, not about geometry.
"""

from __future__ import annotations

import numpy as np

from sketchforge.errors import ContourError
from sketchforge.geometry.contour import signed_area
from sketchforge.geometry.mesh import Mesh
from sketchforge.plugins.hookspecs import hookimpl
from sketchforge.plugins.manager import PluginHost
from sketchforge.plugins.solvers import Inflater, number, validate_params


def make_test_host(*plugins, entry_points: bool = False, allowlist=None) -> PluginHost:
    """A host with the core plugin plus ``plugins`` (objects or modules, in order)."""
    return PluginHost.create(plugins, load_entry_points=entry_points, allowlist=allowlist)


def make_host(*plugins, installed=()) -> PluginHost:
    """A plugin host with the core plugin, ``plugins`` (objects or modules, in order) and the
    installed entry points named in ``installed`` (e.g. ``("inflate",)`` for real meshes),
    nothing else that happens to be installed: what a plugin's tests and scripts build a
    document on (``Document(make_host(my_plugin, installed=("inflate",)))``).

    Raises
    ------
    PluginError
        A plugin in ``plugins`` whose hooks cannot be used (a typo in a hook name, a wrapper),
        or an entry point of ``installed`` that is not installed.
    """
    from sketchforge.errors import PluginError

    installed = list(installed)
    host = PluginHost.create(plugins, load_entry_points=bool(installed), allowlist=installed, skip_broken=True)
    missing = [name for name in installed if name not in host.plugin_names()]
    if missing:
        why = "; ".join(host.problems_of(name)[0] if host.problems_of(name) else f"{name!r} is not installed"
                        for name in missing)
        raise PluginError(f"entry points {', '.join(map(repr, missing))} are not available: {why}")
    return host


#: The fan's parameters: the built-in's names, so a document written for it replays with the
#: fan (``resolution`` is accepted and unused).
FAN_DEFAULTS = {"resolution": 0.03, "inflation": 1.0, "smoothing": 0.5}
FAN_CHECKS = {
    "resolution": number("resolution", 0.0, lo_open=True),
    "inflation": number("inflation", 0.0),
    "smoothing": number("smoothing", 0.0, 1.0, hi_open=True),
}


def fan_params(params) -> dict:
    return validate_params(params, FAN_DEFAULTS, FAN_CHECKS)


class FanInflater:
    """The inflater ``"fan"``: a polygon becomes a fan around its vertex centroid, z =
    inflation * params-dependent bump at the centre, 0 on the outline. Not a real inflation;
    fast and exact to compare. It cannot cut holes."""

    @hookimpl
    def sketchforge_inflaters(self):
        return [Inflater("fan", self.inflate, check_params=fan_params, holes=False,
                         description="a fan around the centroid (tests)")]

    def inflate(self, points, closed, params, holes=()):
        P = np.asarray(points, dtype=np.float64)
        if len(P) < 3 or not np.all(np.isfinite(P)):
            raise ContourError("a contour needs at least 3 finite points")
        area = signed_area(P)
        if abs(area) < 1e-12:
            raise ContourError("the contour has zero area")
        if area < 0:
            P = P[::-1]
        n = len(P)
        c = P.mean(axis=0)
        h = float(params.get("inflation", 1.0)) * (1.0 + float(params.get("smoothing", 0.0))) * np.sqrt(abs(area))
        V = np.vstack([np.c_[P, np.zeros(n)], [c[0], c[1], h]])
        F = np.array([[i, (i + 1) % n, n] for i in range(n)], dtype=np.int64)
        junction = np.zeros(0, np.int64) if closed else np.array([n - 1, 0], dtype=np.int64)
        return Mesh(V, F, np.arange(n), junction)
