"""The plugin manager and the host facade the document and front ends use.

Registration order is fixed: the built-in core plugin first, then entry points of the group
``sketchforge`` sorted by name, each checked as it is registered (its hooks must exist, no
pluggy wrappers, no replaced legacy hook). Every contribution is named, and a name belongs to
one plugin: a plugin cannot replace the core's, and two plugins registering the same name is
an error naming both (the name is then unusable until one of them goes), never "the last
registered wins" (:meth:`PluginHost._collect`).

``SKETCHFORGE_PLUGINS`` (comma-separated entry-point names) is an allowlist: when set, only
those entry points are loaded ("" loads none). ``SKETCHFORGE_PLUGINS`` does not affect the
built-in core plugin.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable
from functools import cached_property
from importlib import metadata
from importlib.metadata import entry_points

import pluggy

from sketchforge.errors import ParameterError, PluginError, SketchforgeError, UnknownSolverError, quote
from sketchforge.plugins import contracts, hookspecs
from sketchforge.plugins.outputs import check_solver_output
from sketchforge.plugins.solvers import SOLVER_KINDS, json_value

#: Problems are logged at INFO: the front ends show each one once (the CLI on stderr, the app in
#: Help > Plugins and its status bar); a warning here reached stderr once more per host built.
log = logging.getLogger("sketchforge.plugins")
#: The built-in plugin's registration name.
CORE = "sketchforge-core"

ENTRY_POINT_GROUP = "sketchforge"


ALLOWLIST_ENV = "SKETCHFORGE_PLUGINS"


#: Hooks of earlier releases that named registries replaced: a plugin that still implements
#: one is refused with what to write instead.
LEGACY_HOOKS = {
    "sketchforge_inflate": "sketchforge_inflaters (return [Inflater('my_inflater', inflate, check_params)])",
    "sketchforge_assemble": "sketchforge_assemblers (return [Assembler('my_assembler', assemble, check_params)])",
}


class HostPluginManager(pluggy.PluginManager):
    """pluggy's manager with what the host keeps about its plugins beside it."""

    def __init__(self, project_name: str) -> None:
        super().__init__(project_name)
        #: {plugin name: one line} of the plugins left out
        self.skipped: dict[str, str] = {}
        self.problems: list[str] = []
        #: {problem line: [plugin names it concerns]}
        self.problem_owners: dict[str, list[str]] = {}
        self.versions: dict[str, str | None] = {}
        #: {plugin name: distribution name} of the entry points loaded
        self.distributions: dict[str, str] = {}


def add_problem(pm: HostPluginManager, text: str, *plugins: str) -> None:
    """Record one problem line naming ``plugins`` (once: the same line twice is one problem)."""
    owners = pm.problem_owners.setdefault(text, [])
    if text not in pm.problems:
        pm.problems.append(text)
        log.info("%s", text)
    owners.extend(p for p in plugins if p not in owners)


def _hook_problem(pm: HostPluginManager, plugin, name: str) -> str | None:
    """Why a registered plugin's hooks cannot be used (None: they can): a hook the
    specification does not know (a typo, or a legacy hook), or a pluggy wrapper, which the
    host would never call since it calls each plugin's hook on its own."""
    for caller in pm.get_hookcallers(plugin) or []:
        if caller.spec is None:
            if caller.name in LEGACY_HOOKS:
                return (f"plugin {name!r} implements {caller.name}, which was replaced by the named registry "
                        f"{LEGACY_HOOKS[caller.name]}; it was not loaded")
            known = ", ".join(sorted(n for n in dir(hookspecs) if n.startswith("sketchforge_")))
            return f"plugin {name!r} implements the unknown hook {caller.name!r} (known: {known}); it was not loaded"
        for impl in caller.get_hookimpls():
            if impl.plugin is plugin and (getattr(impl, "hookwrapper", False) or getattr(impl, "wrapper", False)):
                return (f"plugin {name!r}: its {caller.name} hook is a pluggy wrapper (wrapper=True); sketchforge calls "
                        "each plugin's hook on its own, so a wrapper would never run: return your contribution from "
                        "a plain hook instead; it was not loaded")
    return None


