"""Bookkeeping for compiled JAX functions: padded batch sizes and a trace counter.

Every batched solver pads its batch to one of ``BATCH_BUCKETS`` and uses the fixed-size grid
of :mod:`sketchforge.geometry.field_jax`, so the set of compiled functions is small and known
in advance (``warm_up`` compiles them). ``TRACES`` counts how often each function was traced;
tests use it to check that a second edit on a different layer does not recompile.
"""

from __future__ import annotations

from collections import Counter

import numpy as np

#: Padded strip-batch sizes.
BATCH_BUCKETS = (64, 256, 1024)

#: Number of traces per function name (incremented inside traced Python code only).
TRACES: Counter = Counter()


def bucket(n: int) -> int:
    """Smallest padded batch size holding n items (n above the largest is split by callers)."""
    for b in BATCH_BUCKETS:
        if n <= b:
            return b
    return BATCH_BUCKETS[-1]


def pad_rows(a: np.ndarray, size: int) -> np.ndarray:
    """Pad a (k, ...) array to (size, ...) by repeating its first row (valid, ignored data)."""
    out = np.empty((size,) + a.shape[1:], a.dtype)
    out[: len(a)] = a
    out[len(a) :] = a[0]
    return out


def run_padded(fn, rows: np.ndarray, *args) -> list[np.ndarray]:
    """Run a batched strip solver on ``rows`` (k, d) in padded batches of ``BATCH_BUCKETS`` sizes.

    ``fn(batch, *args)`` returns samples (b, j, ...) and an alive mask (b, j); the result is
    one array per row, its alive samples only.
    """
    out = []
    big = BATCH_BUCKETS[-1]
    for s in range(0, len(rows), big):
        chunk = rows[s : s + big]
        xs, alive = fn(pad_rows(chunk, bucket(len(chunk))), *args)
        xs, alive = np.asarray(xs), np.asarray(alive)
        out.extend(xs[i][alive[i]] for i in range(len(chunk)))
    return out
