"""When frames go out (pacing), which frames (start, loop, limit) and in what form (size, gray).

Pacing modes of a replayed source (a live device paces itself: every mode publishes as captured):

- ``realtime``: frame k is due at ``t0 + k / fps`` on the monotonic clock; nothing is skipped. A
  stall of more than :data:`REANCHOR_S` (or two frame periods) re-anchors the schedule instead of
  bursting to catch up, so the output keeps the footage's spacing after a hiccup.
- ``rate``: as ``realtime`` at ``rate`` times the footage's speed (2.0: twice as fast).
- ``fast``: as fast as the source decodes and the bus accepts.
- ``lockstep``: as ``fast``; meant for graphs whose consumers subscribe with the ``reliable``
  policy, whose backpressure then blocks the camera so that no frame is dropped anywhere.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import cv2
import numpy as np

PACING_MODES = ("realtime", "rate", "fast", "lockstep")
REANCHOR_S = 0.25
_SLEEP_SLICE_S = 0.05


class Pacer:
    """Schedules frame k of a replay.

    Parameters
    ----------
    mode : str
        One of ``PACING_MODES`` (module docstring).
    fps : float, default=0.0
        Frames per second of the footage (needed by ``realtime`` and ``rate``).
    rate : float, default=1.0
        Speed factor (used by ``rate`` mode).
    clock : callable, default=time.monotonic
        Returns seconds (monotonic).

    Attributes
    ----------
    reanchors : int
        Times a stall re-anchored the schedule.

    Raises
    ------
    ValueError
        For an unknown mode, a paced mode without ``fps`` > 0, or ``rate`` <= 0 in ``rate`` mode.
    """

    def __init__(
        self, mode: str, fps: float = 0.0, rate: float = 1.0, clock: Callable[[], float] = time.monotonic
    ) -> None:
        if mode not in PACING_MODES:
            raise ValueError(f"pacing {mode!r}: expected one of {', '.join(PACING_MODES)}")
        if mode in ("realtime", "rate") and not fps > 0:
            raise ValueError(f"pacing {mode!r} needs the source's frame rate; got fps = {fps!r} (set parameter 'fps')")
        if mode == "rate" and not rate > 0:
            raise ValueError(f"pacing 'rate' needs rate > 0, got {rate!r}")
        self.mode = mode
        self.clock = clock
        self.period = 0.0
        if mode == "realtime":
            self.period = 1.0 / fps
        elif mode == "rate":
            self.period = 1.0 / (fps * rate)
        self.t0: float | None = None
        self.k0 = 0
        self.reanchors = 0

    @property
    def paced(self) -> bool:
        return self.period > 0

    def due(self, k: int) -> float | None:
        """Monotonic time at which frame k is due.

        Parameters
        ----------
        k : int
            Frame index.

        Returns
        -------
        float or None
            Seconds on the clock, or None when unpaced (or before the first frame).
        """
        if not self.paced or self.t0 is None:
            return None
        return self.t0 + (k - self.k0) * self.period

    def wait(self, k: int, should_stop: Callable[[], bool] = lambda: False) -> bool:
        """Sleep until frame k is due (the first call starts the schedule).

        Parameters
        ----------
        k : int
            Frame index.
        should_stop : callable, default=lambda: False
            Polled while waiting.

        Returns
        -------
        bool
            False when ``should_stop()`` became true while waiting.
        """
        if not self.paced:
            return not should_stop()
        now = self.clock()
        if self.t0 is None:
            self.t0, self.k0 = now, k
            return not should_stop()
        due = self.due(k)
        if now - due > max(REANCHOR_S, 2 * self.period):
            self.t0, self.k0 = now, k
            self.reanchors += 1
            return not should_stop()
        while now < due:
            if should_stop():
                return False
            time.sleep(min(_SLEEP_SLICE_S, due - now))
            now = self.clock()
        return not should_stop()


def frames(source, start_frame: int = 0, loop: bool = False, max_frames: int = 0) -> Iterator[tuple[np.ndarray, float]]:
    """Yield the frames of an opened source.

    Parameters
    ----------
    source : object
        An opened source (``read``, ``rewind``, ``skip``, ``live``, ``uri``).
    start_frame : int, default=0
        Frames skipped at the start (and after each loop).
    loop : bool, default=False
        Go back to ``start_frame`` at the end.
    max_frames : int, default=0
        Stop after this many frames (0: no limit).

    Yields
    ------
    image : ndarray
        The frame.
    source_time : float
        Its position in the source, seconds.

    Raises
    ------
    ValueError
        When ``start_frame`` is at or past the end of the source (or the source cannot skip), or
        when ``loop`` is asked of a live source.
    """
    if loop and getattr(source, "live", False):
        raise ValueError(f"loop: source {source.uri} is a live device and cannot loop")
    if start_frame:
        if not hasattr(source, "skip"):
            raise ValueError(f"start_frame: source {source.uri} cannot skip frames")
        if source.skip(start_frame) < start_frame:
            raise ValueError(f"start_frame {start_frame} is past the end of {source.uri}")
    n = 0
    while max_frames <= 0 or n < max_frames:
        ok, image, t = source.read()
        if not ok:
            if not loop:
                return
            source.rewind()
            if start_frame:
                source.skip(start_frame)
            ok, image, t = source.read()
            if not ok:  # an empty loop would spin forever
                return
        yield image, t
        n += 1


class Prefetch:
    """Iterate ``items`` in a background thread, up to ``depth`` items ahead.

    Decoding (``cv2.VideoCapture.read`` releases the GIL) then overlaps with encoding and sending
    the previous frame, so a replay goes out at about the decoder's own rate. Exceptions raised by
    ``items`` are re-raised by ``__next__`` in order. :meth:`close` stops and joins the thread: call
    it before closing the source the items come from.

    Parameters
    ----------
    items : iterator
        The items.
    depth : int, default=4
        Items read ahead at most.

    Raises
    ------
    ValueError
        If ``depth`` < 1.
    """

    _END = object()

    def __init__(self, items: Iterator[Any], depth: int = 4) -> None:
        if depth < 1:
            raise ValueError(f"prefetch depth must be >= 1, got {depth}")
        self._items = items
        self._q: queue.Queue = queue.Queue(maxsize=depth)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="prefetch", daemon=True)
        self._thread.start()

    def _put(self, x: Any) -> bool:
        while not self._stop.is_set():
            try:
                self._q.put(x, timeout=0.05)
                return True
            except queue.Full:
                pass
        return False

    def _run(self) -> None:
        try:
            for x in self._items:
                if not self._put((True, x)):
                    return
        except BaseException as exc:  # handed to the consumer, which decides
            self._put((False, exc))
            return
        self._put((True, self._END))

    def __iter__(self) -> Prefetch:
        return self

    def __next__(self) -> Any:
        ok, x = self._q.get()
        if not ok:
            raise x
        if x is self._END:
            raise StopIteration
        return x

    def close(self) -> None:
        self._stop.set()
        self._thread.join()


#: the least shrink (source pixels per output pixel, along the axis shrunk most) resized by averaging
#: each output pixel's area (INTER_AREA); a smaller one (the real-time graph's 400 -> 320 px: 1.25)
#: is interpolated (INTER_LINEAR), whose 2 x 2 neighbourhood still reaches every source pixel below a
#: shrink of 2, at a fifth of the cost of INTER_AREA's general (non-integer) path; the silhouettes'
#: figures on real clips shrunk 1.25 times were the same either way (people found, keypoint coverage)
AREA_MIN_SHRINK = 2.0


def output_size(size: tuple[int, int], width: int = 0, height: int = 0, max_side: int = 0) -> tuple[int, int]:
    """The size of the output for a source.

    Parameters
    ----------
    size : tuple of (int, int)
        The source's (width, height), pixels.
    width, height : int, default=0
        Both 0 keeps the size, one of them scales keeping the aspect ratio, both give that size exactly.
    max_side : int, default=0
        With ``width`` and ``height`` both 0, a source whose longer side is over this many pixels is
        scaled down to it, keeping the aspect ratio (0: never).

    Returns
    -------
    tuple of (int, int)
        The output's (width, height), pixels.
    """
    w0, h0 = size
    if width and height:
        return int(width), int(height)
    if width:
        return int(width), max(1, round(h0 * width / w0))
    if height:
        return max(1, round(w0 * height / h0)), int(height)
    if max_side and max(w0, h0) > max_side:
        return (
            (int(max_side), max(1, round(h0 * max_side / w0)))
            if w0 >= h0
            else (max(1, round(w0 * max_side / h0)), int(max_side))
        )
    return int(w0), int(h0)


def convert(image: np.ndarray, size: tuple[int, int] | None = None, gray: bool = False) -> tuple[np.ndarray, str]:
    """Resize an image when its size differs and make it grey when asked.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image.
    size : tuple of (int, int) or None, default=None
        The output's (width, height), pixels; None keeps it. Shrunk by averaging (INTER_AREA) from
        ``AREA_MIN_SHRINK`` times on, else interpolated (INTER_LINEAR).
    gray : bool, default=False
        Make it (H, W) mono8.

    Returns
    -------
    image : ndarray of shape (H, W, 3) or (H, W), dtype uint8
        The converted image.
    encoding : str
        ``bgr8`` or ``mono8``.
    """
    if size is not None and (image.shape[1], image.shape[0]) != tuple(size):
        shrink = max(image.shape[1] / size[0], image.shape[0] / size[1])
        interp = cv2.INTER_AREA if shrink >= AREA_MIN_SHRINK else cv2.INTER_LINEAR
        image = cv2.resize(image, tuple(size), interpolation=interp)
    if gray:
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), "mono8"
    return image, "bgr8"


def replay_progress(done: int, total: int | None, elapsed_s: float) -> str:
    """One line of a replay's progress, for the log of a long lockstep run.

    Parameters
    ----------
    done : int
        Frames published so far.
    total : int or None
        Frames the replay will publish (None: not known, or looping).
    elapsed_s : float
        Seconds since the first frame was published.

    Returns
    -------
    str
        "frame 300 of 1296 (23%) published, 9.8 frames/s, about 1 min 42 s left", without the
        share and the time left when the total is not known.
    """
    rate = done / elapsed_s if elapsed_s > 0 else 0.0
    if total is None or total <= 0:
        return f"frame {done} published, {rate:.1f} frames/s"
    text = f"frame {done} of {total} ({100 * done // total}%) published, {rate:.1f} frames/s"
    if rate > 0 and done < total:
        left = round((total - done) / rate)
        text += f", about {f'{left // 60} min ' if left >= 60 else ''}{left % 60} s left"
    return text
