"""The isophote edit as a pure function: ``sculpt(mesh, light, pick, band, stroke) -> SculptResult``.

Pipeline (thesis 4.3-4.6, see ARCHITECTURE.md steps 4-8):

1. pick -> isovalue c (0 in shadow), isophote through the pick, band = isophote ⊕ disk(band)
2. stroke: smoothed, resampled, clipped to the band
3. region strips from the contour -> S•, B•, B•*, M•                      (regions.py)
4. shading in B•* re-interpolated with e = c on the stroke                 (interp.py)
5. characteristic strips from the entry curve of ∂M•                       (characteristics.py)
6. heights of M•'s vertices by local multiquadric RBF                      (reconstruct.py)
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import shapely

from sketchforge.errors import NothingToDoError, SculptError, SolverError
from sketchforge.geometry import field_jax
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.reflectance import LAMBERTIAN
from sketchforge.plugins.registry import ReflectanceModel

from .characteristics import CHAR_STEPS, SOLVERS, integrate_characteristics
from .interp import LocalShading, interpolate_shading
from .isophote import band_around, picked_isophote
from .layerdata import LayerData, layer_data
from .gaps import StripGaps, insert_strips
from .regions import Regions, compute_regions
from .reconstruct import reconstruct_heights
from .stroke import clip_to_band, even_parameters, polyline_at, prepare_stroke

#: Options of :func:`sculpt` (lengths "in edge lengths" are multiples of the mean edge length h).
DEFAULT_OPTIONS = {
    "solver": "rk4",  # strip solver: "rk4" (fixed step), "tsit5" or "kvaerno5" (diffrax)
    "rtol": 1e-7,  # tolerance of the adaptive solvers
    "rim_margin": None,  # Ω* = layer minus this margin (drawing units); None: max(3h, 0.12·size)
    "shading_energy": "delta",  # "delta" or "absolute" (thesis 4.4.1 as printed), see interp.py
    "max_gap": 2.0,  # neighbouring region strips near the stroke at most this far (edge lengths)
    "seed_spacing": 0.5,  # spacing of characteristic seeds on the entry curve (edge lengths)
    "cover": 1.5,  # refine characteristic seeds until strips are this close (edge lengths)
    "smoothing": 0.05,  # RBF smoothing λ (thesis 4.6.1)
    "kernel_scale": 4.0,  # multiquadric scale (edge lengths): ε = 1 / (kernel_scale · h)
    "neighbors": 40,  # RBF local support size
    "ring": 3.0,  # width of the ring of untouched support vertices (edge lengths)
}

MAX_COVER_ROUNDS = 4


@dataclass
class SculptResult:
    """Outcome of one isophote edit.

    Attributes
    ----------
    mesh : Mesh
        Same V order (only z changed), same F, boundary, junction.
    changed : (n,) bool
        Vertices whose height changed.
    c : float
        The isovalue.
    isophote : shapely LineString
        The selected isophote.
    band : shapely geometry
    stroke : shapely (Multi)LineString
        The cleaned stroke clipped to the band.
    regions : Regions
        S•, B•, B•*, M•, Ω*, the region strips and the entry curve.
    strips : list of (j, 5) float64
        Integrated characteristic strips (x, y, p, q, z).
    shading : LocalShading
        The interpolated shading on B•*.
    timings : dict[str, float]
        Seconds per step.
    options : dict
    """

    mesh: Mesh
    changed: np.ndarray
    c: float
    isophote: object
    band: object
    stroke: object
    regions: Regions
    strips: list
    shading: LocalShading
    timings: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)


def _mask_nodes(ld: LayerData, region, dilate: float) -> np.ndarray:
    """1 on grid nodes inside ``region`` dilated by ``dilate``, else 0 (G, G)."""
    origin, spacing, face, _ = ld.raster
    G = face.shape[0]
    reg = region.buffer(dilate)
    lo = np.clip(np.floor((np.array(reg.bounds[:2]) - origin) / spacing).astype(int), 0, G - 1)
    hi = np.clip(np.ceil((np.array(reg.bounds[2:]) - origin) / spacing).astype(int), 0, G - 1)
    out = np.zeros((G, G))
    ix = np.arange(lo[0], hi[0] + 1)
    iy = np.arange(lo[1], hi[1] + 1)
    X, Y = np.meshgrid(origin[0] + spacing * ix, origin[1] + spacing * iy, indexing="ij")
    out[lo[0] : hi[0] + 1, lo[1] : hi[1] + 1] = shapely.contains_xy(reg, X, Y)
    return out


def edited_field(ld: LayerData, shading: LocalShading):
    """GridField of the edited shading: old E, replaced on B•*'s triangulation."""
    origin, spacing, face, _ = ld.raster
    nodes = ld.E_nodes.copy()
    if len(shading.F):
        f2, b2 = field_jax.rasterize(shading.V, shading.F, origin, spacing, face.shape[0])
        cov = f2 >= 0
        nodes[cov, 0] = np.einsum("kc,kc->k", b2[cov], shading.e[shading.F[f2[cov]]])
    return field_jax.grid_field_from_nodes(nodes, origin, spacing)


