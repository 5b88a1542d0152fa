"""Plugin host: hook specifications, the plugin manager and the built-in plugin."""

from sketchforge.plugins.hookspecs import hookimpl, hookspec

__all__ = ["default_host", "hookimpl", "hookspec"]


def default_host():
    """The process-wide host with every installed plugin (:func:`sketchforge.plugins.manager.default_host`):
    what a script hands a new document, ``Document(default_host())``."""
    from sketchforge.plugins.manager import default_host as make

    return make()
