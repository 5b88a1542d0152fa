"""Which layer a part's junction attaches to, and which stretch of it is glued: the one rule the
document's commands (mirror about the host, the checks after a redraw, the app's notes before
an assembly and when a stroke is released) and the assembly (``sketchforge_assemble.attach``)
share, so they never disagree.

A part drawn as an open stroke has a junction Γ_conn (its closing segment). People draw
Monster-Mash style: the far legs behind the body and overlapping the near ones, twin ears whose
bases touch, heads whose ends overshoot the body a little (issue 34). So the rule never refuses
a whole junction for one stretch of it:

* **Sides.** A layer behind the part is a host on its *front* face (:data:`FRONT`), a layer in
  front of it on its *back* face (:data:`BACK`): a leg drawn behind the body hangs on the
  body's back, the near leg on its front, and the two never meet on one face.
* **Candidates.** Every layer the junction lies over is a candidate. The stretch of the
  junction a candidate can take is the longest run of junction segments that lie inside its
  region (kept :data:`CLEARANCE_EDGES` host edge lengths from its outline, so the slit cut
  into it leaves no slivers) and over no layer lying *between* the part and the candidate in
  depth (gluing there would pass through that layer).
* **Choice.** The candidate that can take the longest stretch wins (ties: the nearest behind
  first, then the nearest in front): a junction spanning two parts attaches to the one that
  holds most of it. Only that stretch is glued; the rest of the junction becomes ordinary
  outline (the part's rim is closed there like anywhere else), and a note says so.
* **One face, several parts.** Junctions glued onto the same face of one host must keep
  :data:`SEPARATION_EDGES` edge lengths apart (two slits that touch would pinch the surface
  into a non-manifold vertex): parts are placed back to front, and a later part keeps the
  longest stretch of its junction clear of those placed before it (twin ears whose bases
  touch each lose a little of their base, never the model).
* A stretch shorter than :data:`MIN_GLUE_SEGMENTS` segments (or
  :data:`MIN_GLUE_EDGES` of the part's edge lengths) cannot be glued: the part is free and
  the problem sentence says why; the rest of the model still assembles. A junction over empty
  space makes a free part without a problem (the app says so when the stroke is drawn).
* A layer glued by the very same junction (a copy duplicated in place, about to be mirrored)
  is looked past when choosing the host: the part hangs on what its twin hangs on.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely

#: Sides: the part is in front of its host (glued to the host's front face) or behind it.
FRONT = 1
BACK = -1
#: The clearance the junction keeps from the host's outline, in the host's edge lengths (the
#: re-triangulation around the slit then has no slivers).
CLEARANCE_EDGES = 0.05
#: How far apart (in edge lengths, the larger of the two parts') the glued stretches of two
#: junctions on one face of one host stay: the host's vertices within about half an edge of a
#: slit are removed, so this leaves a row of triangles between two slits.
SEPARATION_EDGES = 1.0
#: How far (in the part's edge lengths) a glued stretch keeps from a layer lying between the
#: part and its host in depth.
BETWEEN_EDGES = 0.5
#: The shortest glued stretch: this many junction segments, and this many of the part's edge
#: lengths. Shorter, and the sleeve glued into the host would be a sliver.
MIN_GLUE_SEGMENTS = 2
MIN_GLUE_EDGES = 1.5


@dataclass(frozen=True)
class JunctionHost:
    """Where one part's junction attaches.

    Attributes
    ----------
    host : int or None
        Index of the host in the back-to-front list; None for a free part.
    side : int
        :data:`FRONT` or :data:`BACK` (0 when there is no host).
    problem : str or None
        Why a junction over a layer cannot be glued at all ("the junction of layer 'tail'
        lies on 'body' for less than 2 edge lengths"), None otherwise; the part is then free.
    near : int or None
        The layer holding most of the junction: the host, or, with a problem, the layer that
        came closest (what a person would call the part's host, e.g. to mirror about).
    keep : (int, int) or None
        First and last junction vertex of the glued stretch (inclusive, in the junction's
        order); None without a host.
    note : str or None
        What the person should know although the part attaches: only a stretch of the
        junction is glued (it runs off its host, spans two layers, or touches another part's
        junction on the same face), said in one sentence.
    """

    host: int | None
    side: int = 0
    problem: str | None = None
    near: int | None = None
    keep: tuple[int, int] | None = None
    note: str | None = None

    @property
    def attached(self) -> bool:
        return self.host is not None


def median_edge_length(xy: np.ndarray, F: np.ndarray) -> float:
    """The median edge length of a layer's triangles (xy (n, 2), F (m, 3)): the length scale of
    the tolerances here (the assembly's sheets use the same)."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    return float(np.median(np.linalg.norm(xy[E[:, 0]] - xy[E[:, 1]], axis=1))) if len(E) else 0.0


def _segments(P: np.ndarray):
    """Shapely LineStrings of the k-1 segments of the polyline P (k, 2)."""
    return shapely.linestrings(np.stack([P[:-1], P[1:]], axis=1))


def longest_run(ok: np.ndarray, lengths: np.ndarray) -> tuple[int, int, float]:
    """(first segment, last segment + 1, length) of the longest run of consecutive True in
    ``ok`` (s,) bool, measured by ``lengths`` (s,) float64; ties: the first. (0, 0, 0.0) if
    none."""
    best = (0, 0, 0.0)
    start = None
    for i in range(len(ok) + 1):
        if i < len(ok) and ok[i]:
            if start is None:
                start = i
            continue
        if start is not None:
            total = float(lengths[start:i].sum())
            if total > best[2] * (1 + 1e-12) + 1e-300:
                best = (start, i, total)
            start = None
    return best


def _twins(index: int, junction_ends: Sequence | None) -> set[int]:
    """Layers whose junction has the same two ends as layer ``index``'s (either way round)."""
    if junction_ends is None or junction_ends[index] is None:
        return set()
    ends = np.asarray(junction_ends[index])
    same = 1e-6 * max(1.0, float(np.abs(ends).max()))
    out = set()
    for i, e in enumerate(junction_ends):
        if i == index or e is None:
            continue
        e = np.asarray(e)
        if min(np.abs(e - ends).max(), np.abs(e[::-1] - ends).max()) <= same:
            out.add(i)
    return out


def find_host(junction, index: int, regions: list, edge_lengths: list, names: list[str],
              part_h: float, junction_ends: list | None = None) -> JunctionHost:
    """The host of the junction of layer ``index`` and the stretch glued to it (module
    docstring), before other parts' junctions on the same face are taken into account (see
    :func:`plan_attachments`).

    Parameters
    ----------
    junction : shapely LineString or (k, 2) float64
        The part's junction Γ_conn in the drawing plane, in its vertex order (at least 2
        distinct points); the stretch is counted in these vertices.
    index : int
        The part's place in the back-to-front list.
    regions : list of shapely Polygon or None
        Every layer's region, holes cut out, back to front (None: a layer that takes no part,
        e.g. hidden or without a mesh).
    edge_lengths : list of float
        Every layer's edge length (the host's sets the clearance).
    names : list of str
        Layer names for the sentences (already quoted as they should appear, e.g. "'body'").
    part_h : float
        The part's edge length (sets the tolerances of "lies over" and the shortest stretch).
    junction_ends : list of (2, 2) float64 or None, optional
        Every layer's junction end points (None: no junction); a layer whose junction has the
        part's own ends (either way round) is a twin glued at the same place: looked past.
    """
    P = np.asarray(junction.coords if isinstance(junction, shapely.LineString) else junction, dtype=np.float64)
    seg_len = np.linalg.norm(np.diff(P, axis=0), axis=1)
    total = float(seg_len.sum())
    tol = 1e-6 * max(total, part_h)
    segs = _segments(P)
    line = shapely.LineString(P)
    twins = _twins(index, junction_ends)
    n = len(regions)
    order = [(i, FRONT) for i in range(index - 1, -1, -1)] + [(i, BACK) for i in range(index + 1, n)]
    order = [(i, s) for i, s in order if regions[i] is not None and i not in twins]
    over = [(i, s) for i, s in order if line.intersection(regions[i]).length > tol]
    if not over:
        return JunctionHost(None)
    best = None  # (length, rank, host, side, first, stop, why)
    for rank, (c, side) in enumerate(over):
        inner = regions[c].buffer(-CLEARANCE_EDGES * edge_lengths[c])
        shapely.prepare(inner)
        inside = shapely.within(segs, inner) if not inner.is_empty else np.zeros(len(segs), bool)
        ok = inside.copy()
        met = []  # the layers between the part and this candidate that the junction meets
        between = [i for i in (range(c + 1, index) if side == FRONT else range(index + 1, c))
                   if regions[i] is not None and i not in twins]
        for i in between:
            if not ok.any():
                break
            hit = shapely.intersects(segs, regions[i].buffer(BETWEEN_EDGES * part_h))
            if (hit & ok).any():
                met.append(i)
            ok &= ~hit
        first, stop, length = longest_run(ok, seg_len)
        if best is None or length > best[0] * (1 + 1e-9) + tol:
            best = (length, rank, c, side, first, stop, (bool((~inside).any()), met))
    length, _, c, side, first, stop, (off, met) = best
    part = names[index]
    if stop - first < MIN_GLUE_SEGMENTS or length < MIN_GLUE_EDGES * part_h - tol:
        near = over[0][0] if length <= 0 else c
        return JunctionHost(None, 0, _short_problem(part, names[near], over, names), near)
    note = None
    if stop - first < len(seg_len):
        note = _partial_note(part, c, length / total, over, met, off, names)
    return JunctionHost(c, side, None, c, (first, stop), note)


def _short_problem(part: str, lower: str, over, names) -> str:
    others = [names[i] for i, _ in over if names[i] != lower]
    where = f"lies on {lower}" if not others else f"lies across {lower} and {others[0]}"
    return (f"the junction of layer {part} {where} with no stretch of at least {MIN_GLUE_EDGES:g} edge lengths "
            f"inside one of them, so it is assembled as a free part; redraw its ends so that they lie inside one part")


def _partial_note(part: str, c: int, share: float, over, met, off: bool, names) -> str:
    """One sentence: which stretch of a junction is glued, and why not all of it."""
    host = names[c]
    pct = f"{100 * share:.0f}%"
    others = [names[i] for i, _ in over if i != c and i not in met]
    if others:
        return (f"the junction of layer {part} spans {host} and {others[0]}: it is glued to {host}, which holds most "
                f"of it ({pct})")
    if met:
        return (f"the junction of layer {part} meets {names[met[0]]}, which lies between it and {host}: only the "
                f"{pct} of it clear of {names[met[0]]} is glued to {host}")
    return f"the junction of layer {part} runs off {host}: only the {pct} of it inside {host} is glued"


def plan_attachments(junctions: Sequence, regions: list, edge_lengths: list, names: list[str],
                     junction_ends: list | None = None) -> list[JunctionHost | None]:
    """Every part's :class:`JunctionHost`, with the parts that share a face of one host kept
    apart (module docstring).

    Parameters
    ----------
    junctions : list of (k_i, 2) float64 or None
        Every layer's junction polyline, back to front (None: a free part, or a layer that
        takes no part).
    regions, edge_lengths, names, junction_ends
        As in :func:`find_host`.

    Returns
    -------
    list of JunctionHost or None
        None where ``junctions`` has None.
    """
    out: list[JunctionHost | None] = [None] * len(junctions)
    for k, J in enumerate(junctions):
        if J is None:
            continue
        J = np.asarray(J, dtype=np.float64)
        if len(J) < 2 or float(np.linalg.norm(np.diff(J, axis=0), axis=1).sum()) <= 0:
            continue
        out[k] = find_host(J, k, regions, edge_lengths, names, edge_lengths[k], junction_ends)
    # One face of one host, several junctions: back to front, each keeps clear of the glued
    # stretches placed before it.
    placed: dict[tuple[int, int], list[tuple[int, shapely.LineString]]] = {}
    for k, found in enumerate(out):
        if found is None or found.host is None:
            continue
        J = np.asarray(junctions[k], dtype=np.float64)
        first, stop = found.keep
        face = (found.host, found.side)
        taken = placed.get(face, [])
        if taken:
            seg_len = np.linalg.norm(np.diff(J, axis=0), axis=1)
            ok = np.zeros(len(seg_len), bool)
            ok[first:stop] = True
            segs = _segments(J)
            close = []  # the parts whose glued stretch this junction comes too close to
            for other, glued in taken:
                sep = SEPARATION_EDGES * max(edge_lengths[k], edge_lengths[other], edge_lengths[found.host])
                clear = shapely.distance(segs, glued) >= sep
                if not clear[first:stop].all():
                    close.append(other)
                ok &= clear
            a, b, length = longest_run(ok, seg_len)
            if (a, b) != (first, stop):
                who = " and ".join(names[o] for o in close[:2]) + (f" and {len(close) - 2} more" if len(close) > 2 else "")
                if b - a < MIN_GLUE_SEGMENTS or length < MIN_GLUE_EDGES * edge_lengths[k]:
                    out[k] = JunctionHost(None, 0, f"the junction of layer {names[k]} lies where the junction of "
                                                   f"{who} is glued on the same side of {names[found.host]}, so it is "
                                                   "assembled as a free part; move one of them apart", found.host)
                    continue
                share = length / float(seg_len.sum())
                note = (f"the junction of layer {names[k]} touches the junction of {who} on {names[found.host]}: "
                        f"{100 * share:.0f}% of it is glued")
                out[k] = JunctionHost(found.host, found.side, None, found.host, (a, b), note)
                first, stop = a, b
        placed.setdefault(face, []).append((k, shapely.LineString(J[first:stop + 1])))
    return out
