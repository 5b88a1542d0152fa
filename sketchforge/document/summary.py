"""A document file described without its plugins: what ``sketchforge info`` shows of a document
whose plugins are not installed (opening it still refuses, naming them:
:func:`sketchforge.document.provenance.check_available`)."""

from __future__ import annotations

from typing import Any

from sketchforge.document.fileformat import _layer_from_dict, _parse_light, validate_header
from sketchforge.document.layer import Layer, Light
from sketchforge.errors import DocumentFormatError, LimitError


def read_snapshot(data: Any, source: str = "document") -> tuple[list[Layer] | None, Light]:
    """The layers of a file's snapshot and its current light, read without its plugins (their
    edits and parameters unchecked, the meshes validated): what ``sketchforge info`` describes
    when the document's plugins are not installed. The layers are None for a file without a
    snapshot (only a replay, which needs the plugins, would make them); the light is then the
    journal's initial one.

    Raises
    ------
    DocumentFormatError
        A header, layer or mesh that is not valid whatever the plugins.
    """
    light, _ = validate_header(data, source)
    snap = data.get("snapshot")
    if snap is None:
        return None, light
    if not isinstance(snap, dict) or not isinstance(snap.get("layers"), list):
        raise DocumentFormatError(f"{source}: field 'snapshot' must be an object with a 'layers' list")
    from sketchforge.document.document import MAX_LAYERS

    if len(snap["layers"]) > MAX_LAYERS:
        raise LimitError(f"{source}: the snapshot has {len(snap['layers']):,} layers; a document holds at most {MAX_LAYERS}")
    layers = [_layer_from_dict(l, f"{source}: snapshot.layers[{i}]") for i, l in enumerate(snap["layers"])]
    return layers, _parse_light(snap.get("light", data.get("light", [1.0, 0.0, 0.0])), f"{source}: snapshot.light",
                                data["version"])
