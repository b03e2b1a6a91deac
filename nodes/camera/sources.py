"""Frame sources: video files, image folders, V4L2 devices and the built-in simulator.

Every source is a plain class with one interface, usable without any process running::

    src = make_source("file:clip.avi")   # or "folder:frames/", "v4l2:/dev/video0", "sim:handshake?seed=3"
    src.open()
    ok, image, source_time = src.read()  # image (H, W, 3) uint8 BGR; source_time in seconds
    src.close()

Attributes after :meth:`open`: ``fps`` (frames per second of the footage, 0.0 when unknown),
``size`` ((width, height) in pixels), ``frame_count`` (frames in the source, None when unknown or
live), ``live`` (a device that paces itself and cannot rewind), ``uri`` (what was opened).
Replay sources also implement ``rewind()`` (back to frame 0) and ``skip(n)`` (drop n frames).

Problems opening a source raise :class:`SourceError` (a ValueError) whose message names the file or
device and says what to check.
"""

from __future__ import annotations

import glob
import logging
import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol
from urllib.parse import parse_qsl

import cv2
import numpy as np

from counterpart.body.image_sequence import IMAGE_PATTERN, list_images
from counterpart.bus.plugins import PluginError, simulator

log = logging.getLogger(__name__)

#: waits between retries of a failed live read (seconds); after the last one the stream ends
RETRY_DELAYS_S: tuple[float, ...] = (0.1, 0.2, 0.4, 0.8)


class SourceError(ValueError):
    """A source that cannot be opened or read; the message names it and what to check."""


class FrameSource(Protocol):
    """What the camera node needs of a source (see the module docstring)."""

    uri: str
    fps: float
    size: tuple[int, int]
    frame_count: int | None
    live: bool

    def open(self) -> None: ...
    def read(self) -> tuple[bool, np.ndarray | None, float]: ...
    def close(self) -> None: ...


