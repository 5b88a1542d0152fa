"""Exporting a whole document (an exporter with ``write_document``, such as an animation) on a
worker thread: seconds of solving must not freeze the window."""

from __future__ import annotations


class DocumentValues:
    """What a document exporter reads, taken on the GUI thread (immutable values), so the
    export can run on a worker while the user goes on editing."""

    def __init__(self, doc) -> None:
        self._mesh = doc.export_mesh()
        self._data = {k: doc.plugin_data(k) for k in doc.plugin_data_keys}

    def export_mesh(self, layer_id=None):
        return self._mesh

    def plugin_data(self, key, default=None):
        return self._data.get(key, default)


def export_document_in_background(window, exporter, path) -> bool:
    """Run ``exporter.write_document`` on the window's job runner with the progress indicator,
    through the host (temp file, atomic rename, one-line errors naming the plugin). Raises a
    SketchforgeError before starting if the document cannot be read (the caller shows it)."""
    from pathlib import Path

    from sketchforge.qt.errors_ui import show_error

    values = DocumentValues(window.doc)

    def done(summary):
        window.show_message(f"exported {path} ({summary})")

    def failed(exc, tb):
        show_error(window, "Cannot export", exc, tb)

    window.jobs.start(lambda: window.host.export(path, doc=values), done, failed, label=f"Exporting {Path(path).name}")
    return True