def make_plugin_manager(
    plugins: Iterable = (), load_entry_points: bool = True, allowlist=None, skip_broken: bool = False
) -> HostPluginManager:
    """Build a manager: core plugin, then ``plugins`` (objects or modules, in order), then
    installed entry points (filtered by ``allowlist`` or the environment variable).

    Each plugin's hooks are checked as it is registered (:func:`_hook_problem`). A plugin given
    in ``plugins`` that fails raises PluginError. With ``skip_broken`` an entry point that
    fails to import or to register is left out instead of failing the whole host (the app, the
    CLI and a script's document must start even if one plugin is broken or lacks a dependency);
    the failures are in ``pm.skipped`` ({name: one line}) and ``pm.problems``, each with the
    plugins it concerns in ``pm.problem_owners``."""
    from sketchforge.plugins import builtin

    pm = HostPluginManager("sketchforge")
    pm.add_hookspecs(hookspecs)
    pm.register(builtin, name=CORE)

    def register(plugin, name: str, explicit: bool) -> bool:
        pm.register(plugin, name=name)
        problem = _hook_problem(pm, plugin, name)
        if problem is None:
            return True
        pm.unregister(name=name)
        if explicit or not skip_broken:
            raise PluginError(problem)
        pm.skipped[name] = problem
        add_problem(pm, problem, name)
        return False

    for i, plugin in enumerate(plugins):
        register(plugin, getattr(plugin, "__name__", None) or f"plugin-{i}-{type(plugin).__name__}", True)
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
                    # One line naming the plugin and what it lacks (a missing dependency is a
                    # ModuleNotFoundError naming the module).
                    text = f"plugin {ep.name!r} could not be loaded: {type(exc).__name__}: {exc}"
                    pm.skipped[ep.name] = f"{type(exc).__name__}: {exc}"
                    add_problem(pm, text, ep.name)
                    continue
                if not register(plugin, ep.name, False):
                    continue
                dist = getattr(ep, "dist", None)
                if dist is not None:
                    pm.versions[ep.name] = dist.version
                    pm.distributions[ep.name] = dist.metadata["Name"] or ep.name
    pm.check_pending()
    return pm


