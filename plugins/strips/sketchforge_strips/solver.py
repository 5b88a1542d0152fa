"""The sculpt solver ``strips``: the thesis' method (4.3–4.6), made robust (issue 36).

1. **Strips (4.3, 4.5)** — seeds on the stroke (extended by one band radius), spread by flux
   across the flow (:mod:`.regions`); their base characteristics traced both ways with
   diffrax until they stop, in the rim margin or where the flow vanishes, in segments of a
   fixed shape (one compiled function; :mod:`.integrate`). Their sweep is S•.
2. **Shading (4.4)** — the smoothest change δE on B•* = band ∩ S• (without its edge strips)
   ∩ Ω*, E + δE = c along the stroke (the host's service), faded out over the band's outer
   half so it ends C¹, and left alone where the shading barely responds to the slope.
3. **Heights along the strips (4.5)** — the linearised system is triangular: the path depends
   only on the old surface, and dδz/ds = −δE along it is a quadrature on the saved points.
   SfS fixes δz only up to a function constant along the characteristics; that freedom is
   used so that the change is shared by the strip's two ends (half each when both reach the
   rim margin, all of it at the end that can take it when one stops where the flow vanishes),
   fades where strips converge (so a narrow ribbon of them carries no crease), and returns to
   0 smoothly across the rim margin (README, "Thesis corrections").
4. **Reconstruction (4.6)** — δz at the vertices by local multiquadric RBF, solved in batches
   (:mod:`.reconstruct`), from the strips' samples and the untouched vertices around S•,
   tapered to 0 across the rim margin and beside the sweep, and lightly smoothed on the mesh.
5. **Newton** — the strips integrate the change linearised about the old surface; a second
   pass integrates, along the same strips, the shading still missing on B•* at the new
   surface (damped: the whole correction if it helps, else half, else a quarter).
6. **Shape limit** — the change scaled down, as little as needed, so that no interior edge
   creases or jumps in shading beyond the host's bounds (2.4 times the layer's as inflated,
   30° at most; or what it had) and no triangle of the rim margin folds.

The host then bounds the change (at most 60% of the peak), clamps heights at 0, keeps the
rim at 0, refuses non-finite values, and keeps the edit only if the isophote ends no farther
from the stroke (trying half and a quarter of the change): what every sculpt solver gets.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial import cKDTree

from sketchforge.plugin_api import (
    LRUCache,
    NothingToDoError,
    ParameterError,
    SculptProblem,
    SculptSolution,
    SculptSolver,
    array_key,
    choice,
    interior_edges,
    number,
    validate_params,
)

from .field import Raster
from .reconstruct import rbf_weights
from .regions import extend, flux_seeds, triangles_region

#: Bumped when the same edit would give other heights (4: crease bounds relative to the fresh layer).
VERSION = "4"

#: Parameters of ``strips``; lengths in edge lengths h.
DEFAULT_PARAMS = {
    "integrator": "tsit5",  # "tsit5" (explicit) or "kvaerno5" (the thesis' implicit solver)
    "step_control": "fixed",  # "fixed" (one step per saved point) or "pid" (adaptive, rtol/atol; kvaerno5 always)
    "rtol": 1e-6,  # the PID step controller's tolerances
    "atol": 1e-9,
    "strip_spacing": 1.0,  # distance between neighbouring strips, across the flow (h)
    "sample_spacing": 0.5,  # distance between a strip's saved points: the RBF's supports (h)
    "rbf_smoothing": 0.05,  # the thesis' λ_smooth (4.6.1)
    "rbf_scale": 3.0,  # the multiquadric's scale 1/ε (h)
    "rbf_neighbors": 16,  # supports of each query's local RBF fit
    "ring": 3.0,  # width of the ring of untouched vertices (δz = 0) around the impacted region (h)
}

#: Finite ranges, the tighter of issue 38's and this solver's own. Issue 38's keep the dearest
#: accepted set (kvaerno5 at the tightest tolerances, the densest strips and samples, the most
#: RBF neighbours, the widest ring) to about 15 s of CPU for one edit along a whole isophote of
#: a 5k-vertex layer, compile included (the former bounds, rtol 1e-12, atol 1e-15, spacings
#: 0.25 and 0.1, 256 neighbours, ran 145-157 s before refusing; the implicit solver's cost
#: grows with the strips times its steps; see benchmarks/bench_param_extremes.py). This
#: solver's own are tighter on the neighbours (<= 64): a corner looser than these (kvaerno5 at
#: rtol 1e-9, strip_spacing 0.5, sample_spacing 0.25, 64 neighbours, ring 20) took 7.4 s CPU,
#: 13 s wall at load ~6, for one edit on a 4.5k-vertex layer.
_CHECKS = {
    "integrator": choice("integrator", ("tsit5", "kvaerno5")),
    "step_control": choice("step_control", ("fixed", "pid")),
    "rtol": number("rtol", 1e-8, 1e-2),
    "atol": number("atol", 1e-11, 1e-2),
    "strip_spacing": number("strip_spacing", 1.0, 8.0),
    "sample_spacing": number("sample_spacing", 0.25, 4.0),
    "rbf_smoothing": number("rbf_smoothing", 0.0, 10.0),
    "rbf_scale": number("rbf_scale", 0.25, 20.0),
    "rbf_neighbors": number("rbf_neighbors", 8, 64, integer=True),
    "ring": number("ring", 1.0, 20.0),
}

#: Distances to the isophote below this many edge lengths are below what first-order vertex
#: normals resolve (the host's never-worse check uses the same figure).
RESOLUTION = 0.25

#: Most strips one edit may seed (a stroke 2000 edge lengths across the flow): beyond, the
#: spacing is widened rather than the batch grown without bound.
MAX_STRIPS = 2048


def check_params(params) -> dict:
    """The complete parameters of ``strips`` (defaults filled in, each checked)."""
    return validate_params(params, DEFAULT_PARAMS, _CHECKS)


def _smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


_RASTERS = LRUCache(8, name="strips rasters")


def _raster(V2: np.ndarray, F: np.ndarray) -> Raster:
    """The layer's grid raster, cached on its planar positions and triangles (an edit changes
    only heights, so a layer's later edits reuse it)."""
    return _RASTERS.get_or_make(array_key(V2, F), lambda: Raster(V2, F))


