"""A test plugin whose solvers die the way a segfaulting native library does: ``os.abort()``
(SIGABRT; no Python ``finally`` runs, nothing is flushed). Used by tests/test_crash_recovery.py,
in a subprocess.

Also :func:`live_session`: another sketchforge process, still running, in the middle of its
solves (tests/test_crash_recovery.py, tests/qt/test_qt_crash_recovery.py)."""

from __future__ import annotations

import os
import select
import subprocess
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
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
    def from_dict(cls, d: dict) -> AbortSolve:
        return cls(layer=parse_field(d, "layer", str, cls.name))


class AbortPlugin:
    @hookimpl
    def sketchforge_commands(self):
        return [AbortSolve]


def _abort(layers, params):
    os.abort()


class AbortingAssembler:
    """An assembler that crashes (as OSQP might)."""

    @hookimpl
    def sketchforge_assemblers(self):
        from sketchforge.plugin_api import Assembler

        return [Assembler("aborting", _abort)]


# Another session: an autosave with the record of the solve running on it (unsaved work), and a
# record alone (a solve on a document without unsaved changes); then it stays in those solves.
LIVE_SCRIPT = r"""
import sys, time
from pathlib import Path
from sketchforge.document import Document
from sketchforge.document import commands as C
from sketchforge.document.autosave import Autosaver
from sketchforge.plugins.testing import FanInflater, make_test_host

folder = Path(sys.argv[1])
host = make_test_host(FanInflater())
triangle = [[0, 0], [2, 0], [1, 1]]
dirty = Document(host=host)
dirty.execute({"command": "add_layer", "id": "a", "name": "Alpha"})
dirty.execute({"command": "set_contour", "layer": "a", "points": triangle})
Autosaver(dirty, original_path=folder.parent / "mine.json", folder=folder).begin_solve(C.SetContour(layer="a", points=triangle))
clean = Document(host=host)
clean.execute({"command": "add_layer", "id": "b", "name": "Beta"})
clean.undo_stack.set_clean()
Autosaver(clean, original_path=folder.parent / "other.json", folder=folder).begin_solve(C.SetContour(layer="b", points=triangle))
print("ready", flush=True)
time.sleep(600)  # in the middle of both solves until the test ends it
"""


@contextmanager
def live_session(folder: Path):
    """A second sketchforge process that has written, in ``folder``, an autosave with the
    record of its running solve on layer 'Alpha' (of mine.json) and the record of a solve on
    layer 'Beta' of a document without unsaved changes (other.json), and is still running.
    Yields the ``Popen``; the test may ``kill()`` and ``wait()`` it (a crash); it is killed at
    the end in any case."""
    root = Path(__file__).resolve().parent.parent
    proc = subprocess.Popen(
        [sys.executable, "-c", LIVE_SCRIPT, str(folder)], cwd=root, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        readable, _, _ = select.select([proc.stdout], [], [], 120)
        line = proc.stdout.readline() if readable else ""
        if line.strip() != "ready":
            proc.kill()
            raise AssertionError(f"the live session did not start: {proc.stderr.read()[-3000:]}")
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        proc.stdout.close()
        proc.stderr.close()
