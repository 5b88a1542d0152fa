"""pytest fixtures and helpers for plugin authors, shipped with sketchforge (entry point
``pytest11``), as napari ships ``make_napari_viewer``: installing sketchforge makes them
available in any test.

- ``make_sketchforge_host(*plugins, installed=(), strict=True)``: a host with the core plugin,
  your plugin objects or modules, and the installed entry points named in ``installed``
  (e.g. ``("inflate",)`` for real meshes); nothing else that happens to be installed. With
  ``strict`` a contribution the host refuses (a broken contract, a hook that raised) fails
  the test with the host's message.
- ``make_sketchforge_document(host=None, contour=ELLIPSE, layer="a", inflater=None, **params)``:
  a document with one layer inflated from ``contour`` by the inflater named ``inflater``
  (None: the host's default) with ``params`` (checked by that inflater); needs an inflater in
  the host: ``installed=("inflate",)`` or ``sketchforge_fan_inflater``.
- ``assert_replays(doc)``: replays the document's journal headlessly, and reloads it from the
  saved file, and asserts both are bit-identical to ``doc`` (layers, meshes, light, plugin
  data); returns the replayed document. The check every command must pass.
- ``sketchforge_fan_inflater``: a plugin object with the inflater ``"fan"``, a tiny exact
  stand-in for the inflate plugin when a test is about commands, not geometry.
- ``sketchforge_layer_at(doc, point)``: the id of the front-most visible layer under a point
  (:func:`sketchforge.plugin_api.layer_at`, what a tool calls on a press).
- ``sketchforge_isophote(doc, layer, pick, model=None)``: ``(c, polyline)``, the isophote
  through a pick under the document's light, as the app shows and picks it
  (:func:`sketchforge.plugin_api.isophote_through`).
- ``make_sculpt_edit(doc, layer, pick, offset, half=0.25, band=None, model=None)``: the journal
  entry of a sculpt edit that redraws the isophote through ``pick`` ``offset`` to its darker
  side (:func:`sculpt_edit`), to ``doc.execute``; what a sculpt solver's tests need.

Nothing here imports sketchforge until a fixture is used, so the plugin costs pytest nothing.
"""

from __future__ import annotations

import pytest


def _ellipse(n: int = 48, a: float = 1.0, b: float = 0.7):
    import numpy as np

    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.c_[a * np.cos(t), b * np.sin(t)]


def sculpt_edit(doc, layer: str, pick, offset: float, half: float = 0.25, band: float | None = None,
                model: str | None = None, command: str = "sculpt_isophote") -> dict:
    """A sculpt edit's journal entry: the isophote through ``pick`` redrawn ``offset`` to its
    side, as a person redraws it in the app (the isophote tool's ``sculpt_isophote``).

    Parameters
    ----------
    doc : Document
    layer : str
        The layer's id.
    pick : (2,) float64
        Where the isophote is picked.
    offset : float
        Sideways shift of the stroke, drawing units; > 0 towards the darker side.
    half : float
        Half the stroke's length along the isophote, on each side of the pick.
    band : float, optional
        The band radius; None: 2·|offset| + 0.05.
    model : str, optional
        A reflectance model's name (None: Lambertian); the entry names it.
    command : str
        The command the entry is for.

    Returns
    -------
    dict
        ``{"command", "layer", "pick", "band", "stroke"}`` (and ``"model"``), JSON values.
    """
    import numpy as np
    import shapely
    import shapely.ops

    from sketchforge.errors import SculptError
    from sketchforge.tools.queries import isophote_through

    mesh = doc.layer(layer).mesh
    if mesh is None:
        raise SculptError(f"layer {layer!r} has no surface: draw its outline first")
    reflectance = None if model is None else doc.host.reflectance_models[model]
    pick = np.asarray(pick, dtype=np.float64).reshape(2)
    _, line = isophote_through(mesh, pick, doc.light.direction, reflectance)
    iso = shapely.LineString(line)
    s0 = iso.project(shapely.Point(pick))
    piece = shapely.ops.substring(iso, max(s0 - half, 0.0), min(s0 + half, iso.length))
    if offset:
        # The brighter side is on the isophote's left: a positive offset goes right (darker).
        piece = piece.offset_curve(-float(offset))
        # GEOS may leave a stray short fragment on the concave side: keep the main curve.
        piece = max(getattr(piece, "geoms", [piece]), key=lambda g: g.length)
    entry = {"command": command, "layer": layer, "pick": [float(v) for v in pick],
             "band": float(band if band is not None else 2.0 * abs(offset) + 0.05),
             "stroke": np.asarray(piece.coords, dtype=np.float64)[:, :2].tolist()}
    if model is not None:
        entry["model"] = model
    return entry


@pytest.fixture
def make_sketchforge_host():
    def make(*plugins, installed=(), strict: bool = True):
        from sketchforge.plugins.testing import make_host

        host = make_host(*plugins, installed=installed)  # PluginError: a plugin given is broken or missing
        problems = host.validate()
        if strict and problems:
            pytest.fail("the host refused plugin contributions:\n" + "\n".join(problems))
        return host

    return make


@pytest.fixture
def make_sketchforge_document(make_sketchforge_host):
    def make(host=None, contour=None, layer: str = "a", closed: bool = True, inflater: str | None = None, **params):
        from sketchforge.document import Document

        host = make_sketchforge_host(installed=("inflate",)) if host is None else host
        doc = Document(host=host)
        if contour is not False:
            pts = _ellipse() if contour is None else contour
            doc.execute({"command": "add_layer", "id": layer})
            if inflater is not None:  # chosen before the first inflation: its own parameters only
                doc.execute({"command": "set_inflate_params", "layer": layer, "solver": inflater, "params": params})
            doc.execute({"command": "set_contour", "layer": layer, "points": [list(map(float, p)) for p in pts], "closed": closed})
            if params and inflater is None:
                doc.execute({"command": "set_inflate_params", "layer": layer, "params": params})
        return doc

    return make


@pytest.fixture
def assert_replays():
    def check(doc):
        from sketchforge.document import fileformat as ff

        replayed = ff.replay_journal(doc.initial_light, doc.journal(), "journal", host=doc.host)
        diffs = ff.compare(doc, replayed)
        assert not diffs, "replaying the journal differs: " + "; ".join(diffs)
        reloaded = ff.document_from_dict(__import__("json").loads(ff.dumps(doc)), "saved", host=doc.host, use_snapshot=False)
        diffs = ff.compare(doc, reloaded)
        assert not diffs, "replaying the saved file differs: " + "; ".join(diffs)
        return replayed

    return check


@pytest.fixture
def sketchforge_fan_inflater():
    from sketchforge.plugins.testing import FanInflater

    return FanInflater()


@pytest.fixture
def sketchforge_layer_at():
    from sketchforge.tools.queries import layer_at

    return layer_at


@pytest.fixture
def sketchforge_isophote():
    def isophote(doc, layer: str, pick, model: str | None = None):
        from sketchforge.tools.queries import isophote_through

        reflectance = None if model is None else doc.host.reflectance_models[model]
        return isophote_through(doc.layer(layer).mesh, pick, doc.light.direction, reflectance)

    return isophote


@pytest.fixture
def make_sculpt_edit():
    return sculpt_edit
