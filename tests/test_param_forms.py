"""Solver parameter forms (issue 37): what ``number``, ``choice``, ``flag`` and
``validate_params`` declare is the solver's own check, for every installed solver and the
test suite's third-party ones, so the form the app generates never offers a value the solver
refuses and never hides one it accepts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sketchforge.plugin_api import (
    MAX_PARAMETER,
    ParameterError,
    SculptSolver,
    choice,
    declare_params,
    describe_params,
    flag,
    number,
    validate_params,
)
from sketchforge.plugins.param_forms import ParamField


def _solvers(host):
    from third_party_solvers import ThirdPartySolvers

    from sketchforge.plugins.testing import FanInflater, make_host

    out = []
    for h in (host, make_host(ThirdPartySolvers(), FanInflater())):
        for kind in ("inflate", "sculpt", "assemble"):
            out += [(kind, name, s) for name, s in h.solvers(kind).items()]
    return out


def _accepts(solver, key, value) -> bool:
    try:
        out = solver.check_params({key: value})
    except ParameterError:
        return False
    return out[key] == value or (value is not None and out[key] is not None and float(out[key]) == float(value))


def _nudge(x: float, up: bool) -> float:
    step = max(abs(x) * 1e-9, 1e-12)
    return x + step if up else x - step


def test_every_declared_range_and_option_is_the_solver_s_own_check(real_host):
    rng = np.random.default_rng(37)
    checked = 0
    for kind, name, solver in _solvers(real_host):
        fields = describe_params(solver.check_params)
        assert [f.key for f in fields] == list(solver.check_params({})), name
        for f in fields:
            where = f"{kind} {name!r}: {f.key}"
            assert _accepts(solver, f.key, f.default), where
            if f.kind in ("number", "integer"):
                whole = f.kind == "integer"  # a form sends a whole number as an int
                if f.lo is not None:
                    assert _accepts(solver, f.key, int(f.lo) if whole else f.lo) != f.lo_open, where
                    assert not _accepts(solver, f.key, int(f.lo) - 1 if whole else _nudge(f.lo, up=False)), where
                if f.hi is not None:
                    assert _accepts(solver, f.key, int(f.hi) if whole else f.hi) != f.hi_open, where
                    assert not _accepts(solver, f.key, int(f.hi) + 1 if whole else _nudge(f.hi, up=True)), where
                lo = f.lo if f.lo is not None else -1e3
                hi = f.hi if f.hi is not None else lo + 1e3
                for x in rng.uniform(lo, hi, 5):
                    x = int(round(x)) if f.kind == "integer" else float(x)
                    assert _accepts(solver, f.key, x) == f.accepts(x), f"{where} = {x}"
                if f.kind == "integer" and f.default is not None:
                    assert not _accepts(solver, f.key, f.default + 0.5), where
                assert _accepts(solver, f.key, None) == f.optional, where
                assert not _accepts(solver, f.key, "1"), where
            elif f.kind == "choice":
                assert all(_accepts(solver, f.key, o) for o in f.options), where
                assert not _accepts(solver, f.key, "__no_such_option__"), where
            elif f.kind == "flag":
                assert _accepts(solver, f.key, True) and _accepts(solver, f.key, False), where
            checked += 1
    assert checked >= 30


def test_the_built_in_solvers_declare_every_parameter(real_host):
    """No parameter of a built-in falls back to a guess from its default: each has a range,
    options or a switch, and the built-ins say what each one means."""
    for kind in ("inflate", "sculpt", "assemble"):
        for name in real_host.solvers(kind):
            fields = real_host.solver_fields(kind, name)
            assert all(f.declared for f in fields), (name, [f.key for f in fields if not f.declared])
            if name != "strips":  # the thesis' solver states its ranges only
                assert all(f.help for f in fields), (name, [f.key for f in fields if not f.help])


def test_the_helpers_declare_what_they_check():
    check = number("w", 0.0, 2.0, lo_open=True, optional=True)
    assert check.field == ParamField("w", "number", None, 0.0, 2.0, True, False, True)
    assert check.field.range_text() == "0 < w <= 2" and check.field.title == "W"
    assert number("n", 1, 9, integer=True).field.kind == "integer"
    # every number has a finite range (issue 38): an infinite bound is the core's, and the form says so
    wide = number("x", float("-inf"), math.inf).field
    assert (wide.lo, wide.hi) == (-MAX_PARAMETER, MAX_PARAMETER)
    assert wide.accepts(MAX_PARAMETER) and not wide.accepts(2 * MAX_PARAMETER)
    assert choice("c", ["a", "b"]).field.options == ("a", "b")
    assert flag("f").field.kind == "flag" and ParamField("stroke_weight", "number").title == "Stroke weight"


def test_a_hand_written_check_declares_its_form_and_keeps_its_messages():
    def by_hand(params):
        p = {"size": 1.0, "mode": "a", "note": "x", "auto": None, "extra": [1, 2], **params}
        if not 0 < p["size"] <= 10:
            raise ParameterError("size: my own words")
        return p

    declared = declare_params(by_hand, {"size": 1.0, "mode": "a"},
                              {"size": number("size", 0.0, 10.0, lo_open=True), "mode": choice("mode", ("a", "b"))},
                              help={"size": "the size"}, labels={"size": "Size (m)"})
    fields = {f.key: f for f in describe_params(declared)}
    assert fields["size"].range_text() == "0 < size <= 10" and fields["size"].help == "the size"
    assert fields["size"].title == "Size (m)" and fields["mode"].title == "Mode"
    assert fields["mode"].options == ("a", "b") and fields["mode"].declared
    # undeclared keys are inferred from the defaults, without a range
    assert [(fields[k].kind, fields[k].declared) for k in ("note", "auto", "extra")] == [
        ("text", False), ("number", False), ("value", False)]
    assert fields["auto"].optional
    with pytest.raises(ParameterError, match="size: my own words"):
        declared({"size": 20.0})


def test_a_solver_using_validate_params_needs_no_declaration_of_its_own():
    defaults = {"k": 3, "on": False, "how": "fast"}
    checks = {"k": number("k", 1, 8, integer=True), "on": flag("on"), "how": choice("how", ("fast", "exact"))}
    solver = SculptSolver("s", lambda problem, params: None, lambda p: validate_params(p, defaults, checks))
    fields = describe_params(solver.check_params)
    assert [(f.key, f.kind, f.default, f.declared) for f in fields] == [
        ("k", "integer", 3, True), ("on", "flag", False, True), ("how", "choice", "fast", True)]
