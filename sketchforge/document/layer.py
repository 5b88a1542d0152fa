"""Layer and Light: immutable values held by the Document.

Layers are frozen: a command changes a layer by putting a new Layer value in its place, and
keeps the old value for undo. Meshes and point arrays are read-only, so values can be shared
freely between the document, the undo history and views.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from sketchforge.errors import ParameterError
from sketchforge.geometry.inflate_params import DEFAULT_INFLATE_PARAMS  # noqa: F401 (re-exported)
from sketchforge.geometry.mesh import Mesh, frozen_array


def _holes(a) -> tuple:
    if a is None:
        return ()
    out = []
    for n, ring in enumerate(a, start=1):
        try:
            arr = frozen_array(ring, np.float64)
        except (TypeError, ValueError):
            raise ParameterError(f"hole {n} must be a list of [x, y] number pairs") from None
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise ParameterError(f"hole {n} must be a list of [x, y] pairs, got shape {arr.shape}")
        out.append(arr)
    return tuple(out)


def _points(a) -> np.ndarray | None:
    if a is None:
        return None
    arr = frozen_array(a, np.float64)  # a layer's own (read-only) points: shared, not copied
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ParameterError(f"contour points must be a list of [x, y] pairs, got shape {arr.shape}")
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

    def evolve(self, **changes: Any) -> Layer:
        """A copy with some fields changed."""
        return replace(self, **changes)

    def same_state(self, other: Layer) -> bool:
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

BEHIND = ("the light must face the viewer (z >= 0): a light from behind the drawing would leave every "
          "front surface in shadow")


@dataclass(frozen=True)
class Light:
    """A directional light: the unit vector (x, y, z) pointing towards the light, anywhere on the
    hemisphere facing the viewer (z >= 0; z = 1 is straight overhead). z = 0 is the thesis'
    light in the drawing plane (ch. 4), the default and what the in-plane drag sets."""

    x: float = 1.0 / math.sqrt(2.0)
    y: float = 1.0 / math.sqrt(2.0)
    z: float = 0.0

    def __post_init__(self) -> None:
        x, y, z = float(self.x), float(self.y), float(self.z)
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
            raise ParameterError("the light direction must be finite numbers")
        if z < 0.0:
            raise ParameterError(BEHIND)
        z += 0.0  # -0.0 is 0.0: an in-plane light is written and compared as one
        # An in-plane light is normalised exactly as before lights could leave the plane
        # (hypot of two), so files written then replay bit for bit.
        norm = math.hypot(x, y) if z == 0.0 else math.hypot(x, y, z)
        if norm < 1e-12:
            raise ParameterError("the light direction must not be the zero vector")
        # A vector that is already unit (to rounding) is kept bit for bit: normalising it again
        # moves it by an ulp for about 1 direction in 5, and a journal replay would then shade
        # and sculpt with a different light than the session that wrote it.
        if abs(norm - 1.0) > _UNIT_TOL:
            x, y, z = x / norm, y / norm, z / norm
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "z", z)

    @classmethod
    def from_vector(cls, v) -> Light:
        """From a (2,) vector (a light in the drawing plane) or a (3,) one (z >= 0)."""
        v = list(v)
        if len(v) not in (2, 3):
            raise ParameterError(f"a light direction has 2 or 3 components, got {len(v)}")
        try:
            comps = [float(c) for c in v]
        except OverflowError:
            raise ParameterError("the light direction must be numbers within float range") from None
        except ParameterError:
            raise  # Light's own sentence (the zero vector): not wrapped in "must be numbers: ..."
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"the light direction must be numbers: {exc}") from None
        return cls(*comps)

    @classmethod
    def from_angle(cls, degrees: float, elevation: float = 0.0) -> Light:
        """Azimuth ``degrees`` counter-clockwise from +x in the drawing plane, ``elevation``
        degrees above it (0: in the plane, 90: straight overhead, whatever the azimuth)."""
        e = float(elevation)
        if not (math.isfinite(e) and 0.0 <= e <= 90.0):
            raise ParameterError(f"the light's elevation must be between 0 and 90 degrees, got {e:g}")
        a = math.radians(float(degrees))
        if e == 0.0:
            return cls(math.cos(a), math.sin(a))
        if e == 90.0:  # cos(pi/2) is 6e-17, not 0: overhead is overhead
            return cls(0.0, 0.0, 1.0)
        er = math.radians(e)
        return cls(math.cos(er) * math.cos(a), math.cos(er) * math.sin(a), math.sin(er))

    @classmethod
    def from_drag(cls, center, point, elevation: float = 0.0) -> Light:
        """From a drag in the drawing plane (thesis 4.1): the azimuth points from ``center``
        (2,) towards ``point`` (2,); ``elevation`` degrees above the plane (0: the thesis'
        in-plane light). Raises ParameterError for non-finite input or a drag of no length
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
        if elevation == 0.0:
            return cls(float(d[0]), float(d[1]))
        return cls.from_angle(math.degrees(math.atan2(d[1], d[0])), elevation)

    @property
    def direction(self) -> np.ndarray:
        """(3,) float64 unit vector towards the light."""
        return np.array([self.x, self.y, self.z])

    @property
    def angle(self) -> float:
        """Azimuth: degrees, counter-clockwise from +x (0 for a light straight overhead)."""
        return math.degrees(math.atan2(self.y, self.x))

    @property
    def elevation(self) -> float:
        """Degrees above the drawing plane: 0 in the plane, 90 straight overhead."""
        return 0.0 if self.z == 0.0 else math.degrees(math.atan2(self.z, math.hypot(self.x, self.y)))

    @property
    def in_plane(self) -> bool:
        """The thesis' light (z = 0)."""
        return self.z == 0.0

    def to_list(self) -> list[float]:
        """[x, y, z] as saved in a document."""
        return [self.x, self.y, self.z]
