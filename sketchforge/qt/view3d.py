"""OBSERVATION mode: the model in 3D (pyqtgraph.opengl), smooth shaded, with an orbit camera.

Normals are per triangle corner from the geometry core (smooth, creases only where the surface
folds). The camera frames the model the first time it is shown and on "Fit view"; orbit and zoom
are kept when the source (assembled / per layer) changes or the model is rebuilt. Display styles:
"shaded" (a head light), "cel" (the three cel tones of the document's light, in the drawing
plane or raised above it) and
"isophotes" (shaded, with lines n·l = j/(K+1) of the document's light), computed per pixel in
the fragment shader from the interpolated model-space normal, as on the canvas.

The OpenGL widget (:class:`sketchforge.qt.glview.GLView`: pyqtgraph's 3D view rendered
offscreen) is created the first time observation mode is shown, so the editing view
never needs OpenGL (it runs with ``QT_QPA_PLATFORM=offscreen``; OpenGL needs a display, e.g.
Xvfb with the xcb platform). Shows the assembled model (computed by the assemble plugin on a
pool thread) or each visible layer's own mesh.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import numpy as np
from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import QLabel, QStackedLayout, QWidget

from sketchforge.qt.errors_ui import error_text

if TYPE_CHECKING:  # imported when the first 3D view is made (OpenGL)
    from sketchforge.qt.glview import GLView

#: Platforms where QOpenGLWidget cannot work.
NO_GL_PLATFORMS = ("offscreen", "minimal")
CLAY = (0.84, 0.74, 0.62, 1.0)
LAYER_COLOURS = ((0.84, 0.74, 0.62, 1), (0.62, 0.74, 0.84, 1), (0.70, 0.84, 0.62, 1), (0.84, 0.62, 0.70, 1))
#: A layer an assembly error names.
FAILED_COLOUR = (0.88, 0.30, 0.24, 1.0)


#: Smooth shading with a light at the viewer's upper right (eye coordinates), so the faces that
#: face the camera are lit (pyqtgraph's own "shaded" program lights from behind the scene), and
#: the document light's cel tones or isophote lines (model coordinates = document coordinates).
#: One program per style (``shader_name(style)``): llvmpipe, the software OpenGL of a machine
#: without a GPU, runs every branch of a shader for every pixel, so one program choosing the
#: style per pixel cost its rasteriser threads ~13 ms more per frame of the 16k-vertex model
#: than the shaded style's own program (issue 34: a played frame cost 52 ms in all).
SHADER_NAME = "sketchforge_observe"
#: Display styles (the program of each is ``shader_name(style)``).
STYLES = {"shaded": 0.0, "cel": 1.0, "isophotes": 2.0}
#: Field of view (degrees, horizontal) and the share of the smaller view side the model fills.
FOV = 45.0
FILL = 0.92
#: Dihedral angle (degrees) beyond which the surface is drawn with a crease.
CREASE_DEG = 50.0

_VERTEX = """
uniform mat4 u_mvp;
uniform mat3 u_normal;
attribute vec4 a_position;
attribute vec3 a_normal;
attribute vec4 a_color;
varying vec4 v_color;
varying vec3 v_normal;
varying vec3 v_model_normal;
void main() {
    v_normal = normalize(u_normal * a_normal);
    v_model_normal = a_normal;
    v_color = a_color;
    gl_Position = u_mvp * a_position;
}
"""
#: The isophotes style's vertex shader: the head light's shading and n·l of the document's
#: light, per vertex. Why: llvmpipe (software OpenGL) spent 18 ms of its rasteriser threads per
#: played frame of the 16k-vertex model on the per-pixel normalizes, dots and line test (the
#: frame cost 34 ms of CPU in all, 25 shaded; issue 34 asks 30); with both per vertex, 11 ms
#: (26 in all). An isophote of a triangle mesh is piecewise linear anyway: the product finds
#: the curves it sculpts from per-vertex shading (:func:`sketchforge.geometry.isophotes.isophotes`),
#: so lines through the interpolated per-vertex value are the lines it works with; and the
#: shading, interpolated over ~2-pixel triangles, differs from the per-pixel one in 0.7% of the
#: pixels by more than 10 of 255 (frame 12 of examples/animated.json, compared side by side
#: at 3x: no facets). The line count stays a fragment uniform only: Mesa refused to validate
#: the program with one uniform declared in both stages, and the model was not drawn.
_VERTEX_ISOPHOTES = """
uniform mat4 u_mvp;
uniform mat3 u_normal;
uniform float u_light[3];
attribute vec4 a_position;
attribute vec3 a_normal;
attribute vec4 a_color;
varying vec4 v_color;
varying vec3 v_normal;
varying float v_e;
varying float v_lit;
void main() {
    v_normal = normalize(u_normal * a_normal);
    float p = dot(v_normal, normalize(vec3(0.4, 0.5, 1.0)));
    v_lit = 0.25 + 0.75 * (p < 0. ? 0.15 * -p : p);
    v_e = dot(normalize(a_normal), vec3(u_light[0], u_light[1], u_light[2]));
    v_color = a_color;
    gl_Position = u_mvp * a_position;
}
"""

_HEADER = """
#ifdef GL_ES
%(extension)s
precision mediump float;
#endif
varying vec4 v_color;
varying vec3 v_normal;
"""
#: The head light's shading of the clay colour, per pixel (shaded style).
_LIT = """
    float p = dot(normalize(v_normal), normalize(vec3(0.4, 0.5, 1.0)));
    p = p < 0. ? 0.15 * -p : p;
    vec3 rgb = v_color.rgb * (0.25 + 0.75 * p);
