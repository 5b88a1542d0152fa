"""The main window's layer actions: add, remove, duplicate (in place, aside, by double click),
mirror, reorder, nudge and transform a part, select it by a click, and change its inflater,
its parameters (edits made during a solve wait for its end) or the assembler."""

from __future__ import annotations

import numpy as np

from sketchforge.document import commands as C
from sketchforge.errors import SketchforgeError
from sketchforge.geometry.parts import part_at
from sketchforge.qt.errors_ui import error_text

#: Ctrl+D moves the copy this many part widths to the right: beside it with a gap (a second
#: eye, leg...), so the copy's junction does not lie across the original.
DUPLICATE_OFFSET = 1.25
#: An arrow key moves the selected part this many screen pixels.
NUDGE_PIXELS = 10


class LayerActions:
    """Turns the window's (``win``) layer gestures, menu entries and panel edits into
    commands."""

    def __init__(self, win) -> None:
        self.win = win

    def _on_current(self, fn) -> None:
        if self.win.current_layer is not None and self.win.current_layer in self.win.doc.layer_ids():
            fn(self.win.current_layer)
        else:
            self.win.show_message("select a part first (click it in the drawing or in the Layers list)")

    def add_layer(self) -> None:
        cmd = C.AddLayer()
        if self.win.push(cmd):
            self.win.layers_panel.select(cmd.id)

    def remove_layer(self, layer_id: str) -> None:
        self.win.push(C.RemoveLayer(layer=layer_id))

    def duplicate_layer(self, layer_id: str) -> None:
        cmd = C.DuplicateLayer(layer=layer_id)
        if self.win.push(cmd):
            self.win.layers_panel.select(cmd.new_id)

    def mirror_layer(self, layer_id: str, axis: str = "host") -> None:
        """Mirror about the host's vertical axis (a left leg becomes a right leg; a free part
        about its own), or with ``axis="own"`` about the part's own axis."""
        if self.win._refuse_if_busy():
            return
        cmd = C.MirrorLayer(layer=layer_id, axis=axis)
        name = self.win.doc.layer(layer_id).name

        def done(c):
            where = "its host's axis" if c.used_axis == "host" else "its own axis"
            self.win.show_message(f"mirrored “{name}” about {where}")

        self.win.runner.run(cmd, label="Inflating", on_done=done)

    def set_params(self, params: dict) -> None:
        if self.win.current_layer is None:
            self.win.show_message("select a part first (click it) to change its parameters")
            return
        if self.win.runner.busy:
            # Coalesced: the edits made during a solve run together when it ends, the last
            # value of each parameter wins, none is dropped.
            self.win._pending_params.setdefault(self.win.current_layer, {}).update(params)
            self.win.show_message("a solve is running: this change is applied when it ends")
            return
        self.win._run_params(self.win.current_layer, params)

    def set_inflater(self, name: str) -> None:
        """The Creation panel's inflater: the selected part is inflated by it (from its
        defaults; one undo step, its sculpt edits re-applied or the switch refused), and new
        parts are too."""
        layer = self.win.doc.layer(self.win.current_layer) if self.win.current_layer in self.win.doc.layer_ids() else None
        if layer is None or layer.solver == name or (layer.solver is None and name == self.win.host.default_solver_name("inflate")):
            self.win.show_message(f"new parts are inflated by “{name}”")
            return
        if self.win._refuse_if_busy():
            self.win._sync_current_layer()
            return
        self.win.runner.run(
            C.SetInflateParams(layer=layer.id, solver=name),
            label=f"Inflating with {name}",
            on_done=lambda *_: self.win.show_message(f"“{layer.name}” is inflated by “{name}”; new parts are too"),
            on_error=lambda exc: self.win._sync_current_layer() or False,
        )

    def set_assembly(self, solver, params: dict) -> None:
        """The Assembly panel: choose the assembler (``solver``, from its defaults) or change
        its parameters; one ``set_assembly`` (one undo step). A value the assembler refuses is
        one status line, and the panel shows the document's values again."""
        if self.win._refuse_if_busy():
            self.win.assembly_panel.show_assembly(self.win.doc.assembly)
            return
        try:
            self.win.doc.push(C.SetAssembly(solver=solver, params=dict(params)))
        except SketchforgeError as exc:
            self.win.show_message(error_text(exc))
            self.win.assembly_panel.show_assembly(self.win.doc.assembly)

    def _run_params(self, layer_id: str, params: dict) -> None:
        edits = len(self.win.doc.layer(layer_id).edits)
        # With sculpt edits the layer is re-inflated and its edits re-applied in order (or the
        # change is refused with the reason); say so, since it takes longer and may fail.
        label = f"Inflating and re-applying {edits} sculpt edit{'s' * (edits != 1)}" if edits else "Inflating"
        self.win.runner.run(
            C.SetInflateParams(layer=layer_id, params=params),
            label=label,
            on_done=(
                lambda *_: self.win.show_message(
                    f"re-applied {edits} sculpt edit{'s' * (edits != 1)} to the rebuilt surface"
                )
            )
            if edits
            else None,
            on_error=lambda exc: self.win._sync_current_layer() or False,
        )

    def _run_pending_params(self) -> None:
        if self.win.runner.busy or not self.win._pending_params:
            return
        layer_id = next(iter(self.win._pending_params))
        params = self.win._pending_params.pop(layer_id)
        if layer_id not in self.win.doc.layer_ids():
            self.win._sync_current_layer()
            return
        old = self.win.doc.layer(layer_id).params
        if all(old.get(k) == v for k, v in params.items()):
            self.win._sync_current_layer()
            self.win._run_pending_params()
            return
        self.win._run_params(layer_id, params)

    def _selected_or_say(self, what: str):
        if self.win.current_layer not in self.win.doc.layer_ids():
            self.win.show_message(f"select a part first (click it) to {what}")
            return None
        return self.win.doc.layer(self.win.current_layer)

    def select_at(self, point) -> None:
        k = part_at(point, self.win._outlines())
        if k < 0:
            self.win.show_message("no part here: drag to draw one, click a part to select it")
            return
        self.win.layers_panel.select(self.win.doc.layers[k].id)
        self.win.show_message(f"selected “{self.win.doc.layers[k].name}”")

    def duplicate_at(self, point, button: str) -> None:
        """Double click: duplicate the part under the pointer, behind it (left) or in front
        (right), as Monster Mash does."""
        k = part_at(point, self.win._outlines())
        if k < 0:
            self.win.show_message("double-click a part to duplicate it (left: behind it, right: in front)")
            return
        layer = self.win.doc.layers[k]
        cmd = C.DuplicateLayer(layer=layer.id, index=k if button == "left" else k + 1)
        if self.win.push(cmd):
            self.win.layers_panel.select(cmd.new_id)
            self.win.show_message(
                f"duplicated “{layer.name}” {'behind' if button == 'left' else 'in front of'} itself, in place: "
                "the arrow keys move the copy"
            )

    def duplicate_aside(self, layer_id: str) -> None:
        """Ctrl+D: a copy in front, moved right by 1.25 part widths (beside it)."""
        layer = self.win.doc.layer(layer_id)
        pts = layer.points if layer.points is not None else None
        width = float(np.ptp(pts[:, 0])) if pts is not None and len(pts) else 0.0
        step = DUPLICATE_OFFSET * (width if width > 0 else 0.4)
        cmd = C.DuplicateLayer(layer=layer_id, offset=[step, 0.0])
        if self.win.push(cmd):
            self.win.layers_panel.select(cmd.new_id)
            self.win.show_message(f"duplicated “{layer.name}”, moved aside")

    def nudge(self, layer_id: str, step) -> None:
        """Arrow keys: move the selected part NUDGE_PIXELS screen pixels (one undo step)."""
        d = NUDGE_PIXELS * self.win.canvas.pixel_size()
        if self.win.push(C.TransformLayer(layer=layer_id, matrix=[[1.0, 0.0, step[0] * d], [0.0, 1.0, step[1] * d]])):
            self.win.show_message(f"moved “{self.win.doc.layer(layer_id).name}” (arrow keys)")

    def transform_layer(self, layer_id: str, matrix) -> None:
        """The end of a handle drag: one transform_layer with the whole drag's matrix."""
        if layer_id not in self.win.doc.layer_ids() or self.win._refuse_if_busy():
            return
        cmd = C.TransformLayer(layer=layer_id, matrix=matrix)
        if self.win.push(cmd):
            self.win.show_message(f"{cmd.text().split()[0].lower()}d “{self.win.doc.layer(layer_id).name}” (Ctrl+Z undoes it)")

    def move_depth(self, layer_id: str, where) -> None:
        """PgUp / PgDn: one step to the front / back; Home / End: to the very front / back."""
        n = len(self.win.doc.layers)
        i = self.win.doc.index_of(layer_id)
        name = self.win.doc.layer(layer_id).name
        target = {"front": n - 1, "back": 0}.get(where, i + (where if isinstance(where, int) else 0))
        target = max(0, min(n - 1, target))
        if target == i:
            self.win.show_message(f"“{name}” is already at the {'front' if i == n - 1 else 'back'}")
            return
        if self.win.push(C.MoveLayer(layer=layer_id, index=target)):
            self.win.layers_panel.select(layer_id)
            where = "the frontmost" if target == n - 1 else "the backmost" if target == 0 else f"at depth {target + 1} of {n}"
            self.win.show_message(f"“{name}” is now {where} part")
