"""Named solvers: the value types the solver registries return, and the parameter contract.

Three kinds of solver, each a registry hook (:mod:`sketchforge.plugins.hookspecs`):

=========  ===============================  ==========================================  ================
kind       hook                             value                                       built-in
=========  ===============================  ==========================================  ================
inflate    ``sketchforge_inflaters()``      :class:`Inflater` (contour -> front mesh)   ``"poisson"``
sculpt     ``sketchforge_sculpt_solvers()`` :class:`SculptSolver` (shading -> heights)  ``"gauss_newton"``
assemble   ``sketchforge_assemblers()``     :class:`Assembler` (layers -> one mesh)     ``"depth_qp"``
=========  ===============================  ==========================================  ================

A layer names its inflater (``set_inflate_params`` with ``"solver"``), a sculpt edit its sculpt
solver (``sculpt_isophote`` with ``"solver"``), the document its assembler (``set_assembly``);
each passes that solver's own ``params``, which the solver validates itself with
``check_params`` (unknown keys refused: the host probes this when it registers the solver).
Without a name, the built-in is used (on a host without it, the only one of that kind
installed). The name, plugin and version of every solver a document used are saved in its
``providers``, so a replay elsewhere names a missing solver instead of reporting "mesh differs".

``check_params(params: dict) -> dict`` returns the complete parameter set, defaults filled in,
with JSON values only (they are saved in the journal); it raises
:class:`~sketchforge.errors.ParameterError` (one line, naming the key) for an unknown key or a
bad value. :func:`validate_params` does the usual work for a solver with a flat set of
parameters. The host puts the solver's name in front of the message.

What :func:`number`, :func:`choice` and :func:`flag` check, they also declare (``check.field``:
a range, options, a switch; what each parameter means, :func:`~sketchforge.plugins.param_forms.declare_params`
says), and
:func:`validate_params` ties them to the defaults: the app builds each solver's parameter form
from that (:mod:`sketchforge.plugins.param_forms`; a hand-written ``check_params`` declares
its form with :func:`~sketchforge.plugins.param_forms.declare_params`), so a plugin writes no
Qt for its parameters.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from sketchforge.errors import ParameterError, quote
from sketchforge.plugins.param_forms import ParamField, number_field, record_declaration
from sketchforge.solver_kinds import SOLVER_KINDS, SolverChoice, SolverKind, json_value  # noqa: F401 (re-exported)


def no_params(params: Mapping) -> dict:
    """``check_params`` of a solver without parameters: every key is unknown."""
    return validate_params(params, {})


@dataclass(frozen=True)
class Inflater:
    """Turns a drawn stroke into a layer's front surface.

    ``inflate(points, closed, params, holes) -> Mesh``: points (n, 2) float64 as drawn (either
    orientation); closed bool (False: an open stroke's closing segment is the junction);
    params the dict ``check_params`` returned; holes a list of (k_i, 2) float64 inner rings.
    The mesh: V (n, 3) float64 with z >= 0 and z = 0 on every rim, F (m, 3) int64
    counter-clockwise seen from +z, its ``boundary``, ``junction`` and ``holes`` loops. Raise
    :class:`~sketchforge.errors.ContourError` for a stroke that cannot be inflated.
    ``holes=False`` declares that it cannot cut holes (the host refuses a layer with holes
    rather than fill them)."""

    name: str
    inflate: Callable
    check_params: Callable = no_params
    version: str = "1"
    description: str = ""
    holes: bool = True


@dataclass(frozen=True)
class SculptSolver:
    """Turns a wanted shading into heights: ``solve(problem, params) -> SculptSolution`` (or
    the height change δz (n,) float64 alone). ``problem`` is a
    :class:`~sketchforge.plugins.sculpt_problem.SculptProblem` (the layer, the pick, the band,
    the cleaned stroke and services such as the shading of candidate heights); the host clamps
    heights at 0, keeps the rim at 0, refuses non-finite values and, unless switched off,
    keeps the edit only if the isophote ends no farther from the stroke (trying half and a
    quarter of δz).

    The light (``problem.light``) is anywhere on the hemisphere facing the viewer (z >= 0), not
    only in the drawing plane: a solver that cannot handle a tilted light raises a
    ``SculptError`` saying so in one line, never returns a wrong surface.

    ``several_isophotes``: whether ``solve`` takes a joint edit of several isophotes (the
    ``sculpt_isophotes`` command): then ``problem.parts`` holds one problem per isophote and
    ``problem.sample_values`` the shading each stroke sample asks for (see
    :class:`~sketchforge.plugins.sculpt_problem.SculptProblem`). A solver that leaves it False is
    never given one: the host refuses such an edit in one line naming the solver ("the sculpt
    solver 'strips' redraws one isophote per edit: ...")."""

    name: str
    solve: Callable
    check_params: Callable = no_params
    version: str = "1"
    description: str = ""
    #: Shown in the app's sculpt panel ("" : the name).
    label: str = ""
    #: Optional ``warm_up()``: compile or build what the first solve would (the app calls it
    #: on a worker thread when the person chooses the solver).
    warm_up: Callable | None = None
    #: Takes several isophotes in one edit (``problem.parts``); False: one per edit.
    several_isophotes: bool = False


@dataclass(frozen=True)
class Assembler:
    """Assembles layers into one closed mesh: ``assemble(layers, params) -> Mesh`` (layers back
    to front, read-only ``Layer`` values; one outward-oriented mesh, ``boundary`` and
    ``junction`` empty)."""

    name: str
    assemble: Callable
    check_params: Callable = no_params
    version: str = "1"
    description: str = ""


SOLVER_TYPES = {"inflate": Inflater, "sculpt": SculptSolver, "assemble": Assembler}


# --- parameters -------------------------------------------------------------------------------


def validate_params(params: Mapping | None, defaults: Mapping, checks: Mapping[str, Callable] | None = None) -> dict:
    """``defaults`` updated by ``params``, every key known and every value checked.

    Parameters
    ----------
    params : Mapping or None
        What the document gave.
    defaults : Mapping
        Every parameter the solver takes, with its default.
    checks : Mapping[str, Callable] or None
        ``checks[key](value) -> value`` for the keys that need one (see :func:`number`); it
        raises ParameterError with a message that starts with the key.

    Raises
    ------
    ParameterError
        "unknown parameter 'x' (known: a, b)", or the check's message.
    """
    record_declaration(defaults, checks)  # the form the app shows (sketchforge.plugins.param_forms)
    if params is None:
        params = {}
    if not isinstance(params, Mapping):
        raise ParameterError(f"parameters must be an object of name: value, got {type(params).__name__}")
    unknown = sorted(str(k) for k in params if k not in defaults)
    if unknown:
        known = ", ".join(sorted(defaults)) or "none"
        raise ParameterError(f"unknown parameter {quote(unknown[0])} (known: {known})")
    out = dict(defaults)
    out.update(params)
    for key, check in (checks or {}).items():
        if key in out:
            out[key] = check(out[key])
    return out


#: The range of a numeric parameter whose solver gives no bound of its own: the drawing's
#: coordinate range (±1e9 drawing units), beyond which lengths, areas and weights overflow or
#: lose every digit (issue 38: 1e308 passed and failed deep inside a solver).
MAX_PARAMETER = 1e9


def _shown(x) -> str:
    """A number for a message: ``:g`` for a float, an integer's digits up to 20 (its length
    beyond: formatting a 400-digit integer with ``:g`` raised OverflowError)."""
    if isinstance(x, int):
        if abs(x) >= 10**1000:
            return "an integer of over 1000 digits"
        text = str(x)
        return text if len(text.lstrip("-")) <= 20 else f"an integer of {len(text.lstrip('-'))} digits"
    return f"{x:g}"


def number(key: str, lo: float | None = None, hi: float | None = None, *, lo_open: bool = False,
           hi_open: bool = False, integer: bool = False, optional: bool = False) -> Callable:
    """A ``checks`` entry: the value must be a finite real number (not a bool, a string or
    NaN, whatever its type: numpy's included) in the range, a whole number if ``integer``
    (returned as int, else as float), or None if ``optional``. Every parameter has a finite
    range: a bound left out, or beyond ±:data:`MAX_PARAMETER`, is ±:data:`MAX_PARAMETER`. ``lo_open`` / ``hi_open`` exclude the
    bound itself. Messages are one line naming the key."""
    # Never wider than the drawing's range, whatever the caller asks (an infinite bound too).
    lo = -MAX_PARAMETER if lo is None else max(lo, -MAX_PARAMETER)
    hi = MAX_PARAMETER if hi is None else min(hi, MAX_PARAMETER)

    def check(v):
        if v is None and optional:
            return None
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
            raise ParameterError(f"{key!r} must be a number{' or null' if optional else ''}, got {quote(v)}")
        if isinstance(v, numbers.Integral):
            x = seen = int(v)  # exact at any size: compared with the bounds before any float is made
        else:
            try:
                x = float(v)
            except OverflowError:  # a Fraction beyond float range
                raise ParameterError(f"{key!r} is too large for a number") from None
            if not math.isfinite(x):
                raise ParameterError(f"{key!r} must be a finite number, got {x}")
            seen = x
            if integer:
                if not x.is_integer():
                    raise ParameterError(f"{key!r} must be a whole number, got {x!r}")
                x = int(x)
        if x < lo or (lo_open and x == lo):
            raise ParameterError(f"{key!r} must be {'>' if lo_open else '>='} {_shown(lo)}, got {_shown(seen)}")
        if x > hi or (hi_open and x == hi):
            raise ParameterError(f"{key!r} must be {'<' if hi_open else '<='} {_shown(hi)}, got {_shown(seen)}")
        return x if integer else float(x)

    # What the app's form shows: this range (its words: declare_params' help; see param_forms).
    check.field = number_field(key, lo, hi, lo_open, hi_open, integer, optional)
    return check


def choice(key: str, options) -> Callable:
    """A ``checks`` entry: the value must be one of ``options`` (strings)."""
    options = tuple(options)

    def check(v):
        if v not in options:
            raise ParameterError(f"{key!r} must be one of {', '.join(map(repr, options))}, got {quote(v)}")
        return v

    check.field = ParamField(key, "choice", options=options)
    return check


def flag(key: str) -> Callable:
    """A ``checks`` entry: the value must be true or false."""

    def check(v):
        if not isinstance(v, bool):
            raise ParameterError(f"{key!r} must be true or false, got {quote(v)}")
        return v

    check.field = ParamField(key, "flag")
    return check
