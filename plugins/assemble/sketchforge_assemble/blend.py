"""Junctions that blend (issue 12): a fillet where a part meets its host, instead of a fold.

Why a fold appears. Every layer is a height field over the drawing plane, and a part glued by
its junction Γ_conn into a slit of its host overlaps the host on one side of the slit: there
the host's face (the slit's "+" lip) and the part's back face (seen from the front) are two
height fields over the same side of the junction, joined along it. Walking across the junction
from one to the other is a U-turn; with both faces nearly flat it is a 180° crease however the
depths are solved, and on the other lip the part's own inflation, which has a vertical tangent
on its whole outline, rises straight up from a flat host.

How the fold is spread out (all heights relative to the depth unknowns, so the depth QP keeps
every ordering and glue row):

* "+" lip: the U-turn goes through a vertical strip, like the rim bridge of a free part's
  outline. The host's "+" lip keeps its own vertices, lifted by ``plus`` above the host's
  surface, and a strip of height ``step`` joins them to the part's back chain; the host's "+"
  face rises to its lip through a fillet, and the part's back face leaves the strip rising,
  so the 180° are shared by four bends of about 45° each, each spread over a few rings.
* "−" lip: the host's face rises through a fillet of height ``plus + step`` (the height of the
  part's front chain) and the part's front face leaves the lip with the same slope, its own
  inflation faded in over the fillet length (longer for a thick part).
* Springs (soft rows of the depth QP) hold every part vertex within the fillet at the height
  of the host's face next to its junction plus the fillet's clearance, so the part starts
  where the host is and the part's faces are shaped relative to the host, not to the
  drawing plane.

Status (measured by ``benchmarks/bench_junctions.py``): on its own this halves or better the
edges above 90° and lowers the largest angle from ~177° to ~125°, but the turns that are left
(mostly within three edge lengths of a junction's ends, where every amount fades out, and
where the strip meets the faces) keep it well above the issue's 45° target, and a few random
creatures get one self-intersecting pair there. :mod:`.fair` then smooths the rings around
every junction of the assembled mesh, which brings every tested model within the target; the
two together are the default (``fillet`` 4, ``fair`` 14).

All amounts fade to zero at the two ends of the junction, where the part's front and back
faces meet in one vertex (see :func:`.sheet.taper`).
"""

from __future__ import annotations

import numpy as np
import shapely

from .attach import FRONT, Attachment, lo_chain_index
from .sheet import Sheet, end_taper


def profile(t: np.ndarray) -> np.ndarray:
    """(k,) float64: the fillet's shape, 1 at the junction (t = 0), 0 from t = 1 on.

    A parabola: constant curvature, so the bend is shared evenly by every ring of the fillet
    (its slope at t = 0 is -2, i.e. a height ``a`` over a width ``W`` leaves at slope 2a/W).
    """
    t = np.clip(t, 0.0, 1.0)
    return (1.0 - t) ** 2


def distance_to(xy: np.ndarray, line_xy: np.ndarray, reach: float = np.inf) -> np.ndarray:
    """(n,) float64 distance of the points xy (n, 2) to the polyline line_xy (c, 2); with
    ``reach``, inf for every point farther than that from the polyline's bounding box (the
    host of a short junction is mostly far from it: only its few nearby vertices are measured)."""
    if np.isfinite(reach):
        lo, hi = line_xy.min(axis=0) - reach, line_xy.max(axis=0) + reach
        near = np.flatnonzero(np.all((xy >= lo) & (xy <= hi), axis=1))
        out = np.full(len(xy), np.inf)
        out[near] = distance_to(xy[near], line_xy)
        return out
    a, b = line_xy[:-1], line_xy[1:]
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    best = np.full(len(xy), np.inf)
    x, y = xy[:, 0:1], xy[:, 1:2]
    # chunked over segments: junctions have tens of points, layers tens of thousands. The
    # least squared distance, then one square root: sqrt is monotonic and correctly rounded,
    # so the same bits as the least of the distances, at a third of the cost.
    for s in range(0, len(a), 64):
        A, AB, l2 = a[s:s + 64], ab[s:s + 64], L2[s:s + 64]
        t = np.clip(np.einsum("nsk,sk->ns", xy[:, None, :] - A[None], AB) / l2, 0.0, 1.0)
        dx = x - (A[None, :, 0] + t * AB[None, :, 0])
        dy = y - (A[None, :, 1] + t * AB[None, :, 1])
        best = np.minimum(best, np.min(dx * dx + dy * dy, axis=1))
    return np.sqrt(best)


def _distance_and_nearest(xy: np.ndarray, line_xy: np.ndarray, reach: float):
    """((n,) distance of xy (n, 2) to the polyline line_xy (c, 2), inf beyond ``reach`` of its
    bounding box; (n,) int64 the polyline vertex nearest to each point (0 where inf))."""
    from scipy.spatial import cKDTree

    d = distance_to(xy, line_xy, reach=reach)
    nearest = np.zeros(len(xy), np.int64)
    fin = np.flatnonzero(np.isfinite(d))
    if len(fin):
        nearest[fin] = cKDTree(line_xy).query(xy[fin])[1]
    return d, nearest


