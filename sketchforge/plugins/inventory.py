"""What every plugin registers, and its problems: the list ``sketchforge plugins`` prints and
the app's Help > Plugins shows (one source, so the two always agree).

Each problem line the host recorded (a plugin left out, a hook that raised, a contribution
refused, a name two plugins claim) is listed once, numbered; every plugin it names refers to
its number.
"""

from __future__ import annotations

from dataclasses import dataclass, field

#: The kinds of contribution, in the order they are listed: (the host's word, heading).
KINDS = (
    ("inflater", "inflaters"),
    ("sculpt solver", "sculpt solvers"),
    ("assembler", "assemblers"),
    ("command", "commands"),
    ("tool", "tools"),
    ("reflectance model", "reflectance models"),
    ("shader", "shaders"),
    ("exporter", "exporters"),
    ("panel", "panels"),
    ("dataset generator", "dataset generators"),
    ("pose", "posing"),
    ("plugin data", "plugin data"),
)


@dataclass(frozen=True)
class PluginEntry:
    """One plugin as the inventory lists it.

    Attributes
    ----------
    name : str
        The plugin's name (its entry point; ``sketchforge-core`` for the built-in core).
    version : str or None
        The installed version of the distribution that provides it.
    status : str
        "loaded", "disabled" (a hook raised: none of its contributions is used) or
        "not loaded" (it could not be imported or registered).
    registers : dict
        {heading: [names]} of what it contributes, in :data:`KINDS` order, empty kinds left out.
    problems : list of str
        One line per problem that concerns it.
    """

    name: str
    version: str | None
    status: str
    registers: dict = field(default_factory=dict)
    problems: list = field(default_factory=list)


def plugin_inventory(host) -> list[PluginEntry]:
    """Every plugin of ``host``: the core first, then the others by name, then those left out.
    Builds every registry first (``host.validate()``), so what a plugin would break is known."""
    from sketchforge.plugins.manager import CORE
    from sketchforge.plugins.plugin_data import plugin_data_validators

    host.validate()
    found: dict[str, dict[str, list]] = {}
    for (what, name), plugin in sorted(host._providers.items(), key=lambda kv: kv[0][1]):
        found.setdefault(plugin, {}).setdefault(what, []).append(name)
    for impl in host.pm.hook.sketchforge_pose.get_hookimpls():
        found.setdefault(impl.plugin_name, {}).setdefault("pose", []).append("sketchforge_pose")
    try:
        validators = plugin_data_validators(host)
    except Exception:  # noqa: BLE001 - a broken hook is reported when a document is opened
        validators = {}
    for key, (_, plugin) in sorted(validators.items()):
        for p in plugin.split("' and '"):
            found.setdefault(p, {}).setdefault("plugin data", []).append(key)
    loaded = host.plugin_names()
    names = [CORE] + sorted(n for n in loaded if n != CORE)
    out = []
    for name in names:
        contributions = found.get(name, {})
        registers = {heading: sorted(contributions[what]) for what, heading in KINDS if contributions.get(what)}
        out.append(PluginEntry(name, host.provider_version(name), "loaded", registers, host.problems_of(name)))
    for name in sorted(host.skipped):
        if name in loaded:
            continue
        status = "disabled" if "disabled" in " ".join(host.problems_of(name)) else "not loaded"
        out.append(PluginEntry(name, host.pm.versions.get(name), status, {}, host.problems_of(name)))
    return out


def unattributed_problems(host, entries: list[PluginEntry]) -> list[str]:
    """Problem lines no listed plugin owns (shown apart, so none is ever hidden)."""
    listed = {p for e in entries for p in e.problems}
    return [p for p in host.problems if p not in listed]


def numbered_problems(entries: list[PluginEntry], extra_problems=()) -> list[str]:
    """Every problem once, in the order of the plugins listed (then those no plugin owns): the
    numbers a plugin's "problems" refer to."""
    out: list[str] = []
    for e in entries:
        out += [p for p in e.problems if p not in out]
    return out + [p for p in extra_problems if p not in out]


def format_inventory(entries: list[PluginEntry], extra_problems=()) -> list[str]:
    """The inventory as text lines (``sketchforge plugins``): per plugin one heading line
    "NAME VERSION (STATUS)", one line per kind of contribution and the numbers of its
    problems; then each problem once, numbered ("problems:", "  1. ...")."""
    problems = numbered_problems(entries, extra_problems)
    lines = []
    for e in entries:
        head = e.name + (f" {e.version}" if e.version else "")
        if e.status != "loaded":
            head += f" ({e.status})"
        lines.append(head)
        for heading, names in e.registers.items():
            lines.append(f"  {heading}: {', '.join(names)}")
        if not e.registers and e.status == "loaded":
            lines.append("  registers nothing")
        if e.problems:
            refs = ", ".join(str(problems.index(p) + 1) for p in e.problems)
            lines.append(f"  problem{'s' * (len(e.problems) != 1)}: {refs} (below)")
    if problems:
        lines.append(f"{len(problems)} problem{'s' * (len(problems) != 1)}:")
        lines += [f"  {i}. {p}" for i, p in enumerate(problems, 1)]
    return lines
