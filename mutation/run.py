"""Mutation run over one scope of sketchforge (``make mutate SCOPE=document``).

mutmut names a mutant by the file's path relative to where it runs and matches that name against
``function.__module__`` at run time.  The plugins live in ``plugins/<name>/sketchforge_<name>``,
so run from the repository root their mutants would be called ``plugins.assemble....`` while the
code calls itself ``sketchforge_assemble....``: every plugin mutant would look "not covered".
So each scope runs in its own workspace under ``build/mutation/<scope>/`` where the package sits
at the top, exactly as it is imported; the tests and the files they read (examples, README,
Makefile, docs) are copied beside it. The workspace's ``mutants/`` folder comes first on
``sys.path`` inside mutmut, so the mutated copy shadows the editable install.

Usage::

    python mutation/run.py SCOPE [--jobs N] [--fresh]
    python mutation/run.py SCOPE --sample 150  # a seeded sample of the unchecked mutants + estimate
    python mutation/run.py SCOPE --retest      # the survivors again, after adding tests
    python mutation/run.py SCOPE --report      # score + survivors of the last run

Scopes: see ``SCOPES``.  The score and the survivors are written to
``mutation/results/<scope>.txt`` (kept in the repository; the README quotes the scores).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BUILD = ROOT / "build" / "mutation"
RESULTS = ROOT / "mutation" / "results"

# scope -> (package folder in the repository, package name, what to mutate inside the package,
# the test files that exercise it). Test files are the ones that import the scope directly or
# through the document; Qt and OpenGL tests are left out: they cannot run in mutmut's forked
# workers (a QApplication per fork) and their properties are covered headlessly too.
SCOPES: dict[str, tuple[str, str, list[str], list[str]]] = {
    "document": ("sketchforge", "sketchforge", ["sketchforge/document/*"], [
        "tests/test_undo.py", "tests/test_document_stateful.py", "tests/test_stateful_real.py",
        "tests/test_fileformat.py", "tests/test_autosave.py", "tests/test_crash_recovery.py",
        "tests/test_command_roundtrip.py", "tests/test_regressions_planted.py",
        "tests/test_transform.py", "tests/test_limits.py", "tests/test_document_contracts.py",
        "tests/test_holes.py", "tests/test_contour.py", "tests/test_parts.py",
        "tests/test_tools.py", "tests/test_fuzz_loader.py", "tests/attack",
        "tests/test_plugin_platform.py", "tests/test_document_survivors.py", "tests/test_transform_edits.py",
        "tests/test_light_3d.py", "tests/test_undo_memory.py", "tests/test_provenance.py",
        "tests/test_transform_contracts.py",
    ]),
    "geometry": ("sketchforge", "sketchforge", ["sketchforge/geometry/*"], [
        "tests/test_contour.py", "tests/test_inflate.py", "tests/test_laplacian.py",
        "tests/test_locate.py", "tests/test_mesh_quality.py", "tests/test_normals.py",
        "tests/test_raster.py", "tests/test_gbuffer.py", "tests/test_reflectance.py",
        "tests/test_shading.py", "tests/test_isophotes.py", "tests/test_band.py",
        "tests/test_strokes.py", "tests/test_holes.py", "tests/test_transform.py",
        "tests/test_regressions_planted.py", "tests/test_limits.py", "tests/test_exporters.py",
        "tests/test_guard.py", "tests/test_heightfield.py", "tests/test_isophote_wobble.py",
        "tests/test_parts.py", "tests/test_render_survivors.py", "tests/test_strokes_survivors.py",
        "tests/test_locate_band_survivors.py", "tests/test_isophote_normal_survivors.py",
        "tests/test_parts_merge_survivors.py", "tests/test_geometry_misc_survivors.py",
        "tests/test_locator_survivors.py", "tests/test_contour_guard_survivors.py",
    ]),
    "inflate": ("plugins/inflate/sketchforge_inflate", "sketchforge_inflate",
                ["sketchforge_inflate/*"], ["tests/test_inflate.py", "tests/test_holes.py",
                                            "tests/test_plugins.py"]),
    "isophote_tool": ("plugins/isophote_tool/sketchforge_isophote_tool", "sketchforge_isophote_tool",
                      ["sketchforge_isophote_tool/*"], [
                          "tests/test_sculpt.py", "tests/test_sculpt_tool.py",
                          "tests/test_sculpt_fidelity.py", "tests/test_sculpt_holes.py",
                          "tests/test_sculpt_corpus.py", "tests/test_band.py",
                          "tests/test_regressions_planted.py", "tests/test_fidelity_measures.py",
                          "tests/test_sculpt_tool_preview.py", "tests/test_corpus_measures.py",
                          "tests/test_sculpt_display.py", "tests/test_sculpt_pick.py",
                          "tests/test_sculpt_command_format.py", "tests/test_sculpt_tool_state.py",
                          "tests/test_sculpt_stroke_band.py", "tests/test_sculpt_heights.py",
                          "tests/test_sculpt_report.py", "tests/test_transform_edits.py",
                          "tests/test_sculpt_joint.py", "tests/test_sculpt_corpus_beyond.py", "tests/test_light_3d.py"]),
    "assemble": ("plugins/assemble/sketchforge_assemble", "sketchforge_assemble",
                 ["sketchforge_assemble/*"], [
                     "tests/test_assemble.py", "tests/test_assemble_blend.py",
                     "tests/test_assemble_holes.py", "tests/test_regressions_planted.py", "tests/test_assemble_cache.py",
                     "tests/test_transform.py", "tests/test_depth_qp.py", "tests/test_assemble_problem.py",
                     "tests/test_assemble_speed.py", "tests/test_guard.py", "tests/test_assemble_culprit.py",
                     "tests/test_assemble_parts.py", "tests/test_assemble_measures.py",
                     "tests/test_assemble_contracts.py"]),
    "animate": ("plugins/animate/sketchforge_animate", "sketchforge_animate",
                ["sketchforge_animate/*"], ["tests/test_animate.py", "tests/test_animate_oracle.py",
                                            "tests/test_plugin_data_validation.py"]),
    # issue 39: the plugin platform (solver registries, manager, contracts, plugin data), the
    # inflation's child process and the cache helper, and the strips solver had no scope.
    "plugins": ("sketchforge", "sketchforge", ["sketchforge/plugins/*"], [
        "tests/test_plugin_contracts.py", "tests/test_solver_registries.py", "tests/test_plugins.py",
        "tests/test_plugin_platform.py", "tests/test_plugin_data_validation.py", "tests/test_provenance.py",
        ]),
    "core": ("sketchforge", "sketchforge", ["sketchforge/offload.py", "sketchforge/cache.py"], [
        "tests/test_offload.py", "tests/test_cache.py", "tests/test_undo_memory.py"]),
    "strips": ("plugins/strips/sketchforge_strips", "sketchforge_strips", ["sketchforge_strips/*"], [
        "tests/test_strips_parts.py", "tests/test_strips_solver.py", "tests/test_strips_corpus.py"]),
}

# Test inputs, not product: modules (and, in corpus.py, functions marked ``# pragma: no mutate
# block``) that only build the shapes, documents and random edits the tests run on. A mutant there
# changes what is tested, not what the app does, so it survives whenever the tests still pass on
# the other input: it measures nothing about the suite. What measures results (corpus.run_edits,
# Outcome, refusal_reason, fidelity.py) is mutated: a bug there could hide a failing sculpt.
#
# A plugin's qt/ subpackage (its app panel) is left out for another reason: only the Qt tests
# reach it, and they cannot run in mutmut's workers (see SCOPES), so every mutant there would
# survive and say nothing about the suite.
DO_NOT_MUTATE: dict[str, list[str]] = {
    "isophote_tool": ["sketchforge_isophote_tool/testing.py", "sketchforge_isophote_tool/qt/*"],
    # drawn.py: the seeded creatures of issue 34, drawn for the tests and benchmarks to assemble
    "assemble": ["sketchforge_assemble/testing.py", "sketchforge_assemble/drawn.py"],
    "animate": ["sketchforge_animate/qt/*"],
    # test support shipped with the package (fixtures, a test host): inputs, not product
    "plugins": ["sketchforge/plugins/testing.py", "sketchforge/plugins/pytest_plugin.py"],
}

# Left out of every mutation run: a surviving mutant runs every test that reaches its function,
# so these (seconds each: subprocesses, whole creatures assembled) would make a run take hours.
# What they check is also checked in-process by faster tests; a mutant only they would kill
# counts as a survivor (the score errs low).
SLOW_TESTS = [
    "tests/test_crash_recovery.py::test_a_native_crash_in_a_solve_is_recovered_without_the_crashing_step",
    "tests/test_regressions_planted.py::test_a_part_attaches_to_the_nearest_layer_behind_it",
    "tests/attack/test_terminal.py",
    "tests/attack/test_special_files.py",
    "tests/test_plugin_platform.py::test_pytest_fixtures_are_installed_and_strict",
]

# Files the tests read through paths relative to the repository root.
READ_BY_TESTS = ["examples", "README.md", "Makefile", "docs"]


# Appended to the workspace's copy of tests/conftest.py (see workspace()).
SCOPE_FILTER = """

