"""The assembly's choices (``set_assembly``) and where it glues each part: the attachment
queries (host, problem, note) that the app and the mirror command ask."""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, ClassVar

from sketchforge.document.commands.base import Command, parse_field, parse_params
from sketchforge.document.layer import Layer
from sketchforge.errors import SketchforgeError, quote


@dataclass
class SetAssembly(Command):
    """Choose the document's assembler and its parameters (``set_assembly``): ``solver`` (None:
    the default, the built-in ``"depth_qp"``) and its ``params``, checked by the assembler
    (an unknown key or a bad value is refused, naming the assembler and the key). Naming
    another assembler starts from its defaults; otherwise ``params`` are merged into the
    current ones. The assembled model is rebuilt when next shown."""

    name: ClassVar[str] = "set_assembly"
    solver_kind: ClassVar[str | None] = "assemble"
    solver: str | None = None
    params: dict = field(default_factory=dict)
    _old: Any = field(default=None, repr=False)
    _new: Any = field(default=None, repr=False)

    def text(self) -> str:
        return "Set assembly"

    def do(self, doc) -> None:
        from sketchforge.solver_kinds import SolverChoice

        old = doc.assembly
        switch = self.solver is not None and self.solver != old.solver
        solver = self.solver if self.solver is not None else old.solver
        assembler = doc.host.solver("assemble", solver)  # raises for an unknown or ambiguous name
        params = {} if switch else dict(old.params)
        params.update(self.params)
        doc.host.solver_params("assemble", assembler, params)  # checked now: a bad key is refused here
        self._old, self._new = old, SolverChoice(solver, MappingProxyType(params))
        doc._set_assembly(self._new)

    def undo(self, doc) -> None:
        doc._set_assembly(self._old)

    def to_dict(self) -> dict:
        d: dict = {"command": self.name}
        if self.solver is not None:
            d["solver"] = self.solver
        d["params"] = dict(self.params)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> SetAssembly:
        return cls(solver=parse_field(d, "solver", str, cls.name, None), params=parse_params(d, cls.name))


def _attachments(doc, which=None) -> dict:
    """{layer id: JunctionHost or None} for the layers ``which`` (None: every layer) by the one
    rule the assembly uses too (:func:`sketchforge.geometry.attachment.plan_attachments`, on
    the layers the assembly takes: the visible ones with a mesh; parts glued to one face of a
    host kept apart as the assembly keeps them); None for a part without a junction. The
    layers' regions and edge lengths are built once for all of them (the app checks every
    part before an assembly and after a redraw)."""
    from sketchforge.geometry.attachment import find_host, median_edge_length, plan_attachments

    layers = doc.layers
    wanted = [l for l in layers if which is None or l.id in which]
    out: dict = {l.id: None for l in wanted}
    if not any(not l.closed and l.mesh is not None and len(l.mesh.junction) >= 2 for l in wanted):
        return out
    taken = [l.visible and l.mesh is not None for l in layers]
    regions = [_region(l) if t else None for l, t in zip(layers, taken)]
    h = [median_edge_length(l.mesh.V[:, :2], l.mesh.F) if l.mesh is not None else 0.0 for l in layers]
    ends = [l.mesh.V[l.mesh.junction[[0, -1]], :2] if t and len(l.mesh.junction) >= 2 and not l.closed else None
            for l, t in zip(layers, taken)]
    names = [quote(l.name or l.id) for l in layers]
    # every glued part the assembly takes counts for the separation on a face, asked about
    # or not; a hidden part is not assembled (it gets its host alone: to mirror about it)
    junctions = [l.mesh.V[l.mesh.junction, :2] if t and not l.closed and len(l.mesh.junction) >= 2 else None
                 for l, t in zip(layers, taken)]
    plans = plan_attachments(junctions, regions, h, names, ends)
    for k, l in enumerate(layers):
        if l.id not in out:
            continue
        if plans[k] is not None:
            out[l.id] = plans[k]
        elif not taken[k] and l.mesh is not None and not l.closed and len(l.mesh.junction) >= 2:
            out[l.id] = find_host(l.mesh.V[l.mesh.junction, :2], k, regions, h, names, h[k], ends)
    return out


def _attachment(doc, layer: Layer):
    return _attachments(doc, {layer.id})[layer.id]


def host_of(doc, layer: Layer) -> Layer | None:
    """The layer an attached part hangs on, by the assembly's own rule (:func:`attachment`):
    the nearest visible layer behind it that its junction lies over, or failing that the
    nearest in front (a leg drawn behind the body hangs on the body's back face), looking past
    a twin glued by the same junction (a copy duplicated in place, about to be mirrored). A
    junction that runs partly off that layer still names it (the assembly will refuse it, and
    :func:`attachment` says why); None for a free part or a junction over empty space."""
    found = _attachment(doc, layer)
    return None if found is None or found.near is None else doc.layers[found.near]


def _region(layer: Layer):
    """The layer's region in the drawing plane (holes cut out), or None if it has none."""
    from sketchforge.geometry import guard

    mesh = layer.mesh
    if layer.points is None or mesh is None or not len(mesh.boundary):
        return None
    try:
        region = guard.polygon(mesh.V[mesh.boundary, :2], f"the outline of layer {quote(layer.id)}")
        for hole in mesh.holes:
            region = region.difference(guard.polygon(mesh.V[hole, :2], "a hole"))
    except SketchforgeError:
        return None
    return region


def attachment(doc, layer: Layer) -> tuple[Layer | None, str | None]:
    """Where the assembly glues ``layer`` — the one rule of
    :func:`sketchforge.geometry.attachment.plan_attachments`, which the assemble plugin applies
    too: (host, None) for a part glued to a layer (the one that holds the longest stretch of
    its junction; see :func:`attachment_note` for a part glued by a stretch only); (None,
    problem) when no stretch long enough lies inside one layer, clear of the layers between
    and of the junctions glued to that face, the problem a sentence saying the part is
    assembled free and why; (None, None) for a free part (closed, or a junction over empty
    space).

    Cheap (shapely on the outlines), so the app can say at once why an assembly will fail and
    check, after a redraw, whether the parts glued to a layer still are (for many layers at
    once: :func:`attachments`)."""
    return attachments(doc, {layer.id})[layer.id]


def attachment_note(doc, layer: Layer) -> str | None:
    """What to tell the person about how ``layer`` is glued although it is (only the stretch
    of its junction inside its host is glued, it spans two layers and goes to the one holding
    most of it, or it touches another part's junction on one face), or None."""
    found = _attachments(doc, {layer.id})[layer.id]
    return None if found is None else found.note


def attachments(doc, which=None) -> dict:
    """{layer id: (host, problem)} as :func:`attachment` says it, for the layers ``which``
    (ids; None: every layer), with the layers' outlines built once."""
    out = {}
    for lid, found in _attachments(doc, which).items():
        out[lid] = (None, None) if found is None else (
            (doc.layers[found.host] if found.host is not None else None), found.problem)
    return out
