"""One pass of the silhouettes over a video for two readers in turn (``counterpart track``).

``counterpart track`` first estimates the camera from the people of the video's first frames, then
tracks every frame. Both read the silhouette extractor's results from the first frame on; run
twice, the extractor would learn the background and find the people of those frames twice.
:class:`SharedPass` runs it once: the first reader's frames are kept in memory (while they fit a
budget) and given to the second reader again, followed by the rest of the same pass.
"""

from __future__ import annotations

import os
from collections import deque
from collections.abc import Iterable, Iterator
from itertools import islice
from typing import Any

import numpy as np

#: the most bytes of frames and results kept for the second reader (frames of 640 x 480 take
#: about 2.5 MB each with their results: some 200 of them); more, and the video is read again
MAX_KEPT_BYTES = 512 * 2**20


def video_silhouettes(
    path: str | os.PathLike[str],
    frames: Iterable[Any] | None,
    max_frames: int | None,
    train_frames: int,
    **silhouette_params: Any,
) -> Iterable[Any]:
    """A video's frames with the silhouette extractor's results, at most ``max_frames`` of them:
    ``frames`` where a pass is shared (:class:`SharedPass`), else a pass of their own
    (``iter_video`` with an extractor of ``silhouette_params``, its background fitted on the first
    ``train_frames``).
    """
    if frames is None:
        from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, iter_video

        return iter_video(path, SilhouetteExtractor(**silhouette_params), max_frames, train_frames)
    return frames if max_frames is None else islice(frames, max_frames)


def item_bytes(item: Any) -> int:
    """Bytes of the arrays of one item: (frame, result) with the result's array attributes."""
    frame, result = item
    arrays = [frame, *(v for v in vars(result).values() if isinstance(v, np.ndarray))]
    return int(sum(a.nbytes for a in arrays))


class SharedPass:
    """The items of one iterator for two readers in turn: :meth:`first` gives the first ``n``, and
    keeps them; :meth:`again` gives them once more, then the rest of the iterator.

    Parameters
    ----------
    items : iterator of (ndarray, FrameResult)
        The video's frames with the extractor's results (``iter_video``), read once.
    max_bytes : int, default=MAX_KEPT_BYTES
        The most bytes kept (:func:`item_bytes`); past it nothing is kept and :meth:`again` is None.
    """

    def __init__(self, items: Iterator[Any], max_bytes: int = MAX_KEPT_BYTES) -> None:
        self._items = items
        self.max_bytes = int(max_bytes)
        self._kept: deque[Any] = deque()
        self._bytes = 0
        self._over = False
        self._read = 0  # items the first reader was given
        self._done = False  # the first reader read all it was offered

    def first(self, n: int) -> Iterator[Any]:
        """The first ``n`` items (fewer where the iterator ends), kept for :meth:`again`.

        Parameters
        ----------
        n : int
            Items to give, >= 0.

        Yields
        ------
        item
            The iterator's items, in order.
        """
        for item in islice(self._items, n):
            self._read += 1
            if not self._over:
                self._bytes += item_bytes(item)
                if self._bytes > self.max_bytes:
                    self._over = True
                    self._kept.clear()
                else:
                    self._kept.append(item)
            yield item
        self._done = True

    def again(self) -> Iterator[Any] | None:
        """The items :meth:`first` gave, then the rest of the iterator; None where they did not fit
        ``max_bytes`` or the first reader stopped before its last item (read the video again).

        Returns
        -------
        iterator or None
            The items from the first on, each kept one let go once given.
        """
        if self._over or not self._done or len(self._kept) != self._read:
            return None

        def items() -> Iterator[Any]:
            while self._kept:
                yield self._kept.popleft()
            yield from self._items

        return items()


__all__ = ["MAX_KEPT_BYTES", "SharedPass", "item_bytes", "video_silhouettes"]
