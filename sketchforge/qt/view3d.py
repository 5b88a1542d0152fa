"""OBSERVATION mode: the model in 3D (pyqtgraph.opengl), flat shaded, with an orbit camera.

The OpenGL widget is created the first time observation mode is shown, so the editing view
never needs OpenGL (it runs with ``QT_QPA_PLATFORM=offscreen``; OpenGL needs a display, e.g.
Xvfb with the xcb platform). Shows the assembled model (computed by the assemble plugin on a
pool thread) or each visible layer's own mesh.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import QLabel, QStackedLayout, QWidget

from sketchforge.qt.errors_ui import error_text

#: Platforms where QOpenGLWidget cannot work.
NO_GL_PLATFORMS = ("offscreen", "minimal")
CLAY = (0.84, 0.74, 0.62, 1.0)
LAYER_COLOURS = ((0.84, 0.74, 0.62, 1), (0.62, 0.74, 0.84, 1), (0.70, 0.84, 0.62, 1), (0.84, 0.62, 0.70, 1))


#: Flat shading with a light at the viewer's upper right (eye coordinates), so the faces that
#: face the camera are lit (pyqtgraph's own "shaded" program lights from behind the scene).
SHADER_NAME = "sketchforge_headlight"


def _register_shader() -> None:
    from pyqtgraph.opengl import shaders

    if SHADER_NAME in shaders.ShaderProgram.names:
        return
    vertex, _fragment = shaders.getShaderProgram("shaded").shaders
    shaders.ShaderProgram(
        SHADER_NAME,
        [
            vertex,
            shaders.FragmentShader(
                """
                #ifdef GL_ES
                precision mediump float;
                #endif
                varying vec4 v_color;
                varying vec3 v_normal;
                void main() {
                    float p = dot(normalize(v_normal), normalize(vec3(0.4, 0.5, 1.0)));
                    p = p < 0. ? 0.15 * -p : p;
                    gl_FragColor = vec4(v_color.rgb * (0.25 + 0.75 * p), v_color.a);
                }
                """
            ),
        ],
    )


def gl_unavailable_reason() -> str | None:
    platform = QGuiApplication.platformName()
    if platform in NO_GL_PLATFORMS:
        return (
            f"The 3D view needs OpenGL, which the '{platform}' Qt platform does not offer. "
            "Run with a display (under Xvfb: xvfb-run -a with QT_QPA_PLATFORM=xcb)."
        )
    return None


class View3D(QWidget):
    message = Signal(str)
    #: the assembled model now on display (None: layers or nothing are shown); an animation
    #: front end poses ``model_item`` (the model's GLMeshItem) from it
    assembled_shown = Signal(object)

    def __init__(self, doc, jobs, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.jobs = jobs
        self.source = "assembled"
        self.gl = None
        self.model_item = None
        self._items: list = []
        self._job = None
        #: (doc.geometry_revision, mesh) of the last assembly, so that switching modes or the
        #: source back does not assemble an unchanged document again
        self._assembled: tuple[int, object] | None = None
        self._layout = QStackedLayout(self)
        self.info = QLabel("")
        self.info.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.info.setWordWrap(True)
        self._layout.addWidget(self.info)
        self._active = False
        doc.assembly_invalidated.connect(self._invalidated)

    # --- lifecycle ------------------------------------------------------------------------------
    def ensure_gl(self) -> bool:
        if self.gl is not None:
            return True
        reason = gl_unavailable_reason()
        if reason is not None:
            self.info.setText(reason)
            return False
        import pyqtgraph.opengl as gl  # lazily: importing it needs no context, using it does

        _register_shader()
        self.gl = gl.GLViewWidget()
        self.gl.setBackgroundColor((236, 234, 230, 255))
        grid = gl.GLGridItem()
        grid.setColor((0, 0, 0, 40))
        grid.setDepthValue(-10)  # drawn first: the model covers it
        self.gl.addItem(grid)
        self._grid = grid
        self._layout.addWidget(self.gl)
        self._layout.setCurrentWidget(self.gl)
        return True

    def activate(self) -> None:
        self._active = True
        if self.ensure_gl():
            self.refresh()

    def deactivate(self) -> None:
        self._active = False

    def set_source(self, source: str) -> None:
        self.source = source
        if self._active and self.gl is not None:
            self.refresh()

    def _invalidated(self) -> None:
        if self._active and self.gl is not None:
            self.refresh()

    # --- content ---------------------------------------------------------------------------------
    def refresh(self) -> None:
        parts = [l for l in self.doc.layers if l.visible and l.mesh is not None]
        if not parts:
            self._show([], "nothing to show: draw a contour in EDITING mode")
            return
        if self.source == "layers":
            self._show([(l.mesh, LAYER_COLOURS[i % len(LAYER_COLOURS)]) for i, l in enumerate(parts)], "")
            return
        if not self.doc.host.has_assembler():
            self._show([(l.mesh, CLAY) for l in parts], "assemble plugin not installed: showing the layers' own meshes")
            return
        revision = self.doc.geometry_revision
        if self._assembled is not None and self._assembled[0] == revision:
            self._show_assembled(self._assembled[1], parts)
            return
        if self._job is not None and not self._job.done and not self._job.cancelled:
            if self._job.revision == revision:
                return  # this very assembly is under way
            self._job.cancel()
        host = self.doc.host
        layers = list(parts)  # immutable values: safe to read on the pool thread

        def done(mesh):
            self._job = None
            self._assembled = (revision, mesh)
            self.doc.offer_assembled(revision, mesh)  # export and pins need not assemble again
            self._show_assembled(mesh, layers)

        def failed(exc, tb):
            self._job = None
            self._show([(l.mesh, CLAY) for l in layers], f"assembly failed: {error_text(exc)}")

        self._job = self.jobs.start(lambda: host.assemble(layers, {}), done, failed, label="Assembling")
        self._job.revision = revision

    def _show_assembled(self, mesh, layers) -> None:
        if mesh is None:
            self._show([(l.mesh, CLAY) for l in layers], "the assembler returned nothing; showing the layers")
        else:
            self._show([(mesh, CLAY)], "")
            self.model_item = self._items[0] if self._items else None
        self.assembled_shown.emit(mesh)

    def _show(self, meshes, note: str) -> None:
        import pyqtgraph.opengl as gl

        if note:
            self.message.emit(note)
        for item in self._items:
            self.gl.removeItem(item)
        self._items = []
        if self.model_item is not None:
            self.model_item = None
            self.assembled_shown.emit(None)
        allv = []
        for mesh, colour in meshes:
            md = gl.MeshData(vertexes=np.asarray(mesh.V, dtype=np.float32), faces=np.asarray(mesh.F, dtype=np.int32))
            item = gl.GLMeshItem(meshdata=md, smooth=False, shader=SHADER_NAME, color=colour, glOptions="opaque")
            # The drawing stands upright: document (x, y, z) -> world (x, -z, y), so the grid is
            # the ground, y is up and the viewer of the drawing looks along world +y.
            item.rotate(90, 1, 0, 0)
            self.gl.addItem(item)
            self._items.append(item)
            allv.append(mesh.V)
        if allv:
            V = np.concatenate(allv)
            lo, hi = V.min(axis=0), V.max(axis=0)
            centre = 0.5 * (lo + hi)
            size = float(np.max(hi - lo)) or 1.0
            from PySide6.QtGui import QVector3D

            self._grid.resetTransform()
            self._grid.setSize(2 * size, 2 * size)
            self._grid.setSpacing(size / 10, size / 10)
            self._grid.translate(float(centre[0]), -float(centre[2]), float(lo[1]))
            self.gl.setCameraPosition(
                pos=QVector3D(float(centre[0]), -float(centre[2]), float(centre[1])),
                distance=1.9 * size,
                elevation=18,
                azimuth=-65,
            )