# --- appended by mutation/run.py: only this scope's test files, no SLOW_TESTS ----------------
import json as _mjson
from pathlib import Path as _MPath

_MSCOPE = _mjson.loads((_MPath(__file__).resolve().parent / "mutation_tests.json").read_text())

# A property test that fails shrinks its example: hundreds of document replays, which ran past
# the mutant's timeout (a mutant that broke every journal write was reported as a "timeout"
# after minutes). In a mutation run the failure is the verdict; the smallest example is not
# needed. Loaded here, before any test module makes its @settings from the default profile;
# no database, so no mutant replays another's failing example.
from hypothesis import Phase as _MPhase
from hypothesis import settings as _msettings

_msettings.register_profile("mutation", phases=[_MPhase.explicit, _MPhase.generate], database=None)
_msettings.load_profile("mutation")
_MROOT = _MPath(__file__).resolve().parents[1]


def pytest_ignore_collect(collection_path, config):
    path = _MPath(collection_path).resolve()
    if path.is_dir() or path.suffix != ".py" or not path.name.startswith("test_"):
        return None
    for entry in _MSCOPE["tests"]:
        target = (_MROOT / entry).resolve()
        if path == target or target in path.parents:
            return None
    return True


# mutmut's own test times leave out the setup, which is where a module fixture (a whole corpus
# of edits) spends its time; the stats run records the whole time of each test here instead.
_MDURATIONS = "mutation_durations.json"
_MTIMES: dict = {}