def solve(problem: SculptProblem, params: dict) -> SculptSolution:
    """The height change of an edit by the strip method (see the module docstring)."""
    from .integrate import integrate_paths

    T: dict = {}
    t = time.perf_counter()
    V2 = np.ascontiguousarray(problem.V[:, :2])
    F = problem.F
    n, h, r = len(V2), problem.h, problem.band_radius
    interior = ~problem.is_rim
    margin = np.asarray(problem.rim_margin, np.float64)
    Rp, Rq = problem.Rp, problem.Rq
    flow = -np.column_stack([Rp, Rq])  # the base characteristics' direction
    # The rim mask: 0 in the rim margin (Ω*), 1 one edge length inside it; strips stop where
    # it vanishes, samples fade with it.
    mask = _smoothstep((problem.d_rim - margin) / h) * interior
    raster = _raster(V2, F)
    extent = float(np.ptp(V2, axis=0).max())
    spacing = float(params["strip_spacing"]) * h
    step = float(params["sample_spacing"]) * h
    seeds, edge, pid = [], [], []
    for j, piece in enumerate(problem.stroke):
        # extended by a band radius, but never past the layer's size: a band of 1e9 (the whole
        # layer) asked for 2 TiB of seeds along a stroke reaching out to it (issue 38's attack)
        s = flux_seeds(extend(piece, min(r, extent)), lambda P: np.nan_to_num(problem.interpolate(flow, P)), spacing,
                       0.25 * h)
        e = np.zeros(len(s), bool)
        e[[0, -1] if len(s) else []] = True
        seeds.append(s)
        edge.append(e)
        pid.append(np.full(len(s), j))
    seeds = np.concatenate(seeds) if seeds else np.zeros((0, 2))
    edge = np.concatenate(edge) if edge else np.zeros(0, bool)
    pid = np.concatenate(pid) if pid else np.zeros(0, int)
    if len(seeds) > MAX_STRIPS:
        keep = np.linspace(0, len(seeds) - 1, MAX_STRIPS).round().astype(int)
        seeds, edge, pid = seeds[keep], edge[keep], pid[keep]
    if len(seeds) == 0:
        raise NothingToDoError("no characteristic crosses the stroke (it runs along the flow of the shading); "
                               "draw it across the shading's gradient")
    T["seeds"] = time.perf_counter() - t

    # 4.3 and 4.5: the strips through the seeds, traced both ways until they stop (in the rim
    # margin, or where the flow vanishes). Their sweep is S•.
    t = time.perf_counter()
    coeffs = raster.coefficients(np.column_stack([Rp, Rq, mask]))
    down, up, most_steps = integrate_paths(seeds, coeffs, raster.origin, raster.spacing, step, 1.5 * extent,
                                           params["integrator"], params["rtol"], params["atol"],
                                           params["step_control"] == "pid" or params["integrator"] == "kvaerno5")
    # Each strip as one polyline from its upstream end to its downstream end.
    strips = [np.concatenate([u[::-1], s[None], d]) for u, s, d in zip(up, seeds, down)]
    sizes = np.array([len(s) for s in strips])
    X = np.concatenate(strips)
    owner = np.repeat(np.arange(len(strips)), sizes)
    T["strips"] = time.perf_counter() - t

    t = time.perf_counter()
    near = 0.75 * spacing + 0.5 * step
    ring_w = float(params["ring"]) * h
    reach_q = near + ring_w + 1.5 * float(margin.max())
    d_S, nearest = cKDTree(X).query(V2, distance_upper_bound=reach_q)
    inner_X = X[~edge[owner]]
    d_in = cKDTree(inner_X).query(V2, distance_upper_bound=near)[0] if len(inner_X) else np.full(n, np.inf)
    T["regions"] = time.perf_counter() - t

    # 4.4: the shading change on B•* = band ∩ {d_s < r} ∩ Ω* ∩ S•, S• without its two edge
    # strips, so the strips that bound the sweep carry no change and the edit fades out across
    # the flow before the sweep ends.
    t = time.perf_counter()
    d_s = problem.distance_to_stroke(V2, r)
    # Where the shading barely depends on the slope (|∇R| → 0: a tilted light's brightest
    # point, where every strip meets) no height change can move an isophote: the linearised
    # strips turn a shading change there into a height change of δE / |∇R| (measured under an
    # overhead light: 80 times the peak). The shading is left as it is there (as in the rim
    # margin), the stroke's constraints fading out with a weight rising from 0 at |∇R| =
    # FLAT to 1 at twice that.
    respond = _smoothstep((np.hypot(Rp, Rq) - FLAT) / FLAT)
    free = problem.in_band & (d_s < r) & (mask > 0.0) & (d_in <= near) & interior & (respond > 0.0)
    # Where the stroke runs within the resolution of the isophote it asks for no change: the
    # stroke is smoothed and resampled, so a stroke drawn on the isophote is a few hundredths
    # of an edge length off it, and the strips (which turn a shading change into a height
    # change by 1/|∇R|, large on steep parts) would make that drift (6.5% of the peak after
    # ten edits on a thin limb). A weight rising smoothly from 0 at RESOLUTION·h to 1 at
    # 3·RESOLUTION·h from the isophote: continuous, and no real move is touched.
    d_iso = _distance_to_polyline(problem.samples, problem.isophote)
    quiet = _smoothstep((d_iso - RESOLUTION * h) / (2.0 * RESOLUTION * h))
    quiet = quiet * np.nan_to_num(problem.interpolate(respond, problem.samples), nan=0.0)
    # The change is faded in from the rim margin (below), and is 0 in it: the stroke's
    # constraints fade the same way. Asked at full weight right beside the margin, where δE
    # is held at 0, the smoothest change bent past the stroke's value beside it (a plate pulled
    # down next to its clamped edge): a pit 2.2 times deeper than the stroke asked, E = −0.06
    # where c = 0.28, on a blob's eighth edit (a shading jump 3.2 times the fresh layer's).
    to_margin = _smoothstep((problem.d_rim - margin) / (MARGIN_FADE * h))
    quiet = quiet * np.nan_to_num(problem.interpolate(to_margin, problem.samples), nan=0.0)
    dE = problem.shading_change(free, problem.sample_weights * quiet)
    # The smoothest change with δE = 0 off B•* has a kink where B•* ends (0 is imposed there,
    # not its slope): the strips turn it into a kink of the slope, a crease all along the
    # carried shift (measured: 32° across a limb, beside a short stroke). Faded out over the
    # outer half of the band (δE · (1 − smoothstep)) it ends C¹; the stroke's half is kept.
    dE = dE * (1.0 - _smoothstep((d_s - 0.5 * r) / (0.5 * r)))
    # Likewise toward the rim margin, over MARGIN_FADE edge lengths: a change of slope asked
    # right at the margin's edge, where the surface is steep and 1/|∇R| large, tipped the
    # margin's first triangles over (folds after chains of edits on thin limbs and stars).
    dE = dE * to_margin
    T["shading"] = time.perf_counter() - t
    curves = _curves(strips)
    if not free.any() or not np.any(dE):
        return SculptSolution(np.zeros(n), dE, curves=curves, info=_info(T, seeds, 0, most_steps))

    # 4.5: along each strip dδz/ds = −δE, ds = dσ / |∇R|: J(σ) = ∫ δE / |∇R| dσ from the
    # upstream end (trapezoids on the saved points, 'sample_spacing' apart).
    t = time.perf_counter()
    seg = np.linalg.norm(np.diff(X, axis=0), axis=1)
    first = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    last = first + sizes - 1
    # The samples located once: every later field is read on them by the same weights.
    face, bary = problem.locate(X)
    inside = face >= 0
    corners = F[np.where(inside, face, 0)]
    bary = np.where(inside[:, None], bary, 0.0)

    def at_samples(values: np.ndarray) -> np.ndarray:
        """Per-vertex values (n,) or (n, k) at the samples, 0 outside the layer."""
        return np.einsum("sj,sj...->s...", bary, values[corners])

    # SfS fixes δz only up to a function constant along the characteristics: δz = a − J with
    # any a per strip. The thesis takes a = 0 (upstream kept, the whole shift carried
    # downstream). Here the shift is shared between the two ends in proportion to how well
    # each can take it: an end in the rim margin can (the shift returns to 0 across the
    # margin, below), an end where the flow vanishes (a tilted light's brightest point, where
    # every strip meets) or cut off by the length cap cannot (its shift must be 0 there, or the
    # strips meeting there would disagree). Both in the rim margin: half each way, which halves
    # the largest height change of the thesis' choice.
    end_mask = at_samples(mask)
    # A strip stopping in the margin crawls (its speed is the mask's) and is cut where it no
    # longer moves, at a mask near 0.1 that round-off can shift by a sample: read through
    # a ramp that is flat below ENDING, the ends and the weights below do not see which.
    ending = _smoothstep((end_mask - ENDING) / (1.0 - 2.0 * ENDING))
    take_up, take_down = 1.0 - ending[first], 1.0 - ending[last]
    share = (take_up + 1e-6) / (take_up + take_down + 2e-6)
    # Where strips converge (onto a ridge, into a narrow lobe, to the brightest point) a shift
    # carried along them is squeezed into a narrow ribbon: a crease across it (measured on a
    # star's lobe: 58° dihedral angles 37 edge lengths from the stroke after one edit). So the
    # shift is scaled by a smooth clip of w / (CONVERGENCE · spacing), w the strips' spacing
    # there: untouched where the strips are about as far apart as at the stroke or farther,
    # fading with their spacing where they converge, so its slope across the flow stays near
    # the one at the stroke. The fade changes the shading along the strip by
    # |∇R| · d(shift)/dσ, spread over the convergence: the one place the strips knowingly leave
    # the PDE outside the band.
    w = _strip_spacing(X, owner, pid)
    squeeze = _soft_clip(w / (CONVERGENCE * spacing))
    w_s = ending
    # Supports for the RBF: along a strip, about as far apart as the strips are across the
    # flow where they diverge (downstream of a stroke they may fan out to 10 spacings: a query's
    # nearest supports then all lay on one strip, and the fit between strips was noise of 1.5%
    # of the peak from one vertex to the next), and never closer than 'sample_spacing' (a
    # strip that stops saves points closer and closer together).
    apart = np.clip(0.5 * np.nan_to_num(w, posinf=4.0 * spacing), step, 4.0 * spacing)
    # Half a step of phase in: where the samples are kept one by one (a phase step of exactly
    # 1, the saved points being 'sample_spacing' apart), the floor never sits on an integer.
    phase = 0.5 + np.concatenate([[0.0], np.cumsum(_halves(1.0 / apart, seg, owner))])
    keep = np.ones(len(X), bool)
    keep[1:] = (np.floor(phase[1:]) > np.floor(phase[:-1])) | (owner[1:] != owner[:-1])
    keep[last] = True

    def carried(change: np.ndarray, Rp_now: np.ndarray, Rq_now: np.ndarray) -> np.ndarray:
        """δz (N,) at the samples for a shading change (n,) on the surface of slope gradient
        (R_p, R_q) (n,)."""
        v = at_samples(np.column_stack([change, Rp_now, Rq_now]))
        # 1/|∇R| regularised as |∇R| / (|∇R|² + FLAT²) (Levenberg–Marquardt): unchanged where
        # the shading responds to the slope, at most 1 / (2 FLAT) where it barely does, and
        # continuous; the Newton pass below recovers what the damping held back.
        g2 = v[:, 1] ** 2 + v[:, 2] ** 2
        rate = v[:, 0] * np.sqrt(g2) / (g2 + FLAT**2)
        J = np.concatenate([[0.0], np.cumsum(_halves(rate, seg, owner))])
        J = J - J[first][owner]  # from each strip's own upstream end
        return ((J[last] * share)[owner] - J) * squeeze
    T["quadrature"] = time.perf_counter() - t

    # 4.6: heights by RBF on S• and the rim margin beside it; the untouched vertices around S•
    # are supports with δz = 0 (the thesis' "vertices outside of M•").
    t = time.perf_counter()
    # Past the end of a strip that stopped in the rim margin the shift goes on to the rim
    # (tapered below): a vertex there, whose nearest sample is a strip's end, is in S•. Beside
    # the sweep ('lateral' > 0) the untouched vertices are supports with δz = 0.
    is_end = np.zeros(len(X) + 1, bool)  # the extra entry: "no sample within reach"
    is_end[first] = is_end[last] = True
    past_end = (is_end[nearest] & (problem.d_rim < margin + 2.0 * h)
                & (d_S <= near + 1.5 * margin + h))
    lateral = np.where(past_end, -1.0, d_S - near)
    query = interior & (lateral <= ring_w)
    ring = query & (lateral > 0.0)
    qi = np.nonzero(query)[0]
    n_ring = int(ring.sum())
    try:
        fit = rbf_weights(np.concatenate([X[keep], V2[ring]]), np.concatenate([w_s[keep], np.ones(n_ring)]), V2[qi],
                          h, float(params["rbf_scale"]), float(params["rbf_smoothing"]), int(params["rbf_neighbors"]))
    except np.linalg.LinAlgError as exc:
        raise ParameterError(f"the RBF fit is singular ({exc}); raise 'rbf_smoothing'") from None
    except ValueError:
        raise NothingToDoError("the strips through the stroke stay in the rim margin: draw it further inside") from None
    # The shift carried along the characteristics returns to 0 across the rim margin (the
    # issue's rule, and the freedom above), as a smoothstep of the height: δz = Δ · S(z / z_m),
    # z_m the height where the strip entered the margin (read from the strips' ends by the same
    # fits). It is 1 inside the margin's edge, 0 with zero slope at the rim (the silhouette does
    # not move), and C¹; and, in the height rather than the depth, it keeps the margin rising
    # toward the inside: z + Δ S(z / z_m) grows with z as long as Δ > −z_m / 1.5 (a smoothstep
    # of the depth folded the margin in 6 of 12 chains of ten edits, 226 triangles), and the
    # shift is held above −z_m / 1.6 there. Beside the sweep the change fades out over the ring
    # (whose vertices are supports with δz = 0 too, so the fade only removes the RBF's small
    # residue there): continuous in the distance to the sweep.
    z_s = at_samples(problem.z)
    seed_at = first + np.array([len(u) for u in up])
    z_end = np.where(np.arange(len(X)) < seed_at[owner], z_s[first][owner], z_s[last][owner])
    z_m = np.maximum(fit(np.concatenate([z_end[keep], problem.z[ring]])), 1e-9 * max(float(problem.z.max()), 1e-300))
    taper = _smoothstep(problem.z[qi] / z_m) * (1.0 - _smoothstep(lateral / ring_w))[qi]
    # The local fits leave noise from one vertex to the next (each vertex has its own
    # neighbourhood of supports), and a strip edit reads 1/|∇R| of the surface it is made on:
    # noise left by one edit is amplified by the next (a blob's tenth edit: 60° creases among
    # lumps). A light smoothing on the mesh removes it: the δz closest to the RBF's with a
    # squared-Laplacian penalty of weight SMOOTHING·h² (a length scale of about an edge length:
    # the band's features, several edge lengths wide, pass), 0 off the queried vertices, so the
    # change also joins the untouched surface C¹.
    smoother = _Smoother(problem.Q, qi, SMOOTHING * h * h)

    def heights(dz_samples: np.ndarray) -> np.ndarray:
        raw = fit(np.concatenate([dz_samples[keep], np.zeros(n_ring)]))
        out = np.zeros(n)
        out[qi] = smoother(raw * taper)
        return out
    T["rbf"] = time.perf_counter() - t

    # The strips integrate the change linearised about the surface before the edit; where the
    # shading depends weakly on the slope (near the brightest point, steep parts) the realised
    # change overshoots it (measured: a blob's ninth edit darkened two patches to E ≈ 0 where
    # c ≈ 0.6 was asked). So NEWTON_PASSES passes, each integrating along the same strips the
    # shading still missing on B•* at the surface the passes before made: a Newton iteration,
    # each pass costing a quadrature and a gather (the RBF's weights and the smoothing's
    # factor are reused).
    t = time.perf_counter()
    target = np.where(free, problem.E + dE, 0.0)
    dz = heights(carried(dE, Rp, Rq))
    E_now, Rp_now, Rq_now = problem.shading(problem.z + dz)
    for _ in range(NEWTON_PASSES - 1):
        miss = np.where(free, target - E_now, 0.0)
        step_dz = heights(carried(miss, Rp_now, Rq_now))
        # Damped: the whole correction if it leaves less shading missing on B•*, else half,
        # else a quarter, else none. Where the shading barely responds to
        # the slope the correction overshoots as the first pass did (under an overhead light
        # along a limb's ridge, an undamped second pass grew a change of 4 peaks to 39).
        best, before_miss = None, float(np.sum(miss**2))
        for f in (1.0, 0.5, 0.25):
            got = problem.shading(problem.z + dz + f * step_dz)
            if float(np.sum(np.where(free, target - got[0], 0.0) ** 2)) < before_miss:
                best = (f, got)
                break
        if best is None:
            break
        dz = dz + best[0] * step_dz
        E_now, Rp_now, Rq_now = best[1]
    dz[qi] = np.maximum(dz[qi], -taper * z_m / 1.6)  # no fold in the margin (above)
    dz[problem.is_rim] = 0.0
    T["passes"] = time.perf_counter() - t

    # The strips follow the PDE without regard for the shape: beside a stroke drawn near the
    # rim margin or into the notch between two lobes, where the shading barely responds to
    # the slope, they ask for steep changes (a star's single edit: a 93° crease). The change is
    # scaled down, as little as needed, so that no interior edge creases, or jumps in shading,
    # beyond the host's bounds (or what it had) and no triangle of the margin that rose toward
    # the inside falls; the host then keeps it only if the isophote ends closer.
    t = time.perf_counter()
    limit = _shape_limit(problem, dz)
    dz *= limit
    T["limit"] = time.perf_counter() - t

    changed = np.abs(dz) > 1e-9 * max(float(np.abs(problem.z).max()), 1e-300)
    return SculptSolution(
        dz, dE,
        shading_region=lambda: triangles_region(V2, F, free, smooth=h),
        height_region=lambda: triangles_region(V2, F, changed, touching=True, smooth=h),
        curves=curves,
        info={**_info(T, seeds, int(keep.sum()), most_steps), "limit": float(limit),
              "reach": float(np.max(problem.distance_to_stroke(V2[changed], 3.0 * extent), initial=r))},
    )


