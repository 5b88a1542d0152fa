"""The shape of the code base (issue 37): built-in plugins are plugins like any other, the core
is layered, and the core knows no built-in plugin.

- Every package under ``plugins/`` and ``examples/plugins/`` (their tests included) imports
  sketchforge only through ``sketchforge.plugin_api``, and a Qt panel (a ``qt`` subpackage)
  also through ``sketchforge.qt.panel_api``.
- The parts of ``sketchforge`` import each other one way: geometry below the document, the
  document below the plugin host, the front ends (app, CLI, batch) on top; the document is
  handed its host and imports nothing of ``sketchforge.plugins``. Lazy imports inside
  functions count too: a circle through them is still a circle.
- The core (``sketchforge`` outside its pytest plugin) imports no plugin package.
- Every name of the public API is documented in the README's "The public API".
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CORE = ROOT / "sketchforge"
PLUGIN_ROOTS = [ROOT / "plugins", ROOT / "examples" / "plugins"]
PUBLIC = ("sketchforge.plugin_api",)
PANEL_PUBLIC = ("sketchforge.qt.panel_api",)
#: The plugin packages the core must not import.
PLUGIN_PACKAGES = tuple(sorted({p.name for root in PLUGIN_ROOTS for d in root.iterdir() if d.is_dir()
                                for p in d.iterdir() if p.is_dir() and p.name.startswith("sketchforge_")}))


def imported_modules(path: Path) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in a file, lazy ones included; a
    ``from sketchforge import x`` counts as ``sketchforge.x``."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module == "sketchforge":
                out += [(node.lineno, f"sketchforge.{a.name}") for a in node.names]
            else:
                out.append((node.lineno, node.module))
        elif isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", "")) in (
                "import_module", "__import__") and node.args and isinstance(node.args[0], ast.Constant):
            out.append((node.lineno, str(node.args[0].value)))
    return out


def _plugin_files():
    return sorted(p for root in PLUGIN_ROOTS for p in root.rglob("*.py") if ".egg-info" not in str(p))


def test_plugins_import_sketchforge_only_through_the_public_api():
    assert len(_plugin_files()) > 60 and len(PLUGIN_PACKAGES) >= 8
    offenders = []
    for path in _plugin_files():
        in_qt = "qt" in path.relative_to(ROOT).parts[:-1]
        allowed = PUBLIC + (PANEL_PUBLIC if in_qt else ())
        for line, mod in imported_modules(path):
            if mod == "sketchforge" or mod.startswith("sketchforge."):
                if mod not in allowed:
                    offenders.append(f"{path.relative_to(ROOT)}:{line}: {mod}")
    assert offenders == []


def test_the_rule_catches_an_internal_import(tmp_path):
    """The check above is not vacuous: each way of reaching an internal module is seen."""
    bad = tmp_path / "bad.py"
    bad.write_text("from sketchforge.geometry import guard\nimport sketchforge.document.commands\n"
                   "def f():\n    from sketchforge.errors import quote\n    from sketchforge import atomic\n"
                   "    importlib.import_module('sketchforge.plugins.manager')\n")
    found = [m for _, m in imported_modules(bad)]
    assert found == ["sketchforge.geometry", "sketchforge.document.commands", "sketchforge.errors",
                     "sketchforge.atomic", "sketchforge.plugins.manager"]


def _unit(module: str) -> str | None:
    """The part of sketchforge a module belongs to: its subpackage, or its top-level module."""
    parts = module.split(".")
    if parts[0] != "sketchforge" or len(parts) == 1:
        return None
    return parts[1]


def package_graph() -> dict[str, dict[str, list[str]]]:
    """{unit: {unit it imports: [where]}} over every file of sketchforge."""
    graph: dict[str, dict[str, list[str]]] = {}
    for path in sorted(CORE.rglob("*.py")):
        rel = path.relative_to(CORE).parts
        src = rel[0].removesuffix(".py")
        for line, mod in imported_modules(path):
            dst = _unit(mod)
            if dst is not None and dst != src:
                graph.setdefault(src, {}).setdefault(dst, []).append(f"{path.relative_to(ROOT)}:{line}")
    return graph


#: The layers, from the inside out; a unit may import only units of its own layer or below.
LAYERS = [
    {"errors", "numerics", "atomic", "solver_kinds", "cache"},
    {"geometry", "exporters"},
    {"document"},
    {"tools"},
    {"plugins"},
    {"plugin_api", "offload"},
    {"batch", "qt"},
    {"cli"},
    {"__main__"},
]


def test_the_core_is_layered_and_the_document_does_not_import_the_plugin_host():
    graph = package_graph()
    rank = {u: i for i, layer in enumerate(LAYERS) for u in layer}
    assert set(graph) <= set(rank), f"a new part of sketchforge needs a place in LAYERS: {set(graph) - set(rank)}"
    upward = [f"{src} -> {dst} ({where[0]})" for src, deps in graph.items() for dst, where in deps.items()
              if rank[dst] > rank[src]]
    assert upward == []
    assert "plugins" not in graph.get("document", {}), graph["document"]
    assert "document" in graph["plugins"]  # the host builds the document's command registry: one way only


def test_no_part_of_sketchforge_imports_another_in_a_circle():
    graph = {src: set(deps) for src, deps in package_graph().items()}
    seen, stack, cycles = set(), [], []

    def visit(u):
        if u in stack:
            cycles.append(stack[stack.index(u):] + [u])
            return
        if u in seen:
            return
        seen.add(u)
        stack.append(u)
        for v in sorted(graph.get(u, ())):
            visit(v)
        stack.pop()

    for u in sorted(graph):
        visit(u)
    assert cycles == []


def test_the_core_knows_no_built_in_plugin():
    """No module of sketchforge (its batch runs and dataset included) imports a plugin
    package: what the core needs of one comes through a hook (the dataset's shapes and edits:
    ``sketchforge_dataset_generators``). The shipped pytest plugin only names their commands
    in helpers for plugin authors' tests."""
    offenders = []
    for path in sorted(CORE.rglob("*.py")):
        for line, mod in imported_modules(path):
            if mod.split(".")[0].startswith("sketchforge_"):
                offenders.append(f"{path.relative_to(ROOT)}:{line}: {mod}")
    assert offenders == []
    assert PLUGIN_PACKAGES and "sketchforge_assemble" in PLUGIN_PACKAGES


