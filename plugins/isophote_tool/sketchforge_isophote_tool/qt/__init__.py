"""The isophote tool's controls in the desktop app (SCULPTURE), built by the app through the
plugin's ``sketchforge_qt_panels`` hook; only the app imports this package (it imports Qt)."""

from __future__ import annotations

from .panel import IsophoteSculptPanel

__all__ = ["IsophoteSculptPanel", "create_panel"]


def create_panel(app) -> IsophoteSculptPanel:
    """The panel for ``app`` (a :class:`sketchforge.qt.panel_api.AppContext`)."""
    return IsophoteSculptPanel(app)