#: Strips may come this much closer together than at the stroke before the shift they carry
#: fades with their spacing (below 1, so the fade never reaches into the band, where the
#: strips' spacing wobbles by a few percent and the isophote must land).
CONVERGENCE = 0.75


#: Rim mask below which a strip's samples are ending: no weight in the RBF, a full end in the
#: rim margin (above the mask at which a stopping strip is cut, ~0.1).
ENDING = 0.15
#: Edge lengths inside the rim margin over which the shading change fades in.
MARGIN_FADE = 2.0
#: |∇R| below which the shading is taken not to respond to the slope (see ``respond``).
FLAT = 0.02
#: Weight of the squared Laplacian in the final smoothing of δz, in units of h².
SMOOTHING = 1.0
#: Passes of the strips' Newton iteration (the first is the thesis' linearised solve).
NEWTON_PASSES = 2


#: Conjugate-gradient iterations of the final smoothing (a fixed count: the result is then a
#: fixed smooth function of the input; I + αQ with α = h² is well conditioned, and 20 Jacobi-
#: preconditioned iterations left a residual of ~1e-4 of the change, against 78 ms of SuperLU
#: factorisation per edit at 5k vertices).
SMOOTHING_ITERATIONS = 20


class _Smoother:
    """y ↦ argmin_x |x − y|² + alpha xᵀ Q_uu x on the vertices ``u`` (the others 0), by
    :data:`SMOOTHING_ITERATIONS` of Jacobi-preconditioned conjugate gradients from x = y (Q the
    squared Laplacian Lᵀ M⁻¹ L, whose scale is that of a unit-area Laplacian, so alpha is a
    squared length)."""

    def __init__(self, Q, u: np.ndarray, alpha: float) -> None:
        import scipy.sparse as sp

        self.A = sp.csr_matrix(Q)[u][:, u] * alpha + sp.identity(len(u), format="csr")
        self.inv_diag = 1.0 / self.A.diagonal()

    def __call__(self, y: np.ndarray) -> np.ndarray:
        x = np.array(y, dtype=np.float64)
        r = y - self.A @ x
        z = self.inv_diag * r
        p = z.copy()
        rz = float(r @ z)
        for _ in range(SMOOTHING_ITERATIONS):
            if rz <= 0.0:
                break
            Ap = self.A @ p
            step = rz / float(p @ Ap)
            x += step * p
            r -= step * Ap
            z = self.inv_diag * r
            rz_new = float(r @ z)
            p = z + (rz_new / rz) * p
            rz = rz_new
        return x


