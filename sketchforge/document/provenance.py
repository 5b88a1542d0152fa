"""Which plugin (and version) provided each command and reflectance model of a document.

Saved in the file as ``"providers": {"commands": {name: {"plugin": p, "version": v}},
"reflectance_models": {name: {...}}}`` for every command in the journal (macro children
included) and every non-default ``"model"`` an entry names. Opening a document whose
commands or models no installed plugin provides fails with one message listing every missing
plugin, its version and what needs it, instead of the first unknown entry's error.
"""

from __future__ import annotations

from typing import Any, Iterable, Iterator

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
    entries = list(_entries(journal))
    for layer in layers:
        edits = layer.get("edits", []) if isinstance(layer, dict) else getattr(layer, "edits", ())
        entries.extend(_entries(edits if isinstance(edits, (list, tuple)) else []))
    commands = {e["command"] for e in entries if isinstance(e.get("command"), str)}
    models = {e["model"] for e in entries if isinstance(e.get("model"), str) and e["model"] != "lambertian"}
    return commands, models


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
    return out


def _who(host, item) -> dict:
    plugin = host.provider_of(item) if hasattr(host, "provider_of") else None
    version = host.provider_version(plugin) if hasattr(host, "provider_version") else None
    return {"plugin": plugin, "version": version}


def check_available(data: dict, host, source: str) -> None:
    """Raise one DocumentFormatError listing every plugin the document needs that is not
    installed (from the file's ``providers`` when it has them)."""
    journal = data.get("journal", [])
    snap = data.get("snapshot")
    layers = snap.get("layers", []) if isinstance(snap, dict) and isinstance(snap.get("layers"), list) else []
    commands, models = _used(journal if isinstance(journal, list) else [], layers)
    have = set(host.commands.names())
    missing_cmds = sorted(commands - have)
    missing_models = sorted(models - set(host.reflectance_models)) if models else []
    if not missing_cmds and not missing_models:
        return
    providers: Any = data.get("providers")
    providers = providers if isinstance(providers, dict) else {}
    needs: dict[str, list[str]] = {}
    for kind, names, what in (("commands", missing_cmds, "command"), ("reflectance_models", missing_models, "reflectance model")):
        table = providers.get(kind) if isinstance(providers.get(kind), dict) else {}
        for name in names:
            info = table.get(name) if isinstance(table.get(name), dict) else {}
            plugin, version = info.get("plugin"), info.get("version")
            if isinstance(plugin, str):
                key = f"from plugin {quote(plugin)}" + (f" version {shorten(version, 60)}" if isinstance(version, str) else "")
            else:
                key = "its plugin is not recorded in the file"
            needs.setdefault(key, []).append(f"unknown {what} {quote(name)}")
    parts = [f"{', '.join(items)} ({key})" for key, items in needs.items()]
    raise DocumentFormatError(f"{source} needs plugins that are not installed: " + "; ".join(parts))
