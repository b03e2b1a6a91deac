"""The newest messages of one topic by seq, for the message of a frame or the newest before it."""

from __future__ import annotations

import bisect
from collections import OrderedDict
from typing import Any


class SeqHistory:
    """The newest ``size`` messages of one topic by ``seq`` (the order they came decides which go).

    Parameters
    ----------
    size : int
        Messages kept.

    Attributes
    ----------
    max_seq : int
        The highest seq that came (-1: none).
    """

    def __init__(self, size: int) -> None:
        self.size = size
        self.items: OrderedDict[int, Any] = OrderedDict()  # in the order they came
        self.seqs: list[int] = []  # the same seqs, sorted: a lookup bisects instead of scanning
        self.max_seq = -1

    def add(self, msg: Any) -> None:
        """Keep ``msg`` (one with a ``seq``), replacing one of the same seq; the oldest beyond ``size`` go.

        Parameters
        ----------
        msg : object
            The message.
        """
        seq = int(msg.seq)
        if seq not in self.items:
            bisect.insort(self.seqs, seq)
        self.items[seq] = msg
        self.items.move_to_end(seq)
        self.max_seq = max(self.max_seq, seq)
        while len(self.items) > self.size:
            self.seqs.remove(self.items.popitem(last=False)[0])

    def forget_before(self, seq: int) -> None:
        """Forget what no lookup of ``seq`` or a later seq can return (a consumer that has passed
        ``seq``): the messages older than the newest one at or before it, which stays, as it is
        still the one before any later seq that has none of its own.

        Parameters
        ----------
        seq : int
            The seq passed.
        """
        i = bisect.bisect_right(self.seqs, seq) - 1
        if i <= 0:
            return
        for old in self.seqs[:i]:
            del self.items[old]
        del self.seqs[:i]

    def exact(self, seq: int) -> Any:
        """The message of ``seq``, or None."""
        return self.items.get(seq)

    def at_or_before(self, seq: int) -> Any:
        """The message of the highest seq at most ``seq`` (seqs are never negative), or None."""
        i = bisect.bisect_right(self.seqs, seq)
        return self.items[self.seqs[i - 1]] if i and self.seqs[i - 1] >= 0 else None