def pytest_runtest_logreport(report):
    import os
    if os.environ.get("MUTANT_UNDER_TEST") == "stats":
        _MTIMES[report.nodeid] = _MTIMES.get(report.nodeid, 0.0) + report.duration


def pytest_sessionfinish(session):
    if not _MTIMES:
        return
    path = _MPath(_MDURATIONS)
    try:
        old = _mjson.loads(path.read_text())
    except (OSError, ValueError):
        old = {}
    old.update(_MTIMES)
    path.write_text(_mjson.dumps(old))


def pytest_collection_finish(session):
    # mutmut maps each function to the tests that reach it by tracing the tests one at a time
    # (its "stats" run). A module- or session-scoped fixture is built inside the first test that
    # uses it, so whatever the fixture calls was mapped to that one test, and a mutant there never
    # ran the other tests that check the fixture's result: a false survivor. So in the stats run,
    # and only there, every fixture of ours is function-scoped and traced with each test.
    import os
    if os.environ.get("MUTANT_UNDER_TEST") != "stats":
        return
    from _pytest.scope import Scope
    for item in session.items:
        info = getattr(item, "_fixtureinfo", None)
        for defs in (info.name2fixturedefs.values() if info is not None else ()):
            for fd in defs:
                code = getattr(getattr(fd, "func", None), "__code__", None)
                if code is not None and "site-packages" not in code.co_filename and fd._scope is not Scope.Function:
                    fd._scope = Scope.Function


