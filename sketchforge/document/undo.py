"""UndoStack with QUndoStack semantics, without Qt.

- ``push`` runs the command, then drops the redo tail, then tries to merge it into the
  command on top (same ``merge_id``, never across the clean point, never into a command that
  is already below the clean index).
- Macros (``begin_macro``/``end_macro``) run their children as they are pushed and undo them
  in reverse order (pyface's Qt-free port walks forward; we do not).
- The clean index marks the saved state; it becomes unreachable (-1) when the commands that
  led to it are dropped.

Signals (all emitted only when the value really changes):
``index_changed(int)``, ``can_undo_changed(bool)``, ``can_redo_changed(bool)``,
``undo_text_changed(str)``, ``redo_text_changed(str)``, ``clean_changed(bool)``;
``history_trimmed(str)``: once, the first time the history's memory budget drops steps (the
sentence to show; the app puts it in its status bar).

Memory (issue 39): a step keeps what it replaced (a layer value; arrays already read-only are
shared, never copied), so the history grows with every step. Past ``memory_budget`` bytes
(default :data:`DEFAULT_MEMORY_BUDGET`, None: no limit) of arrays that only the history holds,
the oldest steps are dropped after each push. A dropped step can no longer be undone, but its
journal entry moves to the document's ``base_journal``: the journal, the saved file and a
replay are unchanged.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from sketchforge.cache import held_arrays
from sketchforge.document.events import Signal
from sketchforge.errors import PluginError, SketchforgeError

if TYPE_CHECKING:  # pragma: no cover
    from sketchforge.document.commands import Command

#: Bytes of arrays the undo history may hold beyond the document's own (1 GB).
DEFAULT_MEMORY_BUDGET = 10**9


class UndoStack:
    def __init__(self, document, memory_budget: int | None = DEFAULT_MEMORY_BUDGET) -> None:
        self._doc = document
        self._commands: list[Command] = []
        self._index = 0
        self._clean_index = 0
        self._macros: list = []  # open MacroCommands, innermost last
        #: Most bytes of arrays only the history holds (None: no limit); see the module doc.
        self.memory_budget = memory_budget
        #: Steps dropped so far to stay within the budget.
        self.dropped = 0
        self.history_trimmed = Signal(str, name="history_trimmed")
        # The memory tally, kept as commands come and go so that a push costs the same at any
        # depth of history: {id(command): (command, {array id: bytes})}, {array id: commands
        # holding it}, and the bytes of every array some command holds. A command's arrays are
        # read once, when it enters (the top again after a merge): a done command does not
        # swap its values afterwards.
        self._held: dict = {}
        self._users: dict = {}
        self._held_total = 0
        self.index_changed = Signal(int, name="index_changed")
        self.can_undo_changed = Signal(bool, name="can_undo_changed")
        self.can_redo_changed = Signal(bool, name="can_redo_changed")
        self.undo_text_changed = Signal(str, name="undo_text_changed")
        self.redo_text_changed = Signal(str, name="redo_text_changed")
        self.clean_changed = Signal(bool, name="clean_changed")

    # --- queries ------------------------------------------------------------------------------
    @property
    def index(self) -> int:
        return self._index

    @property
    def clean_index(self) -> int:
        return self._clean_index

    def count(self) -> int:
        return len(self._commands)

    def command(self, i: int) -> Command:
        return self._commands[i]

    def commands(self) -> list[Command]:
        """All commands, done ones first (``commands()[:index]``)."""
        return list(self._commands)

    def done_commands(self) -> list[Command]:
        return self._commands[: self._index]

    def can_undo(self) -> bool:
        return not self._macros and self._index > 0

    def can_redo(self) -> bool:
        return not self._macros and self._index < len(self._commands)

    def undo_text(self) -> str:
        return self._commands[self._index - 1].text() if self.can_undo() else ""

    def redo_text(self) -> str:
        return self._commands[self._index].text() if self.can_redo() else ""

    def is_clean(self) -> bool:
        return not self._macros and self._index == self._clean_index

    def in_macro(self) -> bool:
        return bool(self._macros)

    # --- state snapshot for change signals -----------------------------------------------------
    def _state(self):
        return (self._index, self.can_undo(), self.can_redo(), self.undo_text(), self.redo_text(), self.is_clean())

    def _emit_changes(self, before, rows_changed: bool = False) -> None:
        after = self._state()
        signals = (
            self.index_changed,
            self.can_undo_changed,
            self.can_redo_changed,
            self.undo_text_changed,
            self.redo_text_changed,
            self.clean_changed,
        )
        for sig, a, b in zip(signals, before, after):
            if a != b:
                sig.emit(b)
        if before != after or rows_changed:
            self._doc.history_changed.emit()

    # --- mutation -----------------------------------------------------------------------------
    def _run(self, command: Command, method: str) -> None:
        """Call ``command.do``/``undo`` all-or-nothing: if it raises, whatever it changed is
        put back from a snapshot taken before (layers are immutable values, so this is a few
        references), whatever the command's code did. A :class:`SketchforgeError` (the
        command's own answer to bad input) propagates as it is; anything else is a bug of the
        plugin that provides the command and becomes a PluginError naming it."""
        snap = self._doc._snapshot()
        try:
            getattr(command, method)(self._doc)
        except BaseException as exc:
            self._doc._restore_snapshot(snap)
            if isinstance(exc, SketchforgeError) or not isinstance(exc, Exception):
                raise
            host = getattr(self._doc, "host", None)
            who = host.provider_of(type(command)) if host is not None and hasattr(host, "provider_of") else None
            by = f" (from plugin {who!r})" if who else ""
            raise PluginError(
                f"command {command.name!r}{by} failed in {method}: {type(exc).__name__}: {exc}; the document is unchanged"
            ) from exc

    def push(self, command: Command) -> Command:
        """Run ``command`` and record it. If it raises, nothing is recorded, the document is
        restored to its state before (see :meth:`_run`) and the error propagates."""
        before = self._state()
        self._run(command, "do")
        if self._macros:
            macro = self._macros[-1]
            if not (macro.children and macro.children[-1].try_merge(command)):
                macro.children.append(command)
            return command
        if self._index < len(self._commands):
            del self._commands[self._index :]
            if self._clean_index > self._index:
                self._clean_index = -1
        top = self._commands[-1] if self._commands else None
        mergeable = top is not None and self._index != self._clean_index
        if mergeable and top.try_merge(command):
            pass
        else:
            self._commands.append(command)
            self._index += 1
        self._emit_changes(before, rows_changed=self._keep_within_budget() > 0)
        return command

    def undo(self) -> None:
        if not self.can_undo():
            return
        before = self._state()
        self._run(self._commands[self._index - 1], "undo")
        self._index -= 1
        self._emit_changes(before)

    def redo(self) -> None:
        if not self.can_redo():
            return
        before = self._state()
        self._run(self._commands[self._index], "do")
        self._index += 1
        self._emit_changes(before)

    def set_index(self, index: int) -> None:
        """Undo or redo until ``index`` (the history panel's click)."""
        index = max(0, min(int(index), len(self._commands)))
        while self._index > index:
            self.undo()
        while self._index < index:
            self.redo()

    def set_clean(self) -> None:
        before = self._state()
        self._clean_index = self._index
        self._emit_changes(before)

    def reset_clean(self) -> None:
        """No state is the saved one (QUndoStack::resetClean): e.g. recovered work."""
        before = self._state()
        self._clean_index = -1
        self._emit_changes(before)

    def clear(self) -> None:
        """Forget the history (the document keeps its current state), e.g. after opening a file."""
        if self._macros:
            raise RuntimeError("cannot clear the undo stack inside a macro")
        before = self._state()
        self._commands.clear()
        self._held, self._users, self._held_total = {}, {}, 0
        self._index = 0
        self._clean_index = 0
        self._emit_changes(before)

    def begin_macro(self, text: str) -> None:
        from sketchforge.document.commands import MacroCommand

        self._macros.append(MacroCommand(text=text, children=[]))

    def end_macro(self) -> Command | None:
        """Close the innermost macro; an empty macro is dropped."""
        if not self._macros:
            raise RuntimeError("end_macro without begin_macro")
        macro = self._macros.pop()
        if not macro.children:
            return None
        if self._macros:
            self._macros[-1].children.append(macro)
            return macro
        # The children already ran; record the macro without running it again.
        before = self._state()
        if self._index < len(self._commands):
            del self._commands[self._index :]
            if self._clean_index > self._index:
                self._clean_index = -1
        self._commands.append(macro)
        self._index += 1
        self._emit_changes(before, rows_changed=self._keep_within_budget() > 0)
        return macro

    # --- memory -------------------------------------------------------------------------------
    def history_bytes(self) -> int:
        """Bytes of the arrays only the history holds (what forgetting it would free): every
        array a step keeps, counted once however many steps share it, less those of the
        document's current layers."""
        self._sync_tally()
        return self._history_bytes(held_arrays(self._doc.layers))

    def _history_bytes(self, current: dict) -> int:
        return self._held_total - sum(n for k, n in current.items() if k in self._users)

    def _track(self, command) -> None:
        self._untrack(id(command))
        held = held_arrays(command)
        self._held[id(command)] = (command, held)
        for k, n in held.items():
            users = self._users.get(k, 0)
            if users == 0:
                self._held_total += n
            self._users[k] = users + 1

    def _untrack(self, key: int) -> None:
        entry = self._held.pop(key, None)
        if entry is None:
            return
        for k, n in entry[1].items():
            users = self._users[k] - 1
            if users == 0:
                del self._users[k]
                self._held_total -= n
            else:
                self._users[k] = users

    def _sync_tally(self) -> None:
        live = {id(c) for c in self._commands}
        for key in [k for k in self._held if k not in live]:
            self._untrack(key)
        for c in self._commands:
            if id(c) not in self._held:
                self._track(c)
        if self._commands:
            self._track(self._commands[-1])  # a merge may have changed it

    def _keep_within_budget(self) -> int:
        """Drop the oldest steps while the history holds more than ``memory_budget`` bytes,
        keeping the newest step; the first time, say so (``history_trimmed``). Returns how
        many were dropped."""
        self._sync_tally()  # always: it also lets go of the commands that left the stack
        if self.memory_budget is None or self._index < 2:
            return 0
        current = held_arrays(self._doc.layers)
        drop = 0
        while self._history_bytes(current) > self.memory_budget and self._index - drop > 1:
            self._untrack(id(self._commands[drop]))
            drop += 1
        if drop:
            self._drop_oldest(drop)
        return drop

    def _drop_oldest(self, n: int) -> None:
        gone = self._commands[:n]
        # The journal stays whole: the document replays from base_journal + the done steps.
        self._doc.base_journal.extend(c.to_dict() for c in gone)
        del self._commands[:n]
        self._index -= n
        self._clean_index = self._clean_index - n if self._clean_index >= n else -1
        self.dropped += n
        if self.dropped == n:  # the first time: say it once
            budget = self.memory_budget
            self.history_trimmed.emit(
                f"the undo history reached its memory budget of {budget / 1e9:.3g} GB: its oldest steps are dropped "
                f"from now on ({n} so far); the document and its journal are unchanged"
            )

    def abort_macro(self) -> None:
        """Undo the children of the innermost open macro and drop it (an error mid-gesture)."""
        if not self._macros:
            return
        macro = self._macros.pop()
        for child in reversed(macro.children):
            child.undo(self._doc)
