"""Kinds of named solver, a document's choice of one, and the JSON values a journal holds.

Below both the document and the plugin host: the document records which solver of each kind
a layer, an edit or the assembly uses (:class:`SolverChoice`) and names them in messages
(:data:`SOLVER_KINDS`), the host builds the registries of those kinds. Neither needs the other
for that (``sketchforge.plugins.solvers`` re-exports these names, their historical path).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class SolverKind:
    """One kind of solver: its registry hook, how messages name one, its built-in default and
    the name of the function field on its value type."""

    kind: str
    hook: str
    #: "inflater", "sculpt solver", "assembler": how messages name one.
    what: str
    #: The built-in solver's name (the default).
    default: str
    #: The name of the function field on the value type.
    call: str


SOLVER_KINDS: dict[str, SolverKind] = {
    "inflate": SolverKind("inflate", "sketchforge_inflaters", "inflater", "poisson", "inflate"),
    "sculpt": SolverKind("sculpt", "sketchforge_sculpt_solvers", "sculpt solver", "gauss_newton", "solve"),
    "assemble": SolverKind("assemble", "sketchforge_assemblers", "assembler", "depth_qp", "assemble"),
}


def json_value(v: Any, depth: int = 0) -> bool:
    """Whether ``v`` is a value a journal can hold: None, bool, finite number, string, or a
    list / string-keyed object of those (at most 8 levels)."""
    if v is None or isinstance(v, (bool, str)):
        return True
    if isinstance(v, numbers.Real):
        return isinstance(v, int) or math.isfinite(float(v))
    if depth >= 8:
        return False
    if isinstance(v, (list, tuple)):
        return all(json_value(x, depth + 1) for x in v)
    if isinstance(v, Mapping):
        return all(isinstance(k, str) and json_value(x, depth + 1) for k, x in v.items())
    return False


@dataclass(frozen=True)
class SolverChoice:
    """A document's choice of solver for one job: a name (None: the default) and its own
    parameters, as the document stores them (read-only)."""

    solver: str | None = None
    params: Mapping = field(default_factory=dict)

    def to_dict(self) -> dict:
        d: dict = {}
        if self.solver is not None:
            d["solver"] = self.solver
        if self.params:
            d["params"] = dict(self.params)
        return d
