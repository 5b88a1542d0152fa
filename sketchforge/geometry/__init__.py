"""Geometry core: small functions on numpy arrays. No Qt, no document."""

from sketchforge.geometry.mesh import Mesh

__all__ = ["Mesh"]