# ----------------------------------------------------------------------------------- video files
class VideoFileSource:
    """A video file decoded by ``cv2.VideoCapture``, frame by frame, in file order.

    ``source_time`` of frame i is ``i / fps`` (seconds from the start of the file), so it is exact
    and monotonic whatever the container's timestamps say.

    Parameters
    ----------
    path : str or path-like
        The video file.
    fps : float or None, default=None
        Frames per second; overrides the header's rate (None: the header's).

    Attributes
    ----------
    fps : float
        Frames per second once opened (0 when the header gives none and no override).
    size : tuple of (int, int)
        Frame (width, height), pixels, once opened.
    frame_count : int or None
        Frames the header declares (None when it declares none).
    undecodable : int
        Frames that failed to decode and were skipped.
    """

    live = False

    def __init__(self, path: str | os.PathLike[str], fps: float | None = None) -> None:
        self.path = Path(path)
        self.uri = f"file:{self.path}"
        self._fps_override = fps
        self.fps = 0.0
        self.size = (0, 0)
        self.frame_count: int | None = None
        self._cap: cv2.VideoCapture | None = None
        self._pending: np.ndarray | None = None
        self._index = 0
        #: frames that failed to decode and were skipped
        self.undecodable = 0

    def open(self) -> None:
        p = self.path
        if not p.exists():
            raise SourceError(
                f"video file '{p}' does not exist (working directory {Path.cwd()}); check the path, "
                "relative paths are resolved from where the node runs (the repository root under the launcher)"
            )
        if p.is_dir():
            raise SourceError(f"video file '{p}' is a directory; for a folder of images use 'folder:{p}'")
        if not os.access(p, os.R_OK):
            raise SourceError(f"video file '{p}' is not readable by this user; check its permissions")
        if p.stat().st_size == 0:
            raise SourceError(
                f"cannot decode video '{p}': the file is empty (0 bytes); check that it was copied completely"
            )
        self._start()
        # A file can open (a valid header) and still yield nothing: read the first frame now so that
        # the error surfaces at open, where the caller can report it, not as an empty stream.
        ok, frame = self._cap.read()
        if not ok or frame is None:
            self.close()
            raise SourceError(
                f"cannot decode video '{p}': it opened but no frame could be decoded; the file may be "
                "truncated or corrupt, or use a codec this OpenCV build lacks (check that it plays with "
                "ffprobe/ffplay, or re-encode it, e.g. to MJPG or H.264)"
            )
        self._pending = frame
        h, w = frame.shape[:2]
        self.size = (int(w), int(h))
        header_fps = float(self._cap.get(cv2.CAP_PROP_FPS) or 0.0)
        self.fps = (
            float(self._fps_override)
            if self._fps_override
            else (header_fps if np.isfinite(header_fps) and header_fps > 0 else 0.0)
        )
        n = int(self._cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        self.frame_count = n if n > 0 else None

    def _start(self) -> None:
        cap = cv2.VideoCapture(str(self.path))
        if not cap.isOpened():
            cap.release()
            raise SourceError(
                f"cannot decode video '{self.path}': OpenCV could not open it; it is not a video, is corrupt, "
                "or uses a container/codec this OpenCV build lacks (check that it plays with ffprobe/ffplay)"
            )
        self._cap = cap
        self._index = 0

    def read(self) -> tuple[bool, np.ndarray | None, float]:
        if self._cap is None:
            raise SourceError(f"video '{self.path}' is not open; call open() first")
        if self._pending is not None:
            frame, self._pending = self._pending, None
        else:
            ok, frame = self._cap.read()
            if not ok or frame is None:
                frame = self._past_damage()
                if frame is None:
                    return False, None, 0.0
        t = self._index / self.fps if self.fps > 0 else 0.0
        self._index += 1
        return True, frame, t

    def _past_damage(self) -> np.ndarray | None:
        """After a frame failed to decode before the end the header announces: the next frame that
        decodes (each one skipped is counted in ``undecodable`` and keeps its place in time), or
        None at the real end. Headers may overstate the count by a frame or two; that is no damage.
        """
        n = self.frame_count
        while n is not None and self._index < n - 2 and self._cap.grab():
            self.undecodable += 1
            self._index += 1
            ok, frame = self._cap.retrieve()
            if ok and frame is not None:
                log.warning("video '%s': frame %d did not decode; skipped", self.path, self._index - 1)
                return frame
        if n is not None and self._index < n - 1:
            log.warning(
                "video '%s' ended at frame %d of the %d its header announces; the file may be truncated",
                self.path,
                self._index,
                n,
            )
        return None

    def skip(self, n: int) -> int:
        """Drop ``n`` frames by decoding them (exact whatever the codec's keyframes).

        Parameters
        ----------
        n : int
            Frames to drop.

        Returns
        -------
        int
            Frames dropped (fewer at the end of the file).
        """
        done = 0
        for _ in range(n):
            if self._pending is not None:
                self._pending = None
            elif not self._cap.grab():
                break
            self._index += 1
            done += 1
        return done

    def rewind(self) -> None:
        # Reopening is the one way back to frame 0 that is exact for every codec.
        self.close()
        self._start()

    def close(self) -> None:
        if self._cap is not None:
            self._cap.release()
            self._cap = None
        self._pending = None


# ---------------------------------------------------------------------------------- image folders
class ImageFolderSource:
    """The images of a folder in sorted name order, as a video of ``fps`` frames per second.

    Images are decoded as 8-bit BGR; every image must have the size of the first one.

    Parameters
    ----------
    folder : str or path-like
        The folder.
    pattern : str, default="*.png|*.jpg"
        One or more glob patterns joined by ``|``.
    fps : float or None, default=None
        Frames per second (None: 0, unknown).

    Attributes
    ----------
    files : list of Path
        The matching files, once opened.
    size : tuple of (int, int)
        Frame (width, height), pixels, once opened.
    frame_count : int or None
        Number of files, once opened.
    undecodable : int
        Images that failed to decode (or had another size) and were skipped.
    """

    live = False

    def __init__(self, folder: str | os.PathLike[str], pattern: str = IMAGE_PATTERN, fps: float | None = None) -> None:
        self.folder = Path(folder)
        self.pattern = pattern
        self.uri = f"folder:{self.folder}"
        self.fps = float(fps) if fps else 0.0
        self.size = (0, 0)
        self.frame_count: int | None = None
        self.files: list[Path] = []
        self._index = 0
        #: images that failed to decode (or had another size) and were skipped
        self.undecodable = 0

    def open(self) -> None:
        if not self.folder.is_dir():
            what = "is a file, not a folder" if self.folder.exists() else "does not exist"
            raise SourceError(f"image folder '{self.folder}' {what} (working directory {Path.cwd()}); check the path")
        self.files = list_images(self.folder, self.pattern)
        if not self.files:
            raise SourceError(
                f"image folder '{self.folder}' has no file matching '{self.pattern}'; check the folder and pattern"
            )
        first = self._load(0)
        self.size = (int(first.shape[1]), int(first.shape[0]))
        self.frame_count = len(self.files)
        self._index = 0

    def _load(self, i: int) -> np.ndarray:
        path = self.files[i]
        img = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if img is None:
            raise SourceError(
                f"cannot decode image '{path}' (frame {i} of folder '{self.folder}'); check that it is a valid PNG/JPEG"
            )
        return img

    def read(self) -> tuple[bool, np.ndarray | None, float]:
        """The next image; one that does not decode, or has another size than the first, is one bad
        frame: logged, counted in ``undecodable``, skipped (it keeps its place in time).
        """
        while self._index < len(self.files):
            i = self._index
            self._index += 1
            try:
                img = self._load(i)
            except SourceError as exc:
                self._skip_bad(f"{exc}")
                continue
            if (img.shape[1], img.shape[0]) != self.size:
                self._skip_bad(
                    f"image '{self.files[i]}' is {img.shape[1]}x{img.shape[0]} but the folder's first "
                    f"image is {self.size[0]}x{self.size[1]}; every image of a folder source must have "
                    "one size"
                )
                continue
            return True, img, (i / self.fps if self.fps > 0 else 0.0)
        return False, None, 0.0

    def _skip_bad(self, why: str) -> None:
        self.undecodable += 1
        log.warning("%s: skipped%s", why, "" if self.undecodable == 1 else f" ({self.undecodable} so far)")

    def skip(self, n: int) -> int:
        """Drop ``n`` frames without reading them.

        Parameters
        ----------
        n : int
            Frames to drop.

        Returns
        -------
        int
            Frames dropped (fewer at the end).
        """
        done = min(n, len(self.files) - self._index)
        self._index += done
        return done

    def rewind(self) -> None:
        self._index = 0

    def close(self) -> None:
        pass


# ------------------------------------------------------------------------------------ V4L2 devices
def video_devices() -> list[str]:
    """The ``/dev/video*`` device nodes present on this machine, sorted.

    Returns
    -------
    list of str
        Device paths, in numeric order.
    """
    return sorted(glob.glob("/dev/video*"), key=lambda s: (len(s), s))


def read_with_retry(
    read: Callable[[], tuple[bool, Any]],
    delays: Sequence[float] = RETRY_DELAYS_S,
    sleep: Callable[[float], None] = time.sleep,
    what: str = "device",
) -> tuple[bool, Any]:
    """Call ``read()`` until it returns ``(True, x)``; after each failure wait the next of ``delays``.

    Live devices drop a read now and then (USB hiccups, a driver restart); a short backoff rides over
    those, while a device that is gone for good ends the stream in about 1.5 s instead of hanging.

    Parameters
    ----------
    read : callable
        Returns ``(ok, x)``.
    delays : sequence of float, default=RETRY_DELAYS_S
        Waits between tries, seconds.
    sleep : callable, default=time.sleep
        Waits a number of seconds.
    what : str, default="device"
        Name of what is read, for the log.

    Returns
    -------
    ok : bool
        True on success.
    x : Any
        The first success's value, or None once every delay is used up.
    """
    ok, x = read()
    if ok:
        return ok, x
    for i, d in enumerate(delays):
        log.warning("%s: read failed; retry %d/%d in %.1f s", what, i + 1, len(delays), d)
        sleep(d)
        ok, x = read()
        if ok:
            return ok, x
    log.error("%s: read failed %d times; ending the stream", what, len(delays) + 1)
    return False, None


class V4L2Source:
    """A live V4L2 camera (``/dev/videoN`` or index N) through ``cv2.VideoCapture(..., CAP_V4L2)``.

    ``source_time`` is 0 (live).

    Parameters
    ----------
    device : str or int
        ``/dev/videoN``, or the index N.
    width, height : int, default=0
        Frame size requested from the driver, pixels (0: the driver's); it may pick the nearest
        mode it supports.
    fps : float or None, default=None
        Frame rate requested from the driver (None: the driver's).
    retry_delays : sequence of float, default=RETRY_DELAYS_S
        Waits between read retries, seconds (:func:`read_with_retry`).

    Attributes
    ----------
    fps : float
        Frame rate the driver reports, once opened.
    size : tuple of (int, int)
        Frame (width, height) it delivers, pixels, once opened.

    Raises
    ------
    SourceError
        If ``device`` is neither ``/dev/...`` nor an index.
    """

    live = True

    def __init__(
        self,
        device: str | int,
        width: int = 0,
        height: int = 0,
        fps: float | None = None,
        retry_delays: Sequence[float] = RETRY_DELAYS_S,
    ) -> None:
        if isinstance(device, int) or (isinstance(device, str) and device.isdigit()):
            device = f"/dev/video{int(device)}"
        if not isinstance(device, str) or not device.startswith("/dev/"):
            raise SourceError(f"V4L2 device {device!r}: expected /dev/videoN or an index N")
        self.device = device
        self.uri = f"v4l2:{device}"
        self.req = (int(width), int(height), float(fps or 0.0))
        self.retry_delays = tuple(retry_delays)
        self.fps = 0.0
        self.size = (0, 0)
        self.frame_count: int | None = None
        self._cap: cv2.VideoCapture | None = None
        self._pending: np.ndarray | None = None

    def _present(self) -> str:
        devs = video_devices()
        if not devs:
            return (
                "no /dev/video* devices exist on this machine (is a camera connected? in a container, "
                "pass it with --device /dev/video0)"
            )
        return f"present: {', '.join(devs)}"

    def open(self) -> None:
        if not os.path.exists(self.device):
            raise SourceError(f"V4L2 device '{self.device}' does not exist; {self._present()}")
        if not os.access(self.device, os.R_OK | os.W_OK):
            raise SourceError(
                f"V4L2 device '{self.device}' is not accessible to this user (add the user to group "
                f"'video'); {self._present()}"
            )
        cap = cv2.VideoCapture(self.device, cv2.CAP_V4L2)
        if not cap.isOpened():
            cap.release()
            raise SourceError(
                f"V4L2 device '{self.device}' cannot be opened: it is busy (another program holds it: "
                f"check 'fuser {self.device}') or not a capture device; {self._present()}"
            )
        w, h, fps = self.req
        if w:
            cap.set(cv2.CAP_PROP_FRAME_WIDTH, w)
        if h:
            cap.set(cv2.CAP_PROP_FRAME_HEIGHT, h)
        if fps:
            cap.set(cv2.CAP_PROP_FPS, fps)
        self._cap = cap
        # Some drivers open a busy device and fail at the first read: find out now.
        ok, frame = read_with_retry(cap.read, self.retry_delays, what=f"V4L2 device '{self.device}'")
        if not ok:
            self.close()
            raise SourceError(
                f"V4L2 device '{self.device}' opened but delivers no frames: it is busy or not a "
                f"capture device (check 'fuser {self.device}' and 'v4l2-ctl --list-formats'); {self._present()}"
            )
        self._pending = frame
        self.size = (int(frame.shape[1]), int(frame.shape[0]))
        got = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        self.fps = got if got > 0 else fps

    def read(self) -> tuple[bool, np.ndarray | None, float]:
        if self._cap is None:
            raise SourceError(f"V4L2 device '{self.device}' is not open; call open() first")
        if self._pending is not None:
            frame, self._pending = self._pending, None
            return True, frame, 0.0
        ok, frame = read_with_retry(self._cap.read, self.retry_delays, what=f"V4L2 device '{self.device}'")
        return (True, frame, 0.0) if ok else (False, None, 0.0)

    def close(self) -> None:
        if self._cap is not None:
            self._cap.release()
            self._cap = None
        self._pending = None


# --------------------------------------------------------------------------------------- simulator
class SimulatorSource:
    """Adapter for any rendered stream: an object with ``render(i) -> (frame, time)``, ``n_frames``
    and ``fps``. ``frame`` is (H, W, 3) uint8 BGR (or (H, W) uint8, made BGR here); ``time`` is the
    scene time of frame i in seconds.

    Parameters
    ----------
    stream : Any
        The rendered stream.
    uri : str, default="sim"
        The source's URI, for messages.
    fps : float or None, default=None
        Frames per second (None: the stream's).

    Raises
    ------
    SourceError
        If ``stream`` lacks ``render``, ``n_frames`` or ``fps``.
    """

    live = False

    def __init__(self, stream: Any, uri: str = "sim", fps: float | None = None) -> None:
        for attr in ("render", "n_frames", "fps"):
            if not hasattr(stream, attr):
                raise SourceError(f"simulator stream for '{uri}' has no '{attr}'; it needs render(i), n_frames and fps")
        self.stream = stream
        self.uri = uri
        self.fps = float(fps) if fps else float(stream.fps)
        self.frame_count: int | None = int(stream.n_frames)
        self.size = (0, 0)
        self._index = 0

    def open(self) -> None:
        if not self.frame_count:
            raise SourceError(f"simulator stream '{self.uri}' has no frames (n_frames = {self.frame_count})")
        ok, frame, _ = self._render(0)
        self.size = (int(frame.shape[1]), int(frame.shape[0]))
        self._index = 0

    def _render(self, i: int) -> tuple[bool, np.ndarray, float]:
        frame, t = self.stream.render(i)
        frame = np.asarray(frame)
        if frame.dtype != np.uint8 or frame.ndim not in (2, 3):
            raise SourceError(
                f"simulator stream '{self.uri}' rendered {frame.dtype} {frame.shape}; expected uint8 (H, W, 3) BGR"
            )
        if frame.ndim == 2:
            frame = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
        return True, frame, float(t)

    def read(self) -> tuple[bool, np.ndarray | None, float]:
        if self._index >= self.frame_count:
            return False, None, 0.0
        ok, frame, t = self._render(self._index)
        self._index += 1
        return ok, frame, t

    def skip(self, n: int) -> int:
        """Drop ``n`` frames without reading them.

        Parameters
        ----------
        n : int
            Frames to drop.

        Returns
        -------
        int
            Frames dropped (fewer at the end).
        """
        done = min(n, self.frame_count - self._index)
        self._index += done
        return done

    def rewind(self) -> None:
        self._index = 0

    def close(self) -> None:
        close = getattr(self.stream, "close", None)
        if callable(close):
            close()


def open_simulator(
    scenario: str, options: dict[str, str], fps: float | None, width: int, height: int
) -> SimulatorSource:
    """The built-in simulator's stream for ``scenario``.

    Expected simulator API (``sim`` package), called as::

        stream = sim.open_stream(scenario, seed=S, width=W, height=H, fps=F, **options)
        stream.n_frames   # int, frames in the scenario
        stream.fps        # float, frames per second
        stream.render(i)  # -> (image (H, W, 3) uint8 BGR, scene time of frame i in s)

    Parameters
    ----------
    scenario : str
        The scenario's name.
    options : dict of str to str
        The URI's query keys: ``seed``, ``width``, ``height``, ``fps`` override the arguments; the
        others are passed through as strings.
    fps : float or None
        Frames per second (None or 0: the scenario's own).
    width, height : int
        Frame size, pixels (0: the scenario's own).

    Returns
    -------
    SimulatorSource
        The source (not yet opened).

    Raises
    ------
    SourceError
        If the simulator cannot be loaded, ``seed`` is not an integer, or the simulator refuses
        the scenario or options.
    """
    uri = f"sim:{scenario}"
    try:
        sim = simulator()
    except (ImportError, PluginError) as exc:
        raise SourceError(f"source '{uri}': the simulator cannot be loaded ({exc})") from None
    open_stream = getattr(sim, "open_stream", None)
    if not callable(open_stream):
        raise SourceError(
            f"source '{uri}': the simulator is not available yet (sim.open_stream is missing); "
            "use a video file ('file:PATH'), an image folder ('folder:DIR') or a camera ('v4l2:/dev/video0')"
        )
    opts = dict(options)
    try:
        seed = int(opts.pop("seed", 0))
    except ValueError:
        raise SourceError(f"source '{uri}': seed must be an integer") from None
    w = int(opts.pop("width", width or 0)) or None
    h = int(opts.pop("height", height or 0)) or None
    f = float(opts.pop("fps", fps or 0)) or None
    try:
        stream = open_stream(scenario, seed=seed, width=w, height=h, fps=f, **opts)
    except (ValueError, KeyError, TypeError) as exc:
        raise SourceError(f"source '{uri}': the simulator refused it: {exc}") from None
    return SimulatorSource(stream, uri=uri, fps=f)


# ------------------------------------------------------------------------------------ URI factory
SCHEMES = ("file", "folder", "v4l2", "sim")


def parse_uri(uri: str) -> tuple[str, str, dict[str, str]]:
    """Split a source URI.

    Parameters
    ----------
    uri : str
        ``file:PATH`` (or a plain path), ``folder:DIR`` (``?pattern=*.png``), ``v4l2:/dev/videoN``
        (or a plain ``/dev/videoN``, or ``v4l2:N``), ``sim:SCENARIO?seed=S&width=W&...``.

    Returns
    -------
    scheme : str
        One of ``SCHEMES``.
    target : str
        The path, device or scenario.
    options : dict of str to str
        The query keys (``folder`` and ``sim`` only).

    Raises
    ------
    SourceError
        For an empty URI, an unknown scheme, nothing after the scheme, or a folder option other
        than ``pattern``.
    """
    if not isinstance(uri, str) or not uri.strip():
        raise SourceError("empty source; give a video file path, folder:DIR, v4l2:/dev/videoN or sim:SCENARIO")
    uri = uri.strip()
    scheme, sep, rest = uri.partition(":")
    if not sep or len(scheme) <= 1 or "/" in scheme or "." in scheme:
        # a plain path (a one-letter "scheme" would be a Windows drive letter)
        if uri.startswith("/dev/video"):
            return "v4l2", uri, {}
        return "file", uri, {}
    if scheme not in SCHEMES:
        raise SourceError(
            f"source '{uri}': unknown scheme '{scheme}:'; expected one of "
            f"{', '.join(s + ':' for s in SCHEMES)} or a plain file path"
        )
    options: dict[str, str] = {}
    if scheme in ("sim", "folder") and "?" in rest:
        rest, _, query = rest.partition("?")
        options = dict(parse_qsl(query, keep_blank_values=True))
        if scheme == "folder" and set(options) - {"pattern"}:
            raise SourceError(f"source '{uri}': a folder takes only '?pattern=...'")
    if not rest:
        raise SourceError(f"source '{uri}': nothing after '{scheme}:'")
    return scheme, rest, options


def make_source(uri: str, fps: float | None = None, width: int = 0, height: int = 0) -> FrameSource:
    """A (not yet opened) source for ``uri``.

    Parameters
    ----------
    uri : str
        The source (see :func:`parse_uri`).
    fps : float or None, default=None
        Overrides the source's frame rate (image folders need it: default 25).
    width, height : int, default=0
        Frame size requested from devices and the simulator, pixels (other sources are resized by
        the caller).

    Returns
    -------
    FrameSource
        The source.

    Raises
    ------
    SourceError
        If the URI is bad or the simulator cannot provide the stream.
    """
    scheme, target, options = parse_uri(uri)
    if scheme == "file":
        return VideoFileSource(target, fps=fps)
    if scheme == "folder":
        return ImageFolderSource(target, options.get("pattern", IMAGE_PATTERN), fps=fps or 25.0)
    if scheme == "v4l2":
        return V4L2Source(target, width=width, height=height, fps=fps)
    return open_simulator(target, options, fps, width, height)


__all__ = [
    "SourceError",
    "FrameSource",
    "VideoFileSource",
    "ImageFolderSource",
    "V4L2Source",
    "SimulatorSource",
    "make_source",
    "parse_uri",
    "open_simulator",
    "read_with_retry",
    "video_devices",
    "RETRY_DELAYS_S",
]
