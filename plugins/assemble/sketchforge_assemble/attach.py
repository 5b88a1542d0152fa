"""Which part attaches to which face, and which stretch of its junction is glued (thesis 4.7,
first paragraph; issue 34).

The rule is the document's own (:mod:`sketchforge.geometry.attachment`, shared with the app's
notes and the mirror about a host): a junction over layers attaches to the one that can take
the longest stretch of it, on that layer's front face if the layer is behind the part and on
its back face if it is in front; only that stretch is glued (the rest of the junction becomes
outline); junctions glued to one face of one host keep apart. A junction that cannot be glued
anywhere makes a free part, with a warning naming it (or an error, on request); a junction
over empty space makes a free part.
"""

from __future__ import annotations

from dataclasses import dataclass

from sketchforge.plugin_api import BACK, FRONT, GeometryError, guard, plan_attachments

from .errors import AttachmentError
from .sheet import Sheet

__all__ = ["Attachment", "BACK", "FRONT", "find_attachments", "lo_chain_index"]


@dataclass(frozen=True)
class Attachment:
    """Part ``upper`` is glued by its junction into face ``side`` of layer ``lower``.

    ``upper``/``lower`` are indices in the back-to-front list ("upper" is the part that owns
    the junction, whatever its depth); ``side`` is :data:`FRONT` (``upper`` is in front of
    ``lower``) or :data:`BACK`. ``keep``: the first and last vertex (inclusive, positions in
    the part's junction as drawn) of the glued stretch; None for the whole junction.
    """

    upper: int
    lower: int
    side: int
    keep: tuple | None = None


def lo_chain_index(attachments: list[Attachment], a_i: int) -> int:
    """Position of attachment a_i's junction among the chains inserted into its lower layer
    (chains are inserted in attachment order, see :func:`.remesh.insert_chains`)."""
    lower = attachments[a_i].lower
    return sum(1 for at in attachments[:a_i] if at.lower == lower)


def find_attachments(sheets: list[Sheet], names: list[str], on_bad_junction: str = "free", exclude=()):
    """Decide every attachment.

    Parameters
    ----------
    sheets : list of Sheet
        Back to front; a sheet with an empty ``junction`` is free.
    names : list of str
        Layer names for messages.
    on_bad_junction : {"free", "raise"}
        What to do with a junction that cannot be glued (no stretch of it long enough lies
        inside one layer, clear of the layers between and of the junctions already glued to
        that face), that closes a loop of attachments, or has fewer than 2 distinct points:
        make the part free and report it (default: the rest of the model assembles), or raise
        :class:`AttachmentError`.
    exclude : set of int
        Parts assembled free whatever their junction (the assembly frees a part whose glued
        junction its host cannot take); the caller reports them.

    Returns
    -------
    attachments : list of Attachment
    warnings : list of str
        One per junction made free; a part not in ``attachments`` is free.
    notes : list of str
        One per part glued by a stretch of its junction only (it runs off its host, spans two
        layers or touches another junction on the same face).
    """
    polys = [s.polygon() for s in sheets]
    warnings: list[str] = []

    def bad_junction(problem: str) -> None:
        if on_bad_junction == "raise":
            raise AttachmentError(problem[0].upper() + problem[1:] + ".")
        warnings.append(problem if "free part" in problem else problem + " (assembled as a free part)")

    junctions: list = []  # per sheet: its drawn junction (k, 2), or None
    for u, s in enumerate(sheets):
        if len(s.junction) == 0 or u in exclude:
            junctions.append(None)
            continue
        try:
            # The sheet's coordinates are checked (sheet_from_mesh), so this refuses only a
            # junction whose points all coincide (a hand-edited snapshot): a junction problem
            # like the others, not a reason to stop the whole assembly.
            guard.linestring(s.xy[s.drawn_junction()], f"the junction of layer '{names[u]}'")
        except GeometryError as exc:
            bad_junction(f"{exc}, so it cannot be glued to a layer; redraw the part")
            junctions.append(None)
            continue
        junctions.append(s.xy[s.drawn_junction()])
    ends = [t.xy[t.junction[[0, -1]]] if len(t.junction) >= 2 else None for t in sheets]
    plans = plan_attachments(junctions, polys, [t.h for t in sheets], [f"'{n}'" for n in names], ends)
    attachments: list[Attachment] = []
    notes: list[str] = []
    for u, found in enumerate(plans):
        if found is None:
            continue
        if found.host is not None:
            whole = found.keep == (0, len(sheets[u].drawn_junction()) - 1)
            attachments.append(Attachment(u, found.host, found.side, None if whole else tuple(found.keep)))
            if found.note:
                notes.append(found.note)
        elif found.problem is not None:
            bad_junction(found.problem)
        else:
            # over empty space: a free part, as drawn; never an error, but said (a part that was
            # glued and lost its host when a layer moved must not go free without a word)
            warnings.append(f"the junction of layer '{names[u]}' lies on no part, so it is assembled as a free part")
    return _break_loops(attachments, names, bad_junction), warnings, notes


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
