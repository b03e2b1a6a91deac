"""Writing the composited video: H.264 in .mp4 where OpenCV's FFmpeg can, else Motion-JPEG .avi.

OpenCV wheels differ in the encoders their FFmpeg carries (many have no software H.264 encoder;
some open an ``avc1`` writer that then fails). So each candidate codec is probed once per process:
a few frames are written to a temporary file and read back; only a codec whose file decodes with
the right frame count is used. Motion-JPEG in AVI is built into OpenCV and always works.

Motion-JPEG frames are JPEG-encoded by ``cv2.imencode`` (libjpeg-turbo) and handed to FFmpeg's
AVI muxer as they are (``VIDEOWRITER_PROP_RAW_VIDEO``) where this OpenCV can (probed as above):
OpenCV's own MJPG writer encodes with FFmpeg's JPEG encoder, several times the CPU of
libjpeg-turbo's per frame, which the real-time graph's renderer pays on every frame. At
:data:`JPEG_QUALITY` the frames come out at least as close to the rendered ones, and the last row
of an odd-height frame is kept (FFmpeg's 4:2:0 encoder drops it).
"""

from __future__ import annotations

import logging
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np

log = logging.getLogger(__name__)

#: (fourcc, file suffix) tried in order for an .mp4 path; MJPG/.avi is the fallback
H264_CANDIDATES: tuple[tuple[str, str], ...] = (("avc1", ".mp4"), ("H264", ".mp4"))
FALLBACK: tuple[str, str] = ("MJPG", ".avi")
_PROBED: dict[str, bool] = {}
#: frames per second of a video whose stream says nothing of its rate
DEFAULT_FPS = 25.0
#: JPEG quality (1-100) of the Motion-JPEG frames encoded by ``cv2.imencode``
JPEG_QUALITY = 90


def _quiet_opencv() -> int:
    """Silence OpenCV's own log while probing (failed encoders print errors); returns the old level."""
    try:
        old = cv2.utils.logging.getLogLevel()
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
        return old
    except AttributeError:  # builds without the logging module
        return -1


def _restore_opencv(level: int) -> None:
    if level >= 0:
        cv2.utils.logging.setLogLevel(level)


def _from_codec_library(line: str) -> bool:
    """Whether a line on stderr is FFmpeg's (``[h264_v4l2m2m @ 0x55...] ...``) or OpenCV's FFmpeg
    backend's (``OpenCV: FFMPEG: ...``).
    """
    return (line.startswith("[") and " @ 0x" in line.split("]", 1)[0]) or line.startswith("OpenCV: FFMPEG:")


@contextmanager
def _codec_messages_to_debug() -> Iterator[None]:
    """Take what FFmpeg prints on the process's stderr (file descriptor 2, beyond Python's reach
    otherwise) while a codec is probed: a failed candidate prints errors ("Could not find a valid
    device") that read as the run's failure, where the fallback is expected and said in one line.
    Its lines go to this module's debug log; any other line written meanwhile goes back to stderr.
    """
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no stderr to take over
        yield
        return
    with tempfile.TemporaryFile() as caught:
        os.dup2(caught.fileno(), 2)
        try:
            yield
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            caught.seek(0)
            lines = caught.read().decode(errors="replace").splitlines()
    for line in lines:
        if _from_codec_library(line):
            log.debug("codec probe: %s", line)
        else:
            print(line, file=sys.stderr)


def _probed(key: str, probe: Callable[[str], bool]) -> bool:
    """Whether ``probe(folder)`` holds, asked once per process (in a temporary folder, with
    OpenCV's log silenced and FFmpeg's messages sent to the debug log) and remembered under ``key``.
    """
    if key not in _PROBED:
        level = _quiet_opencv()
        try:
            with _codec_messages_to_debug(), tempfile.TemporaryDirectory(prefix="cp-codec-") as tmp:
                _PROBED[key] = probe(tmp)
        finally:
            _restore_opencv(level)
    return _PROBED[key]


def codec_works(fourcc: str, suffix: str, n: int = 5) -> bool:
    """Whether OpenCV here writes ``fourcc`` into a ``suffix`` file that decodes back to ``n``
    frames (probed once per process, in a temporary folder).

    Parameters
    ----------
    fourcc : str
        The codec's four-character code, e.g. ``"avc1"``.
    suffix : str
        The file suffix, e.g. ``".mp4"``.
    n : int, default=5
        Frames (64 x 48 pixels) written in the probe.

    Returns
    -------
    bool
        True when the probe file decodes back to ``n`` frames.
    """

    def probe(tmp: str) -> bool:
        path = os.path.join(tmp, "probe" + suffix)
        wr = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*fourcc), 25.0, (64, 48))
        if not wr.isOpened():
            wr.release()
            return False
        for i in range(n):
            wr.write(np.full((48, 64, 3), 30 * i, np.uint8))
        wr.release()
        return count_frames(path) == n

    return _probed(f"{fourcc}{suffix}", probe)