def test_the_batch_names_no_built_in_plugin_or_its_commands():
    names = ("sketchforge_assemble", "sketchforge_isophote_tool", "sculpt_isophote", "random_creature",
             "random_outline", "random_edit")
    offenders = []
    for path in sorted((CORE / "batch").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                offenders += [f"{path.name}: {n}" for n in names if n in node.value and "``" not in node.value]
    assert offenders == []


def _readme_api_section() -> str:
    text = (ROOT / "README.md").read_text()
    start = text.index("### The public API")
    return text[start: text.index("\n### ", start + 10)]


def test_every_public_name_is_documented():
    import sketchforge.plugin_api as api

    section = _readme_api_section()
    undocumented = [n for n in api.__all__ if f"`{n}`" not in section and f"`{n}(" not in section]
    assert undocumented == []
    unresolved = [n for n in api.__all__ if not hasattr(api, n)]
    assert unresolved == []


def test_public_geometry_is_loaded_when_first_used():
    """Importing the public API does not import JAX or the meshing libraries: the geometry
    names load on first use (a subprocess, so this test's own imports do not count)."""
    import subprocess
    import sys

    code = ("import sys, sketchforge.plugin_api as api\n"
            "heavy = [m for m in ('jax', 'triangle', 'igl') if m in sys.modules]\n"
            "assert not heavy, heavy\n"
            "assert api.guard.mesh and api.triangulate_polygon and api.TriangleLocator and api.evaluate_pq\n"
            "assert 'jax' in sys.modules and 'triangle' in sys.modules\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr[-2000:]
