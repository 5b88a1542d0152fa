"""A solver's parameters as form fields, from what its ``check_params`` declares.

A plugin writes no Qt for its parameters: the app builds a form for every solver (inflater,
sculpt solver, assembler) from :func:`describe_params`, and the checks stay the solver's own.
What a field knows comes from the parameter helpers of :mod:`sketchforge.plugins.solvers`:

- ``number(key, lo, hi, lo_open=, hi_open=, integer=, optional=)`` declares a range (and
  whether None, "automatic", is allowed), ``choice(key, options)`` the options, ``flag(key)``
  a switch; each check carries its :class:`ParamField` as ``check.field``; what a parameter
  means (its tooltip) and its label, :func:`declare_params` adds;
- ``validate_params(params, defaults, checks)`` ties them to the defaults: the host calls
  ``check_params({})`` once while recording the ``validate_params`` call it makes;
- a solver whose ``check_params`` is written by hand declares the same with
  :func:`declare_params` (its own checks and messages unchanged);
- a parameter nobody declared is inferred from its default (a bool is a switch, an int a
  whole number, a float a number, a string text), without a range.

The defaults are always what ``check_params({})`` returns. ``tests/test_param_forms.py``
checks for every installed solver that the declared ranges and options are the ones its
``check_params`` accepts, so a form never offers a value the solver refuses.
"""

from __future__ import annotations

import contextvars
import functools
import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

#: Kinds of field: a real number, a whole number, one of options, a switch, free text, or a
#: value the form cannot edit (a list or an object: shown, kept as it is).
FIELD_KINDS = ("number", "integer", "choice", "flag", "text", "value")


@dataclass(frozen=True)
class ParamField:
    """One parameter as a form shows it.

    Attributes
    ----------
    key : str
    kind : str
        One of :data:`FIELD_KINDS`.
    default : Any
        What ``check_params({})`` returns for it (filled in by :func:`describe_params`).
    lo, hi : float or None
        The range of a number (None: unbounded that side); ``lo_open`` / ``hi_open`` exclude
        the bound itself.
    optional : bool
        None is allowed (a number left "automatic").
    options : tuple of str
        The choices of a ``choice``.
    label, help : str
        What the form says ("": the key, humanised; the range and default).
    declared : bool
        False when inferred from the default alone (no range known).
    """

    key: str
    kind: str
    default: Any = None
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    optional: bool = False
    options: tuple = ()
    label: str = ""
    help: str = ""
    declared: bool = True

    @property
    def title(self) -> str:
        """The label, else the key humanised ("stroke_weight" -> "Stroke weight")."""
        return self.label or self.key.replace("_", " ").strip().capitalize()

    def range_text(self) -> str:
        """"0 <= x < 1", "x > 0", "" (unbounded): the range in words."""
        lo = None if self.lo is None else f"{self.lo:g} {'<' if self.lo_open else '<='} "
        hi = None if self.hi is None else f" {'<' if self.hi_open else '<='} {self.hi:g}"
        if lo and hi:
            return f"{lo}{self.key}{hi}"
        if lo:
            return f"{self.key} {'>' if self.lo_open else '>='} {self.lo:g}"
        if hi:
            return f"{self.key}{hi}"
        return ""

    def accepts(self, value) -> bool:
        """Whether ``value`` is inside the declared range or options (the solver's own check
        decides; a form uses this to keep its widgets in range)."""
        if value is None:
            return self.optional or self.kind in ("value", "text")
        if self.kind == "choice":
            return value in self.options
        if self.kind == "flag":
            return isinstance(value, bool)
        if self.kind in ("number", "integer"):
            if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(float(value)):
                return False
            if self.kind == "integer" and float(value) != int(value):
                return False
            x = float(value)
            if self.lo is not None and (x < self.lo or (self.lo_open and x == self.lo)):
                return False
            return not (self.hi is not None and (x > self.hi or (self.hi_open and x == self.hi)))
        return True


def number_field(key, lo=None, hi=None, lo_open=False, hi_open=False, integer=False, optional=False) -> ParamField:
    """The field ``number(...)`` declares (its bounds as ``number`` made them finite; an
    infinite one left here is no bound)."""
    def bound(b):
        return None if b is None or not math.isfinite(float(b)) else float(b)

    return ParamField(key, "integer" if integer else "number", None, bound(lo), bound(hi), bool(lo_open), bool(hi_open),
                      bool(optional))


# --- recording validate_params ----------------------------------------------------------------

_RECORDING: contextvars.ContextVar[list | None] = contextvars.ContextVar("sketchforge_param_recording", default=None)


def record_declaration(defaults: Mapping, checks: Mapping | None) -> None:
    """Called by ``validate_params``: while :func:`describe_params` runs a ``check_params``,
    remember what it declared."""
    rec = _RECORDING.get()
    if rec is not None:
        rec.append((dict(defaults), dict(checks or {})))


def declare_params(check_params: Callable, defaults: Mapping, checks: Mapping[str, Callable] | None = None,
                   help: Mapping[str, str] | None = None, labels: Mapping[str, str] | None = None) -> Callable:
    """``check_params`` (unchanged: its checks and messages stay its own) declaring its form:
    the ``defaults`` and the ``checks`` made with ``number``, ``choice`` and ``flag`` that
    describe each key's range or options, and optional ``help`` texts and ``labels`` per key
    (a label's default is the key, humanised).

    For a solver whose check is written by hand (or does more than ``validate_params``)::

        Inflater("mine", inflate, check_params=declare_params(my_check, DEFAULTS,
                 {"size": number("size", 0.0, 10.0, lo_open=True)}, help={"size": "..."}))
    """

    @functools.wraps(check_params)
    def check(params):
        return check_params(params)

    check.__sketchforge_params__ = (dict(defaults), dict(checks or {}), dict(help or {}), dict(labels or {}))
    return check


def _inferred(key: str, default) -> ParamField:
    if isinstance(default, bool):
        return ParamField(key, "flag", default, declared=False)
    if isinstance(default, numbers.Integral):
        return ParamField(key, "integer", default, declared=False)
    if isinstance(default, numbers.Real):
        return ParamField(key, "number", default, declared=False)
    if default is None:
        return ParamField(key, "number", None, optional=True, declared=False)
    if isinstance(default, str):
        return ParamField(key, "text", default, declared=False)
    return ParamField(key, "value", default, declared=False)


def describe_params(check_params: Callable) -> list[ParamField]:
    """The form fields of a solver's parameters, one per key of its defaults
    (``check_params({})``), in their order.

    Raises
    ------
    Exception
        Whatever ``check_params({})`` raises (the host names the solver).
    """
    declared = getattr(check_params, "__sketchforge_params__", None)
    rec: list = []
    token = _RECORDING.set(rec)
    try:
        full = dict(check_params({}))
    finally:
        _RECORDING.reset(token)
    if declared is not None:
        _, checks, helps, labels = declared
    elif rec:
        _, checks = rec[0]
        helps, labels = {}, {}
    else:
        checks, helps, labels = {}, {}, {}
    out = []
    for key, value in full.items():
        field = getattr(checks.get(key), "field", None)
        if not isinstance(field, ParamField):
            field = _inferred(key, value)
        elif field.kind in ("number", "integer") and value is None and not field.optional:
            field = _inferred(key, value)
        out.append(_with(field, key=key, default=value, help=helps.get(key, field.help),
                         label=labels.get(key, field.label)))
    return out


def _with(field: ParamField, **changes) -> ParamField:
    from dataclasses import replace

    return replace(field, **changes)
