"""Which plugin (and version) provided each command, reflectance model and solver of a document.

Saved in the file as ``"providers": {"commands": {name: {"plugin": p, "version": v}},
"reflectance_models": {name: {...}}, "solvers": {kind: {name: {"plugin": p, "version": v,
"solver_version": s}}}}`` for every command in the journal (macro children included), every
non-default ``"model"`` an entry names, and every solver (inflater, sculpt solver, assembler)
the document used: named by a layer, an edit or a journal entry, or the default that ran where
none is named. The parameters themselves are in the journal entries and the snapshot.

Opening (or replaying) a document whose commands, models or solvers no installed plugin
provides fails with one message listing every missing one, its plugin and version, instead of
the first unknown entry's error or a "mesh differs".
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import Any

from sketchforge.errors import DocumentFormatError, quote, shorten


def _entries(entries: Iterable) -> Iterator[dict]:
    for e in entries:
        if isinstance(e, dict):
            yield e
            children = e.get("children")
            if isinstance(children, list):
                yield from _entries(children)


def _used(journal: Iterable, layers: Iterable = ()) -> tuple[set[str], set[str]]:
    """Command names and (non-default) model names in a journal and the layers' edits."""
    entries = _all_entries(journal, layers)
    commands = {e["command"] for e in entries if isinstance(e.get("command"), str)}
    models = {e["model"] for e in entries if isinstance(e.get("model"), str) and e["model"] != "lambertian"}
    return commands, models


def _all_entries(journal: Iterable, layers: Iterable = ()) -> list[dict]:
    entries = list(_entries(journal))
    for layer in layers:
        edits = layer.get("edits", []) if isinstance(layer, dict) else getattr(layer, "edits", ())
        entries.extend(_entries(edits if isinstance(edits, (list, tuple)) else []))
    return entries


def used_solvers(host, journal: Iterable, layers: Iterable = (), assembly=None, defaults: bool = True) -> dict:
    """{kind: set of solver names} a document uses: the ``"solver"`` of every journal entry and
    edit of a solver command (its class's ``solver_kind``), each layer's inflater, the
    document's assembler; with ``defaults``, the default of a kind whose commands name none
    (what ran for them on this host)."""
    from sketchforge.solver_kinds import SOLVER_KINDS

    out: dict[str, set] = {k: set() for k in SOLVER_KINDS}
    unnamed: set[str] = set()
    classes = getattr(host.commands, "_classes", {})
    for e in _all_entries(journal, layers):
        cls = classes.get(e.get("command")) if isinstance(e.get("command"), str) else None
        kind = getattr(cls, "solver_kind", None)
        if kind is None:
            continue
        if isinstance(e.get("solver"), str):
            out[kind].add(e["solver"])
        else:
            unnamed.add(kind)
    for layer in layers:
        name = layer.get("solver") if isinstance(layer, dict) else getattr(layer, "solver", None)
        if isinstance(name, str):
            out["inflate"].add(name)
        elif (layer.get("mesh") if isinstance(layer, dict) else getattr(layer, "mesh", None)) is not None:
            unnamed.add("inflate")
    choice = assembly.get("solver") if isinstance(assembly, dict) else getattr(assembly, "solver", None)
    if isinstance(choice, str):
        out["assemble"].add(choice)
    elif "inflate" in unnamed or out["inflate"]:
        unnamed.add("assemble")  # a document with meshes is assembled with the default
    if defaults:
        for kind in unnamed:
            name = host.default_solver_name(kind) if hasattr(host, "default_solver_name") else None
            if name is not None:
                out[kind].add(name)
    return out


def record(doc) -> dict:
    """The ``providers`` field for ``doc`` (empty entries for names no plugin claims)."""
    host = doc.host
    commands, models = _used(doc.journal(), doc.layers)
    out: dict[str, dict] = {"commands": {}, "reflectance_models": {}}
    known = host.commands
    for name in sorted(commands):
        try:
            cls = known.get(name)
        except Exception:  # noqa: BLE001 - an unknown name has no provider to record
            continue
        out["commands"][name] = _who(host, cls)
    if models:
        registry = host.reflectance_models
        for name in sorted(models):
            if name in registry:
                out["reflectance_models"][name] = _who(host, registry[name])
    if hasattr(host, "solvers"):
        solvers: dict = {}
        for kind, names in sorted(used_solvers(host, doc.journal(), doc.layers, doc.assembly).items()):
            reg = host.solvers(kind)
            for name in sorted(names):
                if name in reg:
                    solvers.setdefault(kind, {})[name] = {**_who(host, reg[name]), "solver_version": reg[name].version}
        if solvers:
            out["solvers"] = solvers
    return out


def _as_dict(value) -> dict:
    """``value`` if it is a dict, else an empty one (a file's malformed parts are ignored)."""
    return value if isinstance(value, dict) else {}


def _who(host, item) -> dict:
    plugin = host.provider_of(item) if hasattr(host, "provider_of") else None
    version = host.provider_version(plugin) if hasattr(host, "provider_version") else None
    return {"plugin": plugin, "version": version}


def _recorded_solvers(providers: dict) -> dict:
    """{kind: {name: info}} from a file's ``providers`` (malformed parts ignored)."""
    table = _as_dict(providers.get("solvers"))
    return {k: v for k, v in table.items() if isinstance(k, str) and isinstance(v, dict)}


def _from(info: Any) -> str:
    info = info if isinstance(info, dict) else {}
    plugin, version = info.get("plugin"), info.get("version")
    if isinstance(plugin, str):
        return f"plugin {plugin[:80]!r}" + (f" version {version[:40]}" if isinstance(version, str) else "")
    return "its plugin is not recorded in the file"