def pytest_runtest_setup(item):
    # The same trap as module fixtures, in plain Python: a test helper memoised with
    # functools.lru_cache (a creature assembled once for a whole file) runs the product code
    # inside the first test that calls it, and the stats run mapped that code to that test
    # alone. In the stats run, and only there, every memo of the workspace's modules (tests
    # and the package) is emptied before each test, so each test is traced with what it reads.
    import os
    import sys
    if os.environ.get("MUTANT_UNDER_TEST") != "stats":
        return
    root = str(_MROOT)
    for mod in list(sys.modules.values()):
        path = getattr(mod, "__file__", None) or ""
        if not path.startswith(root) or "site-packages" in path:
            continue
        for value in list(vars(mod).values()):
            if callable(getattr(value, "cache_clear", None)) and hasattr(value, "__wrapped__"):
                value.cache_clear()


def pytest_collection_modifyitems(config, items):
    slow = tuple(_MSCOPE["slow"])
    keep = [item for item in items if not item.nodeid.startswith(slow)]
    if len(keep) != len(items):
        config.hook.pytest_deselected(items=[item for item in items if item.nodeid.startswith(slow)])
        items[:] = keep
    # mutmut runs a mutant's tests with -x in whatever order it lists them (a set). Test files
    # whose selected tests take least time in all go first, so a mutant that a quick file kills
    # does not wait for the slow ones. Files stay whole and in their own order: no test sees
    # another order of its neighbours, and module fixtures are built once.
    import os
    if "__mutmut_" not in os.environ.get("MUTANT_UNDER_TEST", ""):
        return
    try:  # whole test times (setup included) recorded in the stats run, see below
        duration = _mjson.loads(_MPath(_MDURATIONS).read_text())
    except (OSError, ValueError):
        return
    cost, first = {}, {}
    for i, item in enumerate(items):
        f = item.nodeid.split("::")[0]
        cost[f] = cost.get(f, 0.0) + duration.get(item.nodeid, 1.0)
        first.setdefault(f, i)
    items.sort(key=lambda item: (cost[item.nodeid.split("::")[0]], first[item.nodeid.split("::")[0]]))
"""


def workspace(scope: str) -> Path:
    """Build (or refresh) the workspace of one scope; returns its folder."""
    src, package, only, tests = SCOPES[scope]
    ws = BUILD / scope
    ws.mkdir(parents=True, exist_ok=True)
    # Refresh the package and the tests; mutmut's own state (mutants/) is kept unless --fresh.
    for name in (package.split(".")[0], "tests", *READ_BY_TESTS):
        target = ws / name
        if target.is_dir():
            shutil.rmtree(target)
        elif target.exists():
            target.unlink()
    shutil.copytree(ROOT / src, ws / package, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(ROOT / "tests", ws / "tests", ignore=shutil.ignore_patterns("__pycache__"))
    for name in READ_BY_TESTS:
        path = ROOT / name
        target = ws / name
        if path.is_dir():
            shutil.copytree(path, target, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
        else:
            shutil.copy2(path, target)
    pytest_args = ["-p", "no:randomly", "-p", "no:cacheprovider", "-p", "no:xvfb", "-m", "not gl", "-q"]
    # mutmut keys every verdict to its test selection: changing it (a new test file in the
    # scope's list) would throw away every result of a run that takes hours. So the selection
    # mutmut sees never changes ("tests", less the Qt tests), and the workspace's conftest
    # collects only the scope's test files and leaves out SLOW_TESTS (read from
    # tests/mutation_tests.json, written here). After adding tests, `--retest` re-tests the survivors with them.
    selection = ["tests", "--ignore=tests/qt"]
    # (inside tests/: mutmut copies that folder into its own working copy)
    (ws / "tests" / "mutation_tests.json").write_text(json.dumps({"tests": tests, "slow": SLOW_TESTS}, indent=1))
    with open(ws / "tests" / "conftest.py", "a") as f:
        f.write(SCOPE_FILTER)
    # Forking the process that ran the tests (mutmut's default) copies JAX's and BLAS's thread
    # pools mid-lock: a worker then waits on a futex forever and the mutant is reported as a
    # "timeout" that no test caused. A fork server that only collected the tests has no such
    # threads (process_isolation below).
    # A mutant that hangs (a wait in the autosaver that never ends) costs its timeout: 4x the
    # measured time of the tests that reach it, plus 5 s. At 10x the document scope spent minutes
    # on each such mutant; 4x is still twice the spread of test times seen on the loaded machine.
    (ws / "pyproject.toml").write_text(f"""# written by mutation/run.py for scope {scope!r}; do not edit
