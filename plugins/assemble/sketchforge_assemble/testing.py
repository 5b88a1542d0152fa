"""Test support: the layers of a document (dict or JSON path), replayed through the document
itself with only the inflate plugin, so tests and benchmarks of the assembly see exactly the
layers the app would pass to the hook."""

from __future__ import annotations

from pathlib import Path


def document_from(doc):
    """Replay a document's journal headlessly (inflate plugin only) and return the Document."""
    from sketchforge.document import fileformat as ff
    from sketchforge.plugins.testing import make_test_host

    host = make_test_host(entry_points=True, allowlist=["inflate"])
    if isinstance(doc, dict):
        return ff.document_from_dict(doc, host=host, use_snapshot=False)
    return ff.load(Path(doc), host=host, use_snapshot=False)


def layers_from_journal(doc) -> list:
    """The document's layers (``sketchforge.document.Layer``), back to front."""
    return list(document_from(doc).layers)


def meshes_from_journal(doc):
    """(layers, meshes, closed) of the layers that have a mesh, back to front."""
    layers = [layer for layer in layers_from_journal(doc) if layer.mesh is not None]
    return layers, [layer.mesh for layer in layers], [layer.closed for layer in layers]
