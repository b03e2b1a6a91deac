"""Pairing messages of several topics by frame number (``seq``), without any process running.

Every topic arrives in increasing ``seq`` order, but topics interleave arbitrarily and some may skip
frames (a ``latest`` subscription dropping stale messages, a tracker that gave up on a frame). A
frame ``S`` is *decided* once every port either delivered ``S`` or went past it (delivered a newer
seq, or ended): nothing more can arrive for it. Decided frames are released in seq order; the
required port must be among the delivered ones, otherwise the frame is dropped (nothing to label).

A side port that stalls without going past ``S`` would hold every later frame back; ``max_pending``
bounds the frames that have their required message and wait only for side ports: beyond it the
oldest is released with what it has. Side messages that arrive ahead of the required port (camera
frames while the silhouettes are still being computed) wait for it, up to ``max_ahead`` frames;
beyond that the oldest of them are discarded (``overflow``) and their frames go out without them.

A required port whose seq goes backwards means the stream restarted (a camera restarted, a bag
replayed again): what is pending is released first, then the pairing starts afresh and the first
frame after it is flagged ``restart`` so that a streaming consumer can reset its state.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class Paired:
    """One released frame: ``seq``, ``msgs`` port -> message for the ports that delivered it
    (always including the required port), ``restart`` True on the first frame after a restart.
    """

    seq: int
    msgs: dict[str, Any]
    restart: bool = False


@dataclass
class PairingStats:
    """Counters: frames released, released with a port missing (``incomplete``), dropped without
    the required port (``unpaired``), released early by ``max_pending`` (``forced``), side messages
    discarded beyond ``max_ahead`` (``overflow``), messages that arrived after their frame was
    released (``late``), and stream restarts.
    """

    released: int = 0
    incomplete: int = 0
    unpaired: int = 0
    forced: int = 0
    overflow: int = 0
    late: int = 0
    restarts: int = 0
    missing: dict[str, int] = field(default_factory=dict)


class SeqPairer:
    """Collects messages per seq and releases frames in seq order once they are decided.

    ports: every subscribed port; required: the port a frame cannot be released without;
    max_pending: most frames with their required message held back waiting for a slow side port
    (>= 1); max_ahead: most further frames holding side messages that arrived before the required
    one (>= 0).
    """

    def __init__(self, ports: Sequence[str], required: str, max_pending: int = 8, max_ahead: int = 64) -> None:
        ports = list(dict.fromkeys(ports))
        if required not in ports:
            raise ValueError(f"required port {required!r} is not among the ports {ports}")
        if max_pending < 1:
            raise ValueError(f"max_pending must be >= 1 frame, got {max_pending}")
        self.ports = ports
        self.required = required
        if max_ahead < 0:
            raise ValueError(f"max_ahead must be >= 0 frames, got {max_ahead}")
        self.max_pending = max_pending
        self.max_ahead = max_ahead
        self.stats = PairingStats(missing={p: 0 for p in ports})
        self._reset()

    def _reset(self) -> None:
        self._pending: dict[int, dict[str, Any]] = {}
        self._last: dict[str, int] = {p: -1 for p in self.ports}
        self._ended: set[str] = set()
        self._released = -1
        self._restart_next = False

    def _passed(self, port: str, seq: int) -> bool:
        return port in self._ended or self._last[port] > seq

    def _decided(self, seq: int) -> bool:
        got = self._pending[seq]
        return all(p in got or self._passed(p, seq) for p in self.ports)

    def _release(self, seq: int, out: list[Paired]) -> None:
        msgs = self._pending.pop(seq)
        self._released = max(self._released, seq)
        if self.required not in msgs:
            self.stats.unpaired += 1
            return
        absent = [p for p in self.ports if p not in msgs]
        for p in absent:
            self.stats.missing[p] += 1
        self.stats.incomplete += bool(absent)
        self.stats.released += 1
        out.append(Paired(seq, msgs, self._restart_next))
        self._restart_next = False

    def _drain(self, out: list[Paired], force_all: bool = False) -> None:
        waiting = sum(self.required in m for m in self._pending.values())
        for seq in sorted(self._pending):
            if force_all or self._decided(seq):
                waiting -= self.required in self._pending[seq]
                self._release(seq, out)
            elif self.required in self._pending[seq] and waiting > self.max_pending:
                # a side port lags: go on without it
                self.stats.forced += 1
                waiting -= 1
                self._release(seq, out)
            else:
                break  # frames go out in order: a later one waits for this one
        while len(self._pending) > self.max_pending + self.max_ahead:
            seq = min(self._pending)
            if self.required in self._pending[seq]:
                self.stats.forced += 1
                self._release(seq, out)
            else:  # side messages far ahead of the required port: the oldest go
                del self._pending[seq]
                self.stats.overflow += 1

    def add(self, port: str, seq: int, msg: Any) -> list[Paired]:
        """Take one message; return the frames it completes (possibly none), in seq order."""
        if port not in self._last:
            raise KeyError(f"unknown port {port!r}; ports: {', '.join(self.ports)}")
        out: list[Paired] = []
        if seq <= self._last[port]:
            if port != self.required:
                # a side topic that restarted: follow it; frames it skipped count as passed
                self._last[port] = seq
            else:
                self.stats.restarts += 1
                self._drain(out, force_all=True)
                self._reset()
                self._restart_next = True
        self._last[port] = seq
        self._ended.discard(port)
        if seq <= self._released and seq not in self._pending:
            self.stats.late += 1
        else:
            self._pending.setdefault(seq, {})[port] = msg
        self._drain(out)
        return out

    def end(self, port: str) -> list[Paired]:
        """``port`` ended (end of stream): it goes past every frame; return the frames now decided."""
        if port not in self._last:
            raise KeyError(f"unknown port {port!r}; ports: {', '.join(self.ports)}")
        self._ended.add(port)
        out: list[Paired] = []
        self._drain(out)
        return out

    def flush(self) -> list[Paired]:
        """Release everything pending with what it has (at the end of the stream)."""
        out: list[Paired] = []
        self._drain(out, force_all=True)
        return out

    @property
    def pending(self) -> list[int]:
        """Seqs held back, in order."""
        return sorted(self._pending)
