"""The ``bump_brush`` command: ``{"command": "bump_brush", "layer": "a", "center": [x, y],
"radius": r, "height": h}`` raises (h > 0) or sinks (h < 0) the surface by
h (1 - (d / r)²)² within distance r of the centre; the outline stays where it is."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from sketchforge.plugin_api import (
    DocumentFormatError,
    Layer,
    Mesh,
    NothingToDoError,
    ReplaceLayerCommand,
    SculptError,
    parse_field,
    parse_vector,
    transform_points,
)

#: Largest |height| and radius accepted from a journal (drawing units).
MAX_SIZE = 100.0


def bump(mesh: Mesh, center, radius: float, height: float) -> Mesh:
    """The mesh with a bump added.

    Parameters
    ----------
    mesh : Mesh
        V (n, 3) float64; its ``boundary`` vertices are kept fixed (z = 0 on the outline).
    center : (2,) float64
    radius, height : float

    Returns
    -------
    Mesh
        Same F, boundary and junction; V with z changed inside the disc.

    Raises
    ------
    NothingToDoError
        No free vertex lies within ``radius`` of ``center``.
    """
    V = np.array(mesh.V, dtype=np.float64)
    d2 = np.sum((V[:, :2] - np.asarray(center, dtype=np.float64)) ** 2, axis=1) / (radius * radius)
    w = np.where(d2 < 1.0, (1.0 - d2) ** 2, 0.0)
    w[mesh.boundary] = 0.0
    if not np.any(w > 0):
        raise NothingToDoError("the brush touches no vertex inside the outline: brush over the shape")
    V[:, 2] += height * w
    return Mesh(V, mesh.F, mesh.boundary, mesh.junction)


@dataclass
class BumpBrush(ReplaceLayerCommand):
    name: ClassVar[str] = "bump_brush"
    center: list = field(default_factory=lambda: [0.0, 0.0])
    radius: float = 0.3
    height: float = 0.1

    def text(self) -> str:
        return "Bump brush"

    def compute(self, doc, old: Layer) -> Layer:
        # Pure: a new Layer value; the base class swaps it in (do) and back (undo).
        if old.mesh is None:
            raise SculptError(f"layer {old.id!r} has no surface to brush: draw its outline first")
        mesh = bump(old.mesh, self.center, self.radius, self.height)
        # Recorded in edits so that re-inflating the layer (new outline or parameters)
        # re-applies the bump through reapply(); without it the bump would silently vanish.
        return old.evolve(mesh=mesh, edits=tuple(old.edits) + (self.to_dict(),))

    @classmethod
    def reapply(cls, doc, layer: Layer, entry: dict) -> Layer:
        cmd = cls.from_dict(entry)
        mesh = bump(layer.mesh, cmd.center, cmd.radius, cmd.height)
        return layer.evolve(mesh=mesh, edits=tuple(layer.edits) + (dict(entry),))

    @classmethod
    def transform_edit(cls, entry: dict, matrix, scale: float) -> dict:
        # The layer was moved, scaled or rotated: the bump follows it (its centre mapped, its
        # radius and height scaled like the part), so a later re-inflation re-applies it where
        # it now is. A shear would make its footprint an ellipse; it stays round, of the mean
        # radius.
        e = dict(entry)
        c = transform_points(matrix, np.asarray(e["center"], dtype=np.float64))[0]
        e["center"] = [float(c[0]), float(c[1])]
        e["radius"] = float(e["radius"]) * scale
        e["height"] = float(e["height"]) * scale
        return e

    def to_dict(self) -> dict:
        return {
            "command": self.name,
            "layer": self.layer,
            "center": [float(v) for v in self.center],
            "radius": float(self.radius),
            "height": float(self.height),
        }

    @classmethod
    def from_dict(cls, d: dict) -> BumpBrush:
        # Every field of a saved file is user-writable: checked, one-line errors.
        center = parse_vector(d, "center", cls.name)
        radius = parse_field(d, "radius", float, cls.name)
        height = parse_field(d, "height", float, cls.name)
        if len(center) != 2 or not all(math.isfinite(v) for v in center):
            raise DocumentFormatError(f"command {cls.name!r}: 'center' must be 2 finite numbers [x, y]")
        if not (0.0 < radius <= MAX_SIZE):
            raise DocumentFormatError(f"command {cls.name!r}: 'radius' must be in (0, {MAX_SIZE}], got {radius}")
        if not (math.isfinite(height) and abs(height) <= MAX_SIZE):
            raise DocumentFormatError(f"command {cls.name!r}: 'height' must be finite with |height| <= {MAX_SIZE}")
        return cls(layer=parse_field(d, "layer", str, cls.name), center=center, radius=radius, height=height)
