"""Host-side export: the exporter writes into a private temp folder, the host moves the
bytes into place atomically and turns any failure into one line naming the plugin.

Plugins therefore need no atomic-write or error-handling code of their own, and a plugin
exporter behaves like a built-in one: a missing folder is a one-line ExportError (exit 2 in
the CLI, a dialog in the app), the old file survives a failed write, its mode is kept.
"""

from __future__ import annotations

import inspect
import tempfile
from pathlib import Path

from sketchforge.atomic import check_target, write_bytes_atomic
from sketchforge.errors import ExportError, SketchforgeError


def _accepts_progress(fn) -> bool:
    try:
        return "progress" in inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False


def run_exporter(host, path, mesh=None, doc=None, progress=None) -> str:
    """Write ``mesh`` to ``path`` (or, with ``doc`` and no mesh, the document: through a
    document exporter that handles it, else its export mesh). Returns a one-line summary.

    Parameters
    ----------
    host : PluginHost
    path : str or Path
        The file to write; its suffix picks the exporter.
    mesh : Mesh, optional
    doc : Document (or a read-only stand-in with ``export_mesh`` and ``plugin_data``), optional
    progress : callable(i, n), optional
        Passed to a document exporter that takes ``progress``.
    """
    path = Path(path)
    exporter = host.exporter_for(path, doc if mesh is None else None)
    check_target(path)
    data, summary = _produce(host, exporter, path, mesh, doc, progress)
    write_bytes_atomic(path, data)
    return summary


def export_bytes(host, path, mesh=None, doc=None, progress=None) -> tuple[bytes, str]:
    """The bytes :func:`run_exporter` would write to ``path``, and its summary, without
    touching ``path`` (which only names the file: its suffix picks the exporter, and errors
    name it). A batch worker exports this way and the machine that asked writes the file."""
    path = Path(path)
    exporter = host.exporter_for(path, doc if mesh is None else None)
    return _produce(host, exporter, path, mesh, doc, progress)


def _produce(host, exporter, path: Path, mesh, doc, progress) -> tuple[bytes, str]:
    plugin = host.provider_of(exporter) or "unknown plugin"
    whole_document = mesh is None and exporter.write_document is not None
    if mesh is None and not whole_document:
        if doc is None:
            raise ExportError("nothing to export: give a mesh or a document")
        mesh = doc.export_mesh()
    with tempfile.TemporaryDirectory(prefix="sketchforge-export-") as tmp:
        # Same file name: exporters may look at the suffix (".glb" vs ".gltf").
        scratch = Path(tmp) / path.name
        try:
            if whole_document:
                kw = {"progress": progress} if progress is not None and _accepts_progress(exporter.write_document) else {}
                summary = exporter.write_document(scratch, doc, **kw)
            else:
                exporter.write(scratch, mesh)
                summary = f"{mesh.n_vertices} vertices, {mesh.n_faces} triangles"
        except SketchforgeError as exc:
            raise type(exc)(str(exc).replace(str(scratch), str(path))) from None
        except Exception as exc:  # noqa: BLE001 - a plugin's bug, reported as such
            raise ExportError(
                f"cannot write {path}: exporter {exporter.name!r} (plugin {plugin!r}) failed: "
                f"{type(exc).__name__}: {str(exc).replace(str(scratch), str(path))}"
            ) from exc
        if not scratch.is_file():
            raise ExportError(f"cannot write {path}: exporter {exporter.name!r} (plugin {plugin!r}) wrote no file")
        data = scratch.read_bytes()
    return data, (str(summary) if summary else f"{len(data)} bytes")
