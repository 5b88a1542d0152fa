"""The OBSERVATION view's OpenGL widget: pyqtgraph's 3D view (items, camera, orbit and zoom:
``GLViewMixin``) on a plain QWidget that renders into an offscreen framebuffer and paints the
result as an image.

Why not pyqtgraph's ``GLViewWidget`` (a QOpenGLWidget): a window that holds a QOpenGLWidget is
composed with OpenGL on every repaint of any of its widgets (the whole window cleared, the
widget's texture drawn, the window's raster contents blended over it, the window swapped). On
software OpenGL (Mesa llvmpipe: a machine without a GPU, a CI runner, a remote desktop) that
composition cost ~12 ms of CPU per repaint of the 1280x800 window, a quarter of a played
animation frame (issue 34). Here only the 3D view is rendered with OpenGL and read back
(~1 ms at 770x754); the window stays a raster window that sends only what changed. The image
is the same, pixel for pixel.

The widget keeps ``GLViewWidget``'s API (``addItem``, ``opts``, ``setCameraPosition``,
``orbit``, ``projectionMatrix``, ``viewMatrix``, ``grabFramebuffer``, the ``frameSwapped``
signal after each repaint), so plugins drawing in the view need no change.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pyqtgraph.opengl.GLViewWidget import GLViewMixin  # this module is imported when a view is made
from PySide6.QtCore import QSize, Qt, Signal
from PySide6.QtGui import QImage, QOffscreenSurface, QOpenGLContext, QPainter, QSurfaceFormat
from PySide6.QtWidgets import QWidget

if TYPE_CHECKING:  # imported when the first frame is rendered
    from PySide6.QtOpenGL import QOpenGLFramebufferObject


class GLView(GLViewMixin, QWidget):
    """pyqtgraph's 3D view, rendered offscreen (see the module's docstring)."""

    #: emitted after each repaint that showed a new rendering (as QOpenGLWidget's)
    frameSwapped = Signal()  # noqa: N815 - QOpenGLWidget's name

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.setFocusPolicy(Qt.FocusPolicy.ClickFocus)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)  # every pixel is painted
        self._context: QOpenGLContext | None = None
        self._surface: QOffscreenSurface | None = None
        self._fbo: QOpenGLFramebufferObject | None = None

    def create_context(self) -> str | None:
        """Create the OpenGL context; None when it works, else why not (one sentence)."""
        if self._context is not None:
            return None
        context = QOpenGLContext(self)
        context.setFormat(QSurfaceFormat.defaultFormat())
        if not context.create():
            return "OpenGL is not available here (no context could be created)"
        surface = QOffscreenSurface(None, self)
        surface.setFormat(context.format())
        surface.create()
        if not surface.isValid() or not context.makeCurrent(surface):
            return "OpenGL is not available here (no offscreen surface could be made current)"
        self._context, self._surface = context, surface
        self._bind_framebuffer()
        self.initializeGL()  # pyqtgraph's: checks the version, initialises the items
        return None

    # --- what QOpenGLWidget offers pyqtgraph ---------------------------------------------------
    def context(self) -> QOpenGLContext | None:
        return self._context

    def isValid(self) -> bool:  # noqa: N802 - Qt's name
        return self._context is not None

    def makeCurrent(self) -> None:  # noqa: N802 - Qt's name
        """Make the context current with the view's framebuffer bound (sized to the view)."""
        if self._context is None:
            problem = self.create_context()
            if problem is not None:
                raise RuntimeError(problem)
            return
        self._context.makeCurrent(self._surface)
        self._bind_framebuffer()

    def doneCurrent(self) -> None:  # noqa: N802 - Qt's name
        if self._context is not None:
            self._context.doneCurrent()

    def _bind_framebuffer(self) -> None:
        from PySide6.QtOpenGL import QOpenGLFramebufferObject

        size = QSize(max(1, self.deviceWidth()), max(1, self.deviceHeight()))
        if self._fbo is None or self._fbo.size() != size:
            self._fbo = QOpenGLFramebufferObject(size, QOpenGLFramebufferObject.Attachment.CombinedDepthStencil)
        self._fbo.bind()

    def grabFramebuffer(self) -> QImage:  # noqa: N802 - Qt's name
        """The view rendered now, as an image of its device pixels."""
        from OpenGL import GL

        self.makeCurrent()
        GL.glViewport(0, 0, self._fbo.width(), self._fbo.height())
        self.paintGL()  # pyqtgraph's: clears and draws every item
        image = self._fbo.toImage()
        self._fbo.release()
        image.setDevicePixelRatio(self.devicePixelRatioF())
        return image

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt's name
        if self._context is None and self.create_context() is not None:
            return  # View3D checked at creation; nothing to draw with
        image = self.grabFramebuffer()
        painter = QPainter(self)
        painter.drawImage(0, 0, image)
        painter.end()
        self.frameSwapped.emit()
