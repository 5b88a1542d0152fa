"""Animated glTF 2.0 (.glb): one mesh, one morph target per frame, a looping weights channel.

Frame 0 is the base mesh; frame f >= 1 is morph target f-1 (POSITION and NORMAL deltas).
The animation samples every frame at 24 fps with LINEAR interpolation between one-hot weight
vectors (= linear blending of consecutive frames) and ends with frame 0 again at time
``loop / 24``, so a player's loop is seamless. Indices are uint16 up to 65,535 vertices and
uint32 beyond (no vertex cap).
"""

from __future__ import annotations

import json
import struct

import numpy as np

from sketchforge.plugin_api import vertex_normals

from .state import FPS

ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
FLOAT, UNSIGNED_SHORT, UNSIGNED_INT = 5126, 5123, 5125


class _Blob:
    def __init__(self) -> None:
        self.parts: list[bytes] = []
        self.size = 0
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def add(self, arr: np.ndarray, component: int, kind: str, target: int | None = None, minmax: bool = False) -> int:
        data = arr.tobytes()
        view = {"buffer": 0, "byteOffset": self.size, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.views.append(view)
        pad = -len(data) % 4
        self.parts.append(data + b"\0" * pad)
        self.size += len(data) + pad
        width = {"SCALAR": 1, "VEC3": 3}[kind]
        acc = {"bufferView": len(self.views) - 1, "componentType": component, "count": int(arr.size // width), "type": kind}
        if minmax:
            flat = arr.reshape(-1, width)
            acc["min"] = flat.min(axis=0).astype(float).tolist() if len(flat) else [0.0] * width
            acc["max"] = flat.max(axis=0).astype(float).tolist() if len(flat) else [0.0] * width
        self.accessors.append(acc)
        return len(self.accessors) - 1


def animated_glb_bytes(F: np.ndarray, frames: list[np.ndarray], fps: int = FPS, rim_pairs=None,
                       rim_weights=None) -> bytes:
    """F (m,3) int64 triangles shared by every frame; frames: list of (n,3) float64 vertex
    positions (at least 1); rim_pairs (r,2) int64 and rim_weights (r,) float64, an assembled
    model's, whose normals are shared (:func:`sketchforge.plugin_api.vertex_normals`). Returns
    the .glb file's bytes."""
    F = np.asarray(F, dtype=np.int64)
    base = np.asarray(frames[0], dtype=np.float64)
    n = len(base)
    blob = _Blob()
    idx_type = np.dtype("<u2") if n <= 65535 else np.dtype("<u4")
    indices = blob.add(
        F.astype(idx_type).ravel(),
        UNSIGNED_SHORT if idx_type.itemsize == 2 else UNSIGNED_INT,
        "SCALAR",
        ELEMENT_ARRAY_BUFFER,
    )
    base_n = vertex_normals(base, F, rim_pairs, rim_weights)
    pos = blob.add(base.astype("<f4"), FLOAT, "VEC3", ARRAY_BUFFER, minmax=True)
    nrm = blob.add(base_n.astype("<f4"), FLOAT, "VEC3", ARRAY_BUFFER)
    targets = []
    for P in frames[1:]:
        P = np.asarray(P, dtype=np.float64)
        dp = (P - base).astype("<f4")
        dn = (vertex_normals(P, F, rim_pairs, rim_weights) - base_n).astype("<f4")
        targets.append(
            {
                "POSITION": blob.add(dp, FLOAT, "VEC3", ARRAY_BUFFER, minmax=True),
                "NORMAL": blob.add(dn, FLOAT, "VEC3", ARRAY_BUFFER),
            }
        )
    primitive = {"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": indices, "mode": 4}
    mesh: dict = {"name": "sketchforge model", "primitives": [primitive]}
    gltf: dict = {
        "asset": {"version": "2.0", "generator": "sketchforge-animate"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "model"}],
        "meshes": [mesh],
    }
    k = len(targets)
    if k:
        primitive["targets"] = targets
        mesh["weights"] = [0.0] * k
        mesh["extras"] = {"targetNames": [f"frame{f}" for f in range(1, k + 1)]}
        n_keys = k + 2  # frames 0..k, then frame 0 again to close the loop
        times = (np.arange(n_keys, dtype=np.float64) / fps).astype("<f4")
        weights = np.zeros((n_keys, k), dtype="<f4")
        weights[np.arange(1, k + 1), np.arange(k)] = 1.0
        t_acc = blob.add(times, FLOAT, "SCALAR", minmax=True)
        w_acc = blob.add(weights.ravel(), FLOAT, "SCALAR")
        gltf["animations"] = [{
            "name": "loop",
            "samplers": [{"input": t_acc, "output": w_acc, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
        }]
    gltf["buffers"] = [{"byteLength": blob.size}]
    gltf["bufferViews"] = blob.views
    gltf["accessors"] = blob.accessors
    js = json.dumps(gltf, separators=(",", ":")).encode("utf-8")
    js += b" " * (-len(js) % 4)
    bin_ = b"".join(blob.parts)
    total = 12 + 8 + len(js) + 8 + len(bin_)
    return (struct.pack("<III", 0x46546C67, 2, total) + struct.pack("<II", len(js), 0x4E4F534A) + js
            + struct.pack("<II", len(bin_), 0x004E4942) + bin_)


def read_glb(data: bytes) -> tuple[dict, bytes]:
    """Split a .glb into (JSON dict, BIN chunk bytes); raises ValueError when malformed."""
    if len(data) < 20:
        raise ValueError("too short for a .glb")
    magic, version, total = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67 or version != 2 or total != len(data):
        raise ValueError("not a glTF 2.0 binary (bad header)")
    jlen, jtype = struct.unpack_from("<II", data, 12)
    if jtype != 0x4E4F534A:
        raise ValueError("the first chunk is not JSON")
    gltf = json.loads(data[20:20 + jlen])
    off = 20 + jlen
    blen, btype = struct.unpack_from("<II", data, off)
    if btype != 0x004E4942:
        raise ValueError("the second chunk is not BIN")
    return gltf, data[off + 8:off + 8 + blen]


def accessor_array(gltf: dict, blob: bytes, index: int) -> np.ndarray:
    """Read accessor ``index`` as a numpy array ((count,) or (count, 3))."""
    acc = gltf["accessors"][index]
    view = gltf["bufferViews"][acc["bufferView"]]
    dtype = {FLOAT: "<f4", UNSIGNED_SHORT: "<u2", UNSIGNED_INT: "<u4"}[acc["componentType"]]
    width = {"SCALAR": 1, "VEC3": 3}[acc["type"]]
    start = view["byteOffset"] + acc.get("byteOffset", 0)
    arr = np.frombuffer(blob, dtype=dtype, count=acc["count"] * width, offset=start)
    return arr.reshape(-1, 3) if width == 3 else arr
