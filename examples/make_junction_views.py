"""The creature's front-arm junction in the app's 3D view, plain sleeve against the blended
junction (issue 12), for the README: ``docs/screenshots/junction-view3d-{plain,blended}.png``.

Needs OpenGL::

    xvfb-run -a env QT_QPA_PLATFORM=xcb .venv/bin/python examples/make_junction_views.py docs/screenshots
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    from PySide6.QtGui import QVector3D

    from sketchforge.document.document import Document
    from sketchforge.qt.app import ensure_qapp, plugin_host
    from sketchforge.qt.command_runner import JobRunner
    from sketchforge.qt.view3d import CLAY, View3D, gl_unavailable_reason
    from sketchforge_assemble import assemble_detailed
    from sketchforge_assemble.testing import meshes_from_journal

    argv = list(sys.argv[1:] if argv is None else argv)
    out = Path(argv[0]) if argv else ROOT / "docs" / "screenshots"
    app = ensure_qapp()
    reason = gl_unavailable_reason()
    if reason is not None:
        print(f"no OpenGL: {reason}", file=sys.stderr)
        return 2
    layers, meshes, closed = meshes_from_journal(ROOT / "examples" / "creature.json")
    arm = meshes[[layer.id for layer in layers].index("arm_front")]
    host = plugin_host()
    view = View3D(Document(host=host), JobRunner())
    view.resize(640, 480)
    view.ensure_gl()
    view.show()
    for label, params in (("plain", {"fillet": 0.0}), ("blended", {})):
        mesh = assemble_detailed(meshes, closed, params=params).mesh
        view._show([(mesh, CLAY)], "")
        # looking at the arm's junction from the front, a little from below and the side
        j = arm.V[arm.junction]
        near = np.linalg.norm(mesh.V[:, :2] - j[:, :2].mean(axis=0), axis=1) < 0.06
        c = mesh.V[near][np.argmax(mesh.V[near, 2])]
        view.gl.setCameraPosition(pos=QVector3D(float(c[0]), -float(c[2]), float(c[1])), distance=0.9,
                                  elevation=25, azimuth=-120)
        for _ in range(5):
            app.processEvents()
        img = view.gl.grabFramebuffer()
        path = out / f"junction-view3d-{label}.png"
        img.save(str(path), "PNG")
        print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