def blend_junctions(sheets: list[Sheet], attachments: list[Attachment], front_off: list[np.ndarray],
                    back_off: list[np.ndarray], width: float = 4.0, pull: float = 50.0, locators=None):
    """Shape the faces near every junction into a fillet (module docstring); in place.

    Parameters
    ----------
    sheets : list of Sheet
        After junction insertion.
    attachments : list of Attachment
    front_off, back_off : list of (n_i,) float64
        Front z = δ + front_off, back z = δ - back_off of every sheet; changed in place near
        the junctions.
    width : float
        Fillet width in edge lengths of the part.
    pull : float
        Weight of the springs that hold the part near its junction on the host (see
        ``springs``), relative to the part's Dirichlet energy.
    locators : dict, optional
        Point location per sheet face (:func:`.depth.face_locator`), shared with
        :func:`.depth.build_problem` (a host with several parts, the body, is located in
        once); filled as needed.

    Returns
    -------
    lip : list of (c,) float64
        Per attachment, how far the host's "+" lip lies off the host's face at each chain
        vertex, towards the part.
    glue : list of (c,) float64
        Per attachment, how far the part's facing junction chain lies off the host's face
        (``lip`` plus the strip's height).
    springs : list of (part_cols (k,), host_cols (k, 3), bary (k, 3), weight (k,), target (k,))
        Sheet-local indices: soft rows  δ_part(v) - Σ bary·δ_host ≈ target  that make the part
        start where the host is. A part vertex near its junction takes its mid-depth from
        the host's face right under it (plus its fillet and half its own thickness), with a
        weight that fades to 0 over the fillet, so the part's slope continues the host's,
        whatever the depth solve does to the host.
    """
    from .depth import face_locator

    locators = {} if locators is None else locators
    lips, glues, springs = [], [], []
    base_front = [f.copy() for f in front_off]  # before any fillet: the faces as drawn
    base_back = [b.copy() for b in back_off]
    for a_i, at in enumerate(attachments):
        up, lo = sheets[at.upper], sheets[at.lower]
        h = up.h
        W = width * h
        plus, step = 0.7 * W, 0.5 * h  # fillet height of the "+" lip and the strip's height
        rise = plus + step  # height of the part's chain over the host: the "−" fillet
        j_xy = up.xy[up.junction]
        ends = j_xy[[0, -1]]
        taper_r = 3.0 * h
        c = lo.chains[lo_chain_index(attachments, a_i)]

        # the part: its own inflation faded in over the fillet, symmetric about its mid-depth
        d = distance_to(up.xy, j_xy)
        phi = profile(d / W)
        theta = 1.0 - phi
        e = end_taper(up.xy, ends, taper_r)
        margin = base_front[at.upper] - up.z
        # The part keeps its full thickness up to the junction (thickness.full_thickness):
        # the host rises to meet its front chain instead.

        # springs: mid-depth = host face under the vertex + the part's back clearance
        # (rising from the strip's top) + its half thickness
        zone = np.flatnonzero(phi > 0)
        face, bary = face_locator(locators, None, sheets, at.lower, at.side).locate(up.xy[zone])
        ok = face >= 0
        zone, tri, bary = zone[ok], lo.face(at.side)[face[ok]], np.clip(bary[ok], 0.0, 1.0)
        bary /= bary.sum(axis=1, keepdims=True)
        facing = base_front[at.lower] if at.side == FRONT else base_back[at.lower]
        under = np.sum(bary * facing[tri], axis=1)
        # relative to the nearest junction point: where the host falls away under the part
        # (a part glued near the host's outline) the part keeps the junction's height and
        # the pocket between them opens, instead of diving down the host's flank with it
        near_c = c[np.argmin(np.linalg.norm(up.xy[zone][:, None, :] - lo.xy[c][None], axis=2), axis=1)]
        host = np.maximum(under, facing[near_c])
        clear = (rise + plus * theta[zone]) * e[zone] + margin[zone] + up.z[zone]
        sgn = 1.0 if at.side == FRONT else -1.0
        springs.append((zone, near_c[:, None], np.ones((len(zone), 1)), pull * phi[zone], sgn * (host + clear)))

        # the host: a fillet on each side of the slit, rising to the lips. The "-" side rises to
        # the part's front chain: the lip plus the part's thickness there, over a width that
        # grows with that height (slopes of at most about 1 in the fillet's parabola).
        ec = end_taper(lo.xy[c], ends, taper_r)
        thick_j = 2.0 * (up.z[up.junction] + margin[up.junction])
        rise_minus = rise * ec + thick_j
        W_minus = np.maximum(W, 2.0 * rise_minus)
        reach = float(W_minus.max())
        dl, nearest = _distance_and_nearest(lo.xy, lo.xy[c], reach)
        el = end_taper(lo.xy, ends, taper_r)
        inside = np.zeros(lo.n, bool)
        fil = np.flatnonzero(dl < reach)  # only these get a fillet
        inside[fil] = shapely.contains_xy(up.polygon(), lo.xy[fil, 0], lo.xy[fil, 1])
        Wv = np.where(inside, W, W_minus[nearest])
        amount = np.where(inside, plus * el, rise_minus[nearest] * np.maximum(el, thick_j[nearest] / np.maximum(
            rise_minus[nearest], 1e-300))) * profile(dl / Wv)
        amount[c] = 0.0  # the chain's own vertices are replaced by the lips (see stitch)
        if at.side == FRONT:
            front_off[at.lower] = front_off[at.lower] + amount
        else:
            back_off[at.lower] = back_off[at.lower] + amount
        lips.append(plus * ec)
        glues.append(rise * ec)
    return lips, glues, springs
