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

    crops: (T, h, w, 3) uint8 BGR in one fixed box; masks: (T, h, w) bool; valid: (T,) frames with
    the person found; labels: (T, K) int8 (1/0/-1) named ``names``; fps: frames per second;
    box: (x, y, w, h) px of the crop in the original frames; facing: +1 the person faces the image's
    right, -1 its left.
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
    """One box (x, y, w, h) px holding the person on (almost) every frame: the 2nd and 98th
    percentiles of the per-frame boxes' edges (a few frames of a bad mask do not blow it up), widened
    by ``margin`` px and clipped to the frame of ``size`` (W, H).

    boxes: (n, 4) per-frame boxes (x, y, w, h) px of the frames with the person.
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

    pieces: per frame None (nobody found) or (image (bh, bw, 3) uint8, mask (bh, bw) bool, bbox (x, y,
    bw, bh) px) cut at the person's own box; size: (W, H) of the frames. Returns (crops (T, h, w, 3),
    masks (T, h, w), valid (T,), box (x, y, w, h)).
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

    Returns (the recording with the simulator's exact masks and labels, the labels (T_video, K) of
    every video frame: -1 during the empty start). ``video``: also write the frames there (Motion-JPEG
    ``.avi``), as a camera would have recorded them.
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