def integrate_from_entry(ld, light, model, M, entry, E_field, opts, margin) -> list[np.ndarray]:
    """Seed characteristic strips on the entry curves and refine until they cover M•."""
    h = ld.h
    mask = _mask_nodes(ld, M, 1.5 * float(ld.raster[1]))
    minx, miny, maxx, maxy = M.bounds
    length = 1.5 * float(np.hypot(maxx - minx, maxy - miny)) + 2 * h
    ds = length / CHAR_STEPS
    if opts["solver"] != "rk4":
        ds = 0.5 * h  # initial step of the adaptive solvers
    gaps_of = StripGaps(M)

    def run(P):
        pq = field_jax.eval_points(ld.pq_field, P)[0]
        z = ld.locator.interpolate(ld.z, P)
        y0 = np.column_stack([P, pq, z])
        return integrate_characteristics(
            y0, E_field, mask, ld.dist_nodes, light, model, ds, length, 0.5 * margin, opts["solver"], opts["rtol"]
        )

    params = [even_parameters(P, opts["seed_spacing"] * h) for P in entry]
    pts = [polyline_at(P, t) for P, t in zip(entry, params)]
    flat = run(np.concatenate(pts)) if pts else []
    strips, k = [], 0
    for t in params:
        strips.append(flat[k : k + len(t)])
        k += len(t)
    for _ in range(MAX_COVER_ROUNDS):
        new_pts, where = [], []
        for c, (P, t) in enumerate(zip(entry, params)):
            st = strips[c]
            gaps = gaps_of([(st[i], st[i + 1]) for i in range(len(st) - 1)])
            bad = np.nonzero((gaps > opts["cover"] * h) & (np.diff(t) > 1e-3 * h))[0]
            if len(bad):
                nt = 0.5 * (t[bad] + t[bad + 1])
                new_pts.append(polyline_at(P, nt))
                where.append((c, nt))
        if not new_pts:
            break
        res = run(np.concatenate(new_pts))
        k = 0
        for c, nt in where:
            params[c], strips[c] = insert_strips(params[c], strips[c], nt, res[k : k + len(nt)])
            k += len(nt)
    return [s for st in strips for s in st]


