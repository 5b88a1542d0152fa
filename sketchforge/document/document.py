"""The Document: ordered layers, the light, the undo stack, and events. No Qt.

Only commands change a document (through the underscore methods below); everything else
reads it. Signals, emitted after the change:

- ``layer_inserted(int index, Layer layer)``
- ``layer_removed(int index, Layer layer)``
- ``layer_changed(int index, Layer new, Layer old)`` (any field; ``mesh_changed`` follows if
  the mesh object changed)
- ``layer_moved(int from_index, int to_index)``
- ``mesh_changed(str layer_id)``
- ``light_changed(Light light)``
- ``history_changed()`` (undo stack index, texts or clean state)
- ``assembly_invalidated()`` (the assembled model must be recomputed)
- ``plugin_data_changed(str key)`` (a plugin's document-level data, e.g. an animation)
- ``assembly_changed()`` (the assembler or its parameters: ``set_assembly``)

Plugin data: plugins that keep document-level state which is not a layer (the animation's
pins and motions) store it as one JSON value per key (dicts, lists, strings, numbers, bools)
through their own commands. It is saved in the snapshot and compared by ``differences``.
"""

from __future__ import annotations

import numpy as np

from sketchforge.cache import LRUCache
from sketchforge.document.commands import Command
from sketchforge.document.events import Signal
from sketchforge.document.layer import Layer, Light
from sketchforge.document.undo import UndoStack
from sketchforge.errors import LayerNotFoundError, LimitError, SketchforgeError, SolverError, quote, shorten
from sketchforge.geometry.merge import merge_meshes
from sketchforge.solver_kinds import SolverChoice

#: Layers a document may hold. A Monster Mash model has tens of parts; every layer costs
#: the canvas a rasterisation and the assembly depth rows against every layer it overlaps
#: (issue 30: 3 000 copies of one layer ran for hours).
MAX_LAYERS = 256


def check_layer_count(doc) -> None:
    """LimitError when ``doc`` holds MAX_LAYERS layers already (before a layer is added)."""
    if len(doc.layers) >= MAX_LAYERS:
        raise LimitError(f"a document holds at most {MAX_LAYERS} layers; remove some before adding more")


#: Bytes of fresh inflations a document keeps (a 46k-vertex layer's mesh is ~2 MB).
INFLATIONS_BYTES = 64 << 20


