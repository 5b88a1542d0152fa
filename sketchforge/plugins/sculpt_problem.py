"""What a sculpt solver receives and returns (the ``sketchforge_sculpt_solvers`` contract).

The sculpt host (the isophote tool plugin) does the part every solver shares: it picks the
isophote E = c, builds the band around it, cleans the redrawn stroke and clips it to the band.
It hands a :class:`SculptProblem` to the named :class:`~sketchforge.plugins.solvers.SculptSolver`,
which returns the change of height (a :class:`SculptSolution`). The host then keeps the rim at
0 and heights at >= 0, refuses non-finite values, and keeps the edit only if the isophote ends
no farther from the stroke than it started (trying half and a quarter of the change).

Everything is plain numpy (float64, int64) in drawing units; shapely geometries where a
region is one. The services (:meth:`SculptProblem.shading`, :meth:`~SculptProblem.shading_change`,
:meth:`~SculptProblem.distance_after`, :meth:`~SculptProblem.locate`) are the host's, so a
solver evaluates candidate heights exactly as the app will shade them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class SculptProblem:
    """One isophote edit on one layer.

    Attributes
    ----------
    V : (n, 3) float64
        The layer's vertices before the edit (x, y in the drawing plane, z the height).
    F : (m, 3) int64
        Its triangles, counter-clockwise seen from +z.
    is_rim : (n,) bool
        Vertices on the outline or a hole's rim: their height stays 0.
    light : (3,) float64
        Unit direction towards the light, anywhere on the hemisphere facing the viewer
        (z >= 0: in the drawing plane as in the thesis, tilted, or straight overhead).
    model : ReflectanceModel
        The reflectance the edit inverts; ``model.R(n, l)`` is written with ``jax.numpy``.
    E : (n,) float64
        The shading now (signed R at the vertices' display slopes).
    Rp, Rq : (n,) float64
        ∂R/∂p and ∂R/∂q there (properties: evaluated on first use, once per layer state).
    p, q : (n,) float64
        The vertices' display slopes (∂z/∂x, ∂z/∂y) (likewise).
    h : float
        Mean edge length.
    c : float
        The isovalue: the redrawn stroke is where E should become c.
    pick : (2,) float64
    isophote : (j, 2) float64
        The picked isophote (the component of E = c through the pick), as a polyline.
    band : shapely (Multi)Polygon
        Where the shading may change (the picked isophote ⊕ a disk of ``band_radius``,
        clipped to the layer).
    band_radius : float
    in_band : (n,) bool
        Vertices inside the band.
    stroke : list of (k_i, 2) float64
        The cleaned stroke, clipped to the band (one or more pieces, ordered along it).
    samples : (k, 2) float64
        Quadrature points along the stroke for a line integral ∫ f ds ≈ Σ w_k f(P_k).
    sample_weights : (k,) float64
        Their weights, faded to 0 inside the rim margin (where no isophote is promised).
    d_rim : (n,) float64
        Distance of each vertex to the nearest rim.
    rim_margin : (n,) float64
        The rim margin at each vertex (max(3h, 0.12·size), less where the layer is thin): the
        strip along the rim where the surface turns vertical and no isophote is promised.
    outline : shapely Polygon
        The layer, holes cut out.
    Q : (n, n) scipy.sparse.csr_matrix float64
        The layer's squared Laplacian Lᵀ M⁻¹ L (cotangent L, lumped M): minimising xᵀ Q x
        over some vertices with the others fixed is a smooth (C¹) fill.
    before : float
        Mean distance from the stroke (where an isophote is promised) to the isophote now.
    parts : tuple of SculptProblem
        Empty for an edit of one isophote. For a joint edit of several (``sculpt_isophotes``,
        given only to a solver with ``several_isophotes``): one complete problem per isophote,
        each with its own ``c``, ``pick``, ``isophote``, ``band``, ``band_radius``, ``in_band``,
        ``stroke``, ``samples`` and ``before``. The joint problem itself then holds the union
        of the bands (``band``, ``in_band``; ``band_radius`` the largest), every stroke piece
        (``stroke``), every sample (``samples``, ``sample_weights``, ``sample_values``), and
        the first part's ``c``, ``pick`` and ``isophote``; its services act on all the strokes
        (:meth:`shading_change` asks each sample for its own value, :meth:`distance_to_stroke`
        is to the nearest stroke, :meth:`distance_after` the mean over every stroke's samples
        of the distance to its own isophote).
    crease_bound : float
        Degrees: the largest dihedral angle an edit should leave across an interior edge (both
        ends 3 edge lengths or more from the rim) that has less now. The host makes it 2.4 times
        the layer's largest as inflated, before any edit (at most 30), so that a chain of edits
        stays within 2.5 times the fresh layer's creases; 30 when it does not know that layer.
    jump_bound : float
        Likewise for the jump of the vertex shading across such an edge (inf when the host does
        not know the fresh layer).
    host_data : object
        The host's own data for the solvers it ships itself; other solvers must not use it.
    """

    V: np.ndarray
    F: np.ndarray
    is_rim: np.ndarray
    light: np.ndarray
    model: Any
    E: np.ndarray
    h: float
    c: float
    pick: np.ndarray
    isophote: np.ndarray
    band: Any
    band_radius: float
    in_band: np.ndarray
    stroke: list
    samples: np.ndarray
    sample_weights: np.ndarray
    d_rim: np.ndarray
    rim_margin: np.ndarray
    outline: Any
    Q: Any
    before: float
    _slopes: Callable = field(repr=False, default=None)
    _shading: Callable = field(repr=False, default=None)
    _shading_change: Callable = field(repr=False, default=None)
    _distance_after: Callable = field(repr=False, default=None)
    _locate: Callable = field(repr=False, default=None)
    _distance_to_stroke: Callable = field(repr=False, default=None)
    host_data: Any = field(repr=False, default=None)
    parts: tuple = ()
    crease_bound: float = 30.0
    jump_bound: float = math.inf
    _sample_values: Any = field(repr=False, default=None)

    @property
    def sample_values(self) -> np.ndarray:
        """(k,) float64: the shading each sample of :attr:`samples` asks for: ``c`` for an edit
        of one isophote; each stroke's own isovalue in a joint edit, or, when the host retries
        a joint edit with part of one stroke's change (its never-worse fallback),
        E + f·(c − E) there."""
        if self._sample_values is None:
            return np.full(len(self.samples), self.c)
        return self._sample_values

    @property
    def z(self) -> np.ndarray:
        """(n,) float64: the heights before the edit."""
        return self.V[:, 2]

    @property
    def n(self) -> int:
        return len(self.V)

    # The slopes and R's gradient: only some solvers need them (gauss_newton linearises on
    # its own), so they are evaluated when first read.
    @property
    def p(self) -> np.ndarray:
        return self._slopes()[0]

    @property
    def q(self) -> np.ndarray:
        return self._slopes()[1]

    @property
    def Rp(self) -> np.ndarray:
        return self._slopes()[3]

    @property
    def Rq(self) -> np.ndarray:
        return self._slopes()[4]

    def shading(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Shading of candidate heights ``z`` (n,), as the app would show it: E, R_p, R_q (n,)."""
        return self._shading(np.asarray(z, dtype=np.float64))

    def shading_change(self, free: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
        """The smoothest change of shading δE (n,) that is 0 off the ``free`` vertices (n,) bool
        and makes E + δE = c along the stroke (each sample's :attr:`sample_values` in a joint
        edit) (thesis 4.4.1, on the layer's own triangles: the
        stroke enters as a line integral, so no remeshing and no native triangulation).
        ``weights`` (k,) replace :attr:`sample_weights` (e.g. to fade the stroke out where
        the solver cannot act)."""
        w = self.sample_weights if weights is None else np.asarray(weights, dtype=np.float64)
        return self._shading_change(np.asarray(free, dtype=bool), w)

    def distance_after(self, z: np.ndarray) -> float:
        """Mean distance from the stroke to the isophote E = c of heights ``z`` (n,): what the
        host's never-worse check compares with :attr:`before`."""
        return self._distance_after(np.asarray(z, dtype=np.float64))

    def locate(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The triangle (k,) int64 (-1 outside the layer) and barycentric coordinates (k, 3)
        of points P (k, 2)."""
        return self._locate(np.asarray(P, dtype=np.float64).reshape(-1, 2))

    def distance_to_stroke(self, P: np.ndarray, upper: float) -> np.ndarray:
        """Distance (k,) from points P (k, 2) to the stroke, capped at ``upper`` (continuous
        in the stroke and the points)."""
        return self._distance_to_stroke(np.asarray(P, dtype=np.float64).reshape(-1, 2), float(upper))

    def interpolate(self, values: np.ndarray, P: np.ndarray) -> np.ndarray:
        """Barycentric interpolation of per-vertex ``values`` (n,) or (n, k) at points P (j, 2);
        NaN outside the layer."""
        values = np.asarray(values, dtype=np.float64)
        face, bary = self.locate(P)
        inside = face >= 0
        out = np.full((len(face),) + values.shape[1:], np.nan)
        idx = self.F[face[inside]]
        b = bary[inside]
        out[inside] = np.einsum("kj,kj...->k...", b, values[idx])
        return out


@dataclass
class SculptSolution:
    """What a sculpt solver returns.

    Attributes
    ----------
    dz : (n,) float64
        The change of height at every vertex (0 where nothing changes; the host keeps the rim
        at 0 and clamps heights at 0).
    dE : (n,) float64 or None
        The change of shading the solver aimed at, for display and reports.
    shading_region, height_region : shapely geometry or None
        Where the shading was allowed to change, and where heights could change ("show edit
        region" in the app).
    curves : list of (k, 2) float64
        Curves to draw with "show characteristics" (e.g. the strips integrated).
    info : dict
        Numbers for reports (counts, seconds); JSON values.
    """

    dz: np.ndarray
    dE: np.ndarray | None = None
    shading_region: Any = None
    height_region: Any = None
    curves: list = field(default_factory=list)
    info: dict = field(default_factory=dict)