class PluginHost:
    """Typed access to the hooks (what the document, CLI and app call)."""

    def __init__(self, pm: HostPluginManager) -> None:
        self.pm = pm

    @classmethod
    def create(cls, plugins: Iterable = (), load_entry_points: bool = True, allowlist=None, skip_broken: bool = False) -> PluginHost:
        return cls(make_plugin_manager(plugins, load_entry_points, allowlist, skip_broken))

    @property
    def skipped(self) -> dict:
        """Entry points left out because they failed to import ({name: reason})."""
        return dict(self.pm.skipped)

    def plugin_names(self) -> list[str]:
        return [name for name, _ in self.pm.list_name_plugin()]

    # the one firstresult hook ----------------------------------------------------------------
    def _solve(self, hookname: str, **kwargs):
        """A ``firstresult`` hook: at most one plugin may implement it (two are an error naming
        both, never "the last registered wins"); a bug in it (an exception that is not a
        SketchforgeError) becomes a PluginError naming the plugin."""
        impls = getattr(self.pm.hook, hookname).get_hookimpls()
        if len(impls) > 1:
            names = " and ".join(repr(i.plugin_name) for i in impls)
            raise PluginError(f"plugins {names} both implement {hookname}; uninstall one of them (or leave one out "
                              f"with {ALLOWLIST_ENV})")
        for impl in impls:
            try:
                result = impl.function(*[kwargs[a] for a in impl.argnames])
            except SketchforgeError:
                raise
            except Exception as exc:  # noqa: BLE001 - foreign code: named, not hidden
                raise PluginError(f"the {hookname} hook of plugin {impl.plugin_name!r} failed: {type(exc).__name__}: {exc}") from exc
            if result is not None:
                return result
        return None

    # named solvers ----------------------------------------------------------------------------
    def solvers(self, kind: str) -> dict:
        """The installed solvers of one kind ("inflate", "sculpt", "assemble"): {name: value}."""
        return getattr(self, f"_solvers_{kind}")

    @cached_property
    def _solvers_inflate(self) -> dict:
        return self._collect("sketchforge_inflaters", "inflater", contracts.solver_check("inflate"))

    @cached_property
    def _solvers_sculpt(self) -> dict:
        return self._collect("sketchforge_sculpt_solvers", "sculpt solver", contracts.solver_check("sculpt"))

    @cached_property
    def _solvers_assemble(self) -> dict:
        return self._collect("sketchforge_assemblers", "assembler", contracts.solver_check("assemble"))

    def default_solver_name(self, kind: str) -> str | None:
        """The solver a document that names none uses: the built-in, or on a host without it
        the only one of that kind installed; None when that does not decide it."""
        reg = self.solvers(kind)
        default = SOLVER_KINDS[kind].default
        if default in reg:
            return default
        if len(reg) == 1:
            return next(iter(reg))
        return None

    def solver(self, kind: str, name: str | None = None):
        """The solver value ``name`` of ``kind`` (None: :meth:`default_solver_name`).

        Raises
        ------
        UnknownSolverError
            No such solver is installed (the message lists the installed ones).
        PluginError
            Two plugins register that name.
        """
        spec = SOLVER_KINDS[kind]
        reg = self.solvers(kind)
        if name is None:
            name = self.default_solver_name(kind)
            if name is None:
                if not reg:
                    raise UnknownSolverError(f"no {spec.what} is installed (the built-in {spec.default!r} comes with "
                                             "its plugin; is it left out by SKETCHFORGE_PLUGINS?)")
                raise UnknownSolverError(f"no {spec.what} is chosen and the built-in {spec.default!r} is not installed; "
                                         f"name one of: {', '.join(sorted(reg))}")
        if name in reg:
            return reg[name]
        clash = self._ambiguous.get(spec.what, {}).get(name)
        if clash:
            raise PluginError(f"the {spec.what} {name!r} is registered by both plugins {clash[0]!r} and {clash[1]!r}; "
                              f"uninstall one of them (or leave one out with {ALLOWLIST_ENV})")
        known = ", ".join(sorted(reg)) or "none"
        raise UnknownSolverError(f"no {spec.what} named {quote(name)} is installed (installed: {known})")

    def solver_params(self, kind: str, solver, params) -> dict:
        """``solver``'s complete parameters for ``params`` (a mapping, maybe partial), checked by
        the solver itself. Raises ParameterError naming the solver ("sculpt solver 'strips':
        unknown parameter 'x' (known: ...)"), or PluginError if its check is broken."""
        spec = SOLVER_KINDS[kind]
        try:
            out = solver.check_params(dict(params or {}))
        except SketchforgeError as exc:
            raise ParameterError(f"{spec.what} {solver.name!r}: {exc}") from None
        except Exception as exc:  # noqa: BLE001 - foreign code
            raise PluginError(f"the {spec.what} {solver.name!r} (plugin {self.provider_of(solver)!r}) failed to check its "
                              f"parameters: {type(exc).__name__}: {exc}") from exc
        if not isinstance(out, dict) or not json_value(out):
            raise PluginError(f"the {spec.what} {solver.name!r} (plugin {self.provider_of(solver)!r}): check_params must "
                              f"return a dict of JSON values, got {quote(out)}")
        return out

    def solver_fields(self, kind: str, name: str | None = None) -> list:
        """The parameter form of the solver ``name`` of ``kind`` (None: the default): one
        :class:`~sketchforge.plugins.param_forms.ParamField` per parameter, from what its
        ``check_params`` declares (:func:`~sketchforge.plugins.param_forms.describe_params`).

        Raises
        ------
        UnknownSolverError, PluginError
            No such solver; its ``check_params({})`` fails (named with its plugin).
        """
        from sketchforge.plugins.param_forms import describe_params

        spec = SOLVER_KINDS[kind]
        solver = self.solver(kind, name)
        try:
            return describe_params(solver.check_params)
        except Exception as exc:  # noqa: BLE001 - foreign code
            raise PluginError(f"the {spec.what} {solver.name!r} (plugin {self.provider_of(solver)!r}) failed to "
                              f"describe its parameters: {type(exc).__name__}: {exc}") from exc

    def run_solver(self, kind: str, solver, *args):
        """Call ``solver``'s function; a bug in it (not a SketchforgeError) becomes a
        PluginError naming the solver and its plugin."""
        spec = SOLVER_KINDS[kind]
        try:
            return getattr(solver, spec.call)(*args)
        except SketchforgeError:
            raise
        except Exception as exc:  # noqa: BLE001 - foreign code: named, not hidden
            raise PluginError(f"the {spec.what} {solver.name!r} of plugin {self.provider_of(solver)!r} failed: "
                              f"{type(exc).__name__}: {exc}") from exc

    def inflate(self, points, closed: bool, params: dict, holes=(), solver: str | None = None):
        """Inflate with the inflater ``solver`` (None: the default) and its ``params``."""
        from sketchforge.errors import ContourError

        holes = [] if holes is None else list(holes)
        try:
            inflater = self.solver("inflate", solver)
        except UnknownSolverError:
            if solver is None and not self.solvers("inflate"):
                raise SketchforgeError("no inflate plugin is installed, so a contour cannot become a mesh") from None
            raise
        if holes and not inflater.holes:
            raise ContourError(f"the inflater {inflater.name!r} (plugin {self.provider_of(inflater)!r}) cannot cut holes; "
                               "remove the holes or choose one that can")
        full = self.solver_params("inflate", inflater, params)
        mesh = self.run_solver("inflate", inflater, points, closed, full, holes)
        return check_solver_output("inflate", inflater, self.provider_of(inflater), mesh)

    def has_assembler(self) -> bool:
        return bool(self.solvers("assemble"))

    def assemble(self, layers, params: dict | None = None, solver: str | None = None):
        """Assemble with the assembler ``solver`` (None: the default) and its ``params``."""
        assembler = self.solver("assemble", solver)
        full = self.solver_params("assemble", assembler, params)
        mesh = self.run_solver("assemble", assembler, list(layers), full)
        return check_solver_output("assemble", assembler, self.provider_of(assembler), mesh)

    # registries
    @property
    def problems(self) -> list[str]:
        """One line per plugin contribution the host refused or plugin it disabled (a hook that
        raised, a broken contract, a name clash), each naming the plugin. The app shows them
        in the status bar and log; the CLI on stderr."""
        return list(self.pm.problems)

    def report_problem(self, text: str, *plugins: str) -> None:
        """Add a problem a front end found (a panel whose ``create`` failed), naming its
        plugins: it is listed with the others (Help > Plugins, ``problems_of``)."""
        self._report(text, *plugins)

    def problems_of(self, plugin_name: str) -> list[str]:
        """The problem lines that concern ``plugin_name`` (a plugin left out, a contribution
        refused, a name it shares with another plugin)."""
        return [t for t in self.pm.problems if plugin_name in self.pm.problem_owners.get(t, ())]

    def _report(self, text: str, *plugins: str) -> None:
        add_problem(self.pm, text, *plugins)

    def disable(self, plugin_name: str, reason: str) -> None:
        """Unregister a misbehaving plugin (never the core) and forget every registry built so
        far, so none of its contributions stay half-registered."""
        plugin = self.pm.get_plugin(plugin_name)
        if plugin is None or plugin_name == CORE:
            raise PluginError(reason)
        self.pm.unregister(name=plugin_name)
        self.pm.skipped[plugin_name] = reason
        self._report(f"plugin {plugin_name!r} disabled: {reason}", plugin_name)
        for attr in ("commands", "tools", "reflectance_models", "shaders", "exporters", "_exporter_suffixes", "qt_panels",
                     "dataset_generators", "_providers",
                     "_ambiguous", *(f"_solvers_{k}" for k in SOLVER_KINDS)):
            self.__dict__.pop(attr, None)

    def _collect(self, hookname: str, what: str, check=None) -> dict:
        """Call every plugin's registry hook one by one, so a hook that raises disables its
        own plugin only. ``check(item, plugin)`` validates one contribution (raises
        PluginError); a refused item is reported and left out, the plugin's others stay.

        Names: a plugin cannot take a name the core registered (refused); two plugins
        registering one name is an error naming both, and the name is left out of the
        registry (a lookup says why: :attr:`_ambiguous`) until one of them goes. Which one
        would win must never depend on registration order."""
        while True:
            out: dict = {}
            owner: dict = {}
            clashes: dict = {}
            broken = None
            for impl in getattr(self.pm.hook, hookname).get_hookimpls():
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
                        f"plugin {plugin!r}: {hookname} must return a list of {what}s, got {type(items).__name__} (ignored)",
                        plugin,
                    )
                    continue
                for item in items:
                    name = getattr(item, "name", None)
                    if not name or not isinstance(name, str):
                        self._report(f"plugin {plugin!r}: a {what} without a name was registered: {quote(item)} (ignored)",
                                     plugin)
                        continue
                    if name in out and out[name] is item:
                        continue  # the same value twice (one module registered under two names)
                    if check is not None:
                        try:
                            check(item, plugin)
                        except PluginError as exc:
                            self._report(str(exc), plugin, *getattr(exc, "plugins", ()))
                            continue
                    if name in clashes:
                        clashes[name].append(plugin)
                        self._report(f"plugin {plugin!r} also registers the {what} {name!r} (registered by "
                                     f"{' and '.join(map(repr, clashes[name][:-1]))}): error, the name is not usable",
                                     *clashes[name])
                        continue
                    if name in out:
                        first = owner[name]
                        if first == CORE:
                            self._report(f"plugin {plugin!r}: the {what} {name!r} is sketchforge's own; a plugin cannot "
                                         "replace it (refused: register it under another name)", plugin)
                            continue
                        clashes[name] = [first, plugin]
                        del out[name], owner[name]
                        self._report(f"plugins {first!r} and {plugin!r} both register the {what} {name!r}: error, neither "
                                     f"is used until one of them is uninstalled (or left out with {ALLOWLIST_ENV})",
                                     first, plugin)
                        continue
                    out[name] = item
                    owner[name] = plugin
            if broken is None:
                for name, plugin in owner.items():
                    self._providers[(what, name)] = plugin
                self._ambiguous[what] = clashes
                return out
            self.disable(*broken)

    @cached_property
    def _ambiguous(self) -> dict:
        """{what: {name: [plugins]}}: names two or more plugins registered (none is used)."""
        return {}

    @cached_property
    def _providers(self) -> dict:
        return {}

    def provider_of(self, item) -> str | None:
        """The name of the plugin that registered ``item`` (a command or tool class, a model,
        shader or exporter), None when it is not registered."""
        kinds = [("command", "commands"), ("tool", "tools"), ("reflectance model", "reflectance_models"),
                 ("shader", "shaders"), ("exporter", "exporters"), ("panel", "qt_panels"),
                 ("dataset generator", "dataset_generators"),
                 *((spec.what, f"_solvers_{k}") for k, spec in SOLVER_KINDS.items())]
        for kind, attr in kinds:
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

        classes = self._collect("sketchforge_commands", "command", contracts.check_command).values()
        return CommandRegistry(classes, ambiguous=self._ambiguous.get("command", {}))

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
    def dataset_generators(self) -> dict:
        """{name: DatasetGenerator}: the random shapes and edits of ``sketchforge dataset``."""
        return self._collect("sketchforge_dataset_generators", "dataset generator", contracts.check_dataset_generator)

    @cached_property
    def qt_panels(self) -> dict:
        """Panels for the desktop app ({name: Panel}); only the app calls their ``create``."""
        return self._collect("sketchforge_qt_panels", "panel", contracts.check_panel)

    @cached_property
    def exporters(self) -> dict:
        """{name: Exporter}. A suffix is written by one mesh exporter and at most one document
        exporter (an animation, chosen for the documents it handles): a plugin cannot take a
        suffix of the core's (its exporter is refused), and two plugins claiming one suffix is
        an error naming both, the suffix then unusable until one of them goes
        (:meth:`exporter_for`), never "the first one loaded wins"."""
        core: dict = {}

        def check(exp, plugin):
            contracts.check_exporter(exp, plugin)
            for s in exp.suffixes:
                if exp.write_document is None and s in core and plugin != CORE:
                    raise PluginError(
                        f"plugin {plugin!r}: exporter {exp.name!r} claims {s!r}, already written by exporter "
                        f"{core[s]!r} of plugin {CORE!r} (ignored)"
                    )
            if plugin == CORE and exp.write_document is None:
                core.update((s, exp.name) for s in exp.suffixes)

        return self._collect("sketchforge_exporters", "exporter", check)

    @cached_property
    def _exporter_suffixes(self) -> tuple[dict, dict]:
        """({(suffix, kind): Exporter}, {(suffix, kind): clash message}), kind "mesh" or
        "document"; a suffix two plugins claim is only in the second."""
        claims: dict = {}
        for exp in self.exporters.values():
            kind = "mesh" if exp.write_document is None else "document"
            for s in exp.suffixes:
                claims.setdefault((s, kind), []).append(exp)
        table, clashes = {}, {}
        for (suffix, kind), exps in claims.items():
            if len(exps) == 1:
                table[(suffix, kind)] = exps[0]
                continue
            plugins = [self.provider_of(e) or "?" for e in exps]
            what = "document exporters" if kind == "document" else "exporters"
            text = (f"plugins {' and '.join(map(repr, plugins))} both write {suffix!r} ({what} "
                    f"{' and '.join(repr(e.name) for e in exps)}): error, neither is used for {suffix!r} until one of "
                    f"them is uninstalled (or left out with {ALLOWLIST_ENV})")
            clashes[(suffix, kind)] = text
            self._report(text, *plugins)
        return table, clashes

    def validate(self) -> list[str]:
        """Build every registry now (the app at start-up), so a broken plugin is disabled
        before any document uses it. Returns :attr:`problems`."""
        for attr in ("commands", "tools", "shaders", "exporters", "_exporter_suffixes", "reflectance_models", "qt_panels",
                     "dataset_generators"):
            getattr(self, attr)
        for kind in SOLVER_KINDS:
            self.solvers(kind)
        impls = self.pm.hook.sketchforge_pose.get_hookimpls()
        if len(impls) > 1:
            self._report(f"plugins {' and '.join(repr(i.plugin_name) for i in impls)} both implement sketchforge_pose: "
                         "error, posing is refused until one of them is uninstalled", *(i.plugin_name for i in impls))
        return self.problems

    def display_shadings(self) -> dict:
        """Every way the display can shade: {key: shader}, the display shaders by their name,
        then each reflectance model as ``"model:NAME"`` shading by its own R(n, l) (one BRDF
        definition for the sculpt and the display: :mod:`sketchforge.geometry.model_shading`).
        A shader has ``name``, ``shade(N, l)``, ``description``; a model's also
        ``intensity(N, l)`` (its isophote lines)."""
        from sketchforge.geometry.model_shading import model_shader

        out = dict(self.shaders)
        for name, model in self.reflectance_models.items():
            out[f"model:{name}"] = model_shader(model)
        return out

    def validate_plugin_data(self, plugin_data: dict, where: str) -> None:
        """Check a file's plugin data (``snapshot.plugin_data``) with the validators the
        plugins register (:mod:`sketchforge.plugins.plugin_data`)."""
        from sketchforge.plugins.plugin_data import validate_plugin_data

        validate_plugin_data(self, plugin_data, where)

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

    def exporter_for(self, path, doc=None) -> object:
        """The exporter for ``path``'s suffix. With ``doc``, the document exporter of that
        suffix (an animation) if it handles ``doc``, else the suffix's mesh exporter.

        Raises
        ------
        ExportError
            No installed exporter writes that suffix.
        PluginError
            Two plugins claim that suffix (the message names both).
        """
        from pathlib import Path

        from sketchforge.errors import ExportError

        suffix = Path(path).suffix.lower()
        table, clashes = self._exporter_suffixes
        if doc is not None:
            if (suffix, "document") in clashes:
                raise PluginError(clashes[(suffix, "document")])
            exp = table.get((suffix, "document"))
            if exp is not None and exp.handles is not None:
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
        if (suffix, "mesh") in clashes:
            raise PluginError(clashes[(suffix, "mesh")])
        exp = table.get((suffix, "mesh"))
        if exp is not None:
            return exp
        known = ", ".join(sorted({s for s, _ in table} | {s for s, _ in clashes}))
        raise ExportError(f"cannot export to {suffix or 'a file without suffix'!r}: known formats are {known}")


_default: PluginHost | None = None


def default_host() -> PluginHost:
    """The process-wide host with every installed plugin (built on first use): what the CLI
    and a script hand a document (``Document(default_host())``). A plugin that cannot be loaded
    (a missing dependency, a broken hook) is left out with one line in ``problems`` naming it,
    never a traceback: the CLI prints that line once, the app lists it in Help > Plugins, a
    document works with the rest."""
    global _default
    if _default is None:
        _default = PluginHost.create(skip_broken=True)
    return _default
