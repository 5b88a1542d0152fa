"""Mesh file writers (OBJ, PLY, STL, glTF) as plain functions of a Mesh.

All writers go through :func:`sketchforge.atomic.write_bytes_atomic`.
"""

from __future__ import annotations

import base64
import io
import json
import struct

import numpy as np

from sketchforge.atomic import write_bytes_atomic
from sketchforge.geometry.mesh import Mesh
from sketchforge.geometry.normals import face_normals


def obj_bytes(mesh: Mesh) -> bytes:
    out = io.StringIO()
    out.write("# sketchforge\n")
    np.savetxt(out, mesh.V, fmt="v %.9g %.9g %.9g")
    if mesh.n_faces:
        np.savetxt(out, mesh.F + 1, fmt="f %d %d %d")
    return out.getvalue().encode("ascii")


def ply_bytes(mesh: Mesh) -> bytes:
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment sketchforge\n"
        f"element vertex {mesh.n_vertices}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {mesh.n_faces}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode("ascii")
    faces = np.zeros(mesh.n_faces, dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces["n"] = 3
    faces["i"] = mesh.F
    return header + mesh.V.astype("<f4").tobytes() + faces.tobytes()


def stl_bytes(mesh: Mesh) -> bytes:
    rec = np.zeros(mesh.n_faces, dtype=[("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    rec["n"] = face_normals(mesh.V, mesh.F)[0]
    rec["v"] = mesh.V[mesh.F]
    header = b"sketchforge binary STL".ljust(80, b" ")
    return header + struct.pack("<I", mesh.n_faces) + rec.tobytes()


def _gltf_parts(mesh: Mesh) -> tuple[dict, bytes]:
    """The glTF document and its binary buffer: positions, triangles and the display's own
    normals (:func:`sketchforge.geometry.heightfield.layer_normals`: a viewer given none draws
    every triangle flat, glTF 2.0 3.7.2.1; an assembled model's are shared across its rim pairs)."""
    from sketchforge.geometry.heightfield import layer_normals

    pos = mesh.V.astype("<f4")
    idx = mesh.F.astype("<u4").ravel()
    nrm = layer_normals(mesh).astype("<f4") if mesh.n_faces else np.zeros((len(pos), 3), "<f4")
    pos_bytes, idx_bytes, nrm_bytes = pos.tobytes(), idx.tobytes(), nrm.tobytes()
    lo = pos.min(axis=0).tolist() if len(pos) else [0.0, 0.0, 0.0]
    hi = pos.max(axis=0).tolist() if len(pos) else [0.0, 0.0, 0.0]
    gltf = {
        "asset": {"version": "2.0", "generator": "sketchforge"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 2}, "indices": 1}]}],
        "buffers": [{"byteLength": len(pos_bytes) + len(idx_bytes) + len(nrm_bytes)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(pos_bytes), "target": 34962},
            {"buffer": 0, "byteOffset": len(pos_bytes), "byteLength": len(idx_bytes), "target": 34963},
            {"buffer": 0, "byteOffset": len(pos_bytes) + len(idx_bytes), "byteLength": len(nrm_bytes), "target": 34962},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": len(nrm), "type": "VEC3"},
        ],
    }
    return gltf, pos_bytes + idx_bytes + nrm_bytes


def glb_bytes(mesh: Mesh) -> bytes:
    gltf, blob = _gltf_parts(mesh)
    js = json.dumps(gltf, separators=(",", ":")).encode("utf-8")
    js += b" " * (-len(js) % 4)
    blob += b"\0" * (-len(blob) % 4)
    total = 12 + 8 + len(js) + 8 + len(blob)
    return (
        struct.pack("<III", 0x46546C67, 2, total)
        + struct.pack("<II", len(js), 0x4E4F534A)
        + js
        + struct.pack("<II", len(blob), 0x004E4942)
        + blob
    )


def gltf_bytes(mesh: Mesh) -> bytes:
    gltf, blob = _gltf_parts(mesh)
    gltf["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode("ascii")
    return json.dumps(gltf, indent=1).encode("utf-8")


def write_obj(path, mesh: Mesh) -> None:
    write_bytes_atomic(path, obj_bytes(mesh))


def write_ply(path, mesh: Mesh) -> None:
    write_bytes_atomic(path, ply_bytes(mesh))


def write_stl(path, mesh: Mesh) -> None:
    write_bytes_atomic(path, stl_bytes(mesh))


def write_gltf(path, mesh: Mesh) -> None:
    from pathlib import Path

    data = glb_bytes(mesh) if Path(path).suffix.lower() == ".glb" else gltf_bytes(mesh)
    write_bytes_atomic(path, data)
