"""A recording of one person for the video-texture avatar: masked, cropped frames and social labels.

From a video file: ``counterpart.apps.avatar_video`` (``counterpart learn avatar``), which combines
the silhouette node's and the labeller's algorithms. From the simulator (:func:`sim_recording`): a
conversation's listener rendered alone, with the simulator's exact masks and labels, for the default
avatar, the tests and the benchmark.

Alignment (the paper is silent): one fixed crop box for the whole recording
(:func:`crop_box`), the person's own sway kept, so jumps between frames of the
graph join frames in the same image coordinates and the composited avatar stands still where the
person stood still.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

Progress = Callable[[str], None] | None


@dataclass
class Recording:
    """A person's recording ready to learn from.

    Attributes
    ----------
    crops : ndarray of shape (T, h, w, 3), dtype uint8
        BGR crops in one fixed box.
    masks : ndarray of shape (T, h, w), dtype bool
        The person's masks in the crops.
    valid : ndarray of shape (T,), dtype bool
        Frames with the person found.
    labels : ndarray of shape (T, K), dtype int8
        Social labels (1/0/-1), named ``names``.
    names : tuple of str
        The K label names.
    fps : float
        Frames per second.
    box : tuple of (int, int, int, int)
        (x, y, w, h) of the crop in the original frames, pixels.
    facing : float, default=-1.0
        +1 the person faces the image's right, -1 its left.
    """

    crops: np.ndarray
    masks: np.ndarray
    valid: np.ndarray
    labels: np.ndarray
    names: tuple[str, ...]
    fps: float
    box: tuple[int, int, int, int]
    facing: float = -1.0


def crop_box(boxes: np.ndarray, size: tuple[int, int], margin: int = 4) -> tuple[int, int, int, int]:
    """One box holding the person on (almost) every frame.

    The 2nd and 98th percentiles of the per-frame boxes' edges (a few frames of a bad mask do not
    blow it up), widened by ``margin`` and clipped to the frame.

    Parameters
    ----------
    boxes : ndarray of shape (n, 4)
        Per-frame boxes (x, y, w, h), pixels, of the frames with the person.
    size : tuple of (int, int)
        Frame (W, H), pixels.
    margin : int, default=4
        Widening on every side, pixels.

    Returns
    -------
    tuple of (int, int, int, int)
        The box (x, y, w, h), pixels.
    """
    b = np.asarray(boxes, np.float64)
    W, H = size
    x0 = max(int(np.percentile(b[:, 0], 2)) - margin, 0)
    y0 = max(int(np.percentile(b[:, 1], 2)) - margin, 0)
    x1 = min(int(np.ceil(np.percentile(b[:, 0] + b[:, 2], 98))) + margin, W)
    y1 = min(int(np.ceil(np.percentile(b[:, 1] + b[:, 3], 98))) + margin, H)
    return x0, y0, x1 - x0, y1 - y0


def crop_recording(
    pieces: Sequence[tuple[np.ndarray, np.ndarray, tuple[int, int, int, int]] | None], size: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int, int, int]]:
    """Crops in one box from per-frame pieces.

    Parameters
    ----------
    pieces : sequence of tuple or None
        Per frame None (nobody found) or (image (bh, bw, 3) uint8, mask (bh, bw) bool, bbox
        (x, y, bw, bh) pixels) cut at the person's own box.
    size : tuple of (int, int)
        Frame (W, H), pixels.

    Returns
    -------
    crops : ndarray of shape (T, h, w, 3), dtype uint8
        BGR crops in the common box.
    masks : ndarray of shape (T, h, w), dtype bool
        The person's masks in the crops.
    valid : ndarray of shape (T,), dtype bool
        Frames whose mask holds at least a quarter of the median mask area.
    box : tuple of (int, int, int, int)
        The common box (x, y, w, h), pixels.

    Raises
    ------
    ValueError
        If the person is found on no frame.
    """
    T = len(pieces)
    W, H = size
    boxes = np.array([p[2] if p is not None else (0, 0, 0, 0) for p in pieces], np.int64).reshape(T, 4)
    have = np.array([p is not None for p in pieces])
    if not have.any():
        raise ValueError("the person is found on no frame")
    x0, y0, ww, hh = crop_box(boxes[have], size)
    crops = np.zeros((T, hh, ww, 3), np.uint8)
    masks = np.zeros((T, hh, ww), bool)
    for t, p in enumerate(pieces):
        if p is None:
            continue
        img, m, (x, y, w, h) = p
        # the piece's overlap with the common box
        ax0, ay0 = max(x, x0), max(y, y0)
        ax1, ay1 = min(x + w, x0 + ww), min(y + h, y0 + hh)
        if ax1 <= ax0 or ay1 <= ay0:
            continue
        crops[t, ay0 - y0 : ay1 - y0, ax0 - x0 : ax1 - x0] = img[ay0 - y : ay1 - y, ax0 - x : ax1 - x]
        masks[t, ay0 - y0 : ay1 - y0, ax0 - x0 : ax1 - x0] = m[ay0 - y : ay1 - y, ax0 - x : ax1 - x]
    valid = masks.reshape(T, -1).sum(1) >= 0.25 * np.median(masks[have].reshape(int(have.sum()), -1).sum(1))
    return crops, masks, valid, (x0, y0, ww, hh)


def person_piece(
    frame: np.ndarray, mask: np.ndarray
) -> tuple[np.ndarray, np.ndarray, tuple[int, int, int, int]] | None:
    """The piece of a frame cut at the person's own box, for :func:`crop_recording`.

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3), dtype uint8
        The BGR frame.
    mask : ndarray of shape (H, W), dtype bool
        The person's mask.

    Returns
    -------
    tuple or None
        (image (bh, bw, 3), mask (bh, bw), bbox (x, y, bw, bh) pixels), copies; None when the mask
        is empty.
    """
    ys, xs = np.nonzero(mask.any(axis=1)), np.nonzero(mask.any(axis=0))
    if not len(ys[0]):
        return None
    y0, y1, x0, x1 = ys[0][0], ys[0][-1] + 1, xs[0][0], xs[0][-1] + 1
    return frame[y0:y1, x0:x1].copy(), mask[y0:y1, x0:x1].copy(), (int(x0), int(y0), int(x1 - x0), int(y1 - y0))


def sim_recording(
    seconds: float = 60.0,
    seed: int = 0,
    interested: bool = True,
    empty_s: float = 1.6,
    video: str | os.PathLike[str] | None = None,
    say: Progress = None,
) -> tuple[Recording, np.ndarray]:
    """A recorded person with known labels from the simulator: the right person of a ``conversation``
    (who listens and nods half of the time and talks the other half), rendered alone (the other
    person out of view; the labels are those of the conversation), after ``empty_s`` seconds of the
    empty room. The simulator is reached through its entry point (``counterpart.bus.plugins``).

    Parameters
    ----------
    seconds : float, default=60.0
        Length of the conversation, seconds.
    seed : int, default=0
        Seed of the simulator.
    interested : bool, default=True
        Whether the listener is interested.
    empty_s : float, default=1.6
        Seconds of the empty room at the start.
    video : str or path-like or None, default=None
        Also write the frames there (Motion-JPEG ``.avi``), as a camera would have recorded them.
    say : callable or None, default=None
        Progress callback taking a line of text.

    Returns
    -------
    recording : Recording
        The recording with the simulator's exact masks and labels.
    labels : ndarray of shape (T_video, K), dtype int8
        The labels of every video frame: -1 during the empty start.

    Raises
    ------
    ValueError
        If ``video`` cannot be written.
    """
    from counterpart.bus.plugins import simulator

    say = say or (lambda s: None)
    listener = simulator().listener_recording(seconds, seed=seed, interested=interested, empty_s=empty_s)
    T, fps = len(listener), listener.fps
    say(f"simulator: rendering {T} frames ({T / fps:.0f} s) of a listener")
    writer = None
    if video is not None:
        writer = cv2.VideoWriter(os.fspath(video), cv2.VideoWriter_fourcc(*"MJPG"), float(fps), listener.size)
        if not writer.isOpened():
            raise ValueError(f"cannot write video {os.fspath(video)!r}")
    pieces = []
    try:
        for i, (img, mask) in enumerate(listener.frames()):
            if writer is not None:
                writer.write(img)
            pieces.append(person_piece(img, mask) if i >= listener.n_empty else None)
    finally:
        if writer is not None:
            writer.release()
    crops, masks, valid, box = crop_recording(pieces, listener.size)
    labels = listener.labels
    # the listener faces -X: the image's left with the default camera
    return Recording(crops, masks, valid, labels, listener.names, fps, box, facing=-1.0), labels
