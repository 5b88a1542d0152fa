"""Shared test data."""

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