#: Interior edges, for the crease bounds: both ends at least this many edge lengths from the rim
#: (the host's bounds, :attr:`SculptProblem.crease_bound`, are measured on those).
INTERIOR = 3.0
#: Bisection steps for the scale of a change that creases or folds (a fixed count: the scale
#: is then a fixed function of the change).
LIMIT_STEPS = 10


def _shape_limit(problem: SculptProblem, dz: np.ndarray) -> float:
    """The largest scale f in [0, 1] (to 1/2^LIMIT_STEPS) such that z + f·dz creases no
    interior edge beyond max(problem.crease_bound, its angle now), makes no shading jump across
    one beyond max(problem.jump_bound, its jump now), and folds no triangle of the rim margin
    that rises toward the inside now (see :func:`solve`). The bounds are relative to the layer
    as inflated (the host's): a fixed 30° let ten edits crease a finely meshed "C", whose fresh
    edges meet at 10° at most, to 2.9 times that."""
    V2, F, h = problem.V[:, :2], problem.F, problem.h
    z = problem.z
    touched = np.abs(dz) > 0.0
    faces = np.nonzero(touched[F].any(axis=1))[0]
    if len(faces) == 0:
        return 1.0
    Fs = F[faces]
    # Interior edges among the touched triangles: pairs of triangles sharing an edge.
    E, fa, fb = interior_edges(Fs)
    inner = (problem.d_rim[E] >= INTERIOR * h).all(axis=1)
    pairs = np.column_stack([fa, fb])[inner]
    ends = E[inner]
    # Triangles of the margin and their inward direction (the gradient of the rim distance).
    P = V2[Fs]
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    det = np.where(np.abs(det) < 1e-300, 1e-300, det)

    def grad(f):  # per-face gradient (m, 2) of a per-vertex field f (n,)
        a = f[Fs]
        d1, d2 = a[:, 1] - a[:, 0], a[:, 2] - a[:, 0]
        return np.column_stack([(d1 * e2[:, 1] - d2 * e1[:, 1]) / det, (d2 * e1[:, 0] - d1 * e2[:, 0]) / det])

    inward = grad(problem.d_rim)
    margin = np.asarray(problem.rim_margin)[Fs].mean(axis=1)
    in_margin = problem.d_rim[Fs].mean(axis=1) < margin
    rising_now = np.einsum("kd,kd->k", grad(z), inward)
    watch = in_margin & (rising_now > 0.0) & (np.hypot(inward[:, 0], inward[:, 1]) > 0.5)

    def normals(zz):
        g = grad(zz)
        n = np.column_stack([-g, np.ones(len(g))])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def angles(zz):
        n = normals(zz)
        return np.degrees(np.arccos(np.clip(np.einsum("kd,kd->k", n[pairs[:, 0]], n[pairs[:, 1]]), -1.0, 1.0)))

    allowed = np.maximum(angles(z), problem.crease_bound) + 1e-9
    bound_jumps = len(ends) > 0 and np.isfinite(problem.jump_bound)
    jumps_now: list = []  # the jumps before the edit, evaluated only when a jump passes the bound

    def jumps(zz):
        E = problem.shading(zz)[0]
        return np.abs(E[ends[:, 0]] - E[ends[:, 1]])

    def calm(zz):
        j = jumps(zz)
        if np.all(j <= problem.jump_bound):
            return True
        if not jumps_now:
            jumps_now.append(np.maximum(jumps(z), problem.jump_bound) + 1e-9)
        return not np.any(j > jumps_now[0])

    def fine(f):
        zz = z + f * dz
        if len(pairs) and np.any(angles(zz) > allowed):
            return False
        if np.any(np.einsum("kd,kd->k", grad(zz), inward)[watch] <= 0.0):
            return False
        return not bound_jumps or calm(zz)

    if fine(1.0):
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(LIMIT_STEPS):
        mid = 0.5 * (lo + hi)
        if fine(mid):
            lo = mid
        else:
            hi = mid
    return lo


