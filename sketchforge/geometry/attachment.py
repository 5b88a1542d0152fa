"""Which layer a part's junction attaches to: the one rule the document's commands (mirror
about the host, the checks after a redraw, the app's warning before an assembly) and the
assembly (``sketchforge_assemble.attach``) share, so they never disagree.

A part drawn as an open stroke has a junction Γ_conn. Walking from the part, its junction
attaches to the nearest layer *behind* it whose region it lies over (the part is glued to that
layer's front face); failing that, to the nearest layer *in front* whose region holds it, on
that layer's back face (the same rule seen from behind: legs moved behind the body). The
nearest layer over the junction on a side must hold all of it, with a little clearance (the
junction is cut into it as a slit); if it holds only part (the junction runs off its outline,
or spans two layers) and the other side does not attach either, that is a problem, said in
one sentence. A junction over empty space makes a free part. A layer glued by the very same
junction (a copy duplicated in place, about to be mirrored) is looked past: the part hangs on
what its twin hangs on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

#: Sides: the part is in front of its host (glued to the host's front face) or behind it.
FRONT = 1
BACK = -1
#: The clearance the junction keeps from the host's outline, in the host's edge lengths (the
#: re-triangulation around the slit then has no slivers).
CLEARANCE_EDGES = 0.05


@dataclass(frozen=True)
class JunctionHost:
    """Where one part's junction attaches.

    Attributes
    ----------
    host : int or None
        Index of the host in the back-to-front list; None for a free part or a problem.
    side : int
        :data:`FRONT` or :data:`BACK` (0 when there is no host).
    problem : str or None
        Why a junction over a layer cannot attach ("the junction of layer 'tail' runs outside
        layer 'body'; redraw its ends so that both lie inside 'body'"), None otherwise.
    near : int or None
        The nearest layer the junction lies over: the host, or, with a problem, the layer the
        problem names first (what a person would call the part's host, e.g. to mirror about).
    """

    host: int | None
    side: int = 0
    problem: str | None = None
    near: int | None = None


def median_edge_length(xy: np.ndarray, F: np.ndarray) -> float:
    """The median edge length of a layer's triangles (xy (n, 2), F (m, 3)): the length scale of
    the tolerances here (the assembly's sheets use the same)."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    return float(np.median(np.linalg.norm(xy[E[:, 0]] - xy[E[:, 1]], axis=1))) if len(E) else 0.0


def find_host(junction: shapely.LineString, index: int, regions: list, edge_lengths: list, names: list[str],
              part_h: float, junction_ends: list | None = None) -> JunctionHost:
    """The attachment of the junction of layer ``index`` (see the module docstring).

    Parameters
    ----------
    junction : shapely LineString
        The part's junction Γ_conn in the drawing plane (at least 2 distinct points).
    index : int
        The part's place in the back-to-front list.
    regions : list of shapely Polygon or None
        Every layer's region, holes cut out, back to front (None: a layer that takes no part,
        e.g. hidden or without a mesh).
    edge_lengths : list of float
        Every layer's edge length (the host's sets the clearance).
    names : list of str
        Layer names for the sentence (already quoted as they should appear, e.g. "'body'").
    part_h : float
        The part's edge length (sets the tolerance of "lies over").
    junction_ends : list of (2, 2) float64 or None, optional
        Every layer's junction end points (None: no junction); a layer whose junction has the
        part's own ends (either way round) is a twin glued at the same place: looked past.
    """
    tol = 1e-6 * max(junction.length, part_h)
    if junction_ends is not None and junction_ends[index] is not None:
        ends = np.asarray(junction_ends[index])
        same = 1e-6 * max(1.0, float(np.abs(ends).max()))
        regions = [None if (i != index and e is not None and min(np.abs(np.asarray(e) - ends).max(),
                                                                 np.abs(np.asarray(e)[::-1] - ends).max()) <= same)
                   else r for i, (r, e) in enumerate(zip(regions, junction_ends))]
    problem = near = None
    for side, order in ((FRONT, range(index - 1, -1, -1)), (BACK, range(index + 1, len(regions)))):
        hits = [i for i in order if regions[i] is not None and junction.intersection(regions[i]).length > tol]
        if not hits:
            continue
        host = hits[0]
        outside = junction.difference(regions[host].buffer(-CLEARANCE_EDGES * edge_lengths[host])).length
        if outside <= tol:
            return JunctionHost(host, side, None, host)
        # Not on this side; remember why, but still try the other side (a layer partly under
        # the junction behind the part must not stop it attaching to the layer in front that
        # holds the whole junction, e.g. after moving an arm behind everything).
        if problem is not None:
            continue
        near = host
        part, lower = names[index], names[host]
        if len(hits) > 1 and any(junction.difference(regions[host]).intersection(regions[i]).length > tol for i in hits[1:]):
            problem = (f"the junction of layer {part} spans two layers ({lower} and {names[hits[1]]}); "
                       "redraw its ends so that both lie inside one layer")
        else:
            problem = f"the junction of layer {part} runs outside layer {lower}; redraw its ends so that both lie inside {lower}"
    return JunctionHost(None, 0, problem, near)