def sculpt(
    mesh: Mesh,
    light,
    pick,
    band: float,
    stroke,
    model: ReflectanceModel = LAMBERTIAN,
    options: dict | None = None,
) -> SculptResult:
    """Redraw the isophote through ``pick`` along ``stroke``; recompute heights where affected.

    Parameters
    ----------
    mesh : Mesh
        The layer's front surface (z >= 0, z = 0 on ``mesh.boundary``).
    light : (3,) float64
        Unit light direction in the drawing plane (z = 0).
    pick : (2,) float64
        A point on the layer; its shading (0 in shadow) is the isovalue c.
    band : float
        Radius of the band around the isophote (drawing units, > 0).
    stroke : (k, 2) float64
        The redrawn isophote; parts outside the band are ignored.
    model : ReflectanceModel
        Solver-side reflectance (any registered model).
    options : dict or None
        Overrides of :data:`DEFAULT_OPTIONS`.

    Returns
    -------
    SculptResult

    Raises
    ------
    SculptError
        Invalid pick, band or stroke (the message says which).
    NothingToDoError
        The edit changes nothing (e.g. empty impacted region).
    SolverError
        A solver produced non-finite values.
    """
    opts = dict(DEFAULT_OPTIONS)
    if options:
        unknown = set(options) - set(DEFAULT_OPTIONS)
        if unknown:
            raise SculptError(f"unknown sculpt options: {sorted(unknown)}")
        opts.update(options)
    if opts["shading_energy"] not in ("delta", "absolute"):
        raise SculptError(f"unknown shading energy {opts['shading_energy']!r}; choose 'delta' or 'absolute'")
    if opts["solver"] not in SOLVERS:
        raise SculptError(f"unknown strip solver {opts['solver']!r}; choose one of {list(SOLVERS)}")
    try:
        band = float(band)
    except (TypeError, ValueError):
        raise SculptError(f"the band radius must be a number, got {band!r}") from None
    if not (np.isfinite(band) and band > 0):
        raise SculptError(f"the band radius must be a positive number, got {band}")
    light = np.asarray(light, np.float64).reshape(3)
    T = {}
    t0 = time.perf_counter()
    ld = layer_data(mesh, light, model)
    h = ld.h
    # Near the rim p, q are large and a small error in them is a large error in z: strips
    # started or run closer than ~3 edge lengths from the contour drift (measured: 8% of the
    # peak on the pillow with a 2h margin, 1% with 4h).
    # The default is also tied to the layer's size (2·area/perimeter, the radius of a disk) so
    # the same edit at two resolutions recomputes the same region.
    size = 2.0 * ld.outline.area / ld.outline.length
    margin = max(3.0 * h, 0.12 * size) if opts["rim_margin"] is None else float(opts["rim_margin"])
    T["layer"] = time.perf_counter() - t0

    t = time.perf_counter()
    c, iso = picked_isophote(ld, pick)
    P = prepare_stroke(stroke, h)
    band_geom = band_around(ld, iso, band)
    pieces = clip_to_band(P, band_geom, h)
    stroke_geom = shapely.MultiLineString(pieces) if len(pieces) > 1 else shapely.LineString(pieces[0])
    T["isophote"] = time.perf_counter() - t

    t = time.perf_counter()
    regions = compute_regions(ld, light, model, band_geom, stroke_geom, margin, opts["max_gap"] * h, timings=T)
    T["regions"] = time.perf_counter() - t - T.get("strips", 0.0)
    if not regions.entry:
        raise NothingToDoError("no strip enters the impacted region inside the rim margin")

    t = time.perf_counter()
    shading = interpolate_shading(ld, regions.B_star, stroke_geom, c, opts["shading_energy"])
    E_field = edited_field(ld, shading)
    T["interpolation"] = time.perf_counter() - t

    t = time.perf_counter()
    strips = integrate_from_entry(ld, light, model, regions.M, regions.entry, E_field, opts, margin)
    T["integration"] = time.perf_counter() - t

    t = time.perf_counter()
    z, inM = reconstruct_heights(
        ld, regions.M, strips, opts["smoothing"], opts["kernel_scale"], int(opts["neighbors"]), opts["ring"], margin
    )
    T["rbf"] = time.perf_counter() - t
    if not np.isfinite(z).all():
        raise SolverError("the edit produced non-finite heights; the layer was left unchanged")
    if not inM.any():
        raise NothingToDoError("the impacted region holds no vertex of the layer")
    z[ld.is_contour] = 0.0
    z[~inM] = ld.z[~inM]  # bit-identical outside M•
    new_mesh = mesh.with_heights(z)
    changed = z != ld.z
    T["total"] = time.perf_counter() - t0
    return SculptResult(new_mesh, changed, c, iso, band_geom, stroke_geom, regions, strips, shading, T, opts)
