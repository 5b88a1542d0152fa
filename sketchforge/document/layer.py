"""Layer and Light: immutable values held by the Document.

Layers are frozen: a command changes a layer by putting a new Layer value in its place, and
keeps the old value for undo. Meshes and point arrays are read-only, so values can be shared
freely between the document, the undo history and views.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

from sketchforge.errors import ParameterError
from sketchforge.geometry.inflate_params import DEFAULT_INFLATE_PARAMS  # noqa: F401 (re-exported)
from sketchforge.geometry.mesh import Mesh


def _holes(a) -> tuple:
    if a is None:
        return ()
    out = []
    for n, ring in enumerate(a, start=1):
        try:
            arr = np.array(ring, dtype=np.float64, copy=True)
        except (TypeError, ValueError):
            raise ParameterError(f"hole {n} must be a list of [x, y] number pairs") from None
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise ParameterError(f"hole {n} must be a list of [x, y] pairs, got shape {arr.shape}")
        arr.setflags(write=False)
        out.append(arr)
    return tuple(out)


def _points(a) -> np.ndarray | None:
    if a is None:
        return None
    arr = np.array(a, dtype=np.float64, copy=True)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ParameterError(f"contour points must be a list of [x, y] pairs, got shape {arr.shape}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Layer:
    """One drawn part.

    Attributes
    ----------
    id : str
        Stable identifier used by commands and files.
    name : str
        Display name.
    visible : bool
    points : (n, 2) float64 or None
        The stroke as drawn (before cleaning); None until a contour is set.
    closed : bool
        True when the whole outline is free; False lets an open stroke's closing segment be
        the junction Γ_conn.
    params : Mapping[str, Any]
        The inflater's parameters (for the built-in ``poisson``: ``resolution``, ``inflation``,
        ``smoothing``); empty until the layer is first inflated, then the complete set its
        inflater returned (defaults filled in).
    solver : str or None
        The layer's inflater (see :mod:`sketchforge.plugins.solvers`); None until it is first
        inflated (then the default's name is recorded: the built-in ``"poisson"``).
    mesh : Mesh or None
        The current front surface (inflated, then sculpted).
    edits : tuple of dict
        Sculpt commands (as journal dicts) applied since the mesh was last inflated, oldest
        first; re-applied when the inflation parameters change.
    holes : tuple of (n_i, 2) float64
        Inner rings cut out of the part, as drawn (any orientation).
    """

    id: str
    name: str
    visible: bool = True
    points: np.ndarray | None = None
    closed: bool = False
    params: Mapping[str, Any] = field(default_factory=dict)
    mesh: Mesh | None = None
    edits: tuple = ()
    holes: tuple = ()
    solver: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _points(self.points))
        object.__setattr__(self, "holes", _holes(self.holes))
        object.__setattr__(self, "params", MappingProxyType(dict(self.params)))
        object.__setattr__(self, "edits", tuple(self.edits))

    def evolve(self, **changes: Any) -> "Layer":
        """A copy with some fields changed."""
        return replace(self, **changes)

    def same_state(self, other: "Layer") -> bool:
        """Exact equality of every field, meshes compared bit for bit."""
        if not isinstance(other, Layer):
            return False
        pts_equal = (self.points is None and other.points is None) or (
            self.points is not None
            and other.points is not None
            and self.points.shape == other.points.shape
            and self.points.tobytes() == other.points.tobytes()
        )
        mesh_equal = (self.mesh is None and other.mesh is None) or (
            self.mesh is not None and self.mesh.identical(other.mesh)
        )
        holes_equal = len(self.holes) == len(other.holes) and all(
            a.shape == b.shape and a.tobytes() == b.tobytes() for a, b in zip(self.holes, other.holes)
        )
        return (
            holes_equal
            and self.id == other.id
            and self.name == other.name
            and self.visible == other.visible
            and self.closed == other.closed
            and self.solver == other.solver
            and dict(self.params) == dict(other.params)
            and list(self.edits) == list(other.edits)
            and pts_equal
            and mesh_equal
        )


#: |norm - 1| below which a light vector counts as unit already (a few ulps: x / hypot(x, y)
#: is within 2 ulps of unit length).
_UNIT_TOL = 8 * 2.0**-52


@dataclass(frozen=True)
class Light:
    """A directional light in the drawing plane: unit vector (x, y, 0) pointing towards the light."""

    x: float = 1.0 / math.sqrt(2.0)
    y: float = 1.0 / math.sqrt(2.0)

    def __post_init__(self) -> None:
        x, y = float(self.x), float(self.y)
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ParameterError("the light direction must be finite numbers")
        norm = math.hypot(x, y)
        if norm < 1e-12:
            raise ParameterError("the light direction must not be the zero vector")
        # A vector that is already unit (to rounding) is kept bit for bit: normalising it again
        # moves it by an ulp for about 1 direction in 5, and a journal replay would then shade
        # and sculpt with a different light than the session that wrote it.
        if abs(norm - 1.0) > _UNIT_TOL:
            object.__setattr__(self, "x", x / norm)
            object.__setattr__(self, "y", y / norm)
        else:
            object.__setattr__(self, "x", x)
            object.__setattr__(self, "y", y)

    @classmethod
    def from_vector(cls, v) -> "Light":
        """From a (2,) or (3,) vector; any z component is dropped (the light lies in the plane)."""
        v = list(v)
        if len(v) not in (2, 3):
            raise ParameterError(f"a light direction has 2 or 3 components, got {len(v)}")
        try:
            return cls(float(v[0]), float(v[1]))
        except OverflowError:
            raise ParameterError("the light direction must be numbers within float range") from None
        except ParameterError:
            raise  # Light's own sentence (the zero vector): not wrapped in "must be numbers: ..."
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"the light direction must be numbers: {exc}") from None

    @classmethod
    def from_angle(cls, degrees: float) -> "Light":
        """Counter-clockwise angle from +x in the drawing plane."""
        a = math.radians(float(degrees))
        return cls(math.cos(a), math.sin(a))

    @classmethod
    def from_drag(cls, center, point) -> "Light":
        """From a drag in the drawing plane (thesis 4.1): pointing from ``center`` (2,) towards
        ``point`` (2,). Raises ParameterError for non-finite input or a drag of no length
        (relative to the coordinates' size, so the test is the same at any zoom)."""
        c = np.asarray(center, dtype=np.float64).reshape(-1)
        p = np.asarray(point, dtype=np.float64).reshape(-1)
        if c.shape != (2,) or p.shape != (2,):
            raise ParameterError("a light drag needs a 2D centre and a 2D point")
        if not (np.all(np.isfinite(c)) and np.all(np.isfinite(p))):
            raise ParameterError("a light drag needs finite coordinates")
        d = p - c
        scale = max(1.0, float(np.max(np.abs(c))), float(np.max(np.abs(p))))
        if math.hypot(d[0], d[1]) <= 1e-12 * scale:
            raise ParameterError("the light direction is undefined: drag away from the centre of the drawing")
        return cls(float(d[0]), float(d[1]))

    @property
    def direction(self) -> np.ndarray:
        """(3,) float64 unit vector with z = 0."""
        return np.array([self.x, self.y, 0.0])

    @property
    def angle(self) -> float:
        """Degrees, counter-clockwise from +x."""
        return math.degrees(math.atan2(self.y, self.x))
