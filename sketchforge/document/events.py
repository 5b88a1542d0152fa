"""Typed callbacks: the document's and the undo stack's way to tell views what changed.

A :class:`Signal` is declared with the types of its arguments (documentation and a cheap
arity check); listeners are plain callables. Emission order is connection order, so behaviour
never depends on dict or set ordering.
"""

from __future__ import annotations

from collections.abc import Callable


class Signal:
    """A list of listeners called with the same positional arguments."""

    def __init__(self, *arg_types: type, name: str = "") -> None:
        self.arg_types = arg_types
        self.name = name
        self._slots: list[Callable] = []

    def connect(self, slot: Callable) -> Callable:
        """Add a listener (returned, so this works as a decorator)."""
        if slot not in self._slots:
            self._slots.append(slot)
        return slot

    def disconnect(self, slot: Callable) -> None:
        try:
            self._slots.remove(slot)
        except ValueError:
            pass

    def emit(self, *args) -> None:
        if len(args) != len(self.arg_types):
            raise TypeError(f"signal {self.name!r} takes {len(self.arg_types)} arguments, got {len(args)}")
        for slot in list(self._slots):
            slot(*args)

    def __len__(self) -> int:
        return len(self._slots)