"""
#: n·l of the document's light, per pixel (cel style; the isophotes style takes it per vertex).
_LIGHT = """
    float e = dot(normalize(v_model_normal), vec3(u_light[0], u_light[1], u_light[2]));
"""
#: style -> (fragment shader body, its uniforms and their initial values)
_FRAGMENTS = {
    "shaded": ("void main() {" + _LIT + "    gl_FragColor = vec4(rgb, v_color.a);\n}\n", {}),
    "cel": ("uniform float u_light[3];\nvarying vec3 v_model_normal;\nvoid main() {" + _LIGHT + """
    vec3 rgb = e <= 0.0 ? vec3(%(t0)s) : (e <= 0.5 ? vec3(%(t1)s) : vec3(%(t2)s));
    gl_FragColor = vec4(rgb, v_color.a);
}
""", {"u_light": [1.0, 0.0, 0.0]}),
    "isophotes": ("""uniform float u_lines;
varying float v_e;
varying float v_lit;
void main() {
    vec3 rgb = v_color.rgb * v_lit;
    float t = v_e * (u_lines + 1.0);
    float d = abs(t - clamp(floor(t + 0.5), 1.0, u_lines));
    float line = 1.0 - clamp(d / max(fwidth(t), 1e-6) - 0.1, 0.0, 1.0);
    rgb = mix(rgb, vec3(0.12, 0.10, 0.10), 0.85 * line);
    gl_FragColor = vec4(rgb, v_color.a);
}
""", {"u_light": [1.0, 0.0, 0.0], "u_lines": [8.0]}),
}


def shader_name(style: str) -> str:
    """The name of the shader program drawing ``style`` (registered by ``_register_shader``)."""
    return f"{SHADER_NAME}_{style}"


def _register_shader() -> None:
    from pyqtgraph.opengl import shaders

    from sketchforge.geometry.shaders import CEL_TONES

    tones = {f"t{i}": ", ".join(f"{c:.4f}" for c in CEL_TONES[i]) for i in range(3)}
    for style, (body, uniforms) in _FRAGMENTS.items():
        if shader_name(style) in shaders.ShaderProgram.names:
            continue
        extension = "#extension GL_OES_standard_derivatives : enable" if "fwidth" in body else ""
        source = _HEADER % {"extension": extension} + body % tones
        vertex = _VERTEX_ISOPHOTES if style == "isophotes" else _VERTEX
        shaders.ShaderProgram(shader_name(style), [shaders.VertexShader(vertex), shaders.FragmentShader(source)],
                              uniforms=dict(uniforms))


@functools.cache
def _mesh_item_class():
    """GLMeshItem drawing given per-corner normals (pyqtgraph would average face normals)."""
    import pyqtgraph.opengl as gl
    from OpenGL import GL
    from pyqtgraph.opengl.items.GLMeshItem import DirtyFlag

    from sketchforge.geometry.normals import crease_groups, faces_outward, group_normals, shading_vertices

    class CornerNormalMeshItem(gl.GLMeshItem):
        """The model with smooth normals that keep its creases, drawn as an indexed mesh: the
        corners that shade alike share one vertex (about one per mesh vertex, a few more along
        creases), so a posed frame (``set_positions``) computes, converts and uploads ~16k
        positions and normals at 16k vertices instead of 96k corners, and the renderer
        transforms as few. The creases are found once, at rest.

        A closed model whose triangles face out (the assembled model, not a layer's open
        sheet) is drawn without the triangles that face away: they are hidden anyway, and
        software OpenGL shades many before the ones in front cover them (~30% of the model's
        drawing cost). Where a pose folds the surface over itself, the surface behind the
        fold shows instead of the fold's dark back."""

        def __init__(self, V, F, rim_pairs=None, rim_weights=None, **kwds):
            V = np.asarray(V, dtype=np.float64)
            self._F = np.asarray(F, dtype=np.int64)
            groups = crease_groups(V, self._F, CREASE_DEG, rim_pairs, rim_weights)  # an assembled model's rims shade round
            self._src, tris, self._rows = shading_vertices(self._F, groups)
            super().__init__(smooth=True, computeNormals=False, **kwds)
            if faces_outward(V, self._F):
                self.updateGLOptions({GL.GL_CULL_FACE: True, "glCullFace": (GL.GL_BACK,), "glFrontFace": (GL.GL_CCW,)})
            # pyqtgraph's MeshData is not used: the arrays below are what is drawn
            self.faces = np.ascontiguousarray(tris, dtype=np.uint32)
            self._dirty = DirtyFlag.FACES
            self.set_positions(V)

        def set_positions(self, V) -> None:
            """New vertex positions (n, 3) for the same triangles (a posed frame), with their
            own normals: the creases found at rest are kept, the shading follows the pose.
            Only the positions and normals are uploaded at the next paint."""
            V = np.asarray(V, dtype=np.float64)
            self.vertexes = np.ascontiguousarray(V[self._src], dtype=np.float32)
            self.normals = np.ascontiguousarray(group_normals(V, self._F, self._rows), dtype=np.float32)
            self._dirty |= DirtyFlag.POSITION | DirtyFlag.NORMAL
            self.update()

        def setMeshData(self, **kwds):  # noqa: N802 - pyqtgraph's name
            if getattr(self, "_dirty", None) is not None:
                raise TypeError("the model's mesh item takes new positions through set_positions(V)")
            super().setMeshData(**kwds)  # pyqtgraph's own constructor: an empty MeshData

        def parseMeshData(self):  # noqa: N802 - pyqtgraph's name
            dirty, self._dirty = self._dirty, DirtyFlag(0)
            return dirty

    return CornerNormalMeshItem


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
        self.gl: GLView | None = None
        self.model_item = None
        self._items: list = []
        self._job = None
        #: (doc.geometry_revision, mesh) of the last assembly, so that switching modes or the
        #: source back does not assemble an unchanged document again
        self._assembled: tuple[int, object] | None = None
        self.shading_style = "shaded"
        self.isophote_count = 8
        self._framed = False  # the camera was framed on a model: keep the user's orbit from now
        self._bounds = None  # (centre, radius) of a sphere around what is shown (document units)
        self._layout = QStackedLayout(self)
        #: Why the assembled model is not shown (an assembly that failed, naming the part), over
        #: the top of the view for as long as it holds; hidden when an assembly succeeds. A
        #: child laid over the stack, not in a layout: the OpenGL widget keeps its parent.
        self.banner = QLabel("", self)
        self.banner.setWordWrap(True)
        self.banner.setStyleSheet("QLabel { background: #f6d8d2; color: #5a1408; padding: 6px; }")
        self.banner.setVisible(False)
        self.info = QLabel("")
        self.info.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.info.setWordWrap(True)
        self._layout.addWidget(self.info)
        #: The last assembly failure (a sentence naming the part), or None.
        self.failure: str | None = None
        #: What the assembler said about the model on show although it assembled: the parts it
        #: had to leave free, each with why (issue 34); shown in a softer banner.
        self.notice: list[str] = []
        self._active = False
        self.shown: list = []
        doc.assembly_invalidated.connect(self._invalidated)
        doc.light_changed.connect(lambda *a: self._apply_style())

    # --- lifecycle ------------------------------------------------------------------------------
    def ensure_gl(self) -> bool:
        if self.gl is not None:
            return True
        reason = gl_unavailable_reason()
        if reason is not None:
            self.info.setText(reason)
            return False
        import pyqtgraph.opengl as gl  # lazily: importing it needs no context, using it does

        from sketchforge.qt.glview import GLView

        view = GLView()
        problem = view.create_context()
        if problem is not None:
            view.deleteLater()
            self.info.setText(f"The 3D view needs OpenGL: {problem}.")
            return False
        _register_shader()
        self.gl = view
        self.gl.setBackgroundColor((236, 234, 230, 255))
        grid = gl.GLGridItem()
        grid.setColor((0, 0, 0, 40))
        grid.setDepthValue(-10)  # drawn first: the model covers it
        self.gl.addItem(grid)
        self._grid = grid
        self._layout.addWidget(self.gl)
        self._layout.setCurrentWidget(self.gl)
        self._apply_style()
        return True

    # --- display style and camera ------------------------------------------------------------
    def set_style(self, style: str, isophotes: int | None = None) -> None:
        """"shaded", "cel" or "isophotes" (with ``isophotes`` lines, default 8)."""
        if style not in STYLES:
            raise ValueError(f"unknown 3D display style {style!r}: one of {', '.join(STYLES)}")
        self.shading_style = style
        if isophotes is not None:
            self.isophote_count = max(1, int(isophotes))
        self._apply_style()

    def _apply_style(self) -> None:
        if self.gl is None:
            return
        from pyqtgraph.opengl import shaders

        l = np.asarray(self.doc.light.direction, dtype=np.float64)
        light = [float(x) for x in l / max(np.linalg.norm(l), 1e-12)]
        for style in ("cel", "isophotes"):
            shaders.getShaderProgram(shader_name(style))["u_light"] = light
        shaders.getShaderProgram(shader_name("isophotes"))["u_lines"] = [float(self.isophote_count)]
        for item in self._items:
            item.setShader(shader_name(self.shading_style))
        self.gl.update()

    def reframe(self) -> None:
        """Frame the model again the next time it is shown (a new document)."""
        self._framed = False

    def fit(self) -> None:
        """Frame what is shown: centred, filling FILL of the smaller side of the view."""
        if self.gl is None or self._bounds is None:
            return
        from PySide6.QtGui import QVector3D

        centre, radius = self._bounds
        w, h = max(self.gl.width(), 1), max(self.gl.height(), 1)
        half_h = np.arctan(np.tan(np.radians(0.5 * FOV)) * h / w)  # vertical half-angle
        half = min(np.radians(0.5 * FOV), half_h)
        distance = radius / np.sin(half) / FILL
        self.gl.setCameraParams(fov=FOV)
        self.gl.setCameraPosition(
            pos=QVector3D(float(centre[0]), -float(centre[2]), float(centre[1])),
            distance=float(distance),
            elevation=18,
            azimuth=-65,
        )
        self._framed = True

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
            self._set_failure(None)
            self._set_notice([])
            self._show([], "nothing to show: draw a contour in EDITING mode")
            return
        if self.source == "layers":
            # Each layer's own mesh never needs the assembly: usable whatever it says.
            self._show(self._layer_meshes(parts), "")
            self._update_banner()
            return
        if not self.doc.host.has_assembler():
            self._show([(l.mesh, CLAY) for l in parts], "assemble plugin not installed: showing the layers' own meshes")
            return
        revision = self.doc.geometry_revision
        if self._assembled is not None and self._assembled[0] == revision:
            self._set_failure(None)
            self._show_assembled(self._assembled[1], parts)
            return
        if self._job is not None and not self._job.done and not self._job.cancelled:
            if self._job.revision == revision:
                return  # this very assembly is under way
            self._job.cancel()
        host = self.doc.host
        layers = list(parts)  # immutable values: safe to read on the pool thread
        # A junction that runs off its host fails the assembly: said at once, from the
        # document's own attachment rule, instead of after the assembly job (which can wait
        # behind other work), and the assembly is still run to confirm it.
        # A part whose junction the document's rule cannot glue will be assembled free: said
        # at once, before the assembly job (which can wait behind other work) confirms it.
        problems = self._junction_problems()
        if problems:
            self._set_notice([text for _, text in problems])

        def done(mesh):
            self._job = None
            self._assembled = (revision, mesh)
            self.doc.offer_assembled(revision, mesh)  # export and pins need not assemble again
            self._set_failure(None)
            self._show_assembled(mesh, layers)

        def failed(exc, tb):
            self._job = None
            self._fail(error_text(exc), layers)

        choice = self.doc.assembly  # the document's assembler and its parameters (set_assembly)
        self._job = self.jobs.start(lambda: host.assemble(layers, dict(choice.params), choice.solver), done, failed,
                                    label="Assembling")
        self._job.revision = revision

    # --- assembly failures -----------------------------------------------------------------------
    def _junction_problems(self) -> list:
        from sketchforge.document.commands import attachments

        shown = {l.id for l in self.doc.layers if l.visible and l.mesh is not None}
        return [(lid, problem[0].upper() + problem[1:]) for lid, (_, problem) in attachments(self.doc, shown).items()
                if problem]

    def _layer_meshes(self, layers, culprits=()) -> list:
        """Each layer's mesh in its own colour; the layers an error names in red."""
        return [(l.mesh, FAILED_COLOUR if l.id in culprits else LAYER_COLOURS[i % len(LAYER_COLOURS)]) for i, l in enumerate(layers)]

    def _fail(self, text: str, layers, culprits=None) -> None:
        """Show why the assembly failed: in the status bar and a banner over the view, naming
        the part, with each layer's own mesh shown meanwhile (the named ones in red)."""
        if culprits is None:  # the assembler's sentence names the part first, by its name, quoted
            at = {l.id: min((text.find(f"'{n}'") for n in (l.name, l.id) if n and f"'{n}'" in text), default=-1) for l in layers}
            named = sorted((i, lid) for lid, i in at.items() if i >= 0)
            culprits = [named[0][1]] if named else []
        self._set_failure(text)
        self._show(self._layer_meshes(layers, set(culprits)), f"assembly failed: {text}")

    def _set_failure(self, text: str | None) -> None:
        self.failure = text
        self._update_banner()

    def _set_notice(self, warnings) -> None:
        self.notice = [str(w) for w in warnings]
        self._update_banner()

    #: How many of the assembler's warnings the banner lists (the rest are counted).
    NOTICE_LINES = 3

    def _update_banner(self) -> None:
        if self.failure is None and (not self.notice or self.source != "assembled"):
            self.banner.setVisible(False)
            return
        if self.failure is not None:
            where = ("each layer is shown on its own (the part named in red); fix it in EDITING, or pick "
                     "“Per layer”" if self.source == "assembled" else "the layers are shown each on its own")
            self.banner.setStyleSheet("QLabel { background: #f6d8d2; color: #5a1408; padding: 6px; }")
            self.banner.setText(f"The assembly failed: {self.failure}\n{where[0].upper() + where[1:]}.")
        else:
            shown = [w[0].upper() + w[1:] + "." for w in self.notice[: self.NOTICE_LINES]]
            more = len(self.notice) - len(shown)
            if more:
                shown.append(f"… and {more} more (Per layer shows each part on its own).")
            self.banner.setStyleSheet("QLabel { background: #f7ebc8; color: #4d3800; padding: 6px; }")
            self.banner.setText("Assembled, with parts left free — fix them in EDITING:\n" + "\n".join(shown))
        self._place_banner()
        self.banner.setVisible(True)
        self.banner.raise_()

    def _place_banner(self) -> None:
        width = max(self.width(), 1)
        self.banner.setFixedWidth(width)
        self.banner.setFixedHeight(self.banner.heightForWidth(width))
        self.banner.move(0, 0)

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        if self.banner.isVisible():
            self._place_banner()

    def _show_assembled(self, mesh, layers) -> None:
        self._set_notice(getattr(mesh, "warnings", ()))
        notes = getattr(mesh, "notes", ())
        if notes:
            self.message.emit(notes[0][0].upper() + notes[0][1:] + (f" (and {len(notes) - 1} more)" if len(notes) > 1 else ""))
        if mesh is None:
            self._show([(l.mesh, CLAY) for l in layers], "the assembler returned nothing; showing the layers")
        else:
            self._show([(mesh, CLAY)], "")
            self.model_item = self._items[0] if self._items else None
        self.assembled_shown.emit(mesh)

    def _show(self, meshes, note: str) -> None:
        if note:
            self.message.emit(note)
        #: What is on display: [(mesh, colour)] (also without OpenGL, for the tests).
        self.shown = list(meshes)
        if self.gl is None:
            return
        for item in self._items:
            self.gl.removeItem(item)
        self._items = []
        if self.model_item is not None:
            self.model_item = None
            self.assembled_shown.emit(None)
        allv = []
        item_class = _mesh_item_class()
        for mesh, colour in meshes:
            item = item_class(mesh.V, mesh.F, getattr(mesh, "rim_pairs", None), getattr(mesh, "rim_weights", None),
                              shader=shader_name(self.shading_style), color=colour, glOptions="opaque")
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
            self._grid.resetTransform()
            self._grid.setSize(2 * size, 2 * size)
            self._grid.setSpacing(size / 10, size / 10)
            self._grid.translate(float(centre[0]), -float(centre[2]), float(lo[1]))
            self._bounds = (centre, float(np.max(np.linalg.norm(V - centre, axis=1))) or 1.0)
            if not self._framed:
                self.fit()
