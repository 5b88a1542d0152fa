"""A randomized corpus of isophote edits on shapes nobody here drew (fixed seeds).

Shared by ``tests/test_sculpt_corpus.py`` (a reduced subset in CI) and
``benchmarks/bench_sculpt_corpus.py`` (the full set). Everything is deterministic in its seed.

Shapes (:func:`random_outline`), each a closed outline in drawing units, about 1–2.5 across:

``blob``
    A smooth random star-shaped curve r(θ) = R(1 + Σ a_k cos(kθ + φ_k)), k = 2..5.
``star``
    5–8 rounded points with deep notches (r varies by ±35–50%).
``thin``
    A bent limb 0.2–0.3 wide (a buffered arc).
``concave``
    A "C", "U", "L" or "S" letter stroke 0.3–0.45 wide (deep concavities, thin parts).

Edits (:func:`random_edit`): a pick on a lit vertex away from the rim, the isophote through it,
and a stroke made from a piece of that isophote:

``shift``   moved sideways by 1–5 edge lengths;
``bump``    moved by 1–5 edge lengths in the middle, ends kept (a sine profile);
``loop``    a shift or bump with a small loop (radius 1–2 edge lengths) drawn into it;
``outside`` a shift whose ends run on past the band (the part outside must be ignored).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
import shapely.ops

from sketchforge.plugin_api import face_normals

from .creases import largest_creases

SHAPES = ("blob", "star", "thin", "concave")
KINDS = ("shift", "bump", "loop", "outside")

# "pragma: no mutate block" marks the functions that only generate the corpus' inputs: mutation
# testing (mutation/run.py) leaves them alone, since a mutant there changes what the tests run on,
# not what the app does. The functions that measure outcomes are mutated.


def _ring(poly) -> np.ndarray:  # pragma: no mutate block
    return np.asarray(poly.exterior.coords)[:-1]


def random_outline(kind: str, rng: np.random.Generator, n: int = 400) -> np.ndarray:  # pragma: no mutate block
    """A closed outline (k, 2) float64 of a random shape of ``kind`` (see the module docstring)."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    if kind == "blob":
        r = np.ones_like(t)
        for k in range(2, 6):
            r += rng.uniform(0.0, 0.22 / k) * np.cos(k * t + rng.uniform(0, 2 * np.pi))
        a = rng.uniform(0.75, 1.05)
        P = np.column_stack([a * r * np.cos(t), rng.uniform(0.6, 0.9) * r * np.sin(t)])
    elif kind == "star":
        k = int(rng.integers(5, 9))
        depth = rng.uniform(0.35, 0.5)
        # A raised cosine keeps the points rounded (a plain cosine star's notches are sharp).
        w = 0.5 * (1 + np.cos(k * t + rng.uniform(0, 2 * np.pi)))
        r = rng.uniform(0.85, 1.1) * (1 - depth + 2 * depth * w**1.5)
        P = np.column_stack([r * np.cos(t), r * np.sin(t)])
    elif kind == "thin":
        width = rng.uniform(0.2, 0.3)
        bend = rng.uniform(0.4, 1.2)
        s = np.linspace(-0.7, 0.7, 60)
        arc = np.column_stack([np.sin(bend * s) / bend, (1 - np.cos(bend * s)) / bend])
        P = _ring(shapely.LineString(arc).buffer(0.5 * width, quad_segs=16).simplify(0.002))
    elif kind == "concave":
        width = rng.uniform(0.3, 0.45)
        letter = str(rng.choice(["C", "U", "L", "S"]))
        if letter == "C":
            a = np.linspace(0.5, 2 * np.pi - 0.5, 60)
            path = 0.75 * np.column_stack([np.cos(a), np.sin(a)])
        elif letter == "U":
            a = np.linspace(np.pi, 2 * np.pi, 30)
            path = np.concatenate([[[-0.6, 0.8]], 0.6 * np.column_stack([np.cos(a), np.sin(a)]), [[0.6, 0.8]]])
        elif letter == "L":
            path = np.array([[-0.5, 0.9], [-0.5, -0.6], [0.7, -0.6]])
        else:
            a = np.linspace(0, 1.5 * np.pi, 40)
            top = 0.45 * np.column_stack([np.cos(a), np.sin(a)]) + [0, 0.45]
            bot = 0.45 * np.column_stack([-np.cos(a + 0.5 * np.pi), np.sin(a + 0.5 * np.pi)]) + [0, -0.45]
            path = np.concatenate([top[::-1], bot])
        P = _ring(shapely.LineString(path).buffer(0.5 * width, quad_segs=16).simplify(0.002))
    else:
        raise ValueError(f"unknown shape kind {kind!r}; choose one of {SHAPES}")
    theta = rng.uniform(0, 2 * np.pi)
    Rm = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    return P @ Rm.T


