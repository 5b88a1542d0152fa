"""Stroke -> inflated, faired height-field Mesh (thesis 3.2 and 4.2).

Pipeline: :func:`prepare_outline` (validate, thin, trim overshoot, orient) -> vertex budget
check (before any array of the target resolution exists) -> :func:`resample_outline` (smooth
jitter, resample) -> :func:`triangulate_polygon` -> cotangent Laplacian and mass matrix (built
once, shared by the two solves) -> inflation -> fairing.

Parameters and units
--------------------
resolution : target edge length in drawing units; a part narrower than 4 edge lengths is meshed
    finer, down to a sixth of its size (:func:`edge_length_for`).
inflation : height scale; 1 turns a disk of radius R into a hemisphere (height R), other
    values into an ellipsoid of revolution of height inflation·R.
smoothing : the fairing weight α of thesis 4.2.1, in [0, 1). The squared-Laplacian energy is
    measured with lengths in units of ``size / SMOOTHING_UNITS_PER_SIZE``, where
    size = 2·area/perimeter (the radius, for a disk). With that unit α = 0.5 smooths the rim
    over ~3% of the size (β = α/(1-α)·unit⁴ ≈ 1e-6·R⁴ for a disk): the rim loses its vertical
    tangent while the height at r = 0.9 R stays within 4% of the ellipsoid and the peak within
    0.1%. The thesis' α = 2·10⁻⁵ in disk-radius units (β = 2e-5·R⁴) drops the height at r = 0.9
    to ~58%, visibly flattening the blob; in our units it is a barely visible smoothing. Tying
    the unit to the shape's size makes the faired shape independent of the drawing's scale and
    of the resolution.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from sketchforge.plugin_api import (
    DEFAULT_INFLATE_PARAMS,
    MAX_VERTICES,
    MIN_ANGLE,
    ContourError,
    FairingSolver,
    LimitError,
    Mesh,
    check_inflate_params,
    check_vertex_budget,
    inflate_heights,
    laplacian_and_mass,
    prepare_holes,
    prepare_outline,
    resample_outline,
    signed_area,
    triangulate_polygon,
)

#: Default parameters (the same object as the document's defaults).
DEFAULT_PARAMS = DEFAULT_INFLATE_PARAMS
#: Fills in defaults and checks values (shared with the document's journal checks).
validate_params = check_inflate_params

#: The fairing energy's length unit is the shape's size (2·area/perimeter) divided by this.
SMOOTHING_UNITS_PER_SIZE = 32.0


def inflate_stroke(points, closed: bool = False, params: Mapping | None = None, *, max_vertices: int = MAX_VERTICES,
                   holes=None) -> Mesh:
    """Turn a drawn stroke into a layer's front surface.

    Parameters
    ----------
    points : (n, 2) array-like of float
        The stroke as drawn (drawing units, x right, y up), either orientation.
    closed : bool
        True: the whole outline is free. False: if the ends are more than about two edge
        lengths apart, the closing segment is the junction Γ_conn.
    params : mapping, optional
        ``resolution``, ``inflation``, ``smoothing`` (see the module docstring); missing keys
        take :data:`DEFAULT_PARAMS`.
    max_vertices : int
        Size limit checked before triangulating.
    holes : sequence of (n_i, 2) array-like of float, optional
        Inner rings cut out of the part, any orientation (see
        :func:`~sketchforge.geometry.contour.prepare_holes` for what is refused). Every ring
        keeps height 0, in the inflation and in the fairing.

    Returns
    -------
    Mesh
        V (n, 3) float64 with z >= 0 and z = 0 exactly on the boundary; F (m, 3) int64
        counter-clockwise from +z; ``boundary`` (k,) the counter-clockwise boundary loop
        (vertices 0..k-1); ``junction`` the Γ_conn vertices in boundary order, both ends
        included, empty for closed outlines; ``holes`` each hole's clockwise loop.

    Raises
    ------
    ContourError, ParameterError, LimitError
    """
    p = validate_params(params)
    outline = prepare_outline(points, p["resolution"], closed=bool(closed))
    # The size needs the holes' rings, and those are resampled against the contour: with holes
    # the part is resampled as asked first (and again if narrow); without, only once.
    asked = _contour_and_holes(outline, holes, max_vertices) if holes is not None and len(holes) else None
    size = _size(outline, asked[1] if asked else [])
    fine = edge_length_for(size, outline.edge_length)
    contour_rings = None
    if fine < outline.edge_length:
        try:
            contour_rings = _contour_and_holes(replace(outline, edge_length=fine), holes, max_vertices)
        except (LimitError, ContourError):
            # too many vertices that fine, or a hole too close to the outline for the finer
            # spacing: the part is meshed as asked, never refused for being meshed finer
            pass
    contour, rings = contour_rings or asked or _contour_and_holes(outline, holes, max_vertices)
    tri = triangulate_polygon(contour.points, contour.edge_length, MIN_ANGLE, holes=rings)
    rim = np.concatenate([tri.boundary, *tri.holes]) if rings else tri.boundary
    L, M = laplacian_and_mass(tri.V2, tri.F)
    z = inflate_heights(tri.V2, tri.F, rim, p["inflation"], L, M)
    if p["smoothing"] > 0.0 and p["inflation"] > 0.0:
        z = FairingSolver(L, M, rim, p["smoothing"], size / SMOOTHING_UNITS_PER_SIZE).solve(z)
        # The biharmonic fairing has no maximum principle: it can undershoot by a hair next to
        # the rim. Heights are >= 0 by contract (the boundary stays exactly 0: DirichletSolver
        # copies fixed values).
        z = np.maximum(z, 0.0)
    V = np.column_stack([tri.V2, z])
    return Mesh(V, tri.F, tri.boundary, contour.junction, tri.holes)


#: A part narrower than this many edge lengths (its size, 2·area/perimeter: the radius of a
#: disk, half the width of a long limb) is meshed finer, down to a sixth of its size...
NARROW_SIZE_EDGES = 4.0
#: ...at SIZE_EDGES_FINEST edges across its size...
SIZE_EDGES_FINEST = 6.0
#: ...and never finer than this share of the requested edge length (a long stroke two edges
#: wide gets at most 16 times its triangles, not 36; an eye 1.5 edges in size is not held).
FINEST_SHARE = 0.25


def edge_length_for(size: float, h: float) -> float:
    """The edge length to mesh a part of ``size`` (2·area/perimeter, drawing units) at, for the
    requested edge length ``h``: ``h`` for a part at least NARROW_SIZE_EDGES·h in size, finer
    for a narrower one, h/2 at 3h, then size/6 but at least h/4. A continuous function of
    both: a stroke drawn a hair wider never jumps to another mesh.

    Why. At the default resolution a beak, an ear or an eye is 2-3 edges in size: an eye was
    a faceted lump (interior edges bent by 47 degrees against each other), a beak's tip a
    handful of triangles bent by up to 66 degrees, and where the rim turns at the tip the
    assembled mesh folded by up to 129 degrees (issue 34: 26 of the creature benchmark's 60
    creatures had an edge over 90 degrees, most at a beak; the beak's edges were most of those
    bent over 45 degrees near a junction on 6 of them). Meshed finer, an eye's largest bend is
    22 degrees, 5 creatures keep an edge over 90 (each at a beak's drawn tip), and the beaks'
    bends near their junctions fell under 45 degrees on those 6, for ~10% more vertices.
    Meshing every part under 6h in size finer (limbs too) did the same for the beaks but bent
    the limbs' junctions more: their fairing reaches a fixed number of rings.
    """
    h = float(h)
    fine = max(size / SIZE_EDGES_FINEST, FINEST_SHARE * h, h * (size / h - (NARROW_SIZE_EDGES - 2.0)) / 2.0)
    return float(min(h, fine))


def _size(outline, rings) -> float:
    """2·area/perimeter of the part (the radius, for a disk), holes cut out: with holes, the
    surface's own area and rim length make a ring's band as fine and as smooth as a blob its
    width."""
    area = outline.area - sum(abs(signed_area(r)) for r in rings)
    perimeter = outline.perimeter + sum(float(np.sum(np.linalg.norm(r - np.roll(r, 1, axis=0), axis=1))) for r in rings)
    return 2.0 * area / perimeter


def _contour_and_holes(outline, holes, max_vertices: int):
    """(Contour, holes' rings) of ``outline`` resampled at its edge length, the vertex budget
    checked before anything of that size exists."""
    check_vertex_budget(outline.area, outline.perimeter, outline.edge_length, max_vertices)
    contour = resample_outline(outline)
    # Where the outline comes close to itself it is resampled finer than h, and Triangle grades
    # its triangles down to that: count those points (three interior ones per extra boundary
    # point, generously) before Triangle runs.
    extra = len(contour.points) - outline.perimeter / outline.edge_length
    if extra > 0:
        check_vertex_budget(outline.area, outline.perimeter + 4.0 * extra * outline.edge_length, outline.edge_length, max_vertices)
    return contour, prepare_holes(holes, contour)
