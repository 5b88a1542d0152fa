"""A progress bar on a terminal, and failure lines that scroll above it.

On a terminal (the stream is a tty) the bar is redrawn in place on its own line, at most ten
times a second. Anywhere else (a log file, a pipe, CI) there is no bar: only the failure lines
and the final summary, so a log holds nothing but lines worth reading.
"""

from __future__ import annotations

import shutil
import sys
import time
from typing import TextIO

#: Seconds between redraws of the bar.
REDRAW_S = 0.1


def _duration(seconds: float) -> str:
    s = int(round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {(s % 3600) // 60:02d} min"


class ProgressBar:
    """Counts finished and failed jobs out of ``total`` and shows them.

    Parameters
    ----------
    total : int
    noun : str
        What is counted ("documents", "samples").
    stream : text stream, default stderr
    bar : bool or None
        Draw the bar; None: only when ``stream`` is a terminal.
    """

    def __init__(self, total: int, noun: str = "documents", stream: TextIO | None = None, bar: bool | None = None) -> None:
        self.total = int(total)
        self.noun = noun
        self.stream = stream if stream is not None else sys.stderr
        isatty = getattr(self.stream, "isatty", None)
        self.bar = bool(isatty and isatty()) if bar is None else bar
        self.done = 0
        self.failed = 0
        self.start = time.monotonic()
        self._drawn = 0.0
        self._shown = False

    def advance(self, ok: bool) -> None:
        """One more job finished (``ok`` or failed)."""
        self.done += 1
        self.failed += 0 if ok else 1
        now = time.monotonic()
        if self.bar and (now - self._drawn >= REDRAW_S or self.done == self.total):
            self._draw(now)

    def line(self, text: str) -> None:
        """Print a line (a failure) above the bar."""
        if self._shown:
            self._clear()
        print(text, file=self.stream, flush=True)
        if self.bar:
            self._draw(time.monotonic())

    def close(self) -> None:
        """Remove the bar (the summary line that follows says the rest)."""
        if self._shown:
            self._clear()

    def text(self, width: int) -> str:
        """The bar as one line of at most ``width`` characters."""
        elapsed = time.monotonic() - self.start
        rate = self.done / elapsed if elapsed > 0 else 0.0
        tail = f" {self.done}/{self.total} {self.noun}"
        if self.failed:
            tail += f", {self.failed} failed"
        if self.done and rate > 0:
            tail += f", {rate:.2f}/s"
            if self.done < self.total:
                tail += f", {_duration((self.total - self.done) / rate)} left"
        room = width - len(tail) - 3
        if room < 10:
            return tail.strip()[:width]
        filled = room * self.done // max(1, self.total)
        return "[" + "#" * filled + "." * (room - filled) + "]" + tail

    def _draw(self, now: float) -> None:
        width = max(20, shutil.get_terminal_size((80, 24)).columns - 1)
        self.stream.write("\r" + self.text(width) + "\x1b[K")
        self.stream.flush()
        self._drawn = now
        self._shown = True

    def _clear(self) -> None:
        self.stream.write("\r\x1b[K")
        self.stream.flush()
        self._shown = False