@dataclass
class Edit:
    """One corpus edit: the inputs of ``sculpt`` and what the stroke asks for.

    Attributes
    ----------
    shape, kind : str
    pick : (2,) float64
    band : float
    stroke : (k, 2) float64
    move : float
        The requested sideways move in edge lengths (signed: > 0 towards the darker side).
    intended : (j, 2) float64
        The stroke as meant: without the loop and the run-on ends (what fidelity is measured
        against).
    """

    shape: str
    kind: str
    pick: np.ndarray
    band: float
    stroke: np.ndarray
    move: float
    intended: np.ndarray


def _offset(seg: shapely.LineString, profile: np.ndarray, n: int = 80) -> np.ndarray:  # pragma: no mutate block
    """Points of ``seg`` moved along its left normal by ``profile`` (callable of t in [0, 1])."""
    t = np.linspace(0.0, 1.0, n)
    P = np.array([seg.interpolate(s, normalized=True).coords[0] for s in t])
    d = np.gradient(P, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True) + 1e-300
    left = np.column_stack([-d[:, 1], d[:, 0]])
    return P + profile(t)[:, None] * left


def _with_loop(P: np.ndarray, radius: float, rng: np.random.Generator) -> np.ndarray:  # pragma: no mutate block
    """Insert a small closed loop (a circle of ``radius`` tangent to the path) at a random point."""
    k = int(rng.integers(len(P) // 4, 3 * len(P) // 4))
    d = P[k + 1] - P[k - 1]
    d /= np.linalg.norm(d)
    side = float(rng.choice([-1.0, 1.0]))
    centre = P[k] + radius * side * np.array([-d[1], d[0]])
    a0 = np.arctan2(P[k, 1] - centre[1], P[k, 0] - centre[0])
    # Around the circle in the direction that continues the path forward (a hand-drawn curl).
    a = a0 + side * np.linspace(0.0, 2 * np.pi, 24)[1:-1]
    loop = centre + radius * np.column_stack([np.cos(a), np.sin(a)])
    return np.concatenate([P[: k + 1], loop, P[k:]])


def random_edit(shape: str, ld, rng: np.random.Generator, kind: str | None = None, band: float | None = None,  # pragma: no mutate block
                pick=None):
    """A random edit on a layer (see the module docstring), or None when the layer has no
    suitable isophote near the random pick (the caller draws again).

    Parameters
    ----------
    shape : str
        The shape's kind (recorded in the Edit).
    ld : LayerData
        The layer's cached data (``sketchforge_isophote_tool.layerdata.layer_data``); the
        edit is drawn on the isophotes of its shading, under its light.
    rng : numpy Generator
    kind : str or None
        One of :data:`KINDS`; None draws one.
    band : float or None
        Band radius; None: a third of the layer's largest inradius, at most 0.3, at least 3h.
    pick : (2,) float64 or None
        Where to pick (None: a random lit vertex away from the rim, see below).
    """
    from sketchforge.plugin_api import SculptError

    from .isophote import picked_isophote

    h = ld.h
    kind = kind or str(rng.choice(KINDS))
    d = ld.planar.d_rim
    inradius = float(d.max())
    if band is None:
        band = float(np.clip(inradius / 1.5, 3 * h, 0.3))
    # A pick on a lit vertex at least a third of the inradius (and 2h) inside the rim: strokes
    # next to the rim ask for near-vertical surface, which no edit can honour.
    if pick is None:
        cand = np.nonzero((d > max(0.35 * inradius, 2 * h)) & (ld.E > 0.05) & (ld.E < 0.95))[0]
        if len(cand) == 0:
            return None
        pick = ld.V2[int(rng.choice(cand))] + rng.normal(0, 0.1 * h, 2)
    try:
        c, iso = picked_isophote(ld, pick)
    except SculptError:
        return None
    s0 = iso.project(shapely.Point(pick))
    half = rng.uniform(0.6, 1.2) * band
    seg = shapely.ops.substring(iso, max(s0 - half, 0.0), min(s0 + half, iso.length))
    if seg.length < 4 * h:
        return None
    move = float(rng.uniform(1.0, 5.0)) * float(rng.choice([-1.0, 1.0]))
    amount = move * h
    if kind in ("shift", "outside"):
        profile = lambda t: np.full_like(t, -amount)  # noqa: E731  (left = brighter side)
    else:
        profile = lambda t: -amount * np.sin(np.pi * t)  # noqa: E731
    if kind == "loop" and rng.random() < 0.5:
        profile = lambda t: np.full_like(t, -amount)  # noqa: E731
    P = _offset(seg, profile)
    intended = P
    if kind == "loop":
        P = _with_loop(P, rng.uniform(1.0, 2.0) * h, rng)
    if kind == "outside":
        # Run on past the band: straight extensions 1.5 band radii long at both ends.
        a = P[0] - P[1]
        b = P[-1] - P[-2]
        a /= np.linalg.norm(a)
        b /= np.linalg.norm(b)
        ext = np.linspace(0, 1.5 * band, 12)[1:, None]
        P = np.concatenate([(P[0] + ext * a)[::-1], P, P[-1] + ext * b])
    return Edit(shape, kind, np.asarray(pick, float), band, P, move, intended)


def random_pair(shape: str, ld, rng: np.random.Generator, kinds=KINDS):  # pragma: no mutate block
    """Two random edits of different isophotes near each other on one layer, or None (the
    caller draws again): the first as :func:`random_edit`; the second picked on a lit vertex
    0.5–1.5 band radii from the first pick whose shading differs from the first isovalue by at
    least 0.04 (so the bands overlap and one edit's change reaches the other's isophote),
    with the same band radius. Strokes that cross are drawn again (such a pair is
    contradictory: :func:`.joint.check_contradictions` refuses it)."""
    from .isophote import picked_isophote

    first = random_edit(shape, ld, rng, kind=str(rng.choice(kinds)))
    if first is None:
        return None
    c1, _ = picked_isophote(ld, first.pick)
    h, d = ld.h, ld.planar.d_rim
    dist = np.linalg.norm(ld.V2 - first.pick, axis=1)
    cand = np.nonzero((d > max(0.35 * float(d.max()), 2 * h)) & (ld.E > 0.05) & (ld.E < 0.95)
                      & (dist > 0.5 * first.band) & (dist < 1.5 * first.band) & (np.abs(ld.E - c1) > 0.04))[0]
    if len(cand) == 0:
        return None
    pick = ld.V2[int(rng.choice(cand))] + rng.normal(0, 0.1 * h, 2)
    second = random_edit(shape, ld, rng, kind=str(rng.choice(kinds)), band=first.band, pick=pick)
    if second is None or shapely.LineString(first.stroke).intersects(shapely.LineString(second.stroke)):
        return None
    return first, second


def draw_pairs(shape: str, mesh, rng, light, pairs: int, kinds=KINDS) -> list:  # pragma: no mutate block
    """``pairs`` random pairs of edits on one layer (:func:`random_pair`)."""
    from sketchforge.plugin_api import LAMBERTIAN

    from .layerdata import layer_data

    ld = layer_data(mesh, light, LAMBERTIAN)
    out: list = []
    tries = 0
    while len(out) < pairs and tries < 30 * pairs:
        tries += 1
        p = random_pair(shape, ld, rng, kinds)
        if p is not None:
            out.append(p)
    return out


# --- running the corpus ------------------------------------------------------------------------


@dataclass
class Outcome:
    """What one corpus edit did.

    Attributes
    ----------
    shape, kind : str
    move : float
        Requested move, in edge lengths.
    status : str
        "ok", "refused" (a SketchforgeError: the message says why) or "crash" (anything else).
    reason : str
        The refusal or crash message ("" when ok).
    before, after : float
        Mean stroke-to-isophote distance before and after, in edge lengths (nan unless ok).
    fraction : float
        1 for the full edit, less for a partial one (nan unless ok).
    seconds : float
        Wall time of the edit.
    vertices : int
    max_dz : float
        Largest height change, as a fraction of the layer's peak (nan unless ok).
    beside : float
        Mean distance from the new isophote beside the stroke to the stroke, in edge lengths
        (:func:`.fidelity.beside_distance`; nan unless ok).
    changed : float
        Share of the layer's vertices whose height changed (nan unless ok).
    reach : float
        Distance from the stroke to the farthest vertex whose height changed, in edge lengths
        (nan unless ok): how local the edit stayed.
    bounded : float
        0, or the largest height change of the solver's full answer (fraction of the peak) when
        it was over the host's bound and the edit was scaled down (nan unless ok).
    cpu : float
        CPU time of the edit (this process, all threads), seconds.
    """

    shape: str
    kind: str
    move: float
    status: str
    reason: str
    before: float
    after: float
    fraction: float
    seconds: float
    vertices: int
    max_dz: float = np.nan
    beside: float = np.nan
    changed: float = np.nan
    reach: float = np.nan
    bounded: float = np.nan
    cpu: float = np.nan

    @property
    def lands(self) -> bool:
        """The issue's criterion: after <= max(2 edge lengths, 0.3 × before)."""
        return self.status == "ok" and self.after <= max(2.0, 0.3 * self.before)

    @property
    def moved(self) -> bool:
        """Lands, and the isophote beside the stroke is on it too (it moved, rather than a new
        little loop meeting the stroke while the old course stayed)."""
        return self.lands and self.beside <= max(2.0, 0.3 * self.before)


def corpus_layers(shapes=SHAPES, per_shape: int = 4, seed: int = 0, resolution: float = 0.03):  # pragma: no mutate block
    """Yield (shape, index, mesh, rng) for ``per_shape`` random layers of each shape kind; the rng
    (seeded by (seed, shape, index)) then draws that layer's edits."""
    from sketchforge_inflate.inflate import inflate_stroke

    for shape in shapes:
        for i in range(per_shape):
            rng = np.random.default_rng([seed, SHAPES.index(shape), i])
            outline = random_outline(shape, rng)
            mesh = inflate_stroke(outline, True, {"resolution": resolution, "inflation": 1.0, "smoothing": 0.5})
            yield shape, i, mesh, rng


def draw_edits(shape: str, mesh, rng, light, edits: int, kinds=KINDS) -> list[Edit]:  # pragma: no mutate block
    """``edits`` random edits on one layer (kinds in turn), drawn before any runs: so two
    solvers can be given the very same edits."""
    from sketchforge.plugin_api import LAMBERTIAN

    from .layerdata import layer_data

    ld = layer_data(mesh, light, LAMBERTIAN)
    out: list[Edit] = []
    tries = 0
    while len(out) < edits and tries < 20 * edits:
        tries += 1
        e = random_edit(shape, ld, rng, kind=kinds[len(out) % len(kinds)])
        if e is not None:
            out.append(e)
    return out


def run_edit(mesh, light, e: Edit, solver=None, params=None) -> Outcome:
    """Run one corpus edit through ``sculpt`` with ``solver`` (None: the built-in) and measure it."""
    import time

    import shapely

    from sketchforge.plugin_api import LAMBERTIAN, SketchforgeError

    from .fidelity import beside_distance, isophote_lines
    from .layerdata import layer_data, vertex_shading
    from .pipeline import sculpt

    ld = layer_data(mesh, light, LAMBERTIAN)
    t, c = time.perf_counter(), time.process_time()
    try:
        # The corpus' layers are fresh: in the app the edit's crease reference is the layer itself.
        r = sculpt(mesh, light, e.pick, e.band, e.stroke, solver=solver, params=params, reference=mesh)
    except SketchforgeError as exc:
        return Outcome(e.shape, e.kind, e.move, "refused", str(exc), np.nan, np.nan, np.nan, time.perf_counter() - t,
                       mesh.n_vertices, cpu=time.process_time() - c)
    except Exception as exc:  # noqa: BLE001  (what the corpus is for: finding these)
        return Outcome(e.shape, e.kind, e.move, "crash", repr(exc), np.nan, np.nan, np.nan, time.perf_counter() - t, mesh.n_vertices)
    seconds, cpu = time.perf_counter() - t, time.process_time() - c
    max_dz = float(np.abs(r.mesh.V[:, 2] - mesh.V[:, 2]).max() / mesh.V[:, 2].max())
    E_new, _, _ = vertex_shading(ld.planar, r.mesh.V[:, 2], light, LAMBERTIAN)
    beside = beside_distance(isophote_lines(ld.planar, E_new, r.c), r.stroke, 0.5 * e.band, ld.h) / ld.h
    moved = np.nonzero(r.changed)[0]
    reach = float(shapely.distance(shapely.points(ld.V2[moved]), r.stroke).max()) / ld.h if len(moved) else 0.0
    return Outcome(e.shape, e.kind, e.move, "ok", "", r.before / ld.h, r.after / ld.h, r.fraction, seconds,
                   mesh.n_vertices, max_dz, beside, float(r.changed.mean()), reach, r.bounded_from, cpu)


def run_edits(shape: str, mesh, rng, light, edits: int, kinds=KINDS, solver=None, params=None) -> list[Outcome]:
    """Draw ``edits`` random edits on one layer (kinds in turn) and run each through ``sculpt``
    with ``solver`` (None: the built-in ``gauss_newton``) and its ``params``."""
    return [run_edit(mesh, light, e, solver, params) for e in draw_edits(shape, mesh, rng, light, edits, kinds)]


def refusal_reason(message: str) -> str:
    """A short key for a refusal message (for counting refusals by reason)."""
    for key, label in (
        ("rim margin", "stroke in the rim margin"),
        ("no part inside the band", "stroke outside the band"),
        ("cannot take this shading", "no closer isophote reachable"),
        ("nothing to change", "already on the isophote"),
    ):
        if key in message:
            return label
    return message.split(":")[0][:60]


# --- chains of edits ----------------------------------------------------------------------------

def folded_faces(mesh) -> np.ndarray:
    """Triangles (m,) bool within the rim margin whose surface falls toward the inside: the
    height decreases along the direction away from the nearest point of the outline (a fold;
    an inflated layer rises from its rim)."""
    from .layerdata import planar_data

    pd = planar_data(mesh)
    F = pd.F
    C = pd.V2[F].mean(axis=1)
    d = pd.rim_distance(C)
    near = d < pd.margin_at(C)
    # The inward direction: the gradient of the distance to the rim, by central differences.
    eps = 0.25 * pd.h
    gx = pd.rim_distance(C + [eps, 0.0]) - pd.rim_distance(C - [eps, 0.0])
    gy = pd.rim_distance(C + [0.0, eps]) - pd.rim_distance(C - [0.0, eps])
    n, _ = face_normals(mesh.V, F)  # (nx, ny, nz): the height gradient is −(nx, ny) / nz
    rising = -(n[:, 0] * gx + n[:, 1] * gy)
    # A sure inward direction only: at a medial point (two rims equally near) the gradient of
    # the distance vanishes and says nothing.
    sure = np.hypot(gx, gy) > 1.0 * eps
    return near & sure & (rising < 0.0)


def chain_measures(fresh, edited, light) -> dict:
    """How a chain of edits left a layer, against the fresh layer (issue 36, point 1).

    Returns
    -------
    dict
        ``dihedral`` and ``dihedral_fresh``: the largest angle (degrees) between the normals of
        two triangles sharing an interior edge (both ends ≥ 3 edge lengths from the outline);
        ``jump`` and ``jump_fresh``: the largest shading jump across such an edge; ``folds``:
        triangles near the rim folded after the chain that were not before
        (:func:`folded_faces`).
    """
    from sketchforge.plugin_api import LAMBERTIAN

    from .layerdata import layer_data

    out = {}
    for suffix, mesh in (("_fresh", fresh), ("", edited)):
        out["dihedral" + suffix], out["jump" + suffix] = largest_creases(layer_data(mesh, light, LAMBERTIAN))
    out["folds"] = int((folded_faces(edited) & ~folded_faces(fresh)).sum())
    return out


@dataclass
class PairOutcome:
    """What a pair of edits did, made jointly (``sculpt_isophotes``) or one after the other.

    Attributes
    ----------
    shape : str
    status : str
        "ok", "refused" or "crash" (sequential: "ok" when at least one edit applied).
    reason : str
    before, after : (2,) float64
        Mean distance from each stroke to its isophote (its pick's isovalue on the layer before
        the pair) before and after, in edge lengths (nan unless ok).
    fractions : (2,) float64
        The share of each stroke's change kept (joint: 1, 0.5 or 0.25).
    seconds : float
    applied : int
        Edits that were applied (joint: 2 or 0).
    """

    shape: str
    status: str
    reason: str
    before: np.ndarray
    after: np.ndarray
    fractions: np.ndarray
    seconds: float
    applied: int = 0

    @property
    def lands(self) -> np.ndarray:
        """(2,) bool: each stroke's isophote after <= max(2, 0.3 × before) edge lengths."""
        if self.status != "ok":
            return np.zeros(2, bool)
        return self.after <= np.maximum(2.0, 0.3 * self.before)

    @property
    def both_land(self) -> bool:
        return bool(self.lands.all())

    @property
    def worse(self) -> bool:
        """A stroke ended farther from its isophote than it started (resolution: h/4)."""
        return self.status == "ok" and bool(np.any(self.after > np.maximum(self.before, 0.25)))


def _pair_distances(ld0, first, second, z):
    """Each stroke's distance (edge lengths) to its own isophote E = c_i of heights ``z``, over
    the samples a single edit of it would honour on the layer before the pair (c_i, band and
    samples from that layer), and the distances before."""
    from sketchforge.plugin_api import band_radius

    from .fidelity import isophote_lines, mean_distance
    from .layerdata import vertex_shading
    from .pipeline import _prepare

    E, _, _ = vertex_shading(ld0.planar, z, ld0.light, ld0.model)
    before, after = [], []
    for e in (first, second):
        p = _prepare(ld0, e.pick, band_radius(e.band), e.stroke)
        before.append(p.before / ld0.h)
        after.append(mean_distance(p.honoured, isophote_lines(ld0.planar, E, p.c)) / ld0.h)
    return np.array(before), np.array(after)


def run_pair(mesh, light, pair, solver=None, params=None) -> tuple[PairOutcome, PairOutcome]:
    """Run a pair of corpus edits jointly (``sculpt_many``) and one after the other
    (``sculpt`` twice, the second on the first's result); measure both the same way."""
    import time

    from sketchforge.plugin_api import LAMBERTIAN, SketchforgeError

    from .joint import sculpt_many
    from .layerdata import layer_data
    from .pipeline import sculpt

    ld0 = layer_data(mesh, light, LAMBERTIAN)
    first, second = pair
    nan2 = np.full(2, np.nan)
    try:
        b0, _ = _pair_distances(ld0, first, second, ld0.z)
    except SketchforgeError as exc:  # a stroke a single edit refuses (outside its band...)
        out = PairOutcome(first.shape, "refused", str(exc), nan2, nan2, nan2, 0.0)
        return out, out
    t = time.perf_counter()
    try:
        r = sculpt_many(mesh, light, [(e.pick, e.band, e.stroke) for e in pair], solver=solver, params=params,
                        reference=mesh)
        _, after = _pair_distances(ld0, first, second, r.mesh.V[:, 2])
        joint = PairOutcome(first.shape, "ok", "", b0, after, np.array([p.fraction for p in r.parts]),
                            time.perf_counter() - t, 2)
    except SketchforgeError as exc:
        joint = PairOutcome(first.shape, "refused", str(exc), b0, nan2, nan2, time.perf_counter() - t)
    except Exception as exc:  # noqa: BLE001  (what the corpus is for: finding these)
        joint = PairOutcome(first.shape, "crash", repr(exc), b0, nan2, nan2, time.perf_counter() - t)
    t = time.perf_counter()
    cur, applied, fr = mesh, 0, [np.nan, np.nan]
    try:
        for k, e in enumerate(pair):
            try:
                res = sculpt(cur, light, e.pick, e.band, e.stroke, solver=solver, params=params, reference=mesh)
                cur, applied, fr[k] = res.mesh, applied + 1, res.fraction
            except SketchforgeError:
                continue
        _, after = _pair_distances(ld0, first, second, cur.V[:, 2])
        seq = PairOutcome(first.shape, "ok" if applied else "refused", "", b0, after, np.array(fr),
                          time.perf_counter() - t, applied)
    except Exception as exc:  # noqa: BLE001
        seq = PairOutcome(first.shape, "crash", repr(exc), b0, nan2, nan2, time.perf_counter() - t)
    return joint, seq
