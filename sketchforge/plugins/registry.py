"""Small value types that registry hooks return."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

# The value types live below the host (the geometry core uses them); re-exported here, their
# historical path.
from sketchforge.geometry.reflectance_model import ReflectanceModel, Shader

__all__ = ["DatasetGenerator", "Exporter", "Panel", "ReflectanceModel", "Shader"]


@dataclass(frozen=True)
class Exporter:
    """A mesh file format: ``write(path: pathlib.Path, mesh: Mesh) -> None``.

    An exporter of more than one mesh (an animation) also sets ``write_document(path, doc)
    -> str`` (returns a one-line summary) and ``handles(doc) -> bool``; for a document it
    handles, it is chosen over a plain mesh exporter of the same suffix."""

    name: str
    suffixes: tuple[str, ...]
    write: Callable
    description: str = ""
    write_document: Callable | None = None
    handles: Callable | None = None


#: Where a panel shows: the right-hand controls of one of the app's states.
PANEL_PLACES = ("creation", "sculpture", "observation")


@dataclass(frozen=True)
class Panel:
    """A panel of the desktop app contributed by a plugin (``sketchforge_qt_panels``).

    ``create(app)`` builds and returns the widget (a ``QWidget``); it is called once, by the
    app, after its canvas and 3D view exist, with ``app`` a
    :class:`sketchforge.qt.panel_api.AppContext` (the document, the host, the canvas and 3D
    view, a worker to run commands on, the status line). Import Qt inside ``create`` (or in
    a module it imports): the rest of the plugin stays importable without Qt. ``place`` is
    where it shows (:data:`PANEL_PLACES`); ``order`` sorts panels of one place (lower first).
    ``available(host)`` (optional) says whether to build it at all (e.g. only when the
    plugin's commands are registered). A ``create`` that raises, or returns something that is
    not a QWidget, is named with its plugin in the status bar and left out."""

    name: str
    place: str
    create: Callable
    label: str = ""
    order: int = 100
    available: Callable | None = None


#: What a dataset generator makes: a sample's shape, or an edit of one of its layers.
DATASET_KINDS = ("shape", "edit")


@dataclass(frozen=True)
class DatasetGenerator:
    """Random material for ``sketchforge dataset`` (``sketchforge_dataset_generators``).

    ``kind`` "shape": ``make(rng) -> list[dict]``, the journal entries that build a sample's
    layers. ``kind`` "edit": ``make(doc, layer, model, rng) -> dict | None``, one journal
    entry editing the layer with id ``layer`` under the document's light and the reflectance
    model named ``model`` (None: nothing to edit there). ``rng`` is a
    ``numpy.random.Generator``; the sample is reproducible only if every choice comes from it.
    The ``name`` of a shape generator is the sample's ``kind`` in the dataset."""

    name: str
    kind: str
    make: Callable
    description: str = ""

