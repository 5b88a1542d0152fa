"""The plugin platform's own rules, each pinned by the input that breaks it (issue 39, point 1).

Issue 39 planted one-line bugs in the solver registries, the plugin manager and the contracts,
and the suite caught fewer than half: ``number()`` let NaN pass a bounded check, counted True as
a number and ignored ``lo_open``; ``json_value`` accepted NaN; ``disable()`` left a disabled
plugin's solvers listed; two plugins validating one plugin_data key went unnoticed. Each test
here states one rule a plugin author or a user relies on, on both sides of its boundary, with
the one-line message that names what to fix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from sketchforge.document.commands import Command
from sketchforge.errors import (
    ContourError,
    DocumentFormatError,
    ExportError,
    ParameterError,
    PluginError,
    SketchforgeError,
    UnknownSolverError,
)
from sketchforge.geometry.mesh import Mesh
from sketchforge.plugins import contracts, hookspecs
from sketchforge.plugins.hookspecs import hookimpl
from sketchforge.plugins.manager import CORE, PluginHost, make_plugin_manager
from sketchforge.plugins.plugin_data import plugin_data_validators, validate_plugin_data
from sketchforge.plugins.registry import PANEL_PLACES, Exporter, Panel, ReflectanceModel, Shader
from sketchforge.plugins.solvers import (
    SOLVER_KINDS,
    SOLVER_TYPES,
    Assembler,
    Inflater,
    SculptSolver,
    SolverChoice,
    choice,
    flag,
    json_value,
    no_params,
    number,
    validate_params,
)
from sketchforge.plugins.testing import FanInflater, make_test_host
from sketchforge.tools.base import Tool

NAN = float("nan")
INF = float("inf")


def refused(check, value) -> str:
    with pytest.raises(ParameterError) as info:
        check(value)
    return str(info.value)


# --- number(): what a solver's parameter check lets through ------------------------------------


@pytest.mark.parametrize("bad", [NAN, np.float64(NAN), np.float32(NAN), INF, -INF, np.float64(INF)])
def test_number_refuses_nan_and_infinity_even_inside_any_bounds(bad):
    for check in (number("k"), number("k", 0.0), number("k", None, 1.0), number("k", -1.0, 1.0),
                  number("k", -1.0, 1.0, lo_open=True, hi_open=True), number("k", 0.0, 10.0, optional=True)):
        msg = refused(check, bad)
        assert msg.startswith("'k' must be") and "finite" in msg, msg


@pytest.mark.parametrize("bad", [True, False, np.bool_(True), np.bool_(False)])
def test_number_refuses_a_bool_though_python_counts_it_as_an_int(bad):
    for check in (number("flagged"), number("flagged", 0, 1), number("flagged", 0, 5, integer=True)):
        assert refused(check, bad).startswith("'flagged' must be a number"), bad


@pytest.mark.parametrize("bad", ["1", "nan", None, [1.0], {"x": 1}, 1j, object()])
def test_number_refuses_what_is_not_a_real_number(bad):
    msg = refused(number("size", 0.0, 1.0), bad)
    assert msg.startswith("'size' must be a number, got"), msg
    assert "or null" not in msg


def test_number_with_optional_takes_none_and_says_so_when_refusing():
    check = number("cap", 0.0, 1.0, optional=True)
    assert check(None) is None
    assert refused(check, "x") == "'cap' must be a number or null, got 'x'"
    assert refused(check, 2.0) == "'cap' must be <= 1, got 2"


def test_number_lower_bound_closed_and_open():
    closed, opened = number("r", 0.5, 3.0), number("r", 0.5, 3.0, lo_open=True)
    assert closed(0.5) == 0.5 and closed(3.0) == 3.0
    assert refused(closed, 0.49).startswith("'r' must be >= 0.5")
    assert refused(opened, 0.5) == "'r' must be > 0.5, got 0.5"
    assert refused(opened, 0) == "'r' must be > 0.5, got 0"
    assert opened(math.nextafter(0.5, 1.0)) == math.nextafter(0.5, 1.0)
    assert opened(3.0) == 3.0  # the upper bound stays closed


def test_number_upper_bound_closed_and_open():
    closed, opened = number("s", 0.0, 1.0), number("s", 0.0, 1.0, hi_open=True)
    assert closed(1.0) == 1.0 and closed(0) == 0.0
    assert refused(closed, 1.0000001).startswith("'s' must be <= 1, got 1")
    assert refused(opened, 1.0) == "'s' must be < 1, got 1"
    assert opened(math.nextafter(1.0, 0.0)) < 1.0
    assert opened(0.0) == 0.0  # the lower bound stays closed
    assert refused(opened, -1e-9).startswith("'s' must be >= 0")


def test_number_open_bounds_on_both_sides_only_exclude_the_bounds():
    both = number("t", -2.0, 2.0, lo_open=True, hi_open=True)
    for bad, text in ((-2.0, "> -2"), (2.0, "< 2"), (-3.0, "> -2"), (3.0, "< 2")):
        assert text in refused(both, bad)
    assert both(-1.999) == -1.999 and both(1.999) == 1.999 and both(0) == 0.0


def test_number_returns_a_float_or_an_int_for_an_integer_parameter():
    real, whole = number("a", 0.0, 10.0), number("n", 1, 50, integer=True)
    out = real(3)
    assert out == 3.0 and type(out) is float
    assert type(real(np.float32(0.5))) is float and real(np.int64(7)) == 7.0
    for v in (4, 4.0, np.int64(4), np.float64(4.0)):
        got = whole(v)
        assert got == 4 and type(got) is int, v
    assert refused(whole, 4.5) == "'n' must be a whole number, got 4.5"
    assert refused(whole, 0).startswith("'n' must be >= 1")
    assert refused(whole, 51).startswith("'n' must be <= 50")
    assert whole(1) == 1 and whole(50) == 50
    assert "whole number" in refused(whole, NAN) or "finite" in refused(whole, NAN)
    assert "'n' must be" in refused(whole, INF)


def test_validate_params_fills_defaults_checks_values_and_names_an_unknown_key():
    defaults = {"b": 2.0, "a": 1}
    checks = {"a": number("a", 0, 10, integer=True), "b": number("b", 0.0)}
    assert validate_params(None, defaults, checks) == {"a": 1, "b": 2.0}
    assert validate_params({}, defaults) == defaults
    got = validate_params({"a": 3.0}, defaults, checks)
    assert got == {"a": 3, "b": 2.0} and type(got["a"]) is int
    assert defaults == {"b": 2.0, "a": 1}  # the defaults are never changed
    with pytest.raises(ParameterError) as info:
        validate_params({"zz": 1, "c": 2}, defaults, checks)
    assert str(info.value) == "unknown parameter 'c' (known: a, b)"
    with pytest.raises(ParameterError) as info:
        validate_params({"x": 1}, {})
    assert str(info.value) == "unknown parameter 'x' (known: none)"
    with pytest.raises(ParameterError, match="must be an object of name: value, got list"):
        validate_params([("a", 1)], defaults)
    with pytest.raises(ParameterError, match="'b' must be >= 0"):
        validate_params({"b": -1}, defaults, checks)
    # a check applies to the default too: a solver's own bad default is caught
    with pytest.raises(ParameterError, match="'b' must be"):
        validate_params({}, {"b": NAN}, checks)
    assert no_params({}) == {} and no_params(None) == {}
    with pytest.raises(ParameterError, match="unknown parameter 'p'"):
        no_params({"p": 1})


def test_choice_and_flag():
    c = choice("mode", ("fast", "exact"))
    assert c("fast") == "fast" and c("exact") == "exact"
    assert refused(c, "slow") == "'mode' must be one of 'fast', 'exact', got 'slow'"
    f = flag("on")
    assert f(True) is True and f(False) is False
    for bad in (1, 0, "true", None):
        assert refused(f, bad).startswith("'on' must be true or false")


# --- json_value(): what a journal can hold ------------------------------------------------------


@pytest.mark.parametrize("good", [None, True, 0, -3, 10**30, 1.5, -0.0, "", "text", [], {}, (1, 2),
                                  [1, "a", None, [2.5, {"k": False}]], {"a": {"b": [1, 2]}}, np.float64(2.0),
                                  np.int64(3)])
def test_json_value_accepts_what_a_journal_can_hold(good):
    assert json_value(good) is True


@pytest.mark.parametrize("bad", [NAN, INF, -INF, np.float64(NAN), [1.0, NAN], {"a": [INF]}, {"x": {"y": NAN}},
                                 (0, NAN), {1: "non-string key"}, {"a": {2: 3}}, {1, 2}, b"bytes", object(),
                                 np.zeros(3), [object()], {"a": object()}])
def test_json_value_refuses_what_json_cannot_hold_back(bad):
    assert json_value(bad) is False


def test_json_value_allows_eight_levels_of_nesting_and_no_more():
    def nested(k, make):
        v = 1
        for _ in range(k):
            v = make(v)
        return v

    for make in (lambda v: [v], lambda v: {"k": v}, lambda v: (v,)):
        assert json_value(nested(8, make)) is True
        assert json_value(nested(9, make)) is False
    # mixed, with the deep branch second
    assert json_value({"a": 1, "b": nested(7, lambda v: [v])}) is True
    assert json_value({"a": 1, "b": nested(8, lambda v: [v])}) is False
    assert json_value([1, nested(8, lambda v: {"k": v})]) is False


def test_solver_choice_stores_only_what_differs_from_the_default():
    assert SolverChoice().to_dict() == {}
    assert SolverChoice("depth_qp").to_dict() == {"solver": "depth_qp"}
    assert SolverChoice(None, {"w": 1}).to_dict() == {"params": {"w": 1}}
    assert SolverChoice("x", {"w": 1}).to_dict() == {"solver": "x", "params": {"w": 1}}


def test_the_solver_kinds_name_their_own_hook_value_type_and_function():
    assert set(SOLVER_KINDS) == set(SOLVER_TYPES) == {"inflate", "sculpt", "assemble"}
    for kind, spec in SOLVER_KINDS.items():
        assert spec.kind == kind
        assert callable(getattr(hookspecs, spec.hook)), spec.hook
        assert spec.call in SOLVER_TYPES[kind].__dataclass_fields__
        assert spec.default and spec.what
    assert SOLVER_KINDS["inflate"].hook == "sketchforge_inflaters" and SOLVER_KINDS["inflate"].call == "inflate"
    assert SOLVER_KINDS["sculpt"].hook == "sketchforge_sculpt_solvers" and SOLVER_KINDS["sculpt"].call == "solve"
    assert SOLVER_KINDS["assemble"].hook == "sketchforge_assemblers" and SOLVER_KINDS["assemble"].call == "assemble"
    assert [s.what for s in SOLVER_KINDS.values()] == ["inflater", "sculpt solver", "assembler"]
    assert [s.default for s in SOLVER_KINDS.values()] == ["poisson", "gauss_newton", "depth_qp"]


# --- contracts: each check on a good item and on each way an item can be wrong -----------------


def plugin_error(check, item, plugin="acme") -> str:
    with pytest.raises(PluginError) as info:
        check(item, plugin)
    msg = str(info.value)
    assert msg.startswith(f"plugin {plugin!r}: ") and msg.endswith("(ignored)") and "\n" not in msg, msg
    return msg


@dataclass
class GoodCommand(Command):
    name: ClassVar[str] = "good_command"

    def do(self, doc):
        pass

    def undo(self, doc):
        pass

    def to_dict(self):
        return {"command": self.name}

    @classmethod
    def from_dict(cls, d):
        return cls()


def test_check_command():
    contracts.check_command(GoodCommand, "acme")
    assert "must return Command subclasses" in plugin_error(contracts.check_command, GoodCommand())
    assert "must return Command subclasses" in plugin_error(contracts.check_command, int)
    for method in ("do", "undo", "to_dict"):
        lacking = type("Lacking", (GoodCommand,), {method: getattr(Command, method), "name": "lacking"})
        assert f"command 'lacking' does not implement {method}()" in plugin_error(contracts.check_command, lacking)
    lacking = type("Lacking", (GoodCommand,), {"from_dict": classmethod(Command.from_dict.__func__), "name": "lacking"})
    assert "does not implement from_dict()" in plugin_error(contracts.check_command, lacking)


def test_check_tool():
    class Good(Tool):
        name, label, shortcut = "good", "Good", "Shift+G"

    contracts.check_tool(Good, "acme")
    contracts.check_tool(type("NoKey", (Good,), {"shortcut": None}), "acme")
    assert "must return Tool subclasses" in plugin_error(contracts.check_tool, object)
    assert "must return Tool subclasses" in plugin_error(contracts.check_tool, Good(None))
    assert "tool 'good': label must be a string" in plugin_error(contracts.check_tool, type("L", (Good,), {"label": 3}))
    assert "shortcut must be a key sequence string" in plugin_error(contracts.check_tool, type("S", (Good,), {"shortcut": 66}))


def test_check_shader():
    def shade_with(f):
        return Shader("s", lambda N, light: f(np.asarray(N)))

    contracts.check_shader(shade_with(lambda N: np.clip(N, 0.0, 1.0)), "acme")
    contracts.check_shader(shade_with(lambda N: np.zeros((len(N), 3))), "acme")  # 0 and 1 are in range
    contracts.check_shader(shade_with(lambda N: np.ones((len(N), 3))), "acme")
    assert "must return Shader values" in plugin_error(contracts.check_shader, object())
    assert "must return Shader values" in plugin_error(contracts.check_shader, Shader("s", 3))
    msg = plugin_error(contracts.check_shader, shade_with(lambda N: 1 / 0))
    assert "shader 's' raised ZeroDivisionError" in msg
    for f in (lambda N: np.ones((len(N), 4)), lambda N: np.ones((len(N) - 1, 3)), lambda N: np.ones(len(N)),
              lambda N: np.full((len(N), 3), 1.01), lambda N: np.full((len(N), 3), -0.01),
              lambda N: np.full((len(N), 3), NAN)):
        assert "must map (n,3) normals to (n,3) colours in [0, 1]" in plugin_error(contracts.check_shader, shade_with(f))


def test_check_exporter():
    write = lambda path, mesh: None  # noqa: E731
    contracts.check_exporter(Exporter("e", (".off",), write), "acme")
    contracts.check_exporter(Exporter("e", [".off", ".x3d"], write), "acme")
    contracts.check_exporter(Exporter("e", (".glb",), write, write_document=write, handles=lambda d: True), "acme")
    assert "must return Exporter values" in plugin_error(contracts.check_exporter, object())
    for bad in (".off", (), [], None):
        assert "suffixes must be a non-empty tuple" in plugin_error(contracts.check_exporter, Exporter("e", bad, write))
    for bad in ("off", ".OFF", ".", "", 3, ". off"):
        msg = plugin_error(contracts.check_exporter, Exporter("e", (".obj", bad), write))
        assert f"suffix {bad!r} must be lower case and start with a dot" in msg
    assert "write must be callable" in plugin_error(contracts.check_exporter, Exporter("e", (".off",), None))
    for wd, handles in ((write, None), (None, lambda d: True)):
        msg = plugin_error(contracts.check_exporter, Exporter("e", (".glb",), write, write_document=wd, handles=handles))
        assert "a document exporter sets both write_document and handles" in msg


def test_check_panel():
    create = lambda app: None  # noqa: E731
    for place in PANEL_PLACES:
        contracts.check_panel(Panel("p", place, create), "acme")
    contracts.check_panel(Panel("p", "creation", create, available=lambda host: True), "acme")
    assert "must return Panel values" in plugin_error(contracts.check_panel, object())
    msg = plugin_error(contracts.check_panel, Panel("p", "sidebar", create))
    assert "place must be one of creation, sculpture, observation, got 'sidebar'" in msg
    assert "create must be callable" in plugin_error(contracts.check_panel, Panel("p", "creation", "make"))
    assert "available must be callable" in plugin_error(contracts.check_panel, Panel("p", "creation", create, available=True))


def _jax_model(R):
    return ReflectanceModel("m", R)


def test_check_reflectance_model_probes_plugins_and_trusts_the_core():
    import jax.numpy as jnp

    contracts.check_reflectance_model(_jax_model(lambda n, l: jnp.dot(n, l)), "acme")  # signed Lambert
    contracts.check_reflectance_model(_jax_model(lambda n, l: 0.5 * jnp.dot(n, l) + 0.5), "acme")  # half Lambert
    assert "must return ReflectanceModel values" in plugin_error(contracts.check_reflectance_model, object())
    assert "must return ReflectanceModel values" in plugin_error(contracts.check_reflectance_model, ReflectanceModel("m", 1))
    clamped = _jax_model(lambda n, l: jnp.maximum(jnp.dot(n, l), 0.0))
    assert "must be signed, not clamped" in plugin_error(contracts.check_reflectance_model, clamped)
    numpy_model = _jax_model(lambda n, l: float(np.dot(np.asarray(n), np.asarray(l))))
    assert "cannot be differentiated by JAX" in plugin_error(contracts.check_reflectance_model, numpy_model)
    infinite = _jax_model(lambda n, l: jnp.dot(n, l) / (jnp.dot(n, l) - jnp.dot(n, l)))
    assert "gives a non-finite value or gradient" in plugin_error(contracts.check_reflectance_model, infinite)
    # shadow only on one side of the light: a model flat where n·l < 0 only for lights along y
    # is caught because the probe lights include ones off the x axis
    flat_y = _jax_model(lambda n, l: jnp.where(l[1] > 0.5, jnp.maximum(jnp.dot(n, l), 0.0), jnp.dot(n, l)))
    assert "must be signed, not clamped" in plugin_error(contracts.check_reflectance_model, flat_y)
    # the core's own model is not probed (it is the reference)
    contracts.check_reflectance_model(clamped, CORE)


def _solver(kind, **over):
    fn = lambda *a: None  # noqa: E731
    base = {"inflate": Inflater("s", fn), "sculpt": SculptSolver("s", fn), "assemble": Assembler("s", fn)}[kind]
    from dataclasses import replace

    return replace(base, **over)


@pytest.mark.parametrize("kind", ["inflate", "sculpt", "assemble"])
def test_solver_check(kind):
    check = contracts.solver_check(kind)
    spec = SOLVER_KINDS[kind]
    check(_solver(kind), "acme")
    check(_solver(kind, check_params=lambda p: validate_params(p, {"w": 1.0})), "acme")
    other = "sculpt" if kind != "sculpt" else "inflate"
    assert f"{spec.hook} must return {SOLVER_TYPES[kind].__name__} values" in plugin_error(check, _solver(other))
    assert f"{spec.what} 's': {spec.call} must be callable" in plugin_error(check, _solver(kind, **{spec.call: None}))
    assert "check_params must be callable" in plugin_error(check, _solver(kind, check_params=None))
    for v in ("", 2, None):
        assert "version must be a non-empty string" in plugin_error(check, _solver(kind, version=v))
    msg = plugin_error(check, _solver(kind, check_params=lambda p: 1 / 0))
    assert "check_params({}) raised ZeroDivisionError" in msg and "must return the default parameters" in msg
    for bad in ([1], {"w": NAN}, {"w": object()}, None):
        msg = plugin_error(check, _solver(kind, check_params=lambda p, bad=bad: bad))
        assert "check_params({}) must return a dict of JSON values" in msg
    loose = _solver(kind, check_params=lambda p: {"w": 1.0})  # drops what it does not know
    assert f"accepted the unknown parameter {contracts.PROBE_KEY!r}" in plugin_error(check, loose)

    def raises_key_error(p):
        if p:
            raise KeyError(next(iter(p)))
        return {}

    msg = plugin_error(check, _solver(kind, check_params=raises_key_error))
    assert "check_params raised KeyError for an unknown parameter; it must raise ParameterError" in msg
    if kind == "sculpt":
        check(_solver(kind, several_isophotes=True), "acme")
        assert "several_isophotes must be True or False" in plugin_error(check, _solver(kind, several_isophotes=1))


# --- the manager: registration, names, disabling -------------------------------------------------


def _inflater(name, marker=0.0):
    def inflate(points, closed, params, holes):
        V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, marker]], dtype=np.float64)
        return Mesh(V, np.array([[0, 1, 2]]), np.arange(3))

    return Inflater(name, inflate, version="7")


class Solvers:
    """A plugin registering the named solvers it was given (one per kind)."""

    def __init__(self, *inflaters, assemblers=(), sculpt=(), tools=(), shaders=(), exporters=()):
        self._inflaters, self._assemblers, self._sculpt = list(inflaters), list(assemblers), list(sculpt)
        self._tools, self._shaders, self._exporters = list(tools), list(shaders), list(exporters)

    @hookimpl
    def sketchforge_inflaters(self):
        return self._inflaters

    @hookimpl
    def sketchforge_assemblers(self):
        return self._assemblers

    @hookimpl
    def sketchforge_sculpt_solvers(self):
        return self._sculpt

    @hookimpl
    def sketchforge_tools(self):
        return self._tools

    @hookimpl
    def sketchforge_shaders(self):
        return self._shaders

    @hookimpl
    def sketchforge_exporters(self):
        return self._exporters


class Other(Solvers):
    pass


class Third(Solvers):
    pass


def test_disable_takes_every_contribution_of_the_plugin_out_of_every_registry():
    class Tl(Tool):
        name, label = "acme_tool", "Acme"

    shader = Shader("acme_shader", lambda N, light: np.clip(np.asarray(N), 0, 1))
    exporter = Exporter("acme_exp", (".acme",), lambda path, mesh: None)
    host = make_test_host(FanInflater(), Solvers(_inflater("acme"), assemblers=[Assembler("acme_asm", lambda *a: None)],
                                                 sculpt=[SculptSolver("acme_sculpt", lambda *a: None)], tools=[Tl],
                                                 shaders=[shader], exporters=[exporter]))
    name = "plugin-1-Solvers"
    assert host.validate() == []
    assert set(host.solvers("inflate")) == {"fan", "acme"}
    assert "acme_asm" in host.solvers("assemble") and "acme_sculpt" in host.solvers("sculpt")
    assert "acme_tool" in host.tools and "acme_shader" in host.shaders and "acme_exp" in host.exporters
    assert host.provider_of(host.solver("inflate", "acme")) == name
    host.disable(name, "it broke")
    assert set(host.solvers("inflate")) == {"fan"}
    assert host.solvers("assemble") == {} and host.solvers("sculpt") == {}
    assert "acme_tool" not in host.tools and "acme_shader" not in host.shaders and "acme_exp" not in host.exporters
    with pytest.raises(UnknownSolverError, match="no inflater named 'acme' is installed"):
        host.solver("inflate", "acme")
    assert host.default_solver_name("inflate") == "fan"  # the only one left
    assert name not in host.plugin_names() and host.skipped[name] == "it broke"
    assert f"plugin {name!r} disabled: it broke" in host.problems
    with pytest.raises(PluginError, match="cannot"):
        host.disable(CORE, "cannot")  # never the core
    with pytest.raises(PluginError, match="no such"):
        host.disable("not-installed", "no such plugin")


def test_a_hook_that_raises_disables_its_own_plugin_only():
    class Broken:
        @hookimpl
        def sketchforge_inflaters(self):
            raise RuntimeError("boom")

        @hookimpl
        def sketchforge_tools(self):
            return []

    host = make_test_host(FanInflater(), Broken())
    assert set(host.solvers("inflate")) == {"fan"}
    assert "plugin-1-Broken" not in host.plugin_names()
    assert any("plugin-1-Broken" in p and "sketchforge_inflaters hook raised RuntimeError: boom" in p for p in host.problems)


def test_names_belong_to_one_plugin_whatever_the_order():
    a, b, c = Solvers(_inflater("same", 1.0)), Other(_inflater("same", 2.0)), Third(_inflater("same", 3.0))
    for plugins in ((a, b), (b, a)):
        host = make_test_host(*plugins)
        assert "same" not in host.solvers("inflate")
        with pytest.raises(PluginError) as info:
            host.solver("inflate", "same")
        msg = str(info.value)
        assert "the inflater 'same' is registered by both plugins" in msg and "uninstall one of them" in msg
        assert "plugin-0-" in msg and "plugin-1-" in msg
        assert any("both register the inflater 'same'" in p for p in host.problems)
    host = make_test_host(a, b, c)
    assert "same" not in host.solvers("inflate")
    assert any("plugin-2-Third' also registers the inflater 'same'" in p for p in host.problems)
    # A plugin never replaces the core's: the core's stays, the plugin's is refused.
    core_name = "set_light"

    class Cmd(GoodCommand):
        name: ClassVar[str] = core_name

    class Takes:
        @hookimpl
        def sketchforge_commands(self):
            return [Cmd]

    host = make_test_host(Takes())
    assert host.command_class(core_name) is not Cmd
    assert any("is sketchforge's own; a plugin cannot replace it" in p for p in host.problems)


def test_a_refused_item_leaves_the_plugins_other_items_registered():
    host = make_test_host(Solvers(_inflater("good"), Inflater("bad", "not callable"), Inflater("", lambda *a: None)))
    assert set(host.solvers("inflate")) == {"good"}
    assert any("inflater 'bad': inflate must be callable" in p for p in host.problems)
    assert any("inflater without a name was registered" in p for p in host.problems)

    class NotAList:
        @hookimpl
        def sketchforge_inflaters(self):
            return _inflater("x")

    host = make_test_host(NotAList(), Solvers(_inflater("y")))
    assert set(host.solvers("inflate")) == {"y"}
    assert any("sketchforge_inflaters must return a list of inflaters, got Inflater" in p for p in host.problems)
    # the same value twice (one module registered under two names) is not a clash
    same = _inflater("twice")
    host = make_test_host(Solvers(same, same))
    assert host.solver("inflate", "twice") is same and host.problems == []


def test_which_solver_a_document_without_a_name_gets():
    host = make_test_host(FanInflater())
    assert host.default_solver_name("inflate") == "fan"  # not the built-in, but the only one
    assert host.solver("inflate").name == "fan"
    two = make_test_host(Solvers(_inflater("p")), Other(_inflater("q")))
    assert two.default_solver_name("inflate") is None
    with pytest.raises(UnknownSolverError) as info:
        two.solver("inflate")
    assert str(info.value) == "no inflater is chosen and the built-in 'poisson' is not installed; name one of: p, q"
    none = make_test_host()
    assert none.default_solver_name("inflate") is None and not none.has_assembler()
    with pytest.raises(UnknownSolverError, match="no inflater is installed"):
        none.solver("inflate")
    with pytest.raises(SketchforgeError, match="no inflate plugin is installed"):
        none.inflate(np.zeros((3, 2)), True, {})
    with pytest.raises(UnknownSolverError) as info:
        host.solver("inflate", "nope")
    assert str(info.value) == "no inflater named 'nope' is installed (installed: fan)"
    # the built-in name wins over any other installed one
    builtin = Solvers(_inflater("poisson"), _inflater("zz"))
    assert make_test_host(builtin).default_solver_name("inflate") == "poisson"


def test_solver_params_and_run_solver_name_the_solver_and_its_plugin():
    host = make_test_host(FanInflater())
    fan = host.solver("inflate", "fan")
    assert host.solver_params("inflate", fan, {"inflation": 2}) == {"resolution": 0.03, "inflation": 2.0, "smoothing": 0.5}
    assert host.solver_params("inflate", fan, None)["inflation"] == 1.0
    with pytest.raises(ParameterError) as info:
        host.solver_params("inflate", fan, {"smoothing": 1.0})
    assert str(info.value) == "inflater 'fan': 'smoothing' must be < 1, got 1"

    # Both pass the registration probe (defaults fine, an unknown key refused) and break on "w".
    def broken(params):
        if "w" in params:
            raise TypeError("oops")
        return validate_params(params, {})

    def returns_nan(params):
        return {"w": NAN} if "w" in params else validate_params(params, {})

    weird = Solvers(Inflater("broken", lambda *a: None, check_params=broken),
                    Inflater("nan", lambda *a: None, check_params=returns_nan),
                    Inflater("crash", lambda *a: [][1]),
                    Inflater("refuses", lambda *a: (_ for _ in ()).throw(ContourError("too small"))))
    host = make_test_host(weird)
    plugin = "plugin-0-Solvers"
    with pytest.raises(PluginError) as info:
        host.solver_params("inflate", host.solver("inflate", "broken"), {"w": 1})
    assert str(info.value) == (f"the inflater 'broken' (plugin {plugin!r}) failed to check its parameters: "
                               "TypeError: oops")
    with pytest.raises(PluginError, match=r"check_params must return a dict of JSON values, got \{'w': nan\}"):
        host.solver_params("inflate", host.solver("inflate", "nan"), {"w": 1})
    with pytest.raises(PluginError) as info:
        host.run_solver("inflate", host.solver("inflate", "crash"), None, True, {}, [])
    assert str(info.value) == f"the inflater 'crash' of plugin {plugin!r} failed: IndexError: list index out of range"
    with pytest.raises(ContourError, match="too small"):  # the solver's own answer passes as it is
        host.run_solver("inflate", host.solver("inflate", "refuses"), None, True, {}, [])


def test_an_inflater_that_cannot_cut_holes_is_never_given_one():
    host = make_test_host(FanInflater())
    square = np.array([[0, 0], [2, 0], [2, 2], [0, 2.0]])
    hole = np.array([[0.5, 0.5], [1, 0.5], [1, 1.0]])
    assert host.inflate(square, True, {}).n_vertices == 5
    with pytest.raises(ContourError) as info:
        host.inflate(square, True, {}, holes=[hole])
    assert "the inflater 'fan'" in str(info.value) and "cannot cut holes" in str(info.value)
    assert host.inflate(square, True, {}, holes=None).n_vertices == 5


def test_make_plugin_manager_refuses_unknown_legacy_and_wrapper_hooks():
    class Typo:
        @hookimpl
        def sketchforge_inflater(self):  # the registry is sketchforge_inflaters
            return []

    class Legacy:
        @hookimpl
        def sketchforge_inflate(self, points):
            return None

    class Wrapper:
        @hookimpl(wrapper=True)
        def sketchforge_tools(self):
            return (yield)

    with pytest.raises(PluginError) as info:
        make_plugin_manager([Typo()], load_entry_points=False)
    assert "implements the unknown hook 'sketchforge_inflater'" in str(info.value)
    assert "sketchforge_inflaters" in str(info.value)  # the known hooks are listed
    with pytest.raises(PluginError) as info:
        make_plugin_manager([Legacy()], load_entry_points=False)
    assert "replaced by the named registry sketchforge_inflaters" in str(info.value)
    with pytest.raises(PluginError) as info:
        make_plugin_manager([Wrapper()], load_entry_points=False)
    assert "is a pluggy wrapper" in str(info.value)
    pm = make_plugin_manager([FanInflater()], load_entry_points=False)
    assert [n for n, _ in pm.list_name_plugin()][0] == CORE and pm.problems == [] and pm.skipped == {}
    # a plugin passed by hand is never skipped quietly, even where broken entry points are
    with pytest.raises(PluginError, match="unknown hook"):
        make_plugin_manager([Typo()], load_entry_points=False, skip_broken=True)


def test_the_allowlist_loads_only_the_named_entry_points(monkeypatch):
    monkeypatch.setenv("SKETCHFORGE_PLUGINS", "inflate, animate")
    names = PluginHost.create(skip_broken=True).plugin_names()
    assert set(names) == {CORE, "inflate", "animate"}
    monkeypatch.setenv("SKETCHFORGE_PLUGINS", "")
    assert PluginHost.create(skip_broken=True).plugin_names() == [CORE]
    # an explicit allowlist wins over the environment
    assert set(PluginHost.create(allowlist=["strips"], skip_broken=True).plugin_names()) == {CORE, "strips"}
    monkeypatch.delenv("SKETCHFORGE_PLUGINS")
    assert {"inflate", "isophote_tool", "assemble", "animate", "strips"} <= set(PluginHost.create(skip_broken=True).plugin_names())
    host = PluginHost.create(allowlist=["inflate"], skip_broken=True)
    assert host.provider_version("inflate") == host.pm.versions["inflate"] and host.provider_version("inflate")
    assert host.provider_version(CORE) and host.provider_version(None) is None
    assert host.provider_version("plugin-0-FanInflater") is None


def test_two_pose_plugins_are_an_error_naming_both_and_a_broken_one_names_itself():
    class Pose:
        def __init__(self, fn):
            self.fn = fn

        @hookimpl
        def sketchforge_pose(self, doc, frame):
            return self.fn(doc, frame)

    one = make_test_host(Pose(lambda doc, frame: ("posed", frame)))
    assert one.pose(None, 3.0) == ("posed", 3)
    assert one.validate() == []
    two = make_test_host(Pose(lambda d, f: 1), Pose(lambda d, f: 2))
    with pytest.raises(PluginError) as info:
        two.pose(None, 0)
    assert "both implement sketchforge_pose" in str(info.value)
    assert any("both implement sketchforge_pose" in p for p in two.validate())
    bug = make_test_host(Pose(lambda d, f: {}["x"]))
    with pytest.raises(PluginError, match=r"the sketchforge_pose hook of plugin 'plugin-0-Pose' failed: KeyError"):
        bug.pose(None, 0)
    refusal = make_test_host(Pose(lambda d, f: (_ for _ in ()).throw(ParameterError("no pins"))))
    with pytest.raises(ParameterError, match="no pins"):
        refusal.pose(None, 0)
    assert make_test_host().pose(None, 0) is None


def test_exporters_one_suffix_one_mesh_exporter_and_document_exporters_chosen_for_their_documents(tmp_path):
    # (suffixes no exporter of the core (obj, ply, stl, glTF) or of the off plugin claims)
    mesh_exp = Exporter("pts", (".pts",), lambda path, mesh: None)
    clash = Exporter("pts2", (".pts", ".xyz"), lambda path, mesh: None)
    calls = []

    def handles(doc):
        calls.append(doc)
        return doc == "animated"

    doc_exp = Exporter("anim", (".glb",), lambda path, mesh: None, write_document=lambda p, d: "ok", handles=handles)
    host = make_test_host(Solvers(exporters=[mesh_exp, doc_exp]), Other(exporters=[clash]))
    assert {"pts", "pts2", "anim"} <= set(host.exporters)
    # two plugins claiming one suffix: an error naming both, never "the first one loaded wins"
    with pytest.raises(PluginError, match=r"plugins 'plugin-0-Solvers' and 'plugin-1-Other' both write '\.pts' "
                                          r"\(exporters 'pts' and 'pts2'\)"):
        host.exporter_for(tmp_path / "a.PTS")
    assert any("both write '.pts'" in p for p in host.problems)
    assert host.exporter_for(tmp_path / "a.xyz") is clash  # its other suffix is its own
    single = make_test_host(Solvers(exporters=[mesh_exp, doc_exp]))
    assert single.exporter_for(tmp_path / "a.PTS") is mesh_exp
    # a plugin never takes a suffix of the core's
    taker = make_test_host(Solvers(exporters=[Exporter("myobj", (".obj",), lambda path, mesh: None)]))
    assert "myobj" not in taker.exporters and taker.exporter_for(tmp_path / "a.obj").name == "obj"
    assert any("exporter 'myobj' claims '.obj', already written by exporter 'obj' of plugin 'sketchforge-core'" in p
               for p in taker.problems)
    host = single
    assert host.exporter_for(tmp_path / "a.glb", doc="animated") is doc_exp
    assert host.exporter_for(tmp_path / "a.glb", doc="still").name == "gltf"  # the core's mesh exporter
    assert host.exporter_for(tmp_path / "a.glb").name == "gltf" and calls == ["animated", "still"]
    with pytest.raises(ExportError) as info:
        host.exporter_for(tmp_path / "a.doc")
    assert str(info.value).startswith("cannot export to '.doc': known formats are ")
    assert ".glb" in str(info.value) and ".pts" in str(info.value)
    with pytest.raises(ExportError, match="a file without suffix"):
        host.exporter_for(tmp_path / "noext")
    bad = Exporter("bad", (".bad",), lambda p, m: None, write_document=lambda p, d: "", handles=lambda d: 1 / 0)
    host = make_test_host(Solvers(exporters=[bad]))
    with pytest.raises(ExportError, match=r"exporter 'bad' \(plugin 'plugin-0-Solvers'\) failed to inspect the document"):
        host.exporter_for(tmp_path / "x.bad", doc="d")


def test_provider_of_names_the_plugin_of_each_registered_value():
    inf = _inflater("mine")
    host = make_test_host(Solvers(inf))
    assert host.provider_of(inf) == "plugin-0-Solvers"
    assert host.provider_of(_inflater("mine")) is None  # same name, not the registered value
    assert host.provider_of(host.command_class("set_light")) == CORE
    assert host.provider_of(host.exporters["obj"]) == CORE
    assert host.provider_of(object()) is None


# --- plugin data: one validator per key ----------------------------------------------------------


class Validates:
    def __init__(self, **validators):
        self.validators = validators

    @hookimpl
    def sketchforge_plugin_data_validators(self):
        return self.validators


class AlsoValidates(Validates):
    pass


def _positive(v):
    if not isinstance(v, int) or v <= 0:
        raise ParameterError(f"must be a positive whole number, got {v!r}")


def test_plugin_data_is_validated_by_its_plugin_with_a_line_naming_the_key():
    host = make_test_host(Validates(count=_positive))
    validate_plugin_data(host, {"count": 3, "other": "anything"}, "snapshot")
    with pytest.raises(DocumentFormatError) as info:
        validate_plugin_data(host, {"count": -1}, "snapshot")
    assert str(info.value) == "snapshot.plugin_data['count']: must be a positive whole number, got -1"
    buggy = make_test_host(Validates(count=lambda v: v.missing))
    with pytest.raises(PluginError) as info:
        validate_plugin_data(buggy, {"count": 1}, "snapshot")
    assert "the plugin data validator for 'count' (plugin 'plugin-0-Validates') failed: AttributeError" in str(info.value)


def test_two_plugins_validating_one_key_are_an_error_naming_both():
    host = make_test_host(Validates(count=_positive, own=_positive), AlsoValidates(count=lambda v: None))
    validators = plugin_data_validators(host)
    assert validators["own"] == (_positive, "plugin-0-Validates")
    assert validators["count"][0] is None
    with pytest.raises(PluginError) as info:
        validate_plugin_data(host, {"count": 5}, "snapshot")
    msg = str(info.value)
    assert "'count' is validated by both plugins" in msg and "plugin-0-Validates" in msg and "plugin-1-AlsoValidates" in msg
    assert "uninstall one of them" in msg
    # the second plugin's validator accepts anything: neither one silently wins
    with pytest.raises(PluginError):
        validate_plugin_data(host, {"count": -5}, "snapshot")
    validate_plugin_data(host, {"own": 1}, "snapshot")  # the other keys still work
    with pytest.raises(DocumentFormatError):
        validate_plugin_data(host, {"own": 0}, "snapshot")


def test_a_broken_validator_hook_is_named():
    class Raises:
        @hookimpl
        def sketchforge_plugin_data_validators(self):
            raise ValueError("no")

    class Wrong:
        @hookimpl
        def sketchforge_plugin_data_validators(self):
            return {"k": "not callable"}

    class Nothing:
        @hookimpl
        def sketchforge_plugin_data_validators(self):
            return None

    with pytest.raises(PluginError, match="hook of plugin 'plugin-0-Raises' failed: ValueError: no"):
        plugin_data_validators(make_test_host(Raises()))
    with pytest.raises(PluginError, match="plugin 'plugin-0-Wrong': sketchforge_plugin_data_validators must return a dict"):
        plugin_data_validators(make_test_host(Wrong()))
    assert plugin_data_validators(make_test_host(Nothing())) == {}
    assert plugin_data_validators(make_test_host()) == {}


def test_the_animation_plugin_validates_its_key_on_open(real_host):
    validators = plugin_data_validators(real_host)
    assert validators["animate"][1] == "animate"
    validate_plugin_data(real_host, {"animate": {"loop": 0, "pins": []}}, "snapshot")
    with pytest.raises(DocumentFormatError, match=r"^snapshot.plugin_data\['animate'\]: the animation data is malformed"):
        validate_plugin_data(real_host, {"animate": {"loop": -1, "pins": []}}, "snapshot")


def test_disabling_one_of_two_plugins_that_clash_on_a_name_gives_the_name_to_the_other():
    a, b = Solvers(_inflater("same", 1.0)), Other(_inflater("same", 2.0))
    host = make_test_host(a, b)
    with pytest.raises(PluginError):
        host.solver("inflate", "same")
    host.disable("plugin-0-Solvers", "uninstalled")
    assert host.solver("inflate", "same") is b._inflaters[0]
    assert host.provider_of(b._inflaters[0]) == "plugin-1-Other"


def test_lookup_messages_say_what_is_installed():
    none = make_test_host()
    with pytest.raises(UnknownSolverError) as info:
        none.solver("inflate")
    assert str(info.value) == ("no inflater is installed (the built-in 'poisson' comes with its plugin; is it left out "
                               "by SKETCHFORGE_PLUGINS?)")
    with pytest.raises(UnknownSolverError) as info:
        none.solver("assemble", "glue")
    assert str(info.value) == "no assembler named 'glue' is installed (installed: none)"

    class Pose:
        @hookimpl
        def sketchforge_pose(self, doc, frame):
            return None

    class Pose2(Pose):
        pass

    host = make_test_host(Pose(), Pose2())
    assert host.validate() == ["plugins 'plugin-0-Pose' and 'plugin-1-Pose2' both implement sketchforge_pose: error, "
                               "posing is refused until one of them is uninstalled"]


def test_the_host_exports_the_mesh_it_is_given_and_a_document_through_its_exporter(tmp_path):
    written = []

    def write(path, mesh):
        written.append(mesh.n_vertices)
        path.write_text(f"{mesh.n_vertices} vertices\n")

    def write_document(path, doc, progress=None):
        if progress is not None:
            progress(1, 1)
        path.write_text("the whole document")
        return "a document"

    exporters = [Exporter("txt", (".txt",), write), Exporter("docx", (".doc",), write, write_document=write_document,
                                                             handles=lambda d: True)]
    host = make_test_host(Solvers(exporters=exporters))
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]], dtype=np.float64)
    m = Mesh(V, np.array([[0, 1, 2], [1, 3, 2]]))
    assert host.export(tmp_path / "m.txt", mesh=m) == "4 vertices, 2 triangles"
    assert (tmp_path / "m.txt").read_text() == "4 vertices\n" and written == [4]
    steps = []
    assert host.export(tmp_path / "d.doc", doc="the doc", progress=lambda i, n: steps.append((i, n))) == "a document"
    assert (tmp_path / "d.doc").read_text() == "the whole document" and steps == [(1, 1)]
    with pytest.raises(ExportError) as info:
        host.export(tmp_path / "n.txt")
    assert str(info.value) == "nothing to export: give a mesh or a document"

    def broken(path, mesh):
        raise ValueError(f"cannot write {path}")

    bad = make_test_host(Solvers(exporters=[Exporter("bad", (".bad",), broken)]))
    with pytest.raises(ExportError) as info:
        bad.export(tmp_path / "x.bad", mesh=m)
    msg = str(info.value)
    assert msg.startswith(f"cannot write {tmp_path / 'x.bad'}: exporter 'bad' (plugin 'plugin-0-Solvers') failed: ValueError")
    assert str(tmp_path / "x.bad") in msg.split("ValueError: ")[1]  # the temp path is never shown
    assert not (tmp_path / "x.bad").exists()


def test_a_hook_with_nothing_to_give_returns_none_and_that_is_no_problem():
    class Quiet:
        @hookimpl
        def sketchforge_tools(self):
            return None

        @hookimpl
        def sketchforge_inflaters(self):
            return None

    host = make_test_host(FanInflater(), Quiet())
    assert host.validate() == [] and set(host.solvers("inflate")) == {"fan"}
    # a stand-in host without the plugin-data hook has no validators
    from types import SimpleNamespace

    assert plugin_data_validators(SimpleNamespace(pm=SimpleNamespace(hook=SimpleNamespace()))) == {}


def test_validate_builds_the_solver_registries_so_a_broken_solver_is_reported_at_start():
    bad = Inflater("loose", lambda *a: None, check_params=lambda p: {"w": 1.0})  # drops unknown keys
    host = make_test_host(Solvers(bad))
    problems = host.validate()
    assert any("inflater 'loose' accepted the unknown parameter" in p for p in problems), problems
    bad_asm = Assembler("loose_asm", lambda *a: None, check_params=lambda p: {})
    host = make_test_host(Solvers(assemblers=[bad_asm]))
    assert any("assembler 'loose_asm' accepted the unknown parameter" in p for p in host.validate())


def test_the_model_probe_reaches_the_shadow_of_each_probe_light():
    import jax.numpy as jnp

    # flat in shadow only for a light along x: the probe of that light must be in its shadow
    flat_x = _jax_model(lambda n, l: jnp.where(l[0] > 0.9, jnp.maximum(jnp.dot(n, l), 0.0), jnp.dot(n, l)))
    assert "must be signed, not clamped" in plugin_error(contracts.check_reflectance_model, flat_x)
    flat_diag = _jax_model(lambda n, l: jnp.where((l[0] > 0.5) & (l[1] > 0.5), jnp.maximum(jnp.dot(n, l), 0.0),
                                                  jnp.dot(n, l)))
    assert "must be signed, not clamped" in plugin_error(contracts.check_reflectance_model, flat_diag)


def test_the_model_probe_reaches_the_deepest_shadow_it_names_for_every_probe_light():
    """The refusal names n·l = -0.95 (slope 3 straight away from the light): the probe must
    look there for each light, not at a slope merely somewhere in its shadow. A model clamped
    only below n·l = -0.93, and only for one light, is refused whichever light that is; a probe
    a component off (slope (k lx, 0) or (k lx, k lx)) reaches n·l = -0.73 and -0.93 at most
    for the lights off the x axis and passes it."""
    import jax.numpy as jnp

    for light in contracts._PROBE_LIGHTS:
        L = jnp.array(light)

        def R(n, l, L=L):
            this = jnp.all(jnp.abs(l - L) < 1e-9)
            return jnp.where(this, jnp.maximum(jnp.dot(n, l), -0.93), jnp.dot(n, l))

        msg = plugin_error(contracts.check_reflectance_model, _jax_model(R))
        assert "must be signed, not clamped" in msg and "at n·l = -0.95" in msg, (light, msg)
        # only the deepest probe is clamped: the same model with its floor at -0.96 passes
        contracts.check_reflectance_model(
            _jax_model(lambda n, l, L=L: jnp.where(jnp.all(jnp.abs(l - L) < 1e-9), jnp.maximum(jnp.dot(n, l), -0.96),
                                                   jnp.dot(n, l))), "acme")


class _EntryPoint:
    """A stand-in for an installed entry point of the group ``sketchforge``."""

    def __init__(self, name, plugin=None, error=None):
        self.name, self._plugin, self._error = name, plugin, error
        self.dist = None

    def load(self):
        if self._error is not None:
            raise self._error
        return self._plugin


def test_a_broken_entry_point_is_left_out_with_one_line_and_never_half_registered(monkeypatch):
    from sketchforge.plugins import manager

    class Typo:
        @hookimpl
        def sketchforge_inflater(self):
            return []

    eps = [_EntryPoint("good", FanInflater()), _EntryPoint("typo", Typo()),
           _EntryPoint("missing", error=ModuleNotFoundError("No module named 'shapely2'"))]
    monkeypatch.setattr(manager, "entry_points", lambda group: list(eps))
    pm = make_plugin_manager([], load_entry_points=True, allowlist=None, skip_broken=True)
    names = [n for n, _ in pm.list_name_plugin()]
    assert names == [CORE, "good"]  # the one with a bad hook is not left registered
    assert pm.get_plugin("typo") is None and "unknown hook 'sketchforge_inflater'" in pm.skipped["typo"]
    assert pm.skipped["missing"] == "ModuleNotFoundError: No module named 'shapely2'"
    assert len(pm.problems) == 2 and pm.problems[0].startswith("plugin 'missing' could not be loaded")  # by name
    # without skip_broken (a test host) the first broken one, by name, raises
    with pytest.raises(ModuleNotFoundError):
        make_plugin_manager([], load_entry_points=True, skip_broken=False)
    eps.pop()
    with pytest.raises(PluginError, match="unknown hook"):
        make_plugin_manager([], load_entry_points=True, skip_broken=False)
