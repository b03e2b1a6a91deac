"""Progress lines of the long offline commands (``counterpart track``, ``counterpart silhouettes``)."""
from __future__ import annotations

import sys
import time


class FrameProgress:
    """A ``progress(done, declared)`` callback that prints ``[label] frame i/N, x fps`` on stderr at
    most every ``every`` seconds (N left out when the file declares no frame count)."""

    def __init__(self, label: str, every: float = 2.0) -> None:
        self.label = label
        self.every = every
        self.t0: float | None = None
        self.first = 0
        self.last = 0.0

    def __call__(self, done: int, declared: int) -> None:
        now = time.monotonic()
        if self.t0 is None:  # the rate counts from the first frame, not from the set-up before it
            self.t0 = self.last = now
            self.first = done
            return
        if now - self.last >= self.every:
            self.last = now
            of = f"/{declared}" if declared else ""
            fps = (done - self.first) / (now - self.t0)
            print(f"[{self.label}] frame {done}{of}, {fps:.1f} fps", file=sys.stderr, flush=True)