def _open_raw_mjpeg(path: str, fps: float, size: tuple[int, int]) -> cv2.VideoWriter | None:
    """An FFmpeg AVI writer that takes encoded JPEG frames as they are, or None where this OpenCV
    has no such mode.
    """
    prop = getattr(cv2, "VIDEOWRITER_PROP_RAW_VIDEO", None)
    if prop is None:
        return None
    wr = cv2.VideoWriter(path, cv2.CAP_FFMPEG, cv2.VideoWriter_fourcc(*"MJPG"), fps, size, [prop, 1])
    if wr.isOpened():
        return wr
    wr.release()
    return None


def _encode_jpeg(image: np.ndarray) -> np.ndarray:
    """``image`` as JPEG bytes at :data:`JPEG_QUALITY`, one row (what a raw writer takes)."""
    ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    if not ok:
        raise ValueError(f"cannot encode a {image.dtype} {image.shape} image as JPEG")
    return buf.reshape(1, -1)


def raw_mjpeg_works(n: int = 5) -> bool:
    """Whether OpenCV here writes JPEG frames encoded by ``cv2.imencode`` into an AVI file that
    decodes back to ``n`` frames of the right size (probed once per process, in a temporary folder).

    Parameters
    ----------
    n : int, default=5
        Frames (64 x 47 pixels: an odd height) written in the probe.

    Returns
    -------
    bool
        True when the probe file decodes back to ``n`` frames of 64 x 47 pixels.
    """

    def probe(tmp: str) -> bool:
        path = os.path.join(tmp, "probe.avi")
        wr = _open_raw_mjpeg(path, 25.0, (64, 47))
        if wr is None:
            return False
        for i in range(n):
            wr.write(_encode_jpeg(np.full((47, 64, 3), 30 * i, np.uint8)))
        wr.release()
        cap = cv2.VideoCapture(path)
        first_ok, first = cap.read()
        cap.release()
        return bool(first_ok) and first.shape == (47, 64, 3) and count_frames(path) == n

    return _probed("raw-MJPG.avi", probe)


def count_frames(path: str | os.PathLike) -> int:
    """Frames that decode from the video at ``path`` (read through, not the header's count).

    Parameters
    ----------
    path : str or path-like
        The video file.

    Returns
    -------
    int
        Number of frames that decode (0 when the file does not open).
    """
    cap = cv2.VideoCapture(str(path))
    n = 0
    try:
        while cap.isOpened() and cap.grab():
            n += 1
    finally:
        cap.release()
    return n


