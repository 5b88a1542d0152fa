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

import logging
import os
from functools import cached_property
from importlib import metadata
from importlib.metadata import entry_points
from typing import Iterable

import pluggy

from sketchforge.errors import PluginError, SketchforgeError
from sketchforge.plugins import contracts, hookspecs

log = logging.getLogger("sketchforge.plugins")
#: The built-in plugin's registration name.
CORE = "sketchforge-core"

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
    pm.register(builtin, name=CORE)
    pm.skipped = {}
    pm.problems = []
    pm.versions = {}
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
                dist = getattr(ep, "dist", None)
                if dist is not None:
                    pm.versions[ep.name] = dist.version
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
    def _solve(self, hookname: str, **kwargs):
        """A ``firstresult`` hook called implementation by implementation (pluggy's order:
        last registered first), so a bug in one (an exception that is not a SketchforgeError)
        becomes a PluginError naming that plugin."""
        for impl in reversed(getattr(self.pm.hook, hookname).get_hookimpls()):
            if getattr(impl, "hookwrapper", False) or getattr(impl, "wrapper", False):
                continue
            try:
                result = impl.function(*[kwargs[a] for a in impl.argnames])
            except SketchforgeError:
                raise
            except Exception as exc:  # noqa: BLE001 - foreign code: named, not hidden
                raise PluginError(f"the {hookname} hook of plugin {impl.plugin_name!r} failed: {type(exc).__name__}: {exc}") from exc
            if result is not None:
                return result
        return None

    def inflate(self, points, closed: bool, params: dict, holes=()):
        holes = [] if holes is None else list(holes)
        if holes:
            impls = self.pm.hook.sketchforge_inflate.get_hookimpls()
            if impls and "holes" not in impls[-1].argnames:  # the last registered answers first
                from sketchforge.errors import ContourError

                raise ContourError(f"the inflate plugin {impls[-1].plugin_name!r} cannot cut holes; remove the holes or install one that can")
        return self._solve("sketchforge_inflate", points=points, closed=closed, params=params, holes=holes)

    def has_assembler(self) -> bool:
        return bool(self.pm.hook.sketchforge_assemble.get_hookimpls())

    def assemble(self, layers, params: dict | None = None):
        return self._solve("sketchforge_assemble", layers=list(layers), params=dict(params or {}))

    # registries
    @property
    def problems(self) -> list[str]:
        """One line per plugin contribution the host refused or plugin it disabled (a hook that
        raised, a broken contract, a name clash), each naming the plugin. The app shows them
        in the status bar and log; the CLI on stderr."""
        return list(self.pm.problems)

    def _report(self, text: str) -> None:
        if text not in self.pm.problems:
            self.pm.problems.append(text)
            log.warning("%s", text)

    def disable(self, plugin_name: str, reason: str) -> None:
        """Unregister a misbehaving plugin (never the core) and forget every registry built so
        far, so none of its contributions stay half-registered."""
        plugin = self.pm.get_plugin(plugin_name)
        if plugin is None or plugin_name == CORE:
            raise PluginError(reason)
        self.pm.unregister(name=plugin_name)
        self.pm.skipped[plugin_name] = reason
        self._report(f"plugin {plugin_name!r} disabled: {reason}")
        for attr in ("commands", "tools", "reflectance_models", "shaders", "exporters", "_providers"):
            self.__dict__.pop(attr, None)

    def _collect(self, hookname: str, what: str, check=None) -> dict:
        """Call every plugin's registry hook one by one, so a hook that raises disables its
        own plugin only. ``check(item, plugin)`` validates one contribution (raises
        PluginError); a refused item is reported and left out, the plugin's others stay."""
        while True:
            out: dict = {}
            owner: dict = {}
            broken = None
            # Registration order (core first), so a later plugin cannot silently shadow an
            # earlier name: the clash is reported and the first one kept.
            for impl in getattr(self.pm.hook, hookname).get_hookimpls():
                if getattr(impl, "hookwrapper", False) or getattr(impl, "wrapper", False):
                    continue
                plugin = impl.plugin_name
                try:
                    items = impl.function()
                except Exception as exc:  # noqa: BLE001 - foreign code at start-up
                    broken = (plugin, f"its {hookname} hook raised {type(exc).__name__}: {exc}")
                    break
                if items is None:
                    continue
                if not isinstance(items, (list, tuple)):
                    self._report(
                        f"plugin {plugin!r}: {hookname} must return a list of {what}s, got {type(items).__name__} (ignored)"
                    )
                    continue
                for item in items:
                    name = getattr(item, "name", None)
                    if not name or not isinstance(name, str):
                        self._report(f"plugin {plugin!r}: a {what} without a name was registered: {item!r} (ignored)")
                        continue
                    if name in out:
                        if out[name] is not item:
                            self._report(
                                f"plugins {owner[name]!r} and {plugin!r} both register the {what} {name!r}; "
                                f"the one from {owner[name]!r} is used"
                            )
                        continue
                    if check is not None:
                        try:
                            check(item, plugin)
                        except PluginError as exc:
                            self._report(str(exc))
                            continue
                    out[name] = item
                    owner[name] = plugin
            if broken is None:
                for name, plugin in owner.items():
                    self._providers[(what, name)] = plugin
                return out
            self.disable(*broken)

    @cached_property
    def _providers(self) -> dict:
        return {}

    def provider_of(self, item) -> str | None:
        """The name of the plugin that registered ``item`` (a command or tool class, a model,
        shader or exporter), None when it is not registered."""
        for kind, attr in (("command", "commands"), ("tool", "tools"), ("reflectance model", "reflectance_models"), ("shader", "shaders"), ("exporter", "exporters")):
            if kind == "reflectance model" and (kind, getattr(item, "name", None)) not in self._providers:
                continue  # probing models imports JAX: only when one was asked for
            reg = getattr(self, attr)
            name = getattr(item, "name", None)
            try:
                known = reg.get(name) if kind != "command" else reg._classes.get(name)
            except Exception:  # noqa: BLE001 - an unknown name
                known = None
            if known is item:
                return self._providers.get((kind, name))
        return None

    def provider_version(self, plugin_name: str | None) -> str | None:
        """The installed version of the distribution that provides a plugin (the core's is
        sketchforge's own); None for a plugin registered by hand (tests)."""
        if plugin_name is None:
            return None
        if plugin_name == CORE:
            try:
                return metadata.version("sketchforge")
            except metadata.PackageNotFoundError:
                return None
        return self.pm.versions.get(plugin_name)

    @cached_property
    def commands(self):
        from sketchforge.document.commands import CommandRegistry

        return CommandRegistry(self._collect("sketchforge_commands", "command", contracts.check_command).values())

    def command_class(self, name: str):
        return self.commands.get(name)

    @cached_property
    def tools(self) -> dict:
        return self._collect("sketchforge_tools", "tool", contracts.check_tool)

    @cached_property
    def reflectance_models(self) -> dict:
        return self._collect("sketchforge_reflectance_models", "reflectance model", contracts.check_reflectance_model)

    @cached_property
    def shaders(self) -> dict:
        return self._collect("sketchforge_shaders", "shader", contracts.check_shader)

    @cached_property
    def exporters(self) -> dict:
        suffix_owner: dict = {}

        def check(exp, plugin):
            contracts.check_exporter(exp, plugin)
            for s in exp.suffixes:
                # A second mesh exporter for a suffix would never be chosen; a document
                # exporter (chosen only for documents it handles) may share one.
                if s in suffix_owner and exp.write_document is None:
                    other_name, other_plugin = suffix_owner[s]
                    raise PluginError(
                        f"plugin {plugin!r}: exporter {exp.name!r} claims {s!r}, already written by exporter "
                        f"{other_name!r} of plugin {other_plugin!r} (ignored)"
                    )
            for s in exp.suffixes:
                if exp.write_document is None:
                    suffix_owner[s] = (exp.name, plugin)

        return self._collect("sketchforge_exporters", "exporter", check)

    def validate(self) -> list[str]:
        """Build every registry now (the app at start-up), so a broken plugin is disabled
        before any document uses it. Returns :attr:`problems`."""
        for attr in ("commands", "tools", "shaders", "exporters", "reflectance_models"):
            getattr(self, attr)
        return self.problems

    def export(self, path, mesh=None, doc=None, progress=None) -> str:
        """Write ``mesh`` (or, with ``doc``, the whole document when a document exporter
        handles it) to ``path``, atomically and with one-line errors naming the plugin.

        The exporter writes to a path in a private temp folder (same file name, so suffix
        checks hold); the host then moves the bytes into place with
        :func:`sketchforge.atomic.write_bytes_atomic` (a reader sees the old file or the new
        one; the old file's mode is kept). Returns a one-line summary."""
        from sketchforge.plugins.export import run_exporter

        return run_exporter(self, path, mesh=mesh, doc=doc, progress=progress)

    def pose(self, doc, frame: int):
        """The document's model posed at animation ``frame`` by an animation plugin (None:
        no animation plugin is installed)."""
        return self._solve("sketchforge_pose", doc=doc, frame=int(frame))

    def exporter_for(self, path, doc=None) -> "object":
        """The exporter for ``path``'s suffix. With ``doc``, a document exporter that handles
        it (an animation) is preferred, the most recently registered first."""
        from pathlib import Path

        from sketchforge.errors import ExportError

        suffix = Path(path).suffix.lower()
        if doc is not None:
            for exp in reversed(list(self.exporters.values())):
                if suffix in exp.suffixes and exp.write_document is not None and exp.handles is not None:
                    try:
                        handles = exp.handles(doc)
                    except SketchforgeError:
                        raise
                    except Exception as exc:  # noqa: BLE001 - foreign code
                        raise ExportError(
                            f"exporter {exp.name!r} (plugin {self.provider_of(exp)!r}) failed to inspect the document: "
                            f"{type(exc).__name__}: {exc}"
                        ) from exc
                    if handles:
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
