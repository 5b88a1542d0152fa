"""Validation of a document's plugin data when it is opened (``snapshot.plugin_data``).

Plugin data is written only by a plugin's own commands, but a saved file is user-writable: a
hand-edited or corrupted value (65 pins, a motion of the wrong length) would otherwise reach
the plugin's solvers unchecked. Plugins register a validator per key through the
``sketchforge_plugin_data_validators`` hook (:mod:`sketchforge.plugins.hookspecs`); this module
collects them and runs them on load. Kept apart from the manager so that the hook stays one
small, self-contained addition.
"""

from __future__ import annotations

from sketchforge.errors import DocumentFormatError, PluginError, SketchforgeError, quote

HOOK = "sketchforge_plugin_data_validators"


def plugin_data_validators(host) -> dict:
    """{key: (validate, plugin name)} from every plugin. The one override rule of every hook
    kind holds here too: two plugins validating one key is an error naming both (the key is
    then refused when a file holds it), never "the first one wins"."""
    hook = getattr(host.pm.hook, HOOK, None)
    out: dict = {}
    if hook is None:
        return out
    for impl in hook.get_hookimpls():
        if getattr(impl, "hookwrapper", False) or getattr(impl, "wrapper", False):
            continue
        try:
            found = impl.function()
        except Exception as exc:  # noqa: BLE001 - foreign code: named, not hidden
            raise PluginError(f"the {HOOK} hook of plugin {impl.plugin_name!r} failed: {type(exc).__name__}: {exc}") from exc
        if found is None:
            continue
        if not isinstance(found, dict) or not all(isinstance(k, str) and callable(v) for k, v in found.items()):
            raise PluginError(f"plugin {impl.plugin_name!r}: {HOOK} must return a dict of key -> validate(value)")
        for key, validate in found.items():
            if key in out and out[key][1] != impl.plugin_name:
                out[key] = (None, f"{out[key][1]}' and '{impl.plugin_name}")
            else:
                out[key] = (validate, impl.plugin_name)
    return out


def validate_plugin_data(host, plugin_data: dict, where: str) -> None:
    """Run each key's validator on its value. Raises DocumentFormatError "WHERE.plugin_data['key']:
    problem" for a bad value, PluginError naming the plugin for a validator that breaks."""
    validators = plugin_data_validators(host)
    for key, value in plugin_data.items():
        if key not in validators:
            continue
        validate, plugin = validators[key]
        if validate is None:
            raise PluginError(f"the plugin data {quote(key)} is validated by both plugins '{plugin}'; uninstall one of them")
        try:
            validate(value)
        except SketchforgeError as exc:
            raise DocumentFormatError(f"{where}.plugin_data[{quote(key)}]: {exc}") from None
        except Exception as exc:  # noqa: BLE001 - a validator's own bug, not the file's
            raise PluginError(
                f"the plugin data validator for {quote(key)} (plugin {plugin!r}) failed: {type(exc).__name__}: {exc}"
            ) from exc