[tool.mutmut]
source_paths = [{json.dumps(package)}]
only_mutate = {json.dumps(only)}
do_not_mutate = {json.dumps(DO_NOT_MUTATE.get(scope, []))}
also_copy = {json.dumps(READ_BY_TESTS)}
pytest_add_cli_args = {json.dumps(pytest_args)}
pytest_add_cli_args_test_selection = {json.dumps(selection)}
timeout_multiplier = 4.0
timeout_constant = 5.0
use_git_change_detection = false
process_isolation = "forkserver"

[tool.pytest.ini_options]
markers = ["gl: needs OpenGL"]
""")
    return ws


def equivalents(scope: str) -> dict[str, str]:
    """Mutants judged equivalent (no test can tell them apart from the code), with the reason:
    ``mutation/equivalent/<scope>.txt``, one ``name  reason`` per line. Mutant names are
    numbered per function, so a change of the function can shift them: the report names any
    listed mutant that no longer survives, so the list is re-checked after each run."""
    path = ROOT / "mutation" / "equivalent" / f"{scope}.txt"
    out = {}
    if path.exists():
        for line in path.read_text().splitlines():
            if line.strip() and not line.startswith("#"):
                name, _, reason = line.strip().partition(" ")
                out[name] = reason.strip()
    return out


def forget_survivors(ws: Path, patterns: list[str], keep: set[str] = frozenset()) -> list[str]:
    """Clear the verdict of every surviving (or untested) mutant matching ``patterns`` (all if
    empty), except the listed equivalents ``keep``, so the next run tests it again; mutmut keeps
    verdicts until the code changes, and picks up new tests by itself. Returns the names
    cleared (sorted)."""
    import fnmatch

    out = subprocess.run([sys.executable, "-m", "mutmut", "results"], cwd=ws, capture_output=True,
                         text=True, check=False).stdout
    names = set()
    for line in out.splitlines():
        name, _, status = line.strip().rpartition(": ")
        if name in keep:
            continue  # an equivalent survives every test: re-running it costs all its tests
        if status in ("survived", "no tests") and (not patterns or any(fnmatch.fnmatch(name, p) for p in patterns)):
            names.add(name)
    cleared: list[str] = []
    for meta in (ws / "mutants").rglob("*.py.meta"):
        data = json.loads(meta.read_text())
        hit = [k for k in data.get("exit_code_by_key", {}) if k in names]
        for k in hit:
            data["exit_code_by_key"][k] = None
        if hit:
            meta.write_text(json.dumps(data, indent=4))
            cleared += hit
    print(f"{len(cleared)} survivors will be tested again")
    return sorted(cleared)


def statuses(ws: Path) -> dict[str, str]:
    """Every mutant of a workspace and its status ("killed", "survived", "not checked", ...)."""
    out = subprocess.run([sys.executable, "-m", "mutmut", "results", "--all", "true"], cwd=ws,
                         capture_output=True, text=True, check=False).stdout
    found = {}
    for line in out.splitlines():
        name, _, status = line.strip().rpartition(": ")
        if name:
            found[name] = status
    return found


def module_of(name: str) -> str:
    """``pkg.mod.xǁClassǁmeth__mutmut_3`` or ``pkg.mod.x_func__mutmut_3`` -> ``pkg.mod``."""
    return name.rsplit(".", 1)[0]


def draw_sample(scope: str, size: int, seed: int, exclude: set[str] = frozenset()) -> list[str]:
    """A seeded uniform sample of ``size`` of the scope's unchecked mutants, drawn per module in
    proportion to its unchecked count (at least one from each). The pool it was drawn from is
    written to ``mutation/results/<scope>.sample.json``: the report estimates the mutants left
    unchecked in each module from the sample's kill rate there."""
    import random

    ws = BUILD / scope
    pool: dict[str, list[str]] = {}
    for name, status in sorted(statuses(ws).items()):
        if status == "not checked" and name not in exclude:  # not --retest's, not known equivalents
            pool.setdefault(module_of(name), []).append(name)
    total = sum(len(v) for v in pool.values())
    rng = random.Random(seed)
    chosen: list[str] = []
    for module in sorted(pool):
        names = pool[module]
        k = min(len(names), max(1, round(size * len(names) / total))) if total else 0
        chosen += rng.sample(names, k)
    (RESULTS / f"{scope}.sample.json").write_text(json.dumps(
        {"seed": seed, "size": size, "pool": pool, "sample": sorted(chosen)}, indent=0))
    return sorted(chosen)


