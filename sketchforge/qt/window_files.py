"""The main window's files: New, Open (and Open Recent), Save, Save As (asking before it writes
over a file changed on disk), Export, the reference image; the autosave of unsaved work, the
guard that flushes it before a native solve, and the recovery offered at the next start."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtWidgets import QFileDialog, QMessageBox

from sketchforge.atomic import refuse_input_as_output, same_file
from sketchforge.document import fileformat as ff
from sketchforge.document.autosave import describe_stop, find_recoverable, forget, recover, set_aside
from sketchforge.errors import SketchforgeError
from sketchforge.qt import errors_ui
from sketchforge.qt.errors_ui import ask_yes_no, error_text, show_error

FILE_FILTER = "sketchforge documents (*.json *.sketchforge);;All files (*)"
MAX_RECENT = 8


class AutosaveGuard:
    """The CommandRunner's (and the assembly's) guard: the window's current Autosaver writes
    the state before the solve and names it (``Autosaver.begin_solve``), and forgets the record
    when the solver has returned, even after a save or an open in between (the record was
    handed over to the new Autosaver, ``Autosaver.hand_over``). A failing disk is reported but
    never blocks the solve."""

    def __init__(self, window) -> None:
        self.window = window

    def before(self, cmd=None, **kwargs):
        saver = getattr(self.window, "autosaver", None)
        if saver is None:
            return None
        try:
            return saver, saver.begin_solve(cmd, **kwargs)
        except (SketchforgeError, OSError) as exc:
            self.window.show_message(f"autosave before the solve failed: {error_text(exc)}")
            return None

    def after(self, token) -> None:
        saver, inner = token
        try:
            saver.end_solve(inner)  # the autosaver that started it passes it on if it was handed over
        except (SketchforgeError, OSError) as exc:
            self.window.show_message(f"autosave failed: {error_text(exc)}")


class FileActions:
    """The window's file actions and its autosave and recovery. The document, its path and the
    Autosaver stay on the window (``win``); the window's methods of the same names call these."""

    def __init__(self, win) -> None:
        self.win = win

    def maybe_save(self) -> bool:
        """True when it is fine to drop the document (saved, or the person chose to)."""
        if not self.win.is_modified():
            return True
        answer = QMessageBox.question(
            self.win,
            "Unsaved changes",
            "The document has unsaved changes. Save them first?",
            QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Discard | QMessageBox.StandardButton.Cancel,
            QMessageBox.StandardButton.Save,
        )
        if answer == QMessageBox.StandardButton.Save:
            return self.win.save()
        return answer == QMessageBox.StandardButton.Discard

    def adopt(self, loaded, path: Path | None, stamp: tuple | None = None) -> None:
        """Take over the state of a freshly loaded document (history starts here). ``stamp``:
        what ``path`` held when ``loaded`` was read from it (:func:`ff.stamp_of`), so that a
        save can tell whether someone else changed the file since."""
        self.win._pending_strokes.clear()
        self.win._pending_params.clear()
        self.win.runner.cancel()
        self.win.doc.adopt(loaded)
        self.win.path = path
        self.win.disk_stamp = stamp if path is not None else None
        # A new autosave file; the records of solves still running (a cancelled one, the
        # assembly) go on until those solves end.
        self.win.autosaver = self.win.autosaver.hand_over(path, original_sha256=self.win.disk_stamp[4] if self.win.disk_stamp else None)
        self.win.current_layer = None
        self.win.canvas.rebuild()
        self.win._sync_all()
        self.win.history_panel.rebuild()
        self.win.canvas.fit()
        self.win.view3d.reframe()  # a new model: frame it when it is next shown

    def new_document(self) -> None:
        if self.win._refuse_if_busy() or not self.win.maybe_save():
            return
        from sketchforge.document.document import Document

        self.win.adopt(Document(host=self.win.host), None)

    def open_dialog(self) -> None:
        if self.win._refuse_if_busy() or not self.win.maybe_save():
            return
        path, _ = QFileDialog.getOpenFileName(self.win, "Open document", str(self.win._dir()), FILE_FILTER)
        if path:
            self.win.open_path(Path(path), ask=False)

    def open_path(self, path: Path, ask: bool = True) -> bool:
        """Open a file; on error show it and keep the open document untouched."""
        if ask and (self.win._refuse_if_busy() or not self.win.maybe_save()):
            return False
        info: dict = {}
        try:
            loaded = ff.load(path, host=self.win.host, info=info)
        except SketchforgeError as exc:
            show_error(self.win, "Cannot open the document", exc)
            return False
        except Exception as exc:  # noqa: BLE001 - a bug, but the open document must survive
            show_error(self.win, "Cannot open the document", exc)
            return False
        self.win.adopt(loaded, Path(path), ff.stamp_of(info["stat"], info["sha256"]))
        self.win._add_recent(path)
        self.win.show_message(f"opened {path}")
        return True

    def save(self) -> bool:
        if self.win.path is None:
            return self.win.save_as()
        return self.win.save_to(self.win.path)

    def save_as(self) -> bool:
        path, _ = QFileDialog.getSaveFileName(self.win, "Save document", str(self.win._dir() / "untitled.json"), FILE_FILTER)
        if not path:
            return False
        return self.win.save_to(Path(path))

    def save_to(self, path: Path) -> bool:
        if self.win._refuse_if_busy():
            return False
        if self.win.path is not None and same_file(path, self.win.path):
            changed, self.win.disk_stamp = ff.changed_on_disk(path, self.win.disk_stamp)
            if changed:
                return self.win._save_over_a_changed_file(Path(path))
        try:
            stamp = ff.save(self.win.doc, path)
        except SketchforgeError as exc:
            show_error(self.win, "Cannot save the document", exc)
            return False
        self.win.path = Path(path)
        self.win.disk_stamp = stamp
        # running solves keep their record
        self.win.autosaver = self.win.autosaver.hand_over(self.win.path, original_sha256=stamp[4])
        self.win._add_recent(path)
        self.win._sync_title()
        self.win.history_panel.rebuild()
        self.win.show_message(f"saved {path}")
        return True

    def _save_over_a_changed_file(self, path: Path) -> bool:
        """The window's file was changed on disk since it was opened or saved here (another
        window or program saved over it): saving now would destroy that work without a word
        (issue 38). Ask; Enter chooses Save As, which loses nobody's work."""
        choice = errors_ui.ask_choice(
            self.win,
            "The file changed on disk",
            f"{path} was changed on disk since this window opened or saved it (by another window or program).\n\n"
            "Overwrite: replace it with this window's document (the other changes are lost).\n"
            "Save As: save this window's document as another file (nothing is lost).\n"
            "Reload: open the file as it is on disk (this window's unsaved changes are lost).",
            ["Overwrite", "Save As…", "Reload", "Cancel"],
            default=1,
            cancel=3,
        )
        if choice == 0:
            self.win.disk_stamp = None  # the person chose: write over it
            return self.win.save_to(path)
        if choice == 1:
            return self.win.save_as()
        if choice == 2:
            self.win.open_path(path, ask=False)
            return False
        self.win.show_message(f"not saved: {path} changed on disk")
        return False

    def export_dialog(self) -> None:
        filters = ";;".join(
            f"{e.description} ({' '.join('*' + s for s in e.suffixes)})" for e in self.win.host.exporters.values()
        )
        path, _ = QFileDialog.getSaveFileName(self.win, "Export mesh", str(self.win._dir() / "model.obj"), filters)
        if path:
            self.win.export_to(Path(path))

    def export_to(self, path: Path) -> bool:
        """Export the assembled model (the visible layers merged without an assembler)."""
        try:
            refuse_input_as_output(path, [self.win.path], "export")  # never over the open document
            exporter = self.win.host.exporter_for(path, self.win.doc)
            if exporter.write_document is not None:  # a whole document (an animation): seconds of solving
                from sketchforge.qt.document_export import export_document_in_background

                return export_document_in_background(self.win, exporter, path)
            summary = self.win.host.export(path, mesh=self.win.doc.export_mesh())  # atomic, errors name the plugin
        except SketchforgeError as exc:
            show_error(self.win, "Cannot export", exc)
            return False
        self.win.show_message(f"exported {path} ({summary})")
        return True

    def reference_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self.win, "Reference image", str(self.win._dir()), "Images (*.png *.jpg *.jpeg *.bmp)")
        if path:
            try:
                self.win.canvas.set_reference_image(path)
            except SketchforgeError as exc:
                show_error(self.win, "Cannot show the image", exc)

    def _dir(self) -> Path:
        return self.win.path.parent if self.win.path is not None else Path.cwd()

    def recent_files(self) -> list[str]:
        value = self.win.settings.value("recent_files", [])
        if isinstance(value, str):
            value = [value]
        return [str(v) for v in (value or [])]

    def _add_recent(self, path) -> None:
        p = str(Path(path).resolve())
        files = [p] + [f for f in self.win.recent_files() if f != p]
        self.win.settings.setValue("recent_files", files[:MAX_RECENT])
        self.win.update_recent_menu()

    def update_recent_menu(self) -> None:
        self.win.recent_menu.clear()
        files = self.win.recent_files()
        for f in files:
            act = self.win.recent_menu.addAction(f)
            act.triggered.connect(lambda _=False, f=f: self.win.open_path(Path(f)))
        self.win.recent_menu.setEnabled(bool(files))

    def _autosave(self) -> None:
        """Timer tick. A failure (full disk, a file where the data folder should be) is shown
        once in the status bar, where it stays, and the autosave is retried at every interval;
        the first success after it says so."""
        try:
            wrote = self.win.autosaver.tick()
        except (SketchforgeError, OSError) as exc:
            text = f"autosave failed: {error_text(exc)} (retrying every {self.win.autosaver.interval_s:g} s)"
            if text != self.win.autosave_error:
                self.win.autosave_error = text
                self.win.statusBar().showMessage(text)  # no timeout: it stays until the next message
            return
        if self.win.autosave_error is not None and (wrote or self.win.doc.undo_stack.is_clean()):
            self.win.autosave_error = None
            self.win.show_message("autosave works again")

    def offer_recovery(self) -> bool:
        """At start: offer the newest autosave left by a session that did not end normally,
        naming the step that was running if a solver crashed (that step is not in the
        autosave, so it is not replayed). Returns True when one was recovered (it opens as
        unsaved changes). Declining keeps the autosave: it is offered again next time. The files
        of another sketchforge still running are never offered, reported or removed."""
        set_aside_notes: list[str] = []
        items = find_recoverable(set_aside_notes=set_aside_notes)  # also removes killed autosaves' temps
        if set_aside_notes:
            QMessageBox.information(self.win, "An autosave was set aside", "\n\n".join(n[:1].upper() + n[1:] for n in set_aside_notes))
        reports = [i for i in items if not i.has_document]
        if reports:
            # A crash during a solve on a document without unsaved changes: nothing to
            # recover, but the person should know which step brought sketchforge down.
            lines = []
            for r in reports:
                name = r.original or "the untitled document"
                if any(rec.get("unsaved") for rec in r.running):  # the autosave could not be written
                    lines.append(f"{describe_stop(r)} The unsaved changes to {name} could not be autosaved "
                                 "before that step; the step was not applied.")
                else:
                    lines.append(f"{describe_stop(r)} There were no unsaved changes to {name}, so nothing was "
                                 "lost; that step was not applied.")
            QMessageBox.information(self.win, "sketchforge stopped during a computation", "\n\n".join(lines))
            for r in reports:
                forget(r)
        items = [i for i in items if i.has_document]
        if not items:
            return False
        item = items[0]
        where = item.original or "an untitled document"
        stopped = describe_stop(item)
        if stopped and any(r.get("command") is not None for r in item.running):
            question = f"{stopped} Your work on {where} up to that step can be recovered; that step was left out. Recover it?"
        elif stopped:
            question = f"{stopped} Your work on {where} can be recovered (that computation is not part of it). Recover it?"
        else:
            question = f"sketchforge found unsaved work on {where} from a session that did not close normally. Recover it?"
        question += f"\n\nNo keeps the autosave ({item.path}); it is offered again at the next start."
        if not ask_yes_no(self.win, "Recover unsaved work?", question, default_yes=True):
            return False  # the autosave stays where it is: this session never writes or removes it
        try:
            loaded = recover(item, host=self.win.host)
        except Exception as exc:  # noqa: BLE001 - a bad autosave must never end the app
            # Kept for the user, but out of the way: it would fail the same way at every start.
            note = set_aside(item.path, error_text(exc))
            QMessageBox.critical(self.win, "Cannot recover the autosave", note)
            return False
        # The file's digest when the crashed session last read or saved it: a save over it
        # asks first if it changed since.
        stamp = (None, None, None, None, item.original_sha256) if item.original and item.original_sha256 else None
        self.win.adopt(loaded, Path(item.original) if item.original else None, stamp)
        self.win.doc.undo_stack.reset_clean()  # recovered work is not saved anywhere yet
        self.win._sync_title()
        try:
            self.win.autosaver.save_now()  # the new autosaver takes over from here...
        except (SketchforgeError, OSError) as exc:
            self.win.show_message(f"autosave failed: {error_text(exc)}; the recovered autosave {item.path} is kept")
            return True
        forget(item)  # ...and only then is the old one removed
        if stopped:
            self.win.show_message("recovered; the step that was running when sketchforge stopped was left out")
        return True
