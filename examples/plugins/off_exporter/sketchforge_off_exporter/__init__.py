"""Example exporter plugin: OFF (Object File Format), a plain-text triangle mesh.

The host hands ``write`` a path in a private temp folder and moves the finished file into
place atomically (keeping the old file's mode); any error becomes one line naming this
plugin. So the exporter just writes.
"""

from __future__ import annotations

import io

import numpy as np

from sketchforge.plugin_api import Exporter, Mesh, hookimpl


def off_bytes(mesh: Mesh) -> bytes:
    """OFF text for a mesh: V (n, 3) float64 written with 17 significant digits (exact
    round trip), F (m, 3) int64 as ``3 i j k`` lines."""
    out = io.StringIO()
    out.write(f"OFF\n{mesh.n_vertices} {mesh.n_faces} 0\n")
    np.savetxt(out, mesh.V, fmt="%.17g")
    if mesh.n_faces:
        np.savetxt(out, np.c_[np.full(mesh.n_faces, 3), mesh.F], fmt="%d")
    return out.getvalue().encode("ascii")


def write_off(path, mesh: Mesh) -> None:
    with open(path, "wb") as fh:
        fh.write(off_bytes(mesh))


@hookimpl
def sketchforge_exporters():
    return [Exporter("off", (".off",), write_off, "Object File Format (text)")]
