"""Screenshots of the app for the docs: ``python -m sketchforge.qt.screenshots DOC OUTDIR``.

Writes ``editing.png``, ``sculpt.png``, ``light-raised.png`` and ``light-panel.png`` (the light
raised 40°), ``sculpt-overhead.png`` (an edit under a light straight overhead),
``sculpt-two-isophotes.png`` (two isophotes redrawn in one edit) and, with the strips plugin installed,
``sculpt-strips.png`` (the same edit by the ``strips`` solver; these need no OpenGL: run with
``QT_QPA_PLATFORM=offscreen``) and, where OpenGL works (``xvfb-run -a`` with
``QT_QPA_PLATFORM=xcb``), ``observation.png``. ``sketchforge --screenshot`` is the same path for
one mode; the sculpt screenshot stages an isophote edit on the document's largest layer like a
person would: pick, band, redrawn stroke (applied when the isophote plugin is installed).

Issue 37's (:func:`plugin_screenshots`, also ``python -m sketchforge.qt.screenshots --plugins
DOC OUTDIR``): ``plugins-dialog.png`` (Help > Plugins, with two demonstration plugins that break
the rules: both claim the suffix ``.xyz``, and one's tool hook raises), ``params-creation.png``,
``params-sculpt.png`` (the ``strips`` solver's form unfolded) and ``params-assembly.png`` (the
generated parameter forms), and ``model-shading.png`` (the canvas shaded by the soft Lambert
reflectance model, when its example plugin is installed).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np


def stage_sculpt(window, app) -> None:
    """Pick an isophote on the largest visible layer and redraw it a little further out."""
    from sketchforge.qt.app import settle

    window.set_mode("sculpture")
    layers = [l for l in window.doc.layers if l.visible and l.mesh is not None]
    if not layers:
        return
    layer = max(layers, key=lambda l: np.ptp(l.mesh.V[:, 0]) * np.ptp(l.mesh.V[:, 1]))
    V = layer.mesh.V
    centre = 0.5 * (V[:, :2].min(axis=0) + V[:, :2].max(axis=0))
    half = 0.5 * np.ptp(V[:, :2], axis=0)
    light = window.doc.light.direction[:2]
    pick = centre + 0.45 * half * light
    sc = window.sculpt
    sc.set_radius(0.18 * float(min(half)))
    if not sc.pick(pick):
        return
    iso = np.asarray(sc._isophote)[:, :2]
    # the stroke: the picked isophote pushed towards the light by half the band radius
    stroke = iso + 0.5 * sc.radius * light
    sc.stroke_press(stroke[0])
    for p in stroke[1:]:
        sc.stroke_move(p)
    if sc.available():
        sc.stroke_release(stroke[-1])
        settle(window, app, timeout_s=300)
    # where the shading changed and where heights could change (dashed), and the
    # characteristics through the stroke (the tool panel's two "show" boxes follow)
    sc.set_show(strips=True, regions=True)
    settle(window, app)


def _largest(window):
    layers = [l for l in window.doc.layers if l.visible and l.mesh is not None]
    layer = max(layers, key=lambda l: np.ptp(l.mesh.V[:, 0]) * np.ptp(l.mesh.V[:, 1]))
    V = layer.mesh.V
    return 0.5 * (V[:, :2].min(axis=0) + V[:, :2].max(axis=0)), 0.5 * np.ptp(V[:, :2], axis=0)


def _draw(sc, stroke) -> None:
    sc.stroke_press(stroke[0])
    for p in stroke[1:]:
        sc.stroke_move(p)
    sc.stroke_release(stroke[-1])


def stage_raised_light(window, app) -> None:
    """EDITING with the light raised 40° above the drawing plane (the Light panel's disc)."""
    from sketchforge.document.layer import Light
    from sketchforge.qt.app import settle

    window.set_mode("editing")
    light = Light.from_angle(135.0, 40.0)
    window.set_light_elevation(light.elevation)
    window.set_light_angle(light.angle)
    settle(window, app)
    from PySide6.QtTest import QTest

    QTest.qWait(800)  # the layer thumbnails follow the light once it rests
    settle(window, app)


def _bump(piece: np.ndarray, direction, amount: float) -> np.ndarray:
    """``piece`` (k, 2) moved by ``amount`` along ``direction`` (2,) or (k, 2) in its middle,
    ends kept (a sine profile): a hand-drawn local redraw."""
    t = np.linspace(0.0, 1.0, len(piece))
    return piece + amount * np.sin(np.pi * t)[:, None] * np.asarray(direction, dtype=np.float64)


def _middle(iso: np.ndarray, around, length: float) -> np.ndarray:
    """The stretch of the polyline ``iso`` (k, 2) within ``length`` of arc of its point nearest
    to ``around``."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(iso, axis=0), axis=1))])
    s0 = s[int(np.argmin(np.linalg.norm(iso - around, axis=1)))]
    return iso[np.abs(s - s0) <= length]


def stage_overhead_edit(window, app) -> None:
    """The light straight overhead (the isophotes are contour lines of the slope: rings about
    each part's crest; 8 lines drawn), and one of them redrawn: a piece pushed outwards."""
    from sketchforge.qt.app import settle

    window.set_light_elevation(90.0)
    window.canvas.set_isoline_count(8)
    window.set_mode("sculpture")
    centre, half = _largest(window)
    sc = window.sculpt
    sc.set_radius(0.2 * float(min(half)))
    pick = centre + [-0.55 * half[0], 0.1 * half[1]]
    if not sc.pick(pick):
        return
    piece = _middle(np.asarray(sc._isophote)[:, :2], pick, 0.9 * float(min(half)))
    if len(piece) < 4:
        return
    out = (piece - centre) / np.linalg.norm(piece - centre, axis=1, keepdims=True)
    _draw(sc, _bump(piece, out, 0.8 * sc.radius))
    settle(window, app, timeout_s=300)


def stage_two_isophotes(window, app) -> None:
    """Two isophotes picked (click, then Shift+click), each redrawn towards the light in its
    middle: one edit, applied when the second stroke is released."""
    from sketchforge.qt.app import settle

    window.set_mode("sculpture")
    centre, half = _largest(window)
    light = window.doc.light.direction[:2]
    light = light / max(float(np.linalg.norm(light)), 1e-12)
    sc = window.sculpt
    sc.set_radius(0.16 * float(min(half)))
    picks = [centre + 0.55 * half * light, centre + 0.15 * half * light]
    if not (sc.pick(picks[0]) and sc.pick(picks[1], add=True)):
        return
    for p, at in zip(sc.tool.picks, picks):
        _draw(sc, _bump(_middle(p.isophote, at, 0.8 * float(min(half))), light, 0.7 * sc.radius))
    settle(window, app, timeout_s=300)


class _DemoFormats:
    """A demonstration plugin for the Plugins screenshot: an exporter of ``.xyz``."""

    def __init__(self, name: str) -> None:
        self.__name__ = name

    def sketchforge_exporters(self):
        from sketchforge.plugin_api import Exporter

        return [Exporter(f"{self.__name__}_xyz", (".xyz",), lambda path, mesh: None)]


class _DemoBrokenTools:
    """A demonstration plugin whose tool hook raises (a half-installed package)."""

    __name__ = "demo_broken_tools"

    def sketchforge_tools(self):
        raise ImportError("No module named 'demo_backend'")


def _demo_plugins() -> list:
    from sketchforge.plugin_api import hookimpl

    out = []
    for obj in (_DemoFormats("demo_points"), _DemoFormats("demo_scans"), _DemoBrokenTools()):
        for name in ("sketchforge_exporters", "sketchforge_tools"):
            fn = getattr(type(obj), name, None)
            if fn is not None:
                setattr(type(obj), name, hookimpl(fn))
        out.append(obj)
    return out


def plugin_screenshots(doc_path: Path, out: Path) -> None:
    """The Plugins dialog, the generated parameter forms and a reflectance model's shading."""
    from sketchforge.document import fileformat as ff
    from sketchforge.document.document import Document
    from sketchforge.plugins.manager import PluginHost
    from sketchforge.qt.app import WINDOW_SIZE, ensure_qapp, settle
    from sketchforge.qt.main_window import MainWindow

    app = ensure_qapp()
    host = PluginHost.create(_demo_plugins(), skip_broken=True)
    w = MainWindow(Document(host=host), host=host)
    w.resize(*WINDOW_SIZE)
    w.adopt(ff.load(doc_path, host=host), doc_path)
    w.show()
    w.canvas.fit()
    settle(w, app)
    dialog = w.show_plugins()
    dialog.resize(820, 700)
    settle(w, app)
    dialog.grab().save(str(out / "plugins-dialog.png"))
    dialog.close()
    biggest = max((l for l in w.doc.layers if l.mesh is not None), key=lambda l: l.mesh.n_vertices)
    w.layers_panel.select(biggest.id)
    settle(w, app)
    panel = w.plugin_panels.get("isophote_sculpt")
    if panel is not None and panel.solver.findData("strips") >= 0:
        w.set_mode("sculpture")
        panel.solver.setCurrentIndex(panel.solver.findData("strips"))
        panel.params.toggle.setChecked(True)
        settle(w, app)
        w.sculpt_panel.grab().save(str(out / "params-sculpt.png"))
    w.set_mode("observation")
    settle(w, app)
    w.assembly_panel.grab().save(str(out / "params-assembly.png"))
    w.set_mode("editing")
    shadings = w.creation_panel.shader
    if shadings.findData("model:soft_lambert") >= 0:
        from sketchforge.document.layer import Light

        light = Light.from_angle(135.0, 40.0)
        w.set_light_elevation(light.elevation)
        w.set_light_angle(light.angle)
        shadings.setCurrentIndex(shadings.findData("model:soft_lambert"))
        w.creation_panel.isolines.setValue(6)
        settle(w, app)
        w.canvas.render_now()
        w.center.grab().save(str(out / "model-shading.png"))
    w.creation_panel.grab().save(str(out / "params-creation.png"))
    w.close_now()
    print(f"wrote the plugin screenshots in {out}", file=sys.stderr)


def main(argv=None) -> int:
    from PySide6.QtGui import QGuiApplication

    from sketchforge.document import fileformat as ff
    from sketchforge.document.document import Document
    from sketchforge.qt.app import WINDOW_SIZE, ensure_qapp, grab_window, plugin_host, settle
    from sketchforge.qt.main_window import MainWindow
    from sketchforge.qt.view3d import gl_unavailable_reason

    argv = list(sys.argv[1:] if argv is None else argv)
    only_plugins = argv[:1] == ["--plugins"]
    argv = argv[1:] if only_plugins else argv
    if len(argv) != 2:
        print("usage: python -m sketchforge.qt.screenshots DOC OUTDIR", file=sys.stderr)
        return 2
    doc_path, out = Path(argv[0]), Path(argv[1])
    out.mkdir(parents=True, exist_ok=True)
    plugin_screenshots(doc_path, out)
    if only_plugins:
        return 0
    app = ensure_qapp()
    host = plugin_host()

    def window_on_doc():
        w = MainWindow(Document(host=host), host=host)
        w.resize(*WINDOW_SIZE)
        w.adopt(ff.load(doc_path, host=host), doc_path)
        w.show()
        w.canvas.fit()
        settle(w, app)
        return w

    if gl_unavailable_reason() is None:
        w = window_on_doc()
        w.set_mode("observation")
        settle(w, app)
        settle(w, app)
        grab_window(w, out / "observation.png")
        w.close_now()
        print(f"wrote {out / 'observation.png'}", file=sys.stderr)
    else:
        print(f"skipped observation.png ({QGuiApplication.platformName()} platform: no OpenGL)", file=sys.stderr)

    w = window_on_doc()
    grab_window(w, out / "editing.png")
    print(f"wrote {out / 'editing.png'}", file=sys.stderr)
    stage_sculpt(w, app)
    grab_window(w, out / "sculpt.png")
    print(f"wrote {out / 'sculpt.png'}", file=sys.stderr)
    w.close_now()
    # Beyond the thesis (issue 35): a raised light, an edit under an overhead one, and two
    # isophotes redrawn in one edit.
    w = window_on_doc()
    stage_raised_light(w, app)
    grab_window(w, out / "light-raised.png")
    w.light_panel.grab().save(str(out / "light-panel.png"))
    print(f"wrote {out / 'light-raised.png'} and {out / 'light-panel.png'}", file=sys.stderr)
    w.close_now()
    for name, stage in (("sculpt-overhead.png", stage_overhead_edit), ("sculpt-two-isophotes.png", stage_two_isophotes)):
        w = window_on_doc()
        stage(w, app)
        grab_window(w, out / name)
        print(f"wrote {out / name}: {w.sculpt.status}", file=sys.stderr)
        w.close_now()
    if "strips" in host.solvers("sculpt"):
        # The same edit with the thesis' solver, chosen in the panel as a person would.
        w = window_on_doc()
        w.set_mode("sculpture")
        panel = w.plugin_panels.get("isophote_sculpt")
        combo = getattr(panel, "solver", None)
        if combo is not None and combo.findData("strips") >= 0:
            combo.setCurrentIndex(combo.findData("strips"))
            stage_sculpt(w, app)
            grab_window(w, out / "sculpt-strips.png")
            print(f"wrote {out / 'sculpt-strips.png'}", file=sys.stderr)
        w.close_now()
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
