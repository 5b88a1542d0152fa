"""pytest fixtures for plugin authors, shipped with sketchforge (entry point ``pytest11``), as
napari ships ``make_napari_viewer``: installing sketchforge makes them available in any test.

- ``make_sketchforge_host(*plugins, installed=(), strict=True)``: a host with the core plugin,
  your plugin objects or modules, and the installed entry points named in ``installed``
  (e.g. ``("inflate",)`` for real meshes); nothing else that happens to be installed. With
  ``strict`` a contribution the host refuses (a broken contract, a hook that raised) fails
  the test with the host's message.
- ``make_sketchforge_document(host=None, contour=ELLIPSE, layer="a", inflater=None, **params)``:
  a document with one layer inflated from ``contour`` by the inflater named ``inflater``
  (None: the host's default) with ``params`` (checked by that inflater); needs an inflater in
  the host: ``installed=("inflate",)`` or :class:`~sketchforge.plugins.testing.FanInflater`.
- ``assert_replays(doc)``: replays the document's journal headlessly, and reloads it from the
  saved file, and asserts both are bit-identical to ``doc`` (layers, meshes, light, plugin
  data); returns the replayed document. The check every command must pass.

Nothing here imports sketchforge until a fixture is used, so the plugin costs pytest nothing.
"""

from __future__ import annotations

import pytest


def _ellipse(n: int = 48, a: float = 1.0, b: float = 0.7):
    import numpy as np

    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.c_[a * np.cos(t), b * np.sin(t)]


@pytest.fixture
def make_sketchforge_host():
    def make(*plugins, installed=(), strict: bool = True):
        from sketchforge.plugins.manager import PluginHost

        host = PluginHost.create(plugins, load_entry_points=bool(installed), allowlist=list(installed))
        missing = [name for name in installed if name not in host.plugin_names()]
        if missing:
            pytest.fail(f"entry points {missing} are not installed (pip install the plugins that provide them)")
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
