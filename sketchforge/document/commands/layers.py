"""Commands on the layer list: add, remove, rename, show/hide, reorder."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from sketchforge.document.commands.base import Command, ReplaceLayerCommand, parse_field
from sketchforge.document.layer import Layer
from sketchforge.errors import ParameterError, quote


@dataclass
class AddLayer(Command):
    name: ClassVar[str] = "add_layer"
    id: str | None = None
    layer_name: str | None = None
    index: int | None = None  # None: on top (in front)
    _layer: Layer | None = field(default=None, repr=False)

    def text(self) -> str:
        return "Add layer"

    def do(self, doc) -> None:
        if self.id is None:
            self.id = doc.new_layer_id()
        if self.id in doc.layer_ids():
            raise ParameterError(f"a layer with id {quote(self.id)} already exists")
        from sketchforge.document.document import check_layer_count

        check_layer_count(doc)
        if self.layer_name is None:
            self.layer_name = self.id.replace("_", " ").capitalize()
        n = len(doc.layers)
        idx = n if self.index is None else self.index
        if not 0 <= idx <= n:
            raise ParameterError(f"layer index {idx} is outside 0..{n}")
        if self._layer is None:  # the same value on redo, so later commands' caches stay valid
            self._layer = Layer(id=self.id, name=self.layer_name)
        doc._insert_layer(idx, self._layer)

    def undo(self, doc) -> None:
        doc._remove_layer(doc.index_of(self.id))

    def to_dict(self) -> dict:
        d: dict = {"command": self.name, "id": self.id, "name": self.layer_name}
        if self.index is not None:
            d["index"] = self.index
        return d

    @classmethod
    def from_dict(cls, d: dict) -> AddLayer:
        return cls(
            id=parse_field(d, "id", str, cls.name, None),
            layer_name=parse_field(d, "name", str, cls.name, None),
            index=parse_field(d, "index", int, cls.name, None),
        )


@dataclass
class RemoveLayer(Command):
    name: ClassVar[str] = "remove_layer"
    layer: str
    _removed: Layer | None = field(default=None, repr=False)
    _index: int = field(default=-1, repr=False)

    def text(self) -> str:
        return "Remove layer"

    def do(self, doc) -> None:
        self._index = doc.index_of(self.layer)
        self._removed = doc._remove_layer(self._index)

    def undo(self, doc) -> None:
        doc._insert_layer(self._index, self._removed)

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer}

    @classmethod
    def from_dict(cls, d: dict) -> RemoveLayer:
        return cls(layer=parse_field(d, "layer", str, cls.name))


@dataclass
class RenameLayer(ReplaceLayerCommand):
    name: ClassVar[str] = "rename_layer"
    new_name: str = ""

    def text(self) -> str:
        return "Rename layer"

    def compute(self, doc, old: Layer) -> Layer:
        if not self.new_name.strip():
            raise ParameterError("a layer name must not be empty")
        return old.evolve(name=self.new_name)

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer, "name": self.new_name}

    @classmethod
    def from_dict(cls, d: dict) -> RenameLayer:
        return cls(layer=parse_field(d, "layer", str, cls.name), new_name=parse_field(d, "name", str, cls.name))


@dataclass
class SetLayerVisible(ReplaceLayerCommand):
    name: ClassVar[str] = "set_layer_visible"
    visible: bool = True

    def text(self) -> str:
        return "Show layer" if self.visible else "Hide layer"

    def compute(self, doc, old: Layer) -> Layer:
        return old.evolve(visible=bool(self.visible))

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer, "visible": bool(self.visible)}

    @classmethod
    def from_dict(cls, d: dict) -> SetLayerVisible:
        return cls(layer=parse_field(d, "layer", str, cls.name), visible=parse_field(d, "visible", bool, cls.name))


@dataclass
class MoveLayer(Command):
    """Move a layer to ``index`` in the back-to-front list (0 = furthest back)."""

    name: ClassVar[str] = "move_layer"
    layer: str = ""
    index: int = 0
    _from: int = field(default=-1, repr=False)

    def text(self) -> str:
        return "Reorder layers"

    def do(self, doc) -> None:
        n = len(doc.layers)
        if not 0 <= self.index < n:
            raise ParameterError(f"layer index {self.index} is outside 0..{n - 1}")
        self._from = doc.index_of(self.layer)
        doc._move_layer(self._from, self.index)

    def undo(self, doc) -> None:
        doc._move_layer(self.index, self._from)

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer, "index": self.index}

    @classmethod
    def from_dict(cls, d: dict) -> MoveLayer:
        return cls(layer=parse_field(d, "layer", str, cls.name), index=parse_field(d, "index", int, cls.name))
