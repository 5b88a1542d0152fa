"""Which part attaches to which face (thesis 4.7, first paragraph).

A part drawn as an open stroke has a junction Γ_conn. Walking from the front, its junction
attaches to the nearest layer *behind* it whose region it lies over (the part is glued to that
layer's front face); failing that, to the nearest layer *in front* whose region holds the
junction, on that layer's back face (the same rule seen from behind, e.g. legs moved behind
the body). The nearest layer over the junction on a side must hold all of it; if it holds only
part (the junction spans two layers, or runs off the layer's outline) and the other side does
not attach either, the junction is an error (or, on request, a free part). A junction over
empty space makes a free part.
"""

from __future__ import annotations

from dataclasses import dataclass

from sketchforge.plugin_api import GeometryError
from sketchforge.plugin_api import guard
from sketchforge.plugin_api import BACK, FRONT, find_host

from .errors import AttachmentError
from .sheet import Sheet

__all__ = ["Attachment", "BACK", "FRONT", "find_attachments", "lo_chain_index"]


@dataclass(frozen=True)
class Attachment:
    """Part ``upper`` is glued by its junction into face ``side`` of layer ``lower``.

    ``upper``/``lower`` are indices in the back-to-front list ("upper" is the part that owns
    the junction, whatever its depth); ``side`` is :data:`FRONT` (``upper`` is in front of
    ``lower``) or :data:`BACK`.
    """

    upper: int
    lower: int
    side: int


def lo_chain_index(attachments: list[Attachment], a_i: int) -> int:
    """Position of attachment a_i's junction among the chains inserted into its lower layer
    (chains are inserted in attachment order, see :func:`.remesh.insert_chains`)."""
    lower = attachments[a_i].lower
    return sum(1 for at in attachments[:a_i] if at.lower == lower)


def find_attachments(sheets: list[Sheet], names: list[str], on_bad_junction: str = "raise"):
    """Decide every attachment.

    Parameters
    ----------
    sheets : list of Sheet
        Back to front; a sheet with an empty ``junction`` is free.
    names : list of str
        Layer names for messages.
    on_bad_junction : {"raise", "free"}
        What to do with a junction that spans two layers, runs partly outside the layer below
        or has fewer than 2 distinct points: raise :class:`AttachmentError` (default: the
        person sees why the part did not attach and can fix the stroke), or make the part
        free and report it.

    Returns
    -------
    attachments : list of Attachment
    warnings : list of str
        One per junction made free (``on_bad_junction="free"``); a part not in
        ``attachments`` is free.
    """
    polys = [s.polygon() for s in sheets]
    attachments: list[Attachment] = []
    warnings: list[str] = []

    def bad_junction(problem: str) -> None:
        if on_bad_junction == "raise":
            raise AttachmentError(problem[0].upper() + problem[1:] + ".")
        warnings.append(problem + " (assembled as a free part)")

    for u, s in enumerate(sheets):
        if len(s.junction) == 0:
            continue
        try:
            # The sheet's coordinates are checked (sheet_from_mesh), so this refuses only a
            # junction whose points all coincide (a hand-edited snapshot): a junction problem
            # like the others, not a reason to stop the whole assembly.
            line = guard.linestring(s.xy[s.junction], f"the junction of layer '{names[u]}'")
        except GeometryError as exc:
            bad_junction(f"{exc}, so it cannot be glued to a layer; redraw the part")
            continue
        # The document's rule (sketchforge.geometry.attachment), shared with its commands and
        # the app's warnings: the junction is cut into the host as a slit, so it must lie
        # inside its outline with a little clearance.
        ends = [t.xy[t.junction[[0, -1]]] if len(t.junction) >= 2 else None for t in sheets]
        found = find_host(line, u, polys, [t.h for t in sheets], [f"'{n}'" for n in names], s.h, ends)
        if found.host is not None:
            attachments.append(Attachment(u, found.host, found.side))
        elif found.problem is not None:
            bad_junction(found.problem)
    return _break_loops(attachments, names, bad_junction), warnings


def _break_loops(attachments: list[Attachment], names: list[str], bad_junction) -> list[Attachment]:
    """The attachments without any that closes a loop.

    Every part has at most one junction, so each attachment is an edge part -> layer and a
    group of attached parts is a tree unless some edges close a cycle (a part glued onto a
    layer whose own junction lies on that part, directly or through others). A cycle would
    glue a sleeve onto itself: the result is no longer a sphere per group (a torus, or a
    non-manifold mesh), so it is refused by name (``bad_junction`` raises, or frees the part
    whose attachment closes the loop and records why).
    """
    parent: dict[int, int] = {}

    def root(a: int) -> int:
        while parent.get(a, a) != a:
            a = parent[a]
        return a

    onto = {a.upper: a.lower for a in attachments}
    kept = []
    for a in attachments:
        ru, rl = root(a.upper), root(a.lower)
        if ru == rl:
            cycle = [a.upper]
            while onto[cycle[-1]] != a.upper:
                cycle.append(onto[cycle[-1]])
            path = " -> ".join(f"'{names[i]}'" for i in cycle + [a.upper])
            bad_junction(
                f"the attachments form a loop ({path}: each is glued onto the next); move one of these "
                f"parts in depth or redraw its junction so that it lies on a layer outside the loop"
            )
            continue
        parent[ru] = rl
        kept.append(a)
    return kept