def choose_codec(path: str | os.PathLike) -> tuple[str, Path]:
    """The fourcc and the actual output path for a requested ``path``.

    Parameters
    ----------
    path : str or path-like
        The requested file: ``.mp4`` gets H.264 when a probe shows it works here, else the same
        name with ``.avi`` and MJPG; ``.avi`` gets MJPG.

    Returns
    -------
    fourcc : str
        The codec's four-character code.
    path : Path
        The file that will be written.

    Raises
    ------
    ValueError
        If the suffix is neither ``.mp4`` nor ``.avi``.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".mp4":
        for fourcc, sfx in H264_CANDIDATES:
            if codec_works(fourcc, sfx):
                return fourcc, p
        fallback = p.with_suffix(FALLBACK[1])
        log.warning("this OpenCV cannot write H.264: writing Motion-JPEG to %s instead of %s", fallback, p)
        return FALLBACK[0], fallback
    if suffix == ".avi":
        return FALLBACK[0], p
    raise ValueError(f"video path {str(path)!r}: use a .mp4 (H.264 where available) or .avi (Motion-JPEG) file")


class VideoWriter:
    """Writes BGR frames of one size to a video file, opened on the first frame.

    ``close()`` is idempotent and must run for a playable file (the node calls it at end of stream
    and in teardown).

    Parameters
    ----------
    path : str or path-like
        The requested file (``.mp4`` or ``.avi``).
    fps : float, default=25.0
        Frames per second written into the file; 0 takes the rate the first :meth:`write` gives
        (the stream's), or ``DEFAULT_FPS`` when that is unknown too.

    Attributes
    ----------
    path : Path
        The file written (``.avi`` when H.264 is not available for ``.mp4``).
    fourcc : str
        The codec used.
    size : tuple of (int, int) or None
        Frame (width, height), pixels, once the first frame is written.
    frames : int
        Frames written so far.

    Raises
    ------
    ValueError
        If ``fps`` is negative or the suffix is neither ``.mp4`` nor ``.avi``.
    """

    def __init__(self, path: str | os.PathLike, fps: float = 25.0) -> None:
        if not fps >= 0:
            raise ValueError(f"video fps={fps!r}: must be > 0 frames per second, or 0 for the stream's")
        self.requested = Path(path)
        self.fourcc, self.path = choose_codec(path)
        self.fps = float(fps)
        self.size: tuple[int, int] | None = None
        self.frames = 0
        self._writer: cv2.VideoWriter | None = None
        #: whether the writer takes JPEG frames encoded here (module docstring)
        self._raw = False
        self._closed = False

    def write(self, image: np.ndarray, stream_fps: float = 0.0) -> None:
        """Append one image.

        Parameters
        ----------
        image : ndarray of shape (H, W, 3) or (H, W), dtype uint8
            BGR image (mono8 is converted); every image must have the size of the first.
        stream_fps : float, default=0.0
            The input's frame rate (0: unknown), used by a writer made with ``fps=0`` when the file
            is opened on the first frame.

        Raises
        ------
        ValueError
            If the writer is closed or the image's size differs from the first.
        OSError
            If the file cannot be opened for writing.
        """
        if self._closed:
            raise ValueError(f"video {self.path} is closed; no more frames can be written")
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        h, w = image.shape[:2]
        if self._writer is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            if not self.fps:
                self.fps = float(stream_fps) if stream_fps > 0 else DEFAULT_FPS
            if self.fourcc == FALLBACK[0] and raw_mjpeg_works():
                self._writer = _open_raw_mjpeg(str(self.path), self.fps, (w, h))
                self._raw = self._writer is not None
            if self._writer is None:
                self._writer = cv2.VideoWriter(str(self.path), cv2.VideoWriter_fourcc(*self.fourcc), self.fps, (w, h))
            if not self._writer.isOpened():
                raise OSError(f"cannot open video {self.path} for writing ({self.fourcc}, {w}x{h})")
            self.size = (w, h)
            log.info("writing %s (%s, %dx%d, %.3g fps)", self.path, self.fourcc, w, h, self.fps)
        elif (w, h) != self.size:
            raise ValueError(
                f"frame of {w}x{h} pixels for video {self.path} of {self.size[0]}x{self.size[1]}; "
                "every frame of a video must have the same size"
            )
        self._writer.write(_encode_jpeg(image) if self._raw else np.ascontiguousarray(image))
        self.frames += 1

    def close(self) -> int:
        """Finish the file.

        Returns
        -------
        int
            The number of frames written.
        """
        if not self._closed:
            self._closed = True
            if self._writer is not None:
                self._writer.release()
                self._writer = None
        return self.frames

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def write_png(path: str | os.PathLike, image: np.ndarray) -> Path:
    """Save ``image`` as a PNG (folders created).

    Parameters
    ----------
    path : str or path-like
        The PNG file.
    image : ndarray of shape (H, W, 3) or (H, W)
        The image, BGR or grey.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    OSError
        Naming the path when writing fails.
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(p), image):
        raise OSError(f"cannot write PNG snapshot {p}")
    return p


def encode_image(image: np.ndarray, ext: str = ".jpg", quality: int = 80) -> bytes:
    """``image`` encoded as JPEG or PNG bytes.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3) or (H, W)
        The image, BGR or grey.
    ext : str, default=".jpg"
        ``".jpg"`` or ``".png"``.
    quality : int, default=80
        JPEG quality, 1-100 (ignored for PNG).

    Returns
    -------
    bytes
        The encoded image.

    Raises
    ------
    ValueError
        If OpenCV cannot encode the image.
    """
    params = [cv2.IMWRITE_JPEG_QUALITY, int(quality)] if ext == ".jpg" else []
    ok, buf = cv2.imencode(ext, image, params)
    if not ok:
        raise ValueError(f"cannot encode a {image.dtype} {image.shape} image as {ext}")
    return buf.tobytes()


__all__ = [
    "VideoWriter",
    "choose_codec",
    "codec_works",
    "raw_mjpeg_works",
    "count_frames",
    "write_png",
    "encode_image",
    "H264_CANDIDATES",
    "FALLBACK",
    "JPEG_QUALITY",
]
