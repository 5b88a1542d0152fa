"""The triangle mesh value type shared by every plugin and the document."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def unwritable(a) -> bool:
    """Whether nobody can write the memory of the array ``a``: it is read-only and so is every
    array it is a view of (a read-only view of a writable array can still change under it),
    and its memory belongs to numpy or to an immutable ``bytes``."""
    while isinstance(a, np.ndarray):
        if a.flags.writeable:
            return False
        if a.base is None:
            return True
        a = a.base
    return isinstance(a, bytes)


def frozen_array(a, dtype) -> np.ndarray:
    """``a`` as a read-only C-contiguous array of ``dtype``: ``a`` itself when it already is
    one that nobody can write (:func:`unwritable`), else a frozen copy. Values share their
    arrays this way: an undo step that moves a layer keeps its new vertices, not another copy
    of its triangles (issue 39: 200 moves of a 36k-vertex layer kept 489 MB)."""
    if isinstance(a, np.ndarray) and a.dtype == dtype and a.flags.c_contiguous and unwritable(a):
        return a
    arr = np.array(a, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


def _frozen(a, dtype, ndim: int, name: str) -> np.ndarray:
    arr = frozen_array(a, dtype)
    if ndim == 2 and arr.size == 0:
        arr = arr.reshape(0, 3)
    if arr.ndim != ndim:
        raise ValueError(f"Mesh.{name} must have {ndim} dimensions, got shape {arr.shape}")
    # Meshes are shared between the document, undo history and views; read-only arrays turn an
    # accidental in-place edit (which would corrupt undo) into an error.
    return arr


@dataclass(frozen=True, eq=False)
class Mesh:
    """An immutable triangle mesh.

    Attributes
    ----------
    V : (n, 3) float64
        Vertex positions: x right, y up in the drawing plane, z towards the viewer.
    F : (m, 3) int64
        Triangles, counter-clockwise seen from +z for a layer's front surface.
    boundary : (k,) int64
        The outer boundary loop as vertex indices, in order (empty for a closed surface).
    junction : (j,) int64
        Vertices on the junction Γ_conn (the closing segment of an open stroke), in order
        along the boundary; empty for a free (closed-outline) part.
    holes : tuple of (k_i,) int64
        The inner boundary loops (holes), each in order with the surface on its left seen
        from +z (clockwise for a front surface); empty when the part has no hole.
    """

    V: np.ndarray
    F: np.ndarray
    boundary: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    junction: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    holes: tuple = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "V", _frozen(self.V, np.float64, 2, "V"))
        object.__setattr__(self, "F", _frozen(self.F, np.int64, 2, "F"))
        object.__setattr__(self, "boundary", _frozen(self.boundary, np.int64, 1, "boundary"))
        object.__setattr__(self, "junction", _frozen(self.junction, np.int64, 1, "junction"))
        object.__setattr__(self, "holes", tuple(_frozen(h, np.int64, 1, "holes") for h in self.holes))
        if self.V.shape[1] != 3 or self.F.shape[1] != 3:
            raise ValueError(f"Mesh needs V (n,3) and F (m,3), got {self.V.shape} and {self.F.shape}")
        n = len(self.V)
        for name, idx in (("F", self.F), ("boundary", self.boundary), ("junction", self.junction),
                          *(("holes", h) for h in self.holes)):
            if idx.size and (idx.min() < 0 or idx.max() >= n):
                raise ValueError(f"Mesh.{name} refers to a vertex outside 0..{n - 1}")

    @property
    def rims(self) -> np.ndarray:
        """(r,) int64: every vertex on a boundary loop, the outline's then each hole's (the
        vertices an inflated front surface keeps at z = 0)."""
        return np.concatenate([self.boundary, *self.holes]) if self.holes else self.boundary

    @property
    def n_vertices(self) -> int:
        return int(len(self.V))

    @property
    def n_faces(self) -> int:
        return int(len(self.F))

    def with_heights(self, z: np.ndarray) -> Mesh:
        """Same connectivity, new z (n,) float64."""
        V = np.array(self.V)
        V[:, 2] = np.asarray(z, dtype=np.float64)
        V.setflags(write=False)  # frozen here: the Mesh takes it without another copy
        return Mesh(V, self.F, self.boundary, self.junction, self.holes)

    def identical(self, other: Mesh | None) -> bool:
        """Bit-identical comparison (positions compared as raw bytes, so -0.0 != 0.0, NaN == NaN)."""
        if other is None:
            return False
        return len(self.holes) == len(other.holes) and all(
            a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
            for a, b in (
                (self.V, other.V),
                (self.F, other.F),
                (self.boundary, other.boundary),
                (self.junction, other.junction),
                *zip(self.holes, other.holes),
            )
        )


@dataclass(frozen=True, eq=False)
class AssembledMesh(Mesh):
    """The assembled model: a closed :class:`Mesh` and what the person should know about how it
    was made (issue 34: one part never refuses the model).

    Attributes
    ----------
    free : tuple of str
        Ids of the layers whose junction could not be glued (they are in the model as free
        parts) or that had no room where they were drawn (left out of it).
    warnings : tuple of str
        One sentence per such part (naming it and why), and any other degradation (a junction
        glued with a plain fold).
    notes : tuple of str
        One sentence per part glued by a stretch of its junction only (it runs off its host,
        spans two layers or touches another part's junction on the same face).
    rim_pairs : (r, 2) int64
        A part's front and back vertex at each point of its rim, which the assembly keeps
        apart (joined by a band of triangles across the rim) and which stand for one round
        rim. Renderers and exporters share their normals by ``rim_weights``
        (:func:`sketchforge.geometry.normals.vertex_normals`); empty when the assembler has
        none (its rims are single vertices, or it does not say).
    rim_weights : (r,) float64 in [0, 1]
        How much each pair shares (1 by default): 1 where the band is the rim as stitched, 0
        where the assembly reshaped it into a surface of its own (a faired junction's rings).
    """

    free: tuple = ()
    warnings: tuple = ()
    notes: tuple = ()
    rim_pairs: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    rim_weights: np.ndarray | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        pairs = frozen_array(np.asarray(self.rim_pairs, dtype=np.int64).reshape(-1, 2), np.int64)
        object.__setattr__(self, "rim_pairs", pairs)
        if pairs.size and (pairs.min() < 0 or pairs.max() >= len(self.V)):
            raise ValueError(f"AssembledMesh.rim_pairs refers to a vertex outside 0..{len(self.V) - 1}")
        w = np.ones(len(pairs)) if self.rim_weights is None else self.rim_weights
        w = frozen_array(np.asarray(w, dtype=np.float64).reshape(-1), np.float64)
        if len(w) != len(pairs) or not np.all((w >= 0.0) & (w <= 1.0)):
            raise ValueError(f"AssembledMesh.rim_weights needs one weight in [0, 1] per rim pair ({len(pairs)})")
        object.__setattr__(self, "rim_weights", w)
