"""The assemble plugin's shapes for ``sketchforge dataset``: random creatures (the corpus of
its tests and benchmarks, :func:`.testing.random_creature`)."""

from __future__ import annotations

import numpy as np

from sketchforge.plugin_api import DatasetGenerator, SketchforgeError

#: Edge length of the random creatures (the app's default resolution).
RESOLUTION = 0.03


def creature_journal(rng: np.random.Generator) -> list[dict]:
    """A random creature's journal: a body, a head, 2-6 limbs and an eye (random stream
    ``rng``); a seed whose head cannot be placed is a SketchforgeError (drawn again)."""
    from .testing import random_creature

    try:
        return random_creature(int(rng.integers(0, 2**62)), resolution=RESOLUTION)["journal"]
    except ValueError as exc:  # the few seeds whose head cannot be placed
        raise SketchforgeError(str(exc)) from None


CREATURE = DatasetGenerator("creature", "shape", creature_journal,
                            "a body, a head, 2-6 limbs (some behind the body) and an eye")
