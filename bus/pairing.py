"""Pairing messages of several inputs by frame number (``seq``): the runtime's one synchroniser.

In the spirit of ROS's ``message_filters.TimeSynchronizer``, keyed on ``seq`` instead of the stamp:
a node declares which of its inputs are paired (:class:`Pairing`) and gets one callback per set,
``Node.on_paired(PairedSet)``. :class:`SeqSynchronizer` is the bus-free part (a test, a notebook or a
node's own book-keeping can drive it by hand).

Every input arrives in increasing ``seq`` order, but inputs interleave arbitrarily and some skip
frames (a ``latest`` subscription dropping stale messages, a node that gave up on a frame). A set
``S`` is *decided* once every input either delivered ``S`` or went past it (delivered a newer seq,
or ended): nothing more can arrive for it. Decided sets go out in seq order. A set needs all of
its ``required`` inputs; one that misses any of them is dropped (counted as ``dropped``); missing
``optional`` inputs are None in the set (``partial``). The policy for what never completes:

* ``max_pending`` sets holding every required message may wait for optional ones; beyond it the
  oldest goes out with what it has (``forced``);
* ``timeout`` (seconds, None: no limit): a set holding every required message waits at most this
  long for the optional ones, measured from the arrival of its last required message, applied by
  :meth:`SeqSynchronizer.poll` (``timed_out``);
* ``max_ahead`` further sets may hold messages that came before a required one (camera frames
  while the silhouettes are still being computed); beyond it the oldest of them are dropped
  (``overflow``): memory stays bounded by ``max_pending + max_ahead`` sets;
* a message whose set was decided already is ``late``: dropped.

A stream restart (a camera restarted, a bag replayed) is the first required input, the *anchor*,
going back (or repeating a seq): a new *epoch* of the stream starts, flagged ``restart`` on its first
set so that a streaming consumer can reset its state. Sets are keyed by (epoch, seq) and every input
follows the anchor into the new epoch when its own seq goes back, so the old stream's stragglers on
an input that has not restarted yet still complete the old stream's sets and never mix with the new
stream's messages of the same seq. An input that goes back before the anchor does is held aside
(up to ``max_ahead`` messages): if the anchor restarts too, its messages join the new stream; if it
comes back past where it was instead, they were only stragglers and count as ``late`` (or fill a
gap in a set still waiting), and the pairing goes on as before. (So an input is taken to restart
ahead of the anchor only while its new stream stays below where its old one ended: inputs of one
camera restart within a few frames of each other.)
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

#: a set's key: (epoch of the stream, seq)
Key = tuple[int, int]


@dataclass(frozen=True)
class Pairing:
    """Which inputs are paired by ``seq``, and what happens to sets that never complete.

    Parameters
    ----------
    required : tuple of str
        Input ports every set must have; a set that misses one is dropped.
    optional : tuple of str
        Input ports waited for, but a set goes out without them (None) once they went past it,
        ended, or the policy below gives up on them.
    max_pending : int
        Most sets with every required message held back for optional ones (>= 1).
    max_ahead : int
        Most further sets holding messages that arrived before a required one (>= 0).
    timeout : float or None
        Seconds a set with every required message waits for the optional ones (None: as long as
        ``max_pending`` allows).

    Raises
    ------
    ValueError
        If there is no required input, an input is listed twice or as both required and optional,
        ``max_pending`` < 1, ``max_ahead`` < 0 or ``timeout`` < 0.
    """

    required: tuple[str, ...]
    optional: tuple[str, ...] = ()
    max_pending: int = 8
    max_ahead: int = 64
    timeout: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "required", tuple(self.required))
        object.__setattr__(self, "optional", tuple(self.optional))
        if not self.required:
            raise ValueError("a pairing needs at least one required input")
        both = sorted(set(self.required) & set(self.optional))
        if both:
            raise ValueError(f"input(s) {', '.join(both)} are declared both required and optional")
        if len(set(self.ports)) != len(self.ports):
            raise ValueError(f"an input is listed twice in {list(self.ports)}")
        if self.max_pending < 1:
            raise ValueError(f"max_pending must be >= 1 set, got {self.max_pending}")
        if self.max_ahead < 0:
            raise ValueError(f"max_ahead must be >= 0 sets, got {self.max_ahead}")
        if self.timeout is not None and not self.timeout >= 0:
            raise ValueError(f"timeout must be >= 0 seconds or None, got {self.timeout}")

    @property
    def ports(self) -> tuple[str, ...]:
        """Every paired input, required first."""
        return self.required + self.optional

    def restrict(self, ports: Sequence[str]) -> Pairing | None:
        """The pairing of the inputs among ``ports`` (a node whose parameters leave some out).

        Parameters
        ----------
        ports : sequence of str
            The input ports the node has.

        Returns
        -------
        Pairing or None
            The pairing without the optional inputs that are not there; None when a required one is
            not there.
        """
        if not set(self.required) <= set(ports):
            return None
        return replace(self, optional=tuple(p for p in self.optional if p in ports))


@dataclass(frozen=True)
class PairedSet:
    """One set that went out.

    Parameters
    ----------
    seq : int
        The set's frame number.
    msgs : dict of str to Any
        Port -> message (None for an optional input that did not deliver).
    restart : bool
        True on the first set after the stream restarted.
    """

    seq: int
    msgs: dict[str, Any]
    restart: bool = False

    def __getitem__(self, port: str) -> Any:
        return self.msgs[port]

    def get(self, port: str) -> Any:
        """The message of ``port``.

        Parameters
        ----------
        port : str
            A paired input port.

        Returns
        -------
        Any
            Its message, None when it did not deliver.
        """
        return self.msgs.get(port)


@dataclass
class PairingStats:
    """Counters since start.

    Attributes
    ----------
    delivered : int
        Sets delivered.
    partial : int
        Sets delivered with an optional input missing.
    dropped : int
        Sets decided without a required message, dropped.
    overflow : int
        Sets (or held-aside messages) dropped beyond ``max_ahead``.
    forced : int
        Sets delivered early by ``max_pending``.
    timed_out : int
        Sets delivered early by ``timeout``.
    late : int
        Messages that came after their set was decided.
    restarts : int
        Stream restarts.
    missing : dict of str to int
        Per port, the sets delivered without it.
    """

    delivered: int = 0
    partial: int = 0
    dropped: int = 0
    overflow: int = 0
    forced: int = 0
    timed_out: int = 0
    late: int = 0
    restarts: int = 0
    missing: dict[str, int] = field(default_factory=dict)

    def figures(self, prefix: str = "paired_") -> dict[str, float]:
        """The counters as a node's stats figures.

        Parameters
        ----------
        prefix : str
            Put before every counter's name.

        Returns
        -------
        dict of str to float
            ``paired_delivered``, ``paired_missing_pose``, ...
        """
        out = {f"{prefix}{k}": float(v) for k, v in vars(self).items() if k != "missing"}
        out.update({f"{prefix}missing_{p}": float(n) for p, n in self.missing.items()})
        return out


@dataclass
class _Set:
    msgs: dict[str, Any] = field(default_factory=dict)
    since: float | None = None  # when its last required message arrived (s, monotonic)


class SeqSynchronizer:
    """Collects messages per (epoch, seq) and delivers sets in order once they are decided.

    Parameters
    ----------
    pairing : Pairing
        The inputs and the policy. ``timeout`` may be changed on the instance while it runs (the
        renderer stops waiting while its partners come late).
    """

    def __init__(self, pairing: Pairing) -> None:
        self.pairing = pairing
        self.ports = pairing.ports
        self.timeout = pairing.timeout
        self.stats = PairingStats(missing={p: 0 for p in self.ports})
        self._pending: dict[Key, _Set] = {}
        self._anchor = pairing.required[0]
        self._stream = 0  # the anchor's epoch
        self._epoch = {p: 0 for p in self.ports}
        #: inputs that went back while the anchor did not: (seq, message, arrival) since then
        self._aside: dict[str, list[tuple[int, Any, float]]] = {}
        self._last = {p: -1 for p in self.ports}
        self._ended: set[str] = set()
        self._decided: Key = (0, -1)  # the newest key delivered or dropped
        self._delivered_epoch = 0

    # ------------------------------------------------------------------------------ input
    def add(self, port: str, seq: int, msg: Any, now: float | None = None) -> list[PairedSet]:
        """Take one message of ``port``; return the sets it decides (possibly none), in order.

        Parameters
        ----------
        port : str
            A paired input port.
        seq : int
            The message's frame number.
        msg : Any
            The message.
        now : float or None
            Its arrival (s, monotonic; default: now), from which ``timeout`` counts.

        Returns
        -------
        list of PairedSet
            The sets now decided, in seq order (possibly none).

        Raises
        ------
        KeyError
            For a port that is not paired.
        """
        if port not in self._last:
            raise KeyError(f"unknown port {port!r}; paired ports: {', '.join(self.ports)}")
        now = time.monotonic() if now is None else now
        out: list[PairedSet] = []
        self._ended.discard(port)
        if port in self._aside:
            if seq <= self._last[port]:
                self._hold_aside(port, seq, msg, now)
                return out
            self._stragglers(port)  # it came back past where it was
        elif seq <= self._last[port]:  # this input's stream restarted
            if port == self._anchor:
                self._restart()
            elif self._epoch[port] < self._stream:  # following the anchor
                self._epoch[port] += 1
            else:  # ahead of the anchor, or a straggler: wait and see
                self._aside[port] = []
                self._hold_aside(port, seq, msg, now)
                return out
        self._put(port, seq, msg, now)
        self._drain(out)
        return out

    def end(self, port: str) -> list[PairedSet]:
        """``port`` ended (end of stream): it goes past every set.

        Parameters
        ----------
        port : str
            A paired input port.

        Returns
        -------
        list of PairedSet
            The sets now decided, in seq order (possibly none).

        Raises
        ------
        KeyError
            For a port that is not paired.
        """
        if port not in self._last:
            raise KeyError(f"unknown port {port!r}; paired ports: {', '.join(self.ports)}")
        self._ended.add(port)  # what it held aside still joins the new stream if the anchor restarts
        out: list[PairedSet] = []
        self._drain(out)
        return out

    def poll(self, now: float | None = None) -> list[PairedSet]:
        """The sets whose wait for optional inputs ran past ``timeout`` at ``now``.

        Parameters
        ----------
        now : float or None
            The time, s, monotonic (default: now).

        Returns
        -------
        list of PairedSet
            The sets now decided, in seq order (possibly none).
        """
        out: list[PairedSet] = []
        self._drain(out, now=time.monotonic() if now is None else now)
        return out

    def flush(self) -> list[PairedSet]:
        """Deliver everything pending with what it has (at the end of the stream).

        Returns
        -------
        list of PairedSet
            Every pending set that holds its required messages, in seq order.
        """
        for port in list(self._aside):
            self._stragglers(port)
        out: list[PairedSet] = []
        self._drain(out, force_all=True)
        return out

    # ---------------------------------------------------------------------------- queries
    @property
    def pending(self) -> list[int]:
        """Seqs of the sets held back, in order."""
        return [seq for _, seq in sorted(self._pending)]

    def next_deadline(self) -> float | None:
        """When the oldest waiting set times out.

        Returns
        -------
        float or None
            The time, s, monotonic; None without a timeout or a waiting set.
        """
        if self.timeout is None:
            return None
        times = [s.since for s in self._pending.values() if s.since is not None]
        return min(times) + self.timeout if times else None

    # --------------------------------------------------------------------------- internals
    def _put(self, port: str, seq: int, msg: Any, now: float, straggler: bool = False) -> None:
        if not straggler:
            self._last[port] = seq
        key = (self._epoch[port], seq)
        held = self._pending.get(key)
        # a straggler only fills a gap: it never replaces what its set has
        if (key <= self._decided and held is None) or (straggler and held is not None and port in held.msgs):
            self.stats.late += 1
            return
        s = self._pending.setdefault(key, _Set())
        s.msgs[port] = msg
        if s.since is None and self._has_required(s):
            s.since = now

    def _hold_aside(self, port: str, seq: int, msg: Any, now: float) -> None:
        held = self._aside[port]
        held.append((seq, msg, now))
        if len(held) > self.pairing.max_ahead:
            held.pop(0)
            self.stats.overflow += 1

    def _stragglers(self, port: str) -> None:
        """What ``port`` held aside belongs to the current stream after all."""
        for seq, msg, now in self._aside.pop(port):
            self._put(port, seq, msg, now, straggler=True)

    def _restart(self) -> None:
        """The anchor went back: a new epoch; inputs that went back before it join it."""
        self._stream += 1
        self.stats.restarts += 1
        self._epoch[self._anchor] = self._stream
        for port, held in list(self._aside.items()):
            del self._aside[port]
            self._epoch[port] = self._stream
            for seq, msg, now in held:
                self._put(port, seq, msg, now)

    def _has_required(self, s: _Set) -> bool:
        return all(p in s.msgs for p in self.pairing.required)

    def _is_decided(self, key: Key, s: _Set) -> bool:
        return all(p in s.msgs or p in self._ended or (self._epoch[p], self._last[p]) > key for p in self.ports)

    def _release(self, key: Key, out: list[PairedSet]) -> None:
        s = self._pending.pop(key)
        self._decided = max(self._decided, key)
        if not self._has_required(s):
            self.stats.dropped += 1
            return
        absent = [p for p in self.ports if p not in s.msgs]
        for p in absent:
            self.stats.missing[p] += 1
        self.stats.partial += bool(absent)
        self.stats.delivered += 1
        out.append(PairedSet(key[1], {p: s.msgs.get(p) for p in self.ports}, key[0] > self._delivered_epoch))
        self._delivered_epoch = key[0]

    def _drain(self, out: list[PairedSet], force_all: bool = False, now: float | None = None) -> None:
        cfg = self.pairing
        waiting = sum(s.since is not None for s in self._pending.values())
        for key in sorted(self._pending):
            s = self._pending[key]
            if force_all or self._is_decided(key, s):
                pass
            elif s.since is not None and waiting > cfg.max_pending:  # an optional input lags: go on
                self.stats.forced += 1
            elif s.since is not None and now is not None and self.timeout is not None and now - s.since >= self.timeout:
                self.stats.timed_out += 1
            else:
                break  # sets go out in order: a later one waits for this one
            waiting -= s.since is not None
            self._release(key, out)
        while len(self._pending) > cfg.max_pending + cfg.max_ahead:
            key = min(self._pending)
            if self._pending[key].since is not None:
                self.stats.forced += 1
                self._release(key, out)
            else:  # messages far ahead of a required input: the oldest go
                del self._pending[key]
                self.stats.overflow += 1


__all__ = ["Pairing", "PairedSet", "PairingStats", "SeqSynchronizer"]
