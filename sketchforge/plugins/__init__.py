"""Plugin host: hook specifications, the plugin manager and the built-in plugin."""

from sketchforge.plugins.hookspecs import hookimpl, hookspec

__all__ = ["hookimpl", "hookspec"]
