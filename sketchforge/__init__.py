"""sketchforge: sculpt 3D shapes by drawing contours and redrawing shading isophotes.

The package is layered (see README, "Architecture"): ``geometry`` (pure array functions),
``document`` (layers, commands, undo, file format), ``plugins`` (pluggy host), ``tools``
(gesture state machines) and ``qt`` (the desktop front end). Only ``qt`` imports Qt.
"""

__version__ = "0.1.0"
