"""The plugin manager and the host facade the document and front ends use.

Registration order is fixed, so ``firstresult`` hooks never depend on how packages were
installed: the built-in core plugin first, then entry points of the group ``sketchforge``
sorted by name, then ``check_pending()``. pluggy calls the most recently registered
implementation first, so an entry-point plugin overrides the core, and of two entry points
the one whose name sorts last wins.

``SKETCHFORGE_PLUGINS`` (comma-separated entry-point names) is an allowlist: when set, only
those entry points are loaded ("" loads none). ``SKETCHFORGE_PLUGINS`` does not affect the
built-in core plugin.
"""

from __future__ import annotations

import os
from functools import cached_property
from importlib.metadata import entry_points
from typing import Iterable

import pluggy

from sketchforge.plugins import hookspecs

ENTRY_POINT_GROUP = "sketchforge"
ALLOWLIST_ENV = "SKETCHFORGE_PLUGINS"


def make_plugin_manager(
    plugins: Iterable = (), load_entry_points: bool = True, allowlist=None, skip_broken: bool = False
) -> pluggy.PluginManager:
    """Build a manager: core plugin, then ``plugins`` (objects or modules, in order), then
    installed entry points (filtered by ``allowlist`` or the environment variable).

    With ``skip_broken`` an entry point that fails to import is left out instead of failing
    the whole host (the app must start even if one plugin is broken); the failures are in
    ``pm.skipped`` ({name: "ExceptionType: message"})."""
    from sketchforge.plugins import builtin

    pm = pluggy.PluginManager("sketchforge")
    pm.add_hookspecs(hookspecs)
    pm.register(builtin, name="sketchforge-core")
    pm.skipped = {}
    for i, plugin in enumerate(plugins):
        pm.register(plugin, name=getattr(plugin, "__name__", None) or f"plugin-{i}-{type(plugin).__name__}")
    if load_entry_points:
        if allowlist is None and ALLOWLIST_ENV in os.environ:
            allowlist = [s.strip() for s in os.environ[ALLOWLIST_ENV].split(",") if s.strip()]
        for ep in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
            if allowlist is not None and ep.name not in allowlist:
                continue
            if pm.get_plugin(ep.name) is None:
                try:
                    plugin = ep.load()
                except Exception as exc:  # noqa: BLE001 - any import error of foreign code
                    if not skip_broken:
                        raise
                    pm.skipped[ep.name] = f"{type(exc).__name__}: {exc}"
                    continue
                pm.register(plugin, name=ep.name)
    pm.check_pending()
    return pm


class PluginHost:
    """Typed access to the hooks (what the document, CLI and app call)."""

    def __init__(self, pm: pluggy.PluginManager) -> None:
        self.pm = pm

    @classmethod
    def create(cls, plugins: Iterable = (), load_entry_points: bool = True, allowlist=None, skip_broken: bool = False) -> "PluginHost":
        return cls(make_plugin_manager(plugins, load_entry_points, allowlist, skip_broken))

    @property
    def skipped(self) -> dict:
        """Entry points left out because they failed to import ({name: reason})."""
        return dict(self.pm.skipped)

    def plugin_names(self) -> list[str]:
        return [name for name, _ in self.pm.list_name_plugin()]

    # solvers
    def inflate(self, points, closed: bool, params: dict, holes=()):
        holes = [] if holes is None else list(holes)
        if holes:
            impls = self.pm.hook.sketchforge_inflate.get_hookimpls()
            if impls and "holes" not in impls[-1].argnames:  # the last registered answers first
                from sketchforge.errors import ContourError

                raise ContourError(f"the inflate plugin {impls[-1].plugin_name!r} cannot cut holes; remove the holes or install one that can")
        return self.pm.hook.sketchforge_inflate(points=points, closed=closed, params=params, holes=holes)

    def has_assembler(self) -> bool:
        return bool(self.pm.hook.sketchforge_assemble.get_hookimpls())

    def assemble(self, layers, params: dict | None = None):
        return self.pm.hook.sketchforge_assemble(layers=list(layers), params=dict(params or {}))

    # registries
    def _collect(self, hook, what: str) -> dict:
        out: dict = {}
        # pluggy returns last-registered first; reverse so the core comes first and a later
        # plugin cannot silently shadow an earlier name.
        for items in reversed(hook()):
            for item in items or ():
                name = getattr(item, "name", None)
                if not name:
                    raise ValueError(f"a {what} without a name was registered: {item!r}")
                if name in out and out[name] is not item:
                    raise ValueError(f"two plugins register the {what} {name!r}")
                out[name] = item
        return out

    @cached_property
    def commands(self):
        from sketchforge.document.commands import CommandRegistry

        return CommandRegistry(self._collect(self.pm.hook.sketchforge_commands, "command").values())

    def command_class(self, name: str):
        return self.commands.get(name)

    @cached_property
    def tools(self) -> dict:
        return self._collect(self.pm.hook.sketchforge_tools, "tool")

    @cached_property
    def reflectance_models(self) -> dict:
        return self._collect(self.pm.hook.sketchforge_reflectance_models, "reflectance model")

    @cached_property
    def shaders(self) -> dict:
        return self._collect(self.pm.hook.sketchforge_shaders, "shader")

    @cached_property
    def exporters(self) -> dict:
        return self._collect(self.pm.hook.sketchforge_exporters, "exporter")

    def pose(self, doc, frame: int):
        """The document's model posed at animation ``frame`` by an animation plugin (None:
        no animation plugin is installed)."""
        return self.pm.hook.sketchforge_pose(doc=doc, frame=int(frame))

    def exporter_for(self, path, doc=None) -> "object":
        """The exporter for ``path``'s suffix. With ``doc``, a document exporter that handles
        it (an animation) is preferred, the most recently registered first."""
        from pathlib import Path

        from sketchforge.errors import ExportError

        suffix = Path(path).suffix.lower()
        if doc is not None:
            for exp in reversed(list(self.exporters.values())):
                if suffix in exp.suffixes and exp.write_document is not None and exp.handles is not None and exp.handles(doc):
                    return exp
        for exp in self.exporters.values():
            if suffix in exp.suffixes:
                return exp
        known = ", ".join(sorted(s for e in self.exporters.values() for s in e.suffixes))
        raise ExportError(f"cannot export to {suffix or 'a file without suffix'!r}: known formats are {known}")


_default: PluginHost | None = None


def default_host() -> PluginHost:
    """The process-wide host with every installed plugin (built on first use)."""
    global _default
    if _default is None:
        _default = PluginHost.create()
    return _default
