"""A test plugin whose solvers die the way a segfaulting native library does: ``os.abort()``
(SIGABRT; no Python ``finally`` runs, nothing is flushed). Used by tests/test_crash_recovery.py,
in a subprocess."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import ClassVar

from sketchforge.document.commands import ReplaceLayerCommand, parse_field
from sketchforge.plugins.hookspecs import hookimpl


@dataclass
class AbortSolve(ReplaceLayerCommand):
    """A layer edit whose solve (``prepare`` -> ``compute``) brings the process down."""

    name: ClassVar[str] = "abort_solve"

    def text(self) -> str:
        return "Abort solve"

    def compute(self, doc, old):
        os.abort()

    def to_dict(self) -> dict:
        return {"command": self.name, "layer": self.layer}

    @classmethod
    def from_dict(cls, d: dict) -> "AbortSolve":
        return cls(layer=parse_field(d, "layer", str, cls.name))


class AbortPlugin:
    @hookimpl
    def sketchforge_commands(self):
        return [AbortSolve]


class AbortingAssembler:
    """An assembler that crashes (as OSQP might)."""

    @hookimpl
    def sketchforge_assemble(self, layers, params):
        os.abort()
