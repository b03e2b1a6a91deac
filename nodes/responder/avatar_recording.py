"""A recording of one person for the video-texture avatar: masked, cropped frames and social labels.

From a video file (``counterpart learn avatar``): the silhouette node's algorithm
(``counterpart.nodes.silhouette.pipeline``: the background fitted on the first frames, which must show the
empty room, then the person's region on every frame; the largest region is the person) gives the
mask, refined into a matte without the fringe of bled colours around the person (:func:`refine_matte`);
the labeller (``counterpart.nodes.labeller``, from the silhouette: nod, shake, activity; from a frontal face:
talking, laughing) gives the per-frame labels unless a label file is given. From the simulator
(:func:`sim_recording`): a conversation's listener rendered alone, with the simulator's exact masks
and labels, for the default avatar, the tests and the benchmark.

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


def _piece(frame: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple[int, int, int, int]] | None:
    ys, xs = np.nonzero(mask.any(axis=1)), np.nonzero(mask.any(axis=0))
    if not len(ys[0]):
        return None
    y0, y1, x0, x1 = ys[0][0], ys[0][-1] + 1, xs[0][0], xs[0][-1] + 1
    return frame[y0:y1, x0:x1].copy(), mask[y0:y1, x0:x1].copy(), (int(x0), int(y0), int(x1 - x0), int(y1 - y0))


#: grey levels (largest channel, 3x3 smoothed) a pixel of the person's region must differ from the
#: background model by to be kept in the matte
MATTE_TAU = 25.0


def refine_matte(frame: np.ndarray, region: np.ndarray, background: np.ndarray, tau: float = MATTE_TAU) -> np.ndarray:
    """The person's matte for the avatar: the region the silhouette algorithm found, less its fringe of
    background pixels (the person's colours bled into them by the camera's and the video codec's
    chroma subsampling, so the background model calls them foreground: composited, they would
    surround the avatar with a halo of the recording room), with enclosed holes filled again.

    frame: (H, W, 3) uint8; region: (H, W) bool; background: (H, W, 3) the background model's mean.
    Returns (H, W) bool within ``region``.
    """
    from counterpart.nodes.silhouette.regions import clean_mask

    d = np.abs(frame.astype(np.float32) - background.reshape(frame.shape)).max(axis=-1)
    d = cv2.GaussianBlur(d, (3, 3), 0)
    return clean_mask(region & (d > tau), open_px=0, close_px=5, fill_holes=True) & region


def read_label_file(
    path: str | os.PathLike[str], person: str, required: Sequence[str] = ()
) -> tuple[np.ndarray, tuple[str, ...]]:
    """(labels (T, K) int8, names) of ``person`` from a label file (``counterpart.nodes.labeller.mining.read_labels``:
    ``.npz`` with signals_a/_b, or ``.csv``); ValueError naming each ``required`` signal that the file
    lacks or that never occurs in it.
    """
    from counterpart.nodes.labeller.mining import read_labels

    from .video_texture import RecordingError

    streams = read_labels(path)
    if person not in streams.people:
        raise ValueError(
            f"{os.fspath(path)}: no person {person!r} (it has {', '.join(streams.people)}); choose one with --person"
        )
    lab = np.asarray(streams.people[person], np.int8)
    names = tuple(streams.names)
    for r in required:
        if r not in names:
            raise RecordingError(
                f"signal {r!r} is not among the labels of {os.fspath(path)} ({', '.join(names)}); "
                "give labels that include it, or leave it out of --signals"
            )
        if not (lab[:, names.index(r)] == 1).any():
            raise RecordingError(
                f"signal {r!r} never occurs in {os.fspath(path)} (0 of {len(lab)} frames of person "
                f"{person} labelled {r}): record the person doing it, or leave it out of --signals"
            )
    return lab, names


def _masks_part(
    path: str, start: int, stop: int | None, train_frames: int, labelling: bool, part: str, one_thread: bool = False
) -> tuple[list, list[np.ndarray], tuple[int, int]]:
    """Frames [start, stop) of a video: per frame the person's piece (``_piece``) and, when
    ``labelling``, the labeller's row of labels (SIGNALS order); and the frame size. ``one_thread``:
    OpenCV on one thread (in a worker process: the processes are the parallelism, and OpenCV's own
    threads on top cost a fifth more CPU on a busy machine).
    """
    from counterpart.bus.cli_offline import FrameProgress

    if one_thread:
        cv2.setNumThreads(1)
    from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, iter_video

    ex = SilhouetteExtractor(outlines=labelling)
    if labelling:
        from counterpart.nodes.labeller.labeller import PersonObservation, SocialLabeller
        from counterpart.nodes.labeller.signals import SIGNALS, UNKNOWN
        from counterpart.nodes.silhouette.pipeline import video_info

        labeller = SocialLabeller(video_info(path)[0] or 25.0)
    progress = FrameProgress(f"learn avatar{part}")
    pieces: list = []
    rows: list[np.ndarray] = []
    size = (0, 0)
    count = None if stop is None else stop - start
    for frame, res in iter_video(path, ex, max_frames=count, train_frames=train_frames, start=start):
        size = (frame.shape[1], frame.shape[0])
        p = max(res.people, key=lambda q: q.area) if res.people else None
        piece = None
        if p is not None:
            x, y, w, h = p.bbox  # the matte is refined inside the person's box only: a fraction of the frame
            box = (slice(y, y + h), slice(x, x + w))
            matte = np.zeros(frame.shape[:2], bool)
            matte[box] = refine_matte(frame[box], res.labels[box] == p.id + 1, ex.subtractor.model.mean_[box])
            piece = _piece(frame, matte)
        pieces.append(piece)
        if labelling:
            row = np.full(len(SIGNALS), UNKNOWN, np.int8)
            if p is not None and p.ref_point is not None:
                obs = PersonObservation(
                    head_px=np.asarray(p.ref_point),
                    ref_px=np.asarray(p.centroid),
                    height_px=float(p.height),
                    control_points=p.ctrl,
                    box=p.bbox,
                )
                out = labeller.update({0: obs}, image=frame)[0]
                row = np.array([out[s][1] for s in SIGNALS], np.int8)
            else:
                labeller.skip()
            rows.append(row)
        progress(start + len(pieces), 0 if stop is None else stop)
    return pieces, rows, size


def video_recording(
    path: str | os.PathLike[str],
    labels: str | os.PathLike[str] | None = None,
    person: str = "a",
    facing: float = -1.0,
    train_frames: int = 30,
    workers: int = 2,
    required: Sequence[str] = (),
    say: Progress = None,
) -> Recording:
    """The recording of the one person in a video file (module docstring).

    labels: a label file (else the labeller labels every frame); person: its person id; required:
    signals that must occur (checked in the label file before the video is read); facing: the
    way the person faces in the video (+1 right, -1 left); train_frames: first frames (the empty
    room) the background is learnt from; workers: processes that cut the masks out, each from its
    part of the video with its own copy of the background model (one when the labeller labels: its
    windows run over the whole video).
    """
    from counterpart.nodes.labeller.signals import SIGNALS
    from counterpart.nodes.silhouette.pipeline import video_info

    say = say or (lambda s: None)
    p = os.fspath(path)
    fps, declared = video_info(p)
    if labels is not None:  # a bad label file fails now, not after minutes of masks
        lab, names = read_label_file(labels, person, required)
    fps = fps or 25.0
    labelling = labels is None
    if labelling:
        say(
            "no label file: the labeller labels every frame (nod, shake, activity from the silhouette; "
            "talking, laughing from a frontal face)"
        )
    n = 1 if labelling or declared < 4 * train_frames else max(1, min(int(workers), os.cpu_count() or 1))
    bounds = [declared * k // n for k in range(n)] + [None]
    if n == 1:
        parts = [_masks_part(p, 0, None, train_frames, labelling, "")]
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        say(f"cutting the masks out in {n} processes, one part of the video each")
        with ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("fork")) as pool:
            futures = [
                pool.submit(_masks_part, p, bounds[k], bounds[k + 1], train_frames, False, f" part {k + 1}/{n}", True)
                for k in range(n)
            ]
            parts = [f.result() for f in futures]
    pieces = [q for part in parts for q in part[0]]
    size = next((part[2] for part in parts if part[2] != (0, 0)), (0, 0))
    if not pieces:
        raise ValueError(f"{p}: no frame decodes")
    if labelling:
        lab, names = np.stack(parts[0][1]), SIGNALS
    elif len(lab) != len(pieces):
        raise ValueError(
            f"{os.fspath(labels)}: {len(lab)} frames of labels for a video of {len(pieces)} frames; "
            "the labels must have one row per video frame"
        )
    found = sum(q is not None for q in pieces)
    say(f"the person is found on {found} of {len(pieces)} frames")
    if found == 0:
        raise ValueError(
            f"{p}: nobody found on any frame; the video must start with about "
            f"{train_frames / fps:.1f} s of the empty room (the background), then the person in view"
        )
    crops, masks, valid, box = crop_recording(pieces, size)
    return Recording(crops, masks, valid, lab, tuple(names), fps, box, facing)


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
    empty room.

    Returns (the recording with the simulator's exact masks and labels, the labels (T_video, K) of
    every video frame: -1 during the empty start). ``video``: also write the frames there (Motion-JPEG
    ``.avi``), as a camera would have recorded them.
    """
    from counterpart.body.pose import DOF_INDEX
    from counterpart.sim.render import Renderer
    from counterpart.sim.scenarios import make_scenario

    say = say or (lambda s: None)
    sc = make_scenario(
        "conversation", seed=seed, duration=seconds, emotion="neutral", strength=0.0, interested=interested
    )
    fps = sc.fps
    n_empty = int(round(empty_s * fps))
    away = sc.poses_a.copy()
    away[:, DOF_INDEX["root_x"]] -= 40.0  # far out of view: the listener alone in the picture
    gone = np.repeat(sc.poses_b[:1], n_empty, axis=0)
    gone[:, DOF_INDEX["root_x"]] += 40.0
    unknown = np.full((n_empty, len(sc.signal_names)), -1, np.int8)
    labels = np.concatenate([unknown, sc.signals_b])
    sc.poses_a = np.concatenate([np.repeat(away[:1], n_empty, axis=0), away])
    sc.poses_b = np.concatenate([gone, sc.poses_b])
    sc.signals_a, sc.signals_b = np.concatenate([unknown, sc.signals_a]), labels
    sc.phase = np.concatenate([np.zeros(n_empty, np.int32), sc.phase])
    r = Renderer(sc, seed=seed)
    T = sc.poses_a.shape[0]
    say(f"simulator: rendering {T} frames ({T / fps:.0f} s) of a listener")
    writer = None
    if video is not None:
        writer = cv2.VideoWriter(os.fspath(video), cv2.VideoWriter_fourcc(*"MJPG"), float(fps), r.size)
        if not writer.isOpened():
            raise ValueError(f"cannot write video {os.fspath(video)!r}")
    pieces = []
    try:
        for i in range(T):
            img, truth = r.render(i)
            if writer is not None:
                writer.write(img)
            pieces.append(_piece(img, truth.masks[1]) if i >= n_empty else None)
    finally:
        if writer is not None:
            writer.release()
    crops, masks, valid, box = crop_recording(pieces, r.size)
    # the listener faces -X: the image's left with the default camera
    return Recording(crops, masks, valid, labels, tuple(sc.signal_names), fps, box, facing=-1.0), labels
