"""The app tells the user once, in the status bar, when the undo history's memory budget starts
dropping its oldest steps; the history panel then starts at "<older steps dropped>" (issue 39)."""

import numpy as np

from sketchforge.document import Document
from sketchforge.document import commands as C


def test_the_status_bar_says_once_that_old_steps_are_dropped(make_window, fan_host):
    doc = Document(host=fan_host)
    t = np.linspace(0, 2 * np.pi, 500, endpoint=False)
    doc.execute({"command": "add_layer", "id": "a", "name": "A"})
    doc.execute({"command": "set_contour", "layer": "a", "points": np.c_[np.cos(t), np.sin(t)].tolist(), "closed": True})
    w = make_window(doc)
    told = []
    doc.undo_stack.history_trimmed.connect(told.append)
    layer = doc.layer("a")
    doc.undo_stack.memory_budget = 3 * (layer.mesh.V.nbytes + layer.points.nbytes)
    for _ in range(8):
        w.push(C.TransformLayer(layer="a", matrix=[[1, 0, 0.05], [0, 1, 0.0]]))
    assert len(told) == 1
    msg = w.statusBar().currentMessage()
    assert msg.startswith("The undo history reached its memory budget") and "oldest steps are dropped" in msg
    h = w.history_panel
    assert h.item(0).text() == "<older steps dropped>"
    assert h.count() == doc.undo_stack.count() + 1 == 4
    assert len(doc.journal()) == 10  # nothing is lost from the file
