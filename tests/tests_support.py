"""Shared test data."""

import os

#: Set by `make mutate`: every surviving mutant runs every test that reaches its function, so
#: property tests run fewer (and fixed) examples there; the normal suite is unchanged.
IN_MUTATION_RUN = bool(os.environ.get("SKETCHFORGE_MUTATION"))


def examples(n: int) -> int:
    """Hypothesis example count: ``n``, or n // 8 (at least 4) in a mutation run."""
    return max(4, n // 8) if IN_MUTATION_RUN else n


SPEC_DOC = {
    "format": "sketchforge",
    "version": 1,
    "light": [0.7071, 0.7071, 0.0],
    "journal": [
        {"command": "add_layer", "id": "body", "name": "Body"},
        {"command": "set_contour", "layer": "body", "points": [[-1.0, -0.6], [1.0, -0.6], [1.0, 0.6], [-1.0, 0.6]], "closed": True},
        {"command": "set_inflate_params", "layer": "body", "params": {"resolution": 0.05, "inflation": 1.0, "smoothing": 0.0}},
        {"command": "set_light", "direction": [1.0, 0.0, 0.0]},
    ],
}


def assert_save_open_replay_agree(doc, host):
    """Saving and reopening (snapshot) and replaying the journal both give ``doc``'s state."""
    import json

    from sketchforge.document import fileformat as ff

    data = json.loads(ff.dumps(doc))
    assert ff.compare(doc, ff.document_from_dict(data, "t", host=host)) == []
    assert ff.compare(doc, ff.document_from_dict(data, "t", host=host, use_snapshot=False)) == []


def assert_undo_all_redo_all(doc, initial_snapshot):
    """Undoing everything gives the initial state exactly; redoing everything gives the final
    one exactly (file dicts compared, meshes as bytes)."""
    from sketchforge.document import fileformat as ff

    stack = doc.undo_stack
    final = ff.document_to_dict(doc)
    index = stack.index
    stack.set_index(0)
    assert ff.document_to_dict(doc)["snapshot"] == initial_snapshot
    stack.set_index(index)
    assert ff.document_to_dict(doc) == final