def missing_solvers(data: dict, host) -> list[str]:
    """One phrase per solver the document was made with that is not installed: "the inflater
    'fan' (plugin 'x' version 1.0)"; from the snapshot, the journal and ``providers``."""
    from sketchforge.solver_kinds import SOLVER_KINDS

    if not hasattr(host, "solvers"):
        return []
    journal = data.get("journal", [])
    snap = _as_dict(data.get("snapshot"))
    layers = snap.get("layers", []) if isinstance(snap.get("layers"), list) else []
    providers = _as_dict(data.get("providers"))
    recorded = _recorded_solvers(providers)
    used = used_solvers(host, journal if isinstance(journal, list) else [], [l for l in layers if isinstance(l, dict)],
                        snap.get("assembly"), defaults=False)
    for kind, table in recorded.items():
        # The default assembler a document was shown with is recorded, but a document does not
        # need it (without one, the layers are exported as they are); one it names, it needs.
        if kind in used and kind != "assemble":
            used[kind] |= {n for n in table if isinstance(n, str)}
    out = []
    for kind in SOLVER_KINDS:
        have = host.solvers(kind)
        for name in sorted(used.get(kind, ())):
            if name not in have:
                out.append(f"the {SOLVER_KINDS[kind].what} {name[:80]!r} ({_from(recorded.get(kind, {}).get(name))})")
    return out


def version_notes(data: dict, host) -> list[str]:
    """Solvers the document records with another version than the installed one: a replay
    that differs from its snapshot is then explained ("the sculpt solver 'strips' was version
    1 of plugin 'strips' 0.1.0; installed: version 2 of 0.2.0")."""
    from sketchforge.solver_kinds import SOLVER_KINDS

    providers = _as_dict(data.get("providers"))
    notes = []
    for kind, table in sorted(_recorded_solvers(providers).items()):
        if kind not in SOLVER_KINDS:
            continue
        have = host.solvers(kind)
        for name, info in sorted(table.items()):
            if name not in have or not isinstance(info, dict):
                continue
            now = {**_who(host, have[name]), "solver_version": have[name].version}
            then = {k: info.get(k) for k in ("version", "solver_version")}
            if then["version"] != now["version"] or then["solver_version"] != now["solver_version"]:
                def of(plugin, version):  # a plugin registered by hand has no version to say
                    return f"{quote(plugin)}" + (f" {version}" if isinstance(version, str) else "")

                notes.append(f"the {SOLVER_KINDS[kind].what} {quote(name)} was version {then['solver_version']} of plugin "
                             f"{of(info.get('plugin'), then['version'])}; installed: version {now['solver_version']} of "
                             f"{of(now['plugin'], now['version'])}")
    return notes


def missing_plugins(data: dict, host) -> list[str]:
    """One phrase per command, reflectance model and solver the document needs that no
    installed plugin provides, with the plugin and version the file records: "the command
    'bump_brush' (plugin 'bump_brush' version 0.1.0)". Empty when everything is installed
    (what ``sketchforge info`` lists for a document it can still describe)."""
    journal = data.get("journal", [])
    snap = data.get("snapshot")
    layers = snap.get("layers", []) if isinstance(snap, dict) and isinstance(snap.get("layers"), list) else []
    commands, models = _used(journal if isinstance(journal, list) else [], layers)
    providers: Any = data.get("providers")
    providers = providers if isinstance(providers, dict) else {}
    out = []
    for kind, names, what in (("commands", sorted(commands - set(host.commands.names())), "command"),
                              ("reflectance_models", sorted(models - set(host.reflectance_models)) if models else [],
                               "reflectance model")):
        table = _as_dict(providers.get(kind))
        out += [f"the {what} {quote(name)} ({_from(table.get(name))})" for name in names]
    return out + missing_solvers(data, host)


def check_available(data: dict, host, source: str) -> None:
    """Raise one DocumentFormatError listing every plugin the document needs that is not
    installed (from the file's ``providers`` when it has them): commands, reflectance models
    and solvers ("DOC was made with the sculpt solver 'strips' (plugin 'strips' version
    0.1.0), which is not installed")."""
    journal = data.get("journal", [])
    snap = data.get("snapshot")
    layers = snap.get("layers", []) if isinstance(snap, dict) and isinstance(snap.get("layers"), list) else []
    commands, models = _used(journal if isinstance(journal, list) else [], layers)
    have = set(host.commands.names())
    missing_cmds = sorted(commands - have)
    missing_models = sorted(models - set(host.reflectance_models)) if models else []
    solvers = missing_solvers(data, host)
    if not missing_cmds and not missing_models:
        if solvers:
            raise DocumentFormatError(f"{source} was made with {', '.join(solvers)}, which "
                                      f"{'is' if len(solvers) == 1 else 'are'} not installed")
        return
    providers: Any = data.get("providers")
    providers = providers if isinstance(providers, dict) else {}
    needs: dict[str, list[str]] = {}
    for kind, names, what in (("commands", missing_cmds, "command"), ("reflectance_models", missing_models, "reflectance model")):
        table = _as_dict(providers.get(kind))
        for name in names:
            info = _as_dict(table.get(name))
            plugin, version = info.get("plugin"), info.get("version")
            if isinstance(plugin, str):
                key = f"from plugin {quote(plugin)}" + (f" version {shorten(version, 60)}" if isinstance(version, str) else "")
            else:
                key = "its plugin is not recorded in the file"
            needs.setdefault(key, []).append(f"unknown {what} {quote(name)}")
    parts = [f"{', '.join(items)} ({key})" for key, items in needs.items()]
    tail = f"; it was made with {', '.join(solvers)}, not installed either" if solvers else ""
    raise DocumentFormatError(f"{source} needs plugins that are not installed: " + "; ".join(parts) + tail)
