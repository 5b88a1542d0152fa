"""Commands: every change of a Document is one of these, pushed on its UndoStack.

A command receives the document as an argument (it never captures an app), so a journal of
command dicts replays headlessly. Contract for ``do``: either the change happens completely,
or the document is left untouched and a :class:`~sketchforge.errors.SketchforgeError` is
raised. Expensive results (an inflated mesh) are computed on the first ``do`` and kept, so
redo is instant and bit-identical.

Plugins add commands through the ``sketchforge_commands`` hook; a command that edits a
layer's mesh after inflation (a sculpt edit) also implements :meth:`Command.reapply` so that
changing the inflation parameters can re-apply it, and :meth:`Command.transform_edit` so that
its edit follows the layer when the layer is moved, scaled or rotated. The core never reads
an edit's fields: only the edit's own command knows what they mean.

The commands live in modules by what they touch; every name is importable from here:

- :mod:`.base`: :class:`Command`, :class:`ReplaceLayerCommand`, :class:`MacroCommand`,
  gesture ids and the checked parsing of journal fields;
- :mod:`.layers`: add, remove, rename, show/hide and reorder layers;
- :mod:`.contours`: draw a stroke, change the inflater or its parameters, and the inflation of
  a layer with its edits re-applied;
- :mod:`.transforms`: transform, translate, mirror and duplicate a layer, and the affine
  helpers;
- :mod:`.assembly`: the assembler's choice and where the assembly glues each part;
- :mod:`.light`: the light direction;
- :mod:`.registry`: the core commands and the registry of journal names.
"""


from __future__ import annotations

from sketchforge.document.commands.assembly import (
    SetAssembly,
    attachment,
    attachment_note,
    attachments,
    host_of,
)
from sketchforge.document.commands.base import (
    MAX_INDEX,
    MAX_MACRO_DEPTH,
    Command,
    MacroCommand,
    ReplaceLayerCommand,
    _digits,  # noqa: F401 - tests check its error text
    new_gesture_id,
    parse_field,
    parse_params,
    parse_points,
    parse_vector,
)
from sketchforge.document.commands.contours import (
    SetContour,
    SetInflateParams,
    inflate_layer,
    inflated,
    layer_inflater,
    reapply_edits,
)
from sketchforge.document.commands.layers import AddLayer, MoveLayer, RemoveLayer, RenameLayer, SetLayerVisible
from sketchforge.document.commands.light import SetLight
from sketchforge.document.commands.registry import CORE_COMMANDS, CommandRegistry
from sketchforge.document.commands.transforms import (
    MIRROR_AXES,
    DuplicateLayer,
    MirrorLayer,
    TransformLayer,
    TranslateLayer,
    check_affine,
    compose_affine,
    mirror_axis_x,
    rotate_about,
    scale_about,
    transform_points,
    transformed_edits,
    twin_source,
)

__all__ = [
    "CORE_COMMANDS", "MAX_INDEX", "MAX_MACRO_DEPTH", "MIRROR_AXES",
    "AddLayer", "Command", "CommandRegistry", "DuplicateLayer", "MacroCommand", "MirrorLayer", "MoveLayer",
    "RemoveLayer", "RenameLayer", "ReplaceLayerCommand", "SetAssembly", "SetContour", "SetInflateParams",
    "SetLayerVisible", "SetLight", "TransformLayer", "TranslateLayer",
    "attachment", "attachment_note", "attachments", "check_affine", "compose_affine", "host_of", "inflate_layer", "inflated",
    "layer_inflater", "mirror_axis_x", "new_gesture_id", "parse_field", "parse_params", "parse_points",
    "parse_vector", "reapply_edits", "rotate_about", "scale_about", "transform_points", "transformed_edits",
    "twin_source",
]
