"""A folder of numbered images read as a video: the layout of most published footage with per-frame
ground truth (CDnet, PETS, many lab recordings), for every command and node that takes a recording.

The camera node's folder source (``counterpart.nodes.camera.sources.ImageFolderSource``) and the
offline commands' reader (:func:`open_video`, :func:`read_frames`, :func:`video_info`) share the
file listing, so both take the same frames in the same order. :class:`ImageSequenceCapture`
answers the part of ``cv2.VideoCapture``'s interface that a sequential reader uses, so code
written for a video file reads a folder unchanged. The offline readers live here, below the nodes,
so that a command checks its video (missing, undecodable) before it imports any algorithm.
"""

from __future__ import annotations

import glob
import logging
import os
from pathlib import Path

import cv2
import numpy as np

log = logging.getLogger(__name__)

#: the images of a folder taken as frames: glob patterns joined by ``|``
IMAGE_PATTERN = "*.png|*.jpg"


def list_images(folder: str | os.PathLike[str], pattern: str = IMAGE_PATTERN) -> list[Path]:
    """The files of a folder matching any of the patterns, in name order (zero-padded frame numbers
    sort as numbers).

    Parameters
    ----------
    folder : str or os.PathLike
        The folder.
    pattern : str, default=IMAGE_PATTERN
        Glob patterns joined by ``|``.

    Returns
    -------
    list of Path
        The matching files (an empty list when none match).
    """
    names: set[str] = set()
    for pat in filter(None, (s.strip() for s in pattern.split("|"))):
        names.update(glob.glob(os.path.join(glob.escape(os.fspath(folder)), pat)))
    return sorted(Path(n) for n in names if os.path.isfile(n))


class ImageSequenceCapture:
    """The images of a folder as a ``cv2.VideoCapture`` that reads them in order.

    An image that does not decode, or that has another size than the first, is skipped with a
    warning and counted in ``skipped``: one bad file does not end a recording.

    Parameters
    ----------
    folder : str or os.PathLike
        The folder.
    pattern : str, default=IMAGE_PATTERN
        Glob patterns joined by ``|``.
    fps : float, default=0.0
        Frame rate reported for ``CAP_PROP_FPS``, Hz (0: unknown, as a folder of images declares
        none).

    Raises
    ------
    FileNotFoundError
        When ``folder`` is not a folder.
    ValueError
        When no file in it matches ``pattern``.
    """

    def __init__(self, folder: str | os.PathLike[str], pattern: str = IMAGE_PATTERN, fps: float = 0.0) -> None:
        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise FileNotFoundError(f"image folder not found: {os.fspath(folder)!r}")
        self.files = list_images(self.folder, pattern)
        if not self.files:
            raise ValueError(
                f"image folder {os.fspath(folder)!r} has no file matching {pattern!r}; "
                "give a folder of numbered PNG or JPEG frames"
            )
        self.fps = float(fps)
        self.skipped = 0
        self._index = 0
        self._size: tuple[int, int] | None = None

    def isOpened(self) -> bool:  # noqa: N802 (cv2.VideoCapture's name)
        return self._index <= len(self.files)

    def grab(self) -> bool:
        """Step over the next file without decoding it; False past the last."""
        if self._index >= len(self.files):
            return False
        self._index += 1
        return True

    def read(self) -> tuple[bool, np.ndarray | None]:
        """The next image that decodes to the first image's size.

        Returns
        -------
        ok : bool
            False past the last file.
        image : ndarray of shape (H, W, 3), dtype uint8, or None
            BGR image.
        """
        while self._index < len(self.files):
            path = self.files[self._index]
            self._index += 1
            img = cv2.imread(str(path), cv2.IMREAD_COLOR)
            size = None if img is None else (img.shape[1], img.shape[0])
            if size is not None and self._size is None:
                self._size = size
            if size is not None and size == self._size:
                return True, img
            self.skipped += 1
            why = "does not decode" if img is None else f"is {size[0]}x{size[1]}, the first image {self._size}"
            log.warning("image %s %s: skipped (%d so far)", path, why, self.skipped)
        return False, None

    def get(self, prop: int) -> float:
        """``CAP_PROP_FPS`` (the given rate), ``CAP_PROP_FRAME_COUNT`` (the files), 0 otherwise."""
        if prop == cv2.CAP_PROP_FPS:
            return self.fps
        if prop == cv2.CAP_PROP_FRAME_COUNT:
            return float(len(self.files))
        return 0.0

    def release(self) -> None:
        self._index = len(self.files) + 1


__all__ = ["IMAGE_PATTERN", "ImageSequenceCapture", "list_images", "open_video", "read_frames", "video_info"]


def open_video(path: str | os.PathLike[str]) -> cv2.VideoCapture | ImageSequenceCapture:
    """A video file, or a folder of numbered images read as one (:class:`ImageSequenceCapture`).

    Parameters
    ----------
    path : str or os.PathLike
        The video file or the folder.

    Returns
    -------
    cv2.VideoCapture or ImageSequenceCapture
        The opened reader.

    Raises
    ------
    FileNotFoundError
        For a missing file or folder.
    ValueError
        For a file OpenCV cannot open.
    """
    p = os.fspath(path)
    if os.path.isdir(p):
        return ImageSequenceCapture(p)
    if not os.path.isfile(p):
        raise FileNotFoundError(f"video file or image folder not found: {p!r}")
    cap = cv2.VideoCapture(p)
    if not cap.isOpened():
        cap.release()
        raise ValueError(f"cannot read video {p!r}: OpenCV could not open it (unknown format or codec)")
    return cap


def read_frames(path: str | os.PathLike[str], max_frames: int | None = None) -> np.ndarray:
    """The first frames of a video that decode.

    Parameters
    ----------
    path : str or os.PathLike
        The video file, or a folder of numbered PNG or JPEG frames.
    max_frames : int or None, default=None
        Frames to read at most (None: all).

    Returns
    -------
    ndarray of shape (N, H, W, 3), dtype uint8
        BGR frames.

    Raises
    ------
    FileNotFoundError
        For a missing file or folder.
    ValueError
        For one OpenCV cannot decode.
    """
    cap = open_video(path)
    frames = []
    try:
        while max_frames is None or len(frames) < max_frames:
            ok, frame = cap.read()
            if not ok:
                break
            frames.append(frame)
    finally:
        cap.release()
    if not frames:
        raise ValueError(f"cannot read video {os.fspath(path)!r}: no frame decodes")
    return np.stack(frames)


def video_info(path: str | os.PathLike[str]) -> tuple[float, int]:
    """The frame rate and frame count a video file declares.

    Parameters
    ----------
    path : str or os.PathLike
        The video file, or a folder of numbered PNG or JPEG frames.

    Returns
    -------
    fps : float
        Declared frame rate, Hz (0 where it declares none).
    n_frames : int
        Declared frame count (0 where it declares none; a guide for progress, not a promise).

    Raises
    ------
    FileNotFoundError
        For a missing file or folder.
    ValueError
        For one OpenCV cannot open.
    """
    cap = open_video(path)
    try:
        return float(cap.get(cv2.CAP_PROP_FPS) or 0.0), max(0, int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0))
    finally:
        cap.release()