def estimate(found: dict[str, str], equivalent: dict[str, str], sample_file: Path) -> list[str]:
    """Lines of the report that estimate the whole scope's score: mutants checked one by one
    count as they are; in each module, the ones still unchecked from the sampled pool count at
    the kill rate of that module's checked sample (listed equivalents left out of the rate).
    The interval is the normal approximation of each module's binomial, with the finite-pool
    correction, summed over modules (95%)."""
    if not sample_file.exists():
        return []
    data = json.loads(sample_file.read_text())
    sample = set(data["sample"])
    killed_exact = total_exact = 0.0
    est_killed = variance = 0.0
    unchecked = 0
    sampled_checked = 0
    in_pool = {n for names in data["pool"].values() for n in names}
    for name, status in found.items():
        if name in equivalent or status in ("skipped", "not checked"):
            continue
        if name in in_pool and name not in sample:
            continue  # checked later by a full run: counted below with its module's pool
        total_exact += 1
        killed_exact += status in ("killed", "timeout", "segfault")
    for module, names in sorted(data["pool"].items()):
        drawn = [n for n in names if n in sample and found.get(n, "not checked") != "not checked"
                 and n not in equivalent]
        eq = sum(1 for n in names if n in sample and n in equivalent)
        rest = [n for n in names if n not in sample and n in found]
        left = [n for n in rest if found[n] == "not checked" and n not in equivalent]
        for n in rest:  # pool members a full run checked after the sample was drawn
            if found[n] not in ("not checked", "skipped") and n not in equivalent:
                total_exact += 1
                killed_exact += found[n] in ("killed", "timeout", "segfault")
        sampled_checked += len(drawn)
        if not left:
            continue
        if not drawn:
            return [f"estimate: module {module} has {len(left)} unchecked mutants and no checked sample"]
        p = sum(found[n] in ("killed", "timeout", "segfault") for n in drawn) / len(drawn)
        share = len(drawn) / (len(drawn) + eq)  # the sample's share of non-equivalent mutants
        n_left = len(left) * share
        unchecked += len(left)
        est_killed += n_left * p
        total_exact += n_left
        pool_size = len(left) + len(drawn)  # what the sample stands for, itself included
        fpc = (pool_size - len(drawn)) / max(1, pool_size - 1)
        variance += n_left ** 2 * p * (1 - p) / len(drawn) * fpc
    score = (killed_exact + est_killed) / total_exact if total_exact else 0.0
    half = 1.96 * variance ** 0.5 / total_exact if total_exact else 0.0
    return [f"estimated score of the whole scope: {100 * score:.1f}% ± {100 * half:.1f}% (95%): "
            f"{unchecked} mutants left unchecked are estimated from a seeded sample of "
            f"{sampled_checked} (seed {data['seed']})"]


