"""Rate-limited logging: a problem that repeats is logged a few times, then counted.

A node fed a burst of odd input (a stream that restarts on every message, frames that change size
each time) would otherwise write one line per message and bury everything else. :class:`RepeatFilter`
lets through the first ``burst`` records of each kind (logger, level and message template, so
"seq went back to %d" is one kind whatever the number) per ``window`` seconds and counts the rest;
the next record of that kind after the window says how many were held back, and so does a last
line when the process exits.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

BURST = 10
WINDOW_S = 10.0


@dataclass
class _Kind:
    start: float
    shown: int = 0
    held: int = 0


class RepeatFilter(logging.Filter):
    """A handler filter letting ``burst`` records of each kind through per ``window`` seconds.

    Parameters
    ----------
    burst : int, default=BURST
        Records of one kind (logger, level, message template) let through per window.
    window : float, default=WINDOW_S
        Length of the window, seconds (monotonic clock).
    """

    def __init__(self, burst: int = BURST, window: float = WINDOW_S) -> None:
        super().__init__()
        self.burst = burst
        self.window = window
        self._kinds: dict[tuple[str, int, str], _Kind] = {}

    def filter(self, record: logging.LogRecord) -> bool:
        """Whether to let ``record`` through; the first one of a kind after a window notes the ones held.

        Parameters
        ----------
        record : logging.LogRecord
            The record; its message is rewritten to say how many were held back when the previous
            window of its kind held some.

        Returns
        -------
        bool
            True to log the record, False when its kind has used up its ``burst`` in this window.
        """
        key = (record.name, record.levelno, str(record.msg))
        now = time.monotonic()
        kind = self._kinds.get(key)
        if kind is None or now - kind.start >= self.window:
            held = kind.held if kind is not None else 0
            kind = self._kinds[key] = _Kind(start=now)
            if held:
                record.msg = f"{record.getMessage()} ({held} more like this in the last {self.window:.0f} s not shown)"
                record.args = None
        if kind.shown >= self.burst:
            kind.held += 1
            return False
        kind.shown += 1
        return True

    def flush_held(self) -> None:
        """Log how many records of each kind were held back and not reported yet (at exit)."""
        for (name, level, msg), kind in list(self._kinds.items()):
            if kind.held:
                logging.getLogger(name).log(level, "%d more lines like %r not shown", kind.held, msg)
                kind.held = 0


__all__ = ["RepeatFilter", "BURST", "WINDOW_S"]
