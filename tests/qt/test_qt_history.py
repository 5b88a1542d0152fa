"""The history panel shows which steps are undone (issue 18: greying of the first undone row
was planted away and nobody noticed)."""

from sketchforge.document import commands as C


def _undone(item) -> bool:
    return item.font().italic()


def test_undone_rows_are_greyed_from_the_first_one(make_window):
    w = make_window()
    w.add_layer()
    w.push(C.RenameLayer(layer="layer1", new_name="Body"))
    w.push(C.RenameLayer(layer="layer1", new_name="Torso"))
    h = w.history_panel
    normal = h.item(1).foreground().color()
    assert not any(_undone(h.item(i)) for i in range(h.count()))
    for undone in (1, 2, 3):
        w.undo()
        rows = [_undone(h.item(i)) for i in range(h.count())]
        # row 0 is "<start>"; rows count - undone .. count - 1 are the undone commands
        assert rows == [False] * (h.count() - undone) + [True] * undone, (undone, rows)
        for i in range(h.count()):
            grey = h.item(i).foreground().color() != normal
            assert grey == rows[i], (undone, i)
        assert h.currentRow() == h.count() - 1 - undone
    w.redo()
    assert [_undone(h.item(i)) for i in range(h.count())] == [False, False, True, True]

