"""Memory of the undo history (issue 39, point 2): 200 moves of a ~36k-vertex layer.

Prints, for the headless document and for the app's case (each step's mesh drawn once on a
1000x800 canvas, as the app does), the memory the moves keep (tracemalloc: what is still
allocated after them), per step, against the bytes of the layer's vertices; then the same
moves with a small memory budget, to show the oldest steps dropped and the one message.

Runs on any checkout (``PYTHONPATH=<checkout> python benchmarks/bench_undo_memory.py`` measures
another one): the budget part is skipped where the undo stack has none.
"""

from __future__ import annotations

import gc
import time
import tracemalloc

import numpy as np

MOVES = 200


def layer_doc(resolution: float = 0.0105):
    from sketchforge.document import Document
    from sketchforge.plugins.manager import PluginHost

    host = PluginHost.create(allowlist=["inflate"], skip_broken=True)
    doc = Document(host=host)
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    doc.execute({"command": "set_inflate_params", "layer": "a", "params": {"resolution": resolution}})
    doc.execute({"command": "set_contour", "layer": "a", "points": np.c_[np.cos(t), 0.7 * np.sin(t)].tolist(), "closed": True})
    return doc


def moves(doc, n: int, draw=None) -> tuple[float, float]:
    """(MB kept, CPU seconds) of ``n`` moves of layer 'a', each its own undo step."""
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    t0 = time.process_time()
    for _ in range(n):
        doc.execute({"command": "transform_layer", "layer": "a", "matrix": [[1, 0, 0.001], [0, 1, 0.0005]]})
        if draw is not None:
            draw(doc)
    cpu = time.process_time() - t0
    gc.collect()
    kept = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    return kept / 1e6, cpu


def main() -> None:
    import os

    from sketchforge.geometry import gbuffer as gb

    print(f"load: {os.getloadavg()[0]:.2f} (1 min)")
    doc = layer_doc()
    m = doc.layer("a").mesh
    print(f"layer: {m.n_vertices} vertices ({m.V.nbytes / 1e6:.2f} MB), {m.n_faces} triangles ({m.F.nbytes / 1e6:.2f} MB)")
    kept, cpu = moves(doc, MOVES)
    print(f"headless: {MOVES} moves keep {kept:.0f} MB, {kept / MOVES:.2f} MB a step ({cpu:.1f} s CPU)")
    stack = doc.undo_stack
    if hasattr(stack, "history_bytes"):
        print(f"  the history's own arrays: {stack.history_bytes() / 1e6:.0f} MB; steps: {stack.count()}")

    doc = layer_doc()
    view = gb.View.framing([doc.layer("a").mesh], 1000, 800)

    def draw(d):
        gb.rasterise([d.layer("a").mesh], view)

    draw(doc)
    kept, cpu = moves(doc, MOVES, draw)
    print(f"drawn (the app's canvas, 1000x800): {MOVES} moves keep {kept:.0f} MB, {kept / MOVES:.2f} MB a step "
          f"({cpu:.1f} s CPU)")

    doc = layer_doc()
    if not hasattr(doc.undo_stack, "memory_budget"):
        print("no memory budget on this checkout")
        return
    told = []
    doc.undo_stack.history_trimmed.connect(told.append)
    doc.undo_stack.memory_budget = 100 * 10**6
    journal = len(doc.journal())
    kept, cpu = moves(doc, MOVES)
    s = doc.undo_stack
    print(f"budget 100 MB: {MOVES} moves keep {kept:.0f} MB; {s.count()} steps can be undone, {s.dropped} dropped; "
          f"history {s.history_bytes() / 1e6:.0f} MB; journal {len(doc.journal())} entries (+{len(doc.journal()) - journal}); "
          f"told {len(told)} time(s): {told[0] if told else ''!r} ({cpu:.1f} s CPU)")


if __name__ == "__main__":
    main()