class Document:
    def __init__(self, host, light: Light | None = None) -> None:
        if host is None:
            raise TypeError("a Document is handed its plugin host: Document(host), e.g. "
                            "Document(sketchforge.plugins.default_host()) for every installed plugin")
        #: The plugin host (:class:`~sketchforge.document.host.DocumentHost`): whoever makes the
        #: document hands it over (the app, the CLI, a test); the document never builds one.
        self.host = host
        self._layers: list[Layer] = []
        self._light = light or Light()
        #: The light at the start of the journal and the entries that came before this
        #: session's undo history (from an opened file).
        self.initial_light: Light = self._light
        self.base_journal: list[dict] = []
        self.revision = 0  # bumped on every change; keys derived caches
        self.geometry_revision = 0  # bumped when layers change (not the light)
        self._assembled = None
        self._assembled_revision = -1
        self._plugin_data: dict = {}
        self._assembly = SolverChoice()
        #: The layers' fresh inflations by their inputs (:func:`~sketchforge.document.commands.
        #: contours.inflated`): what a sculpt edit bounds its creases against, and an undone
        #: contour or parameter change redone without inflating again.
        self.inflations = LRUCache(max_bytes=INFLATIONS_BYTES, name="inflations")

        self.layer_inserted = Signal(int, Layer, name="layer_inserted")
        self.layer_removed = Signal(int, Layer, name="layer_removed")
        self.layer_changed = Signal(int, Layer, Layer, name="layer_changed")
        self.layer_moved = Signal(int, int, name="layer_moved")
        self.mesh_changed = Signal(str, name="mesh_changed")
        self.light_changed = Signal(Light, name="light_changed")
        self.history_changed = Signal(name="history_changed")
        self.assembly_invalidated = Signal(name="assembly_invalidated")
        self.plugin_data_changed = Signal(str, name="plugin_data_changed")
        self.assembly_changed = Signal(name="assembly_changed")
        self.undo_stack = UndoStack(self)

    # --- queries --------------------------------------------------------------------------------
    @property
    def layers(self) -> tuple[Layer, ...]:
        """Back to front: later layers are in front."""
        return tuple(self._layers)

    @property
    def light(self) -> Light:
        return self._light

    @property
    def assembly(self) -> SolverChoice:
        """The assembler (``solver``, None: the default) and its ``params`` (``set_assembly``)."""
        return self._assembly

    def plugin_data(self, key: str, default=None):
        """A plugin's document-level JSON value (treat as read-only), or ``default``."""
        return self._plugin_data.get(key, default)

    @property
    def plugin_data_keys(self) -> list[str]:
        return sorted(self._plugin_data)

    def layer_ids(self) -> list[str]:
        return [layer.id for layer in self._layers]

    def index_of(self, layer_id: str) -> int:
        for i, layer in enumerate(self._layers):
            if layer.id == layer_id:
                return i
        ids = self.layer_ids()
        known = ", ".join(shorten(i, 40) for i in ids[:12]) or "none"
        if len(ids) > 12:
            known += f", and {len(ids) - 12} more"
        raise LayerNotFoundError(f"there is no layer with id {quote(layer_id)} (layers: {known})")

    def layer(self, layer_id: str) -> Layer:
        return self._layers[self.index_of(layer_id)]

    def new_layer_id(self, prefix: str = "layer") -> str:
        taken = set(self.layer_ids())
        i = 1
        while f"{prefix}{i}" in taken:
            i += 1
        return f"{prefix}{i}"

    def journal(self) -> list[dict]:
        """Every command that led from an empty document with ``initial_light`` to now."""
        return list(self.base_journal) + [c.to_dict() for c in self.undo_stack.done_commands()]

    # --- the one way to change a document -----------------------------------------------------
    def push(self, command: Command) -> Command:
        return self.undo_stack.push(command)

    def execute(self, entry: dict) -> Command:
        """Build a command from a journal dict and push it."""
        return self.push(self.host.commands.from_dict(entry))

    # --- assembled model (derived, cached) --------------------------------------------------------
    def assembled(self):
        """The assembled model of the visible layers (None without an assembler or meshes).
        Cached until the next change of a layer (the light does not invalidate it)."""
        if self._assembled_revision != self.geometry_revision:
            parts = [layer for layer in self._layers if layer.visible and layer.mesh is not None]
            a = self._assembly
            self._assembled = self.host.assemble(parts, dict(a.params), a.solver) if parts else None
            self._assembled_revision = self.geometry_revision
        return self._assembled

    def offer_assembled(self, geometry_revision: int, mesh) -> None:
        """A front end that assembled the visible layers on a worker thread hands the result
        back, so exports and pins do not assemble the same layers again. Ignored when the
        layers have changed since."""
        if geometry_revision == self.geometry_revision:
            self._assembled, self._assembled_revision = mesh, geometry_revision

    # --- mutators: commands only ------------------------------------------------------------------
    def _touch(self) -> None:
        self.revision += 1
        self.geometry_revision += 1
        self.assembly_invalidated.emit()

    @staticmethod
    def _check_finite(layer: Layer) -> None:
        """A layer whose mesh has a NaN or infinite coordinate never reaches the document,
        whichever command (a plugin's included) produced it: every view, the assembly and the
        file would be poisoned by it. Raised before anything changes."""
        mesh = layer.mesh
        if mesh is None:
            return
        bad = ~np.isfinite(mesh.V).all(axis=1)
        if bad.any():
            raise SolverError(
                f"the change would leave layer {layer.id[:80]!r} with non-finite heights or positions at {int(bad.sum())} "
                "vertices; it was refused and the document is unchanged"
            )

    def _insert_layer(self, index: int, layer: Layer) -> None:
        self._check_finite(layer)
        self._layers.insert(index, layer)
        self._touch()
        self.layer_inserted.emit(index, layer)

    def _remove_layer(self, index: int) -> Layer:
        layer = self._layers.pop(index)
        self._touch()
        self.layer_removed.emit(index, layer)
        return layer

    def _replace_layer(self, layer: Layer) -> None:
        index = self.index_of(layer.id)
        self._check_finite(layer)
        old = self._layers[index]
        self._layers[index] = layer
        self._touch()
        self.layer_changed.emit(index, layer, old)
        if layer.mesh is not old.mesh:
            self.mesh_changed.emit(layer.id)

    def _move_layer(self, src: int, dst: int) -> None:
        layer = self._layers.pop(src)
        self._layers.insert(dst, layer)
        self._touch()
        self.layer_moved.emit(src, dst)

    def _set_light(self, light: Light) -> None:
        self._light = light
        self.revision += 1  # shading only: the assembled geometry does not depend on the light
        self.light_changed.emit(light)

    def _set_assembly(self, choice: SolverChoice) -> None:
        self._assembly = choice
        self._touch()  # the assembled model depends on it
        self.assembly_changed.emit()

    def _set_plugin_data(self, key: str, value) -> None:
        """Set (or, with None, remove) a plugin's value; the assembled geometry is unaffected."""
        if value is None:
            self._plugin_data.pop(key, None)
        else:
            self._plugin_data[key] = value
        self.revision += 1
        self.plugin_data_changed.emit(key)

    # --- all-or-nothing commands (the undo stack's guard) ---------------------------------------
    def _snapshot(self):
        """The state a command may change, cheaply: layers are immutable values, so a tuple of
        references; plugin data is copied deeply (a buggy command may mutate it in place)."""
        import copy

        return (tuple(self._layers), self._light, copy.deepcopy(self._plugin_data), self._assembly)

    def _restore_snapshot(self, snap) -> None:
        """Put back a :meth:`_snapshot` after a command failed part-way, emitting the signals
        of what really changed so views follow."""
        layers, light, plugin_data, assembly = snap
        if len(layers) != len(self._layers) or any(a is not b for a, b in zip(layers, self._layers)):
            same_ids = [l.id for l in layers] == self.layer_ids()
            if same_ids:
                for layer in layers:
                    if layer is not self._layers[self.index_of(layer.id)]:
                        self._replace_layer(layer)
            else:
                while self._layers:
                    self._remove_layer(len(self._layers) - 1)
                for i, layer in enumerate(layers):
                    self._insert_layer(i, layer)
        if light != self._light:
            self._set_light(light)
        if assembly is not self._assembly:
            self._set_assembly(assembly)
        for key in sorted(set(plugin_data) | set(self._plugin_data)):
            if plugin_data.get(key) != self._plugin_data.get(key):
                self._set_plugin_data(key, plugin_data.get(key))

    # --- comparison (tests, replay checks) --------------------------------------------------------
    def differences(self, other: Document) -> list[str]:
        """What differs between the two states (empty when layers, meshes bit for bit, and
        light are equal)."""
        out = []
        if self._light != other._light:
            out.append(f"light differs: {self._light} vs {other._light}")
        ia, ib = self.layer_ids(), other.layer_ids()
        if ia != ib:
            return out + [f"layers differ: {ia} vs {ib}"]
        for la, lb in zip(self._layers, other._layers):
            if la.solver != lb.solver and None not in (la.solver, lb.solver):
                out.append(f"layer {la.id!r}: made with the inflater {la.solver!r} in one, {lb.solver!r} in the other")
                continue
            if not la.same_state(lb):
                mesh_differs = (la.mesh is None) != (lb.mesh is None) or (la.mesh is not None and not la.mesh.identical(lb.mesh))
                out.append(f"layer {la.id!r}: {'mesh' if mesh_differs else 'fields'} differ")
        for key in sorted(set(self._plugin_data) | set(other._plugin_data)):
            if self._plugin_data.get(key) != other._plugin_data.get(key):
                out.append(f"plugin data {key!r} differs")
        a, b = self._assembly, other._assembly
        if a.solver != b.solver or dict(a.params) != dict(b.params):
            out.append(f"assembly differs: {a.to_dict()} vs {b.to_dict()}")
        return out

    def same_state(self, other: Document) -> bool:
        return not self.differences(other)

    def restore_state(
        self, layers, light: Light, initial_light: Light | None = None, base_journal=(), plugin_data=None,
        assembly: SolverChoice | None = None,
    ) -> None:
        """Set the whole state at once (opening a file): layers, current light, plugin data,
        and the light and journal that led to them. Not undoable: clears history; the result
        is clean."""
        self._layers = list(layers)
        old_keys = set(self._plugin_data)
        self._plugin_data = dict(plugin_data or {})
        self._light = light
        self._assembly = SolverChoice() if assembly is None else assembly
        self.initial_light = light if initial_light is None else initial_light
        self.base_journal = [dict(e) for e in base_journal]
        self._touch()
        for key in sorted(old_keys | set(self._plugin_data)):
            self.plugin_data_changed.emit(key)
        self.undo_stack.clear()

    def adopt(self, other: Document) -> None:
        """Take over another document's state (the app opening a file into its window)."""
        self.restore_state(other.layers, other.light, other.initial_light, other.base_journal, other._plugin_data,
                           other._assembly)

    def export_mesh(self, layer_id: str | None = None):
        """The mesh to export: one layer's own front surface, else the assembled model, else
        (no assembler installed) the visible layers merged. Raises SketchforgeError when there
        is nothing to export."""
        if layer_id is not None:
            mesh = self.layer(layer_id).mesh
            if mesh is None:
                raise SketchforgeError(f"layer {layer_id!r} has no mesh (no contour was drawn)")
            return mesh
        parts = [layer.mesh for layer in self._layers if layer.visible and layer.mesh is not None]
        if not parts:
            raise SketchforgeError("there is nothing to export: no visible layer has a mesh")
        return self.assembled() if self.host.has_assembler() else merge_meshes(parts)
