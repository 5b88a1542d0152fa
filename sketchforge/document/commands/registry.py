"""The document's own commands and the registry that maps journal names to command classes
(core and plugins)."""

from __future__ import annotations

from sketchforge.document.commands.assembly import SetAssembly
from sketchforge.document.commands.base import Command, MacroCommand
from sketchforge.document.commands.contours import SetContour, SetInflateParams
from sketchforge.document.commands.layers import AddLayer, MoveLayer, RemoveLayer, RenameLayer, SetLayerVisible
from sketchforge.document.commands.light import SetLight
from sketchforge.document.commands.transforms import DuplicateLayer, MirrorLayer, TransformLayer, TranslateLayer
from sketchforge.errors import DocumentFormatError, PluginError, SketchforgeError, quote

#: The document's own commands, registered by the built-in plugin.
CORE_COMMANDS: tuple[type[Command], ...] = (
    AddLayer,
    RemoveLayer,
    RenameLayer,
    SetLayerVisible,
    MoveLayer,
    DuplicateLayer,
    TranslateLayer,
    TransformLayer,
    MirrorLayer,
    SetContour,
    SetInflateParams,
    SetAssembly,
    SetLight,
    MacroCommand,
)


class CommandRegistry:
    """Maps journal names to command classes (core + plugins)."""

    def __init__(self, classes, ambiguous: dict | None = None) -> None:
        #: {name: [plugins]}: names two plugins registered (neither is used).
        self._ambiguous = dict(ambiguous or {})
        self._classes: dict[str, type[Command]] = {}
        for cls in classes:
            if not cls.name:
                raise ValueError(f"command class {cls.__name__} has no name")
            if cls.name in self._classes and self._classes[cls.name] is not cls:
                raise ValueError(f"two plugins provide the command {cls.name!r}")
            self._classes[cls.name] = cls

    def names(self) -> list[str]:
        return sorted(self._classes)

    def get(self, name: str) -> type[Command]:
        from sketchforge.errors import UnknownCommandError

        try:
            return self._classes[name]
        except KeyError:
            if name in self._ambiguous:
                both = " and ".join(repr(p) for p in self._ambiguous[name])
                raise PluginError(f"the command {quote(name)} is registered by both plugins {both}; uninstall one of them") from None
            known = ", ".join(self.names())
            raise UnknownCommandError(
                f"unknown command {quote(name)} (is the plugin that provides it installed? known: {known})"
            ) from None

    def from_dict(self, d, depth: int = 1) -> Command:
        if not isinstance(d, dict):
            raise DocumentFormatError(f"a journal entry must be an object, got {type(d).__name__}")
        name = d.get("command")
        if not isinstance(name, str):
            raise DocumentFormatError("a journal entry needs a string field 'command'")
        cls = self.get(name)
        if cls is MacroCommand:
            return MacroCommand.from_dict(d, registry=self, depth=depth)
        try:
            return cls.from_dict(d)
        except SketchforgeError:
            raise
        except (TypeError, ValueError, KeyError, OverflowError) as exc:
            raise DocumentFormatError(f"command {quote(name)}: {exc}") from None
