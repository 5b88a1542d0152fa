"""The main window's drawing: a finished stroke becomes a new part, a redrawn outline or a hole
(strokes drawn during a solve wait for its end); the person hears at once how a part is glued,
and when a redraw leaves parts off their host."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QTimer

from sketchforge.document import commands as C
from sketchforge.errors import ContourError, EditsDoNotApplyError
from sketchforge.qt.errors_ui import ask_yes_no, error_text
from sketchforge.tools import DrawContourTool
from sketchforge.tools.draw import closes, layer_outlines, plan_stroke

#: A redraw stroke's ends must lie this close (screen pixels) to the selected outline.
SPLICE_PIXELS = 10


class DrawingController:
    """Turns the window's (``win``) strokes into parts and redraws (Monster Mash)."""

    def __init__(self, win) -> None:
        self.win = win

    def _run_pending(self) -> None:
        """After a solve: the strokes drawn meanwhile (in order), then the parameter edits."""
        if self.win.runner.busy:
            return
        if self.win._pending_strokes:
            pts, kind = self.win._pending_strokes.pop(0)
            self.win.draw_stroke(pts, kind)
            return
        self.win._run_pending_params()

    def _outlines(self) -> list:
        return layer_outlines(self.win.doc)

    def draw_stroke(self, points, kind: str = "front") -> None:
        """A finished stroke of ``kind`` "front", "behind" or "redraw" (see
        :func:`~sketchforge.tools.draw.plan_stroke` for where it goes)."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if self.win.runner.busy:
            # Drawn while the last part inflates: drawn as soon as it is done, so quick
            # strokes are never lost; where it goes is decided then, on the new document.
            self.win._pending_strokes.append((pts, kind))
            n = len(self.win._pending_strokes)
            self.win.show_message(f"{n} stroke{'s' * (n != 1)} waiting: drawn when the current inflation ends (Esc drops them)")
            return
        if len(pts) < 2:
            self.win.show_message("the stroke is too short: press, drag around the shape and release")
            return
        plan = plan_stroke(self.win.doc, pts, kind, self.win.current_layer, SPLICE_PIXELS * self.win.canvas.pixel_size())
        if plan.refusal is not None:
            self.win.show_message(plan.refusal)
        elif plan.redraw is not None:
            what = {"whole": "redrew the outline", "stretch": "redrew part of the outline", "hole": "cut a hole"}[plan.redraw]
            self.win._redraw(self.win.doc.layer(plan.target), plan.points, plan.closed, what, holes=plan.holes,
                         notes=plan.notes)
        else:
            self.win._new_part(plan)

    def _new_part(self, plan) -> None:
        """A new part (or the contour of the empty layer ``plan.target``)."""
        inflater = self.win.creation_panel.new_part_inflater
        if plan.target is not None and self.win.doc.layer(plan.target).solver is not None:
            inflater = None  # an empty layer keeps the inflater it was given
        tool = DrawContourTool(self.win.doc, target_layer=plan.target, closed=plan.closed, index=plan.index, inflater=inflater)
        before, cmd = tool.commands_for(plan.points)
        kind = "closed" if plan.closed else "open"

        def done(c):
            self.win.layers_panel.select(c.layer)
            notes = list(plan.notes) + self.win._attachment_notes(self.win.doc.layer(c.layer))
            self.win.show_message(f"new {kind} part “{self.win.doc.layer(c.layer).name}”" + "".join("; " + n for n in notes))

        self.win.runner.run(cmd, label="Inflating", macro="Draw layer" if before else None, before=before, on_done=done,
                        on_error=self.win._drawing_slip)

    def _drawing_slip(self, exc) -> bool:
        """A stroke that cannot become an outline (it crosses itself, encloses no area): a slip
        of the hand, said in the status bar; nothing changed and nothing to dismiss (a
        blocking dialog for each slip was too much, issue 38). Other errors: a dialog."""
        if not isinstance(exc, ContourError):
            return False
        self.win.show_message(f"the stroke was not drawn: {error_text(exc)}")
        return True

    def _redraw(self, layer, pts, closed: bool, what: str, keep_edits: bool = True, holes=(), notes=()) -> None:
        """Replace ``layer``'s outline and holes (one undo step); its sculpt edits are kept when
        they still apply, else the person is asked whether to redraw without them."""
        keep = keep_edits and bool(layer.edits)
        tool = DrawContourTool(self.win.doc, target_layer=layer.id, closed=bool(closed), keep_edits=keep, holes=holes)
        _, cmd = tool.commands_for(pts)

        def error(exc) -> bool:
            if self.win._drawing_slip(exc):
                return True
            if not isinstance(exc, EditsDoNotApplyError):
                return False
            if ask_yes_no(
                self.win,
                "Redraw the contour?",
                f"Layer “{layer.name}” has {len(layer.edits)} sculpt edit(s) that do not apply to the new "
                f"outline ({exc}). Redraw it without them? (Undo brings them back.)",
                default_yes=True,  # Yes loses nothing (Undo brings the edits back); No drops the stroke
            ):
                QTimer.singleShot(0, lambda: self.win._redraw(self.win.doc.layer(layer.id), pts, closed, what, keep_edits=False,
                                                          holes=holes, notes=notes))
            else:
                self.win.show_message("the outline was not redrawn: its sculpt edits would be lost")
            return True

        kept = f"; kept its {len(layer.edits)} sculpt edit(s)" if keep else ""
        kept += "".join("; " + n for n in notes)
        glued = self.win._parts_glued_to(layer)

        def done(c) -> None:
            self.win.show_message(f"{what} {'in' if what == 'cut a hole' else 'of'} “{layer.name}”{kept}")
            self.win._check_parts_still_glued(layer.id, glued, what, c)

        self.win.runner.run(cmd, label="Inflating", on_done=done, on_error=error)

    def _attachment_notes(self, layer) -> list[str]:
        """What the person should hear when a part is drawn (issue 34): its junction runs off
        the part it lies on, spans two parts (glued to the one holding most of it) or cannot
        be glued at all (it will be assembled free, and why) — said now, not first in
        OBSERVATION."""
        if layer.closed or layer.mesh is None or len(layer.mesh.junction) < 2:
            return []
        host, problem = C.attachment(self.win.doc, layer)
        if problem:
            return [problem]
        note = C.attachment_note(self.win.doc, layer)
        if note:
            return [note]
        return [f"glued to “{host.name}”"] if host is not None else []

    def _parts_glued_to(self, host) -> list[str]:
        """Ids of the parts the assembly glues to ``host`` now (their junction lies on it)."""
        return [pid for pid, (now, _) in C.attachments(self.win.doc).items() if pid != host.id and now is host]

    def _check_parts_still_glued(self, host_id: str, glued: list[str], what: str, cmd) -> None:
        """After ``host_id``'s outline changed: each part that was glued to it and whose
        junction no longer lies on it is named in the status bar, and the person is offered
        to undo the change (issue 30: a tail left hanging by a redrawn body was only found in
        OBSERVATION, as an assembly error)."""
        if host_id not in self.win.doc.layer_ids():
            return
        host = self.win.doc.layer(host_id)
        left = []
        present = [pid for pid in glued if pid in self.win.doc.layer_ids()]
        for pid, (now, problem) in C.attachments(self.win.doc, set(present)).items():
            part = self.win.doc.layer(pid)
            if now is None or now.id != host_id:
                where = (f"it is now glued to “{now.name}”" if now is not None else
                         problem if problem else "it is now a free part")
                left.append((part, where))
        if not left:
            return
        names = ", ".join(f"“{p.name}”" for p, _ in left)
        self.win.show_message(f"the junction of {names} no longer lies on “{host.name}”: Ctrl+Z undoes the change")
        details = "; ".join(f"“{p.name}”: {w}" for p, w in left)
        if ask_yes_no(
            self.win,
            "Parts left their host",
            f"After this change ({what}), the junction of {names} no longer lies on “{host.name}” ({details}). "
            "Undo the change? (No keeps it: redraw or move those parts to attach them again.)",
            default_yes=False,  # keep what the person just did; Ctrl+Z still undoes it
        ):
            # Only if the change is still the last thing done (a queued stroke may have run
            # while the question was open).
            if self.win.runner.busy or host_id not in self.win.doc.layer_ids() or self.win.doc.layer(host_id) is not cmd._new:
                self.win.show_message("not undone: something changed meanwhile; Ctrl+Z undoes step by step")
                return
            self.win.doc.undo_stack.undo()
            self.win.show_message(f"undid the change of “{host.name}”: {names} glued to it again")

    def set_closed(self, closed: bool) -> None:
        """The panel's box: make the selected part closed (free) or open (attached by its
        closing segment), re-inflated from the same stroke."""
        layer = self.win.doc.layer(self.win.current_layer) if self.win.current_layer in self.win.doc.layer_ids() else None
        if layer is None or layer.points is None:
            self.win.show_message("select a part first (click it) to make it open or closed")
            self.win._sync_current_layer()
            return
        if self.win._refuse_if_busy():
            self.win._sync_current_layer()
            return
        if not closed and closes(layer.points, layer.params):
            self.win._sync_current_layer()
            self.win.show_message(f"“{layer.name}” stays closed: the ends of its stroke meet, so it has no open side to attach by")
            return
        self.win._redraw(layer, layer.points, closed, "made closed" if closed else "made open")
