"""A recording of one person for the video-texture avatar, from a video file (``counterpart learn avatar``).

The silhouette node's algorithm (``counterpart.nodes.silhouette.pipeline``: the background fitted on
the first frames, which must show the empty room, then the person's region on every frame; the
largest region is the person) gives the mask, refined into a matte without the fringe of bled colours
around the person (:func:`refine_matte`); the labeller (``counterpart.nodes.labeller``, from the
silhouette: nod, shake, activity; from a frontal face: talking, laughing) gives the per-frame labels
unless a label file is given. An application: it combines three nodes' algorithms into the
responder's :class:`~counterpart.nodes.responder.avatar_recording.Recording`.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import cv2
import numpy as np

from counterpart.nodes.responder.avatar_recording import Progress, Recording, crop_recording, person_piece

#: grey levels (largest channel, 3x3 smoothed) a pixel of the person's region must differ from the
#: background model by to be kept in the matte
MATTE_TAU = 25.0


def refine_matte(frame: np.ndarray, region: np.ndarray, background: np.ndarray, tau: float = MATTE_TAU) -> np.ndarray:
    """The person's matte for the avatar: the region the silhouette algorithm found, less its fringe of
    background pixels (the person's colours bled into them by the camera's and the video codec's
    chroma subsampling, so the background model calls them foreground: composited, they would
    surround the avatar with a halo of the recording room), with enclosed holes filled again.

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3), dtype uint8
        The video frame.
    region : ndarray of shape (H, W), dtype bool
        The person's region found by the silhouette algorithm.
    background : ndarray of shape (H, W, 3)
        The background model's mean.
    tau : float
        Grey levels (largest channel, 3x3 smoothed) a pixel must differ from the background by to be kept.

    Returns
    -------
    ndarray of shape (H, W), dtype bool
        The matte, within ``region``.
    """
    from counterpart.nodes.silhouette.regions import clean_mask

    d = np.abs(frame.astype(np.float32) - background.reshape(frame.shape)).max(axis=-1)
    d = cv2.GaussianBlur(d, (3, 3), 0)
    return clean_mask(region & (d > tau), open_px=0, close_px=5, fill_holes=True) & region


def read_label_file(
    path: str | os.PathLike[str], person: str, required: Sequence[str] = ()
) -> tuple[np.ndarray, tuple[str, ...]]:
    """The labels of ``person`` from a label file (``counterpart.nodes.labeller.mining.read_labels``:
    ``.npz`` with signals_a/_b, or ``.csv``).

    Parameters
    ----------
    path : str or os.PathLike
        The label file.
    person : str
        The person's id in the file.
    required : sequence of str
        Signals that must be among the labels and occur at least once.

    Returns
    -------
    labels : ndarray of shape (T, K), dtype int8
        The person's per-frame labels.
    names : tuple of str of length K
        The signals' names, in the order of the columns.

    Raises
    ------
    ValueError
        If the file has no such person.
    RecordingError
        Naming a ``required`` signal that the file lacks or that never occurs in it.
    """
    from counterpart.nodes.labeller.mining import read_labels
    from counterpart.nodes.responder.video_texture import RecordingError

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
    """Frames [start, stop) of a video: per frame the person's piece (``person_piece``) and, when
    ``labelling``, the labeller's row of labels (SIGNALS order); and the frame size. ``one_thread``:
    OpenCV on one thread (in a worker process: the processes are the parallelism, and OpenCV's own
    threads on top cost a fifth more CPU on a busy machine).
    """
    from counterpart.apps.offline import FrameProgress

    if one_thread:
        cv2.setNumThreads(1)
    from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, iter_video

    ex = SilhouetteExtractor(outlines=labelling)
    if labelling:
        from counterpart.body.image_sequence import video_info
        from counterpart.nodes.labeller.labeller import PersonObservation, SocialLabeller
        from counterpart.nodes.labeller.signals import SIGNALS, UNKNOWN

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
            piece = person_piece(frame, matte)
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

    Parameters
    ----------
    path : str or os.PathLike
        The video file.
    labels : str or os.PathLike or None
        A label file; None: the labeller labels every frame.
    person : str
        The person's id in the label file.
    facing : float
        The way the person faces in the video (+1 right, -1 left).
    train_frames : int
        First frames (the empty room) the background is learnt from.
    workers : int
        Processes that cut the masks out, each from its part of the video with its own copy of the
        background model (one when the labeller labels: its windows run over the whole video).
    required : sequence of str
        Signals that must occur (checked in the label file before the video is read).
    say : callable or None
        Called with a line of progress text.

    Returns
    -------
    Recording
        The recording: cropped frames, masks, labels, fps and the person's facing.

    Raises
    ------
    ValueError
        When no frame decodes, the label file does not match the video's frame count or the person
        is found on no frame (and for a bad label file, see :func:`read_label_file`).
    """
    from counterpart.body.image_sequence import video_info
    from counterpart.nodes.labeller.signals import SIGNALS

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
        # forkserver, not fork: a fork of a process whose OpenCV or BLAS threads hold a lock can hang
        # its workers forever (seen once in the test suite, which runs after other OpenCV work)
        with ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("forkserver")) as pool:
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