def _halves(f: np.ndarray, seg: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """Trapezoids (N−1,) of samples f (N,) on consecutive points ``seg`` (N−1,) apart, 0
    between two strips (``owner`` (N,) the strip of each point)."""
    piece = 0.5 * (f[1:] + f[:-1]) * seg
    piece[owner[1:] != owner[:-1]] = 0.0
    return piece


def _strip_spacing(X: np.ndarray, owner: np.ndarray, pid: np.ndarray, m: int = 2) -> np.ndarray:
    """The strips' spacing (N,) at every sample X (N, 2) of the strips (``owner`` (N,) the strip
    of each, in order; ``pid`` the stroke piece of each strip): the distance to the strips
    seeded ``m`` places before and after its own on the same piece, over m (one side only at
    the sweep's edges; inf for a lone strip). Over m strips, so that the unevenness of single
    strips averages out (the distance to the next strip alone alternated from strip to strip
    and made the shift streaky); point to polyline (the nearest point alone made a moiré of
    the sample phases: bands of 3-8%)."""
    n_strips = len(pid)
    # One k-d tree for every strip: the strip's index as a third coordinate, far apart, so a
    # query tagged with strip j finds strip j's samples only.
    far = 10.0 * (float(np.ptp(X, axis=0).max()) + 1.0)
    tree = cKDTree(np.column_stack([X, owner * far]))
    same_next = np.zeros(len(X), bool)
    same_next[:-1] = owner[1:] == owner[:-1]
    same_prev = np.zeros(len(X), bool)
    same_prev[1:] = same_next[:-1]
    total = np.zeros(len(X))
    count = np.zeros(len(X))
    for d_own in (-m, m):
        other = owner + d_own
        ok = (other >= 0) & (other < n_strips)
        ok &= pid[np.clip(other, 0, n_strips - 1)] == pid[owner]
        q = np.nonzero(ok)[0]
        if len(q) == 0:
            continue
        _, j = tree.query(np.column_stack([X[q], other[q] * far]))
        best = np.linalg.norm(X[q] - X[j], axis=1)
        for a, b in ((np.where(same_prev[j], j - 1, j), j), (j, np.where(same_next[j], j + 1, j))):
            A, B = X[a], X[b]
            AB = B - A
            t = np.clip(np.einsum("kd,kd->k", X[q] - A, AB) / np.maximum(np.einsum("kd,kd->k", AB, AB), 1e-300), 0.0, 1.0)
            best = np.minimum(best, np.linalg.norm(X[q] - (A + t[:, None] * AB), axis=1))
        total[q] += best
        count[q] += 1
    return np.where(count > 0, total / np.maximum(count, 1) / m, np.inf)


def _soft_clip(x: np.ndarray) -> np.ndarray:
    """min(x, 1) made C¹: x(2 − x) below 1 (0 at 0, slope 0 at 1), 1 above."""
    x = np.clip(x, 0.0, 1.0)
    return x * (2.0 - x)


def _distance_to_polyline(P: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Distance (k,) from points P (k, 2) to a polyline (j, 2)."""
    import shapely

    if len(line) < 2:
        return np.full(len(P), np.inf)
    return shapely.distance(shapely.points(P), shapely.LineString(line))


def _curves(strips: list, most: int = 40) -> list:
    """Up to ``most`` of the integrated strips as polylines (for "show characteristics")."""
    k = len(strips)
    pick = np.unique(np.linspace(0, k - 1, min(k, most)).round().astype(int)) if k else np.zeros(0, int)
    out = []
    for i in pick:
        line = strips[i]
        if len(line) > 1:
            keep = np.concatenate([[True], np.any(np.abs(np.diff(line, axis=0)) > 0, axis=1)])
            out.append(line[keep])
    return out


def _info(T: dict, seeds: np.ndarray, samples: int, steps: int) -> dict:
    return {"timings": T, "strips": int(len(seeds)), "samples": int(samples), "steps_max": int(steps)}


def warm_up() -> None:
    """Compile the default integrator's strip functions ahead of the first edit."""
    from .integrate import warm_up as compile_strips

    compile_strips(DEFAULT_PARAMS["integrator"])


STRIPS = SculptSolver(
    "strips",
    solve,
    check_params=check_params,
    version=VERSION,
    label="Strips (thesis)",
    warm_up=warm_up,
    description="the thesis' method: characteristic strips from the stroke integrated with diffrax, "
                "heights by multiquadric RBF, the change carried downstream to the rim",
)