def report(scope: str) -> str:
    """Score of the last run of ``scope`` and the surviving mutants, as text."""
    ws = BUILD / scope
    found = statuses(ws)
    equivalent = equivalents(scope)
    counts: dict[str, int] = {}
    survivors, stale = [], []
    for name, status in found.items():
        if name in equivalent:
            if status != "survived":
                stale.append(f"{name} is listed as equivalent but is {status}")
            status = "equivalent"
        counts[status] = counts.get(status, 0) + 1
        if status in ("survived", "no tests"):
            survivors.append(f"{status:9s} {name}")
    killed = counts.get("killed", 0) + counts.get("timeout", 0) + counts.get("segfault", 0)
    total = sum(counts.values()) - sum(counts.get(k, 0) for k in ("skipped", "not checked", "equivalent"))
    score = killed / total if total else 0.0
    lines = [f"scope {scope}: {killed}/{total} mutants killed ({100 * score:.1f}%), "
             f"{counts.get('equivalent', 0)} equivalent left out",
             "counts: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())),
             *estimate(found, equivalent, RESULTS / f"{scope}.sample.json"), ""]
    return "\n".join(lines + stale + survivors) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scope", choices=sorted(SCOPES) + ["all"])
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--fresh", action="store_true", help="forget the previous run's results")
    ap.add_argument("--report", action="store_true", help="only print the last run's score")
    ap.add_argument("--retest", action="store_true",
                    help="test the last run's survivors again (after adding tests)")
    ap.add_argument("--only", nargs="*", default=[], metavar="PATTERN",
                    help="mutant name patterns (fnmatch), e.g. 'sketchforge.document.undo.*'")
    ap.add_argument("--sample", type=int, default=0, metavar="N",
                    help="check only a seeded random sample of N of the unchecked mutants; the "
                         "report then estimates the whole scope's score from it")
    ap.add_argument("--seed", type=int, default=20261201)
    args = ap.parse_args(argv)
    scopes = sorted(SCOPES) if args.scope == "all" else [args.scope]
    RESULTS.mkdir(parents=True, exist_ok=True)
    for scope in scopes:
        if not args.report:
            ws = workspace(scope)
            if args.fresh and (ws / "mutants").exists():
                shutil.rmtree(ws / "mutants")
            retest = forget_survivors(ws, args.only, set(equivalents(scope))) if args.retest else []
            # Fewer, fixed property-test examples (tests/tests_support.examples): a survivor runs
            # every test that reaches its function, the stateful machines included.
            env = dict(os.environ, CI="true", QT_QPA_PLATFORM="offscreen", SKETCHFORGE_MUTATION="1",
                       FUZZ_EXAMPLES="10", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
                       MKL_NUM_THREADS="1")
            names = list(args.only)
            if args.retest and not args.only:
                # only the survivors: a run without names would test every unchecked mutant too
                names = retest or ["no.such.mutant"]
            if args.sample:
                if not (ws / "mutants").exists():
                    # mutmut makes the mutants (and traces the tests) on its first run: one that
                    # matches no mutant does only that
                    subprocess.run([sys.executable, "-m", "mutmut", "run", "--max-children", str(args.jobs),
                                    "no.such.mutant"], cwd=ws, env=env, check=False)
                sample = draw_sample(scope, args.sample, args.seed, set(retest) | set(equivalents(scope)))
                print(f"checking a sample of {len(sample)} unchecked mutants (seed {args.seed})")
                names = [n for n in names if n != "no.such.mutant"] + sample
                if not names:
                    names = ["no.such.mutant"]
            rc = subprocess.run([sys.executable, "-m", "mutmut", "run", "--max-children", str(args.jobs),
                                 *names], cwd=ws, env=env).returncode
            if rc != 0:
                print(f"mutmut failed on scope {scope} (exit {rc})", file=sys.stderr)
                return rc
        text = report(scope)
        (RESULTS / f"{scope}.txt").write_text(text)
        print(text.splitlines()[0])
    return 0


if __name__ == "__main__":
    sys.exit(main())
