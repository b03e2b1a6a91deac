"""The silhouette algorithm per frame, and offline over a video file.

frame (H, W, 3) uint8 BGR -> background subtraction (shadows count as background) -> clean-up
-> people with stable ids (merged regions split) -> each person's outline as a closed cubic
B-spline ordered from the top of the head (Johnson, Galata & Hogg 1998).
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from counterpart.body import spline
from counterpart.body.camera import Camera, camera_for_size
from counterpart.body.image_sequence import open_video, video_info

from . import kernels
from .backends import HorprasertSubtractor, make_subtractor
from .background import BACKGROUND
from .colour_switch import ColourSwitch, ColourSwitchConfig
from .regions import Person, PersonTracker, clean_mask
from .switch_replay import SwitchReplay

#: frames before a switch between colour and monochrome whose people's boxes together are the
#: hints of the background learnt again (a person the model missed on one is found on another)
HINT_FRAMES = 5
#: a standing adult, metres: the smallest person is one this tall at ``max_distance_m``
PERSON_HEIGHT_M = 1.7
#: a person's region over the square of their height: about 0.4 h wide, filling 60% of that box
PERSON_AREA_PER_HEIGHT2 = 0.25
#: the shortest region taken for a person whatever the frame size, pixels: shorter blobs are
#: noise and fragments as often as people, and too small for an outline of 32 control points
MIN_PERSON_HEIGHT_PX = 16.0


def person_min_area(width: int, height: int, camera: Camera | None = None, max_distance_m: float = 30.0) -> int:
    """Smallest person region (pixels) in frames of ``width`` x ``height``: a person
    ``PERSON_HEIGHT_M`` tall at ``max_distance_m`` from ``camera`` (None: the default camera of
    ``counterpart.body.camera.camera_for_size``, 55 degrees across the width) is h = fy * 1.7 / d pixels tall
    (pinhole) and covers about 0.25 h^2 pixels. With the default camera and 30 m a person is
    1/14 of the frame height tall, 17 px at 320x240 (76 px of area): people down to 20 px tall
    are kept with a margin, and the threshold follows the frame size and the lens rather than a
    fixed pixel count. h is at least ``MIN_PERSON_HEIGHT_PX`` (64 px of area) in small frames.

    Parameters
    ----------
    width, height : int
        Frame size, pixels.
    camera : Camera or None, default=None
        The camera (None: the default camera for the frame size).
    max_distance_m : float, default=30.0
        The farthest person to find, metres.

    Returns
    -------
    int
        Smallest person region, pixels (at least 1).

    Raises
    ------
    ValueError
        When ``max_distance_m`` is not > 0.
    """
    if max_distance_m <= 0:
        raise ValueError(f"max_distance_m must be > 0 metres, got {max_distance_m}")
    cam = camera_for_size(camera, width, height)
    h = max(cam.fy * PERSON_HEIGHT_M / max_distance_m, MIN_PERSON_HEIGHT_PX)
    return max(1, int(round(PERSON_AREA_PER_HEIGHT2 * h * h)))


@dataclass(frozen=True, eq=False)
class FrameResult:
    """What the extractor found in one frame.

    Parameters
    ----------
    index : int
        0-based number of the frame in this extractor's stream.
    labels : ndarray of shape (H, W), dtype int32
        0 = background, person.id + 1 on each person's pixels.
    people : list of Person
        People seen in this frame, sorted by id, each with ``ctrl`` (n_ctrl, 2) and ``ref_point`` (2,)
        in image pixels (None if the region was too small for an outline).
    classes : ndarray of shape (H, W), dtype uint8, or None
        Background-model classes of the raw pixels (background.BACKGROUND, SHADOW, HIGHLIGHT,
        FOREGROUND), or None if the backend gives none.
    ready : bool
        False while the background model is still learning (no people reported).
    relearn : bool, default=False
        The camera switched between colour and monochrome on this frame (``colour_switch``): the
        background is learnt again from it and the next frames, and the people are new (a replay
        that holds frames back, ``switch_replay.SwitchReplay``, marks the first frame given the
        new model's people instead).
    """

    index: int
    labels: np.ndarray
    people: list[Person]
    classes: np.ndarray | None
    ready: bool
    relearn: bool = False


class SilhouetteExtractor:
    """Frames in, people with B-spline outlines out.

    Parameters
    ----------
    backend : str, default="horprasert"
        Background subtractor name (see ``backends.BACKEND_NAMES``).
    n_ctrl : int, default=32
        Control points per outline (>= 4).
    min_area : int or None, default=300
        Smallest person region, pixels; None: ``person_min_area`` of the frame size, ``camera`` and
        ``max_distance_m`` (a person 1.7 m tall that far away), set on the first frame (for small,
        distant people: 76 px at 320x240 with the defaults).
    camera : Camera or None, default=None
        The camera (``counterpart.body.camera.Camera``, scaled to the frame size) for ``min_area=None``;
        None: the default camera.
    max_distance_m : float, default=30.0
        The farthest person to find, metres, for ``min_area=None``.
    open_px, close_px : int, default=3, 7
        Mask clean-up opening and closing sizes, pixels (``regions.clean_mask``).
    fill_holes : bool, default=True
        Fill holes in the mask (``regions.clean_mask``).
    shadows : bool, default=True
        Shadow and highlight pixels count as background (True) or as foreground (False: every change
        from the background). Grey footage needs neither: the Horprasert model finds it monochrome
        and bounds its shadows tightly (``background.ShadowConfig``).
    backend_params : dict or None, default=None
        Keyword parameters of the subtractor (e.g. train_frames, learning_rate).
    tracker_params : dict or None, default=None
        Keyword parameters of ``PersonTracker`` other than min_area.
    outlines : bool, default=True
        Fit each person's B-spline outline (False: people without ``ctrl``/``ref_point``, for callers
        that need the masks alone, such as learning an avatar; it saves most of the time).
    colour_switch : ColourSwitchConfig or None, default=None
        With the Horprasert backend: when the camera switches between colour and monochrome
        frames (``colour_switch``, a day/night camera turning to infrared), the background is
        learnt again (:meth:`restart_background`; ``FrameResult.relearn``). None:
        ``ColourSwitchConfig()``; ``ColourSwitchConfig(frames=0)``: never.

    Raises
    ------
    ValueError
        For ``n_ctrl`` < 4, ``min_area`` < 1, ``max_distance_m`` <= 0, ``min_area`` in
        ``tracker_params`` or an unknown tracker parameter.
    """

    def __init__(
        self,
        backend: str = "horprasert",
        n_ctrl: int = 32,
        min_area: int | None = 300,
        camera: Camera | None = None,
        max_distance_m: float = 30.0,
        open_px: int = 3,
        close_px: int = 7,
        fill_holes: bool = True,
        shadows: bool = True,
        backend_params: dict[str, Any] | None = None,
        tracker_params: dict[str, Any] | None = None,
        outlines: bool = True,
        colour_switch: ColourSwitchConfig | None = None,
    ) -> None:
        if n_ctrl < 4:
            raise ValueError(f"n_ctrl must be >= 4 control points, got {n_ctrl}")
        if min_area is not None and min_area < 1:
            raise ValueError(f"min_area must be >= 1 pixel or None (from the frame size), got {min_area}")
        if max_distance_m <= 0:
            raise ValueError(f"max_distance_m must be > 0 metres, got {max_distance_m}")
        self.camera = camera
        self.max_distance_m = max_distance_m
        self.backend = backend
        self.n_ctrl = n_ctrl
        self.min_area = min_area
        self.open_px = open_px
        self.close_px = close_px
        self.fill_holes = fill_holes
        self.shadows = shadows
        self.outlines = outlines
        self.backend_params = dict(backend_params or {})
        self.tracker_params = dict(tracker_params or {})
        if "min_area" in self.tracker_params:
            raise ValueError("set min_area on SilhouetteExtractor, not in tracker_params")
        self.subtractor = make_subtractor(backend, **self.backend_params)
        try:
            # with min_area None the tracker's is set from the first frame's size (process)
            self.tracker = PersonTracker(min_area=min_area or 1, **self.tracker_params)
        except TypeError as exc:
            raise ValueError(f"tracker_params: unknown parameter ({exc})") from None
        self._index = 0
        self._auto_size: tuple[int, int] | None = None
        self.colour_switch = ColourSwitch(colour_switch)
        #: the people's boxes (K, 4) of the last frames: as many as a switch can take to be seen,
        #: and ``HINT_FRAMES`` before them, whose boxes are the hints of the background learnt again
        sw = self.colour_switch.config
        self._recent_boxes: deque[np.ndarray] = deque(maxlen=sw.frames + sw.every - 1 + HINT_FRAMES)

    def fit_background(self, frames: np.ndarray | list[np.ndarray], robust: bool = True) -> SilhouetteExtractor:
        """Train the Horprasert model now (e.g. on the first seconds of a recording).

        Parameters
        ----------
        frames : ndarray of shape (N, H, W, 3) or list of ndarray of shape (H, W, 3), dtype uint8
            BGR training frames.
        robust : bool, default=True
            Fit robustly (people may be in view).

        Returns
        -------
        SilhouetteExtractor
            self.

        Raises
        ------
        ValueError
            When the backend is not ``horprasert``.
        """
        if not isinstance(self.subtractor, HorprasertSubtractor):
            raise ValueError(f"fit_background needs backend='horprasert', this extractor uses {self.backend!r}")
        self.subtractor.fit(frames, robust=robust)
        return self

    @property
    def n_frames(self) -> int:
        """Frames given to :meth:`learn` or :meth:`process` so far."""
        return self._index

    def reset_tracks(self) -> None:
        """Forget the people (new ids from 0); the background model is kept."""
        self.tracker.reset()

    def restart_background(self, hints: np.ndarray | None = None) -> None:
        """Forget the background model and the people: a new model of the same parameters learns
        from the next frames (its ``train_frames``, or :meth:`fit_background`), and ids start at 0.

        Parameters
        ----------
        hints : ndarray of shape (K, 4) or None, default=None
            Boxes (x, y, w, h) of people standing in the first of those frames (the Horprasert
            model's people-aware fit learns the room around them, ``people.fit_around_people``).
        """
        self.subtractor = make_subtractor(self.backend, **self.backend_params)
        if isinstance(self.subtractor, HorprasertSubtractor):
            self.subtractor.hints = hints
        self.tracker.reset()
        self.colour_switch.reset()
        self._recent_boxes.clear()

    def rewind(self, frames: int) -> None:
        """Take back the last ``frames`` frames processed: they will be given again (a replay
        holding them back around a switch between colour and monochrome, ``SwitchReplay``), and
        keep their indices.

        Parameters
        ----------
        frames : int
            Frames to take back, 0 to :attr:`n_frames`.
        """
        if not 0 <= frames <= self._index:
            raise ValueError(f"cannot take back {frames} frames of {self._index} processed")
        self._index -= frames

    def learn(self, frame: np.ndarray) -> FrameResult:
        """Feed one frame to the background model only: no clean-up, no people, no tracks (a stream's
        first frames, while an online backend is still warming up).

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame.

        Returns
        -------
        FrameResult
            No people, ``ready`` False.
        """
        self.subtractor.apply(frame)
        index = self._index
        self._index += 1
        return FrameResult(index, np.zeros(frame.shape[:2], np.int32), [], self.subtractor.labels, False)

    def process(self, frame: np.ndarray) -> FrameResult:
        """Run the whole algorithm on one frame.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame.

        Returns
        -------
        FrameResult
            The frame's labels and people (none while the background model is not ready); on a
            switch of the camera between colour and monochrome (``colour_switch``) none, with
            ``relearn``, and this frame is the new model's first training frame.
        """
        sub = self.subtractor
        relearn = (
            isinstance(sub, HorprasertSubtractor) and sub.ready and self.colour_switch.update(frame, *sub.colour_kind)
        )
        if relearn:
            self.restart_background(self._hints())
        fg = self.subtractor.apply(frame)
        classes = self.subtractor.labels
        if not self.shadows and classes is not None:
            fg = classes != BACKGROUND
        index = self._index
        self._index += 1
        if not self.subtractor.ready:
            return FrameResult(index, np.zeros(frame.shape[:2], np.int32), [], classes, False, relearn)
        if self.min_area is None and self._auto_size != frame.shape[:2]:
            self._auto_size = frame.shape[:2]
            self.tracker.min_area = person_min_area(frame.shape[1], frame.shape[0], self.camera, self.max_distance_m)
        # min_area 0: the tracker drops regions below min_area in its own labelling pass
        mask = clean_mask(fg, self.open_px, self.close_px, self.fill_holes, 0)
        labels, people = self.tracker.update(mask)
        if self.outlines:
            people = [self._with_spline(labels, p) for p in people]
        self._recent_boxes.append(np.array([p.bbox for p in people], np.int32).reshape(-1, 4))
        return FrameResult(index, labels, people, classes, True)

    def _hints(self) -> np.ndarray | None:
        """The people's boxes (K, 4) of the ``HINT_FRAMES`` frames before those a switch can take to
        be seen (fewer after a short stream; None without any): they stand where they stood as it began.
        """
        recent = list(self._recent_boxes)
        before = recent[: max(0, len(recent) - (self._recent_boxes.maxlen - HINT_FRAMES))]
        return np.concatenate(before) if before else None

    def _with_spline(self, labels: np.ndarray, p: Person) -> Person:
        x, y, w, h = p.bbox
        # One pixel of margin so the outline of a region touching its bbox is traced closed.
        crop = np.zeros((h + 2, w + 2), bool)
        np.equal(labels[y : y + h, x : x + w], p.id + 1, out=crop[1:-1, 1:-1])
        try:
            ctrl, ref = silhouette_spline(crop, self.n_ctrl)
        except ValueError:  # a sliver left by a split: no outline this frame
            return p
        offset = np.array([x - 1, y - 1], np.float64)
        return dataclasses.replace(p, ctrl=ctrl + offset, ref_point=ref + offset)


def silhouette_spline(mask: np.ndarray, n: int = 32, ref_window: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """``counterpart.body.spline.silhouette_spline``, the same numbers: its boundary ordering and
    arc-length resampling (a few dozen numpy calls on a few hundred points, a good part of a
    frame's outlines) as one compiled pass (``kernels.head_first_samples``).

    ``body.spline`` itself stays free of numba: the renderer, the simulator and the responder
    load it. The tests hold the two to the same control points and reference point.

    Parameters
    ----------
    mask : ndarray of shape (H, W)
        Bool or 0/non-zero.
    n : int
        Number of control points (>= 4).
    ref_window : float
        Half-width of the search for the reference point, as a fraction of the boundary length.

    Returns
    -------
    ctrl : ndarray of shape (n, 2), dtype float64
        Control points, pixels.
    ref_point : ndarray of shape (2,), dtype float64
        The reference point, pixels.

    Raises
    ------
    ValueError
        As ``body.spline.silhouette_spline``.
    """
    if n < 4:
        raise ValueError(f"a closed cubic B-spline needs n >= 4 control points, got n={n}")
    p, c, up, along = spline.boundary_and_axis(mask)
    p = np.ascontiguousarray(p)
    k = len(p)
    m = spline.SAMPLES_PER_CTRL * n
    start, length, samples = kernels.head_first_samples(p, c, up, along, max(2, int(round(ref_window * k))), m)
    if not length > 0.0:
        raise ValueError("boundary has zero length: all points coincide")
    return spline._fit_operator(m, n) @ samples, p[start].copy()


def iter_video(
    path: str | os.PathLike[str],
    extractor: SilhouetteExtractor,
    max_frames: int | None = None,
    train_frames: int = 30,
    start: int = 0,
) -> Iterator[tuple[np.ndarray, FrameResult]]:
    """Yield each frame of a video with the extractor's result.

    With the Horprasert backend the background is first fitted (robustly: people may be in view)
    on the first ``train_frames`` frames, then the video is read again from its first frame, so
    every frame gets a result; where the camera switches between colour and monochrome it is
    fitted again on the frames from there (:func:`process_frames`).

    Parameters
    ----------
    path : str or os.PathLike
        The video file, or a folder of numbered PNG or JPEG frames.
    extractor : SilhouetteExtractor
        The extractor to run.
    max_frames : int or None, default=None
        Frames to process at most (None: all).
    train_frames : int, default=30
        Frames the Horprasert background is fitted on.
    start : int, default=0
        The frames before it are skipped (read, not decoded nor processed; counted exactly as a
        sequential reader counts them, which seeking is not for every codec), so several processes can
        each take a part of one video.

    Yields
    ------
    frame : ndarray of shape (H, W, 3), dtype uint8
        BGR frame.
    result : FrameResult
        ``extractor.process(frame)``.

    Raises
    ------
    FileNotFoundError
        For a missing file or folder.
    ValueError
        For one OpenCV cannot decode (fewer than 2 training frames, or no frame at all).
    """
    cap = open_video(path)
    if isinstance(extractor.subtractor, HorprasertSubtractor):
        train = []
        while len(train) < train_frames:
            ok, frame = cap.read()
            if not ok:
                break
            train.append(frame)
        if len(train) < 2:
            cap.release()
            raise ValueError(f"cannot read video {os.fspath(path)!r}: fewer than 2 frames decode")
        extractor.fit_background(train, robust=True)
        cap.release()
        cap = open_video(path)
    n = 0

    def frames() -> Iterator[np.ndarray]:
        nonlocal n
        while max_frames is None or n < max_frames:
            ok, frame = cap.read()
            if not ok:
                break
            n += 1
            yield frame

    try:
        for _ in range(start):
            if not cap.grab():
                return
        yield from process_frames(extractor, frames(), train_frames)
    finally:
        cap.release()
    if n == 0:
        raise ValueError(f"cannot read video {os.fspath(path)!r}: no frame decodes")


def process_frames(
    extractor: SilhouetteExtractor, frames: Iterable[np.ndarray], train_frames: int = 30
) -> Iterator[tuple[np.ndarray, FrameResult]]:
    """Yield each frame with the extractor's result, in order, learning the background again where
    the camera switches between colour and monochrome (``FrameResult.relearn``): the frames of the
    other kind from the first seen and the ``train_frames`` from the switch are held back, the
    background is fitted on the latter (:meth:`SilhouetteExtractor.fit_background`, robustly) and
    they are all processed then, so that they get the people of the new model, as a recording's
    first frames do (``switch_replay.SwitchReplay``).

    Parameters
    ----------
    extractor : SilhouetteExtractor
        The extractor, its background already fitted (or an online backend).
    frames : iterable of ndarray of shape (H, W, 3), dtype uint8
        BGR frames.
    train_frames : int, default=30
        Frames the background is fitted on again after a switch.

    Yields
    ------
    frame : ndarray of shape (H, W, 3), dtype uint8
        BGR frame.
    result : FrameResult
        Its result (``index`` one more than the frame's before it, held back or not); the first
        frame given the new model's people after a switch has ``relearn``.
    """
    replay: SwitchReplay[np.ndarray] = SwitchReplay(extractor, train_frames)
    for frame in frames:
        yield from replay.push(frame, frame)
    yield from replay.flush()


def _save_people(
    out_npz: str | os.PathLike[str],
    rows: list[tuple[int, Person]],
    n: int,
    n_frames: int,
    size: tuple[int, int],
    fps: float,
    complete: bool,
    params: dict[str, Any],
) -> None:
    """Write ``extract_video``'s file (its docstring gives the layout)."""
    nan2 = np.full(2, np.nan)
    np.savez_compressed(
        out_npz,
        frame=np.array([f for f, _ in rows], np.int32),
        id=np.array([p.id for _, p in rows], np.int32),
        side=np.array([p.side for _, p in rows], dtype="<U5"),
        bbox=np.array([p.bbox for _, p in rows], np.int32).reshape(-1, 4),
        area=np.array([p.area for _, p in rows], np.int32),
        centroid=np.array([p.centroid for _, p in rows], np.float32).reshape(-1, 2),
        height=np.array([p.height for _, p in rows], np.float32),
        merged=np.array([p.merged for _, p in rows], bool),
        ctrl=np.array([p.ctrl if p.ctrl is not None else np.full((n, 2), np.nan) for _, p in rows], np.float32).reshape(
            -1, n, 2
        ),
        ref_point=np.array([p.ref_point if p.ref_point is not None else nan2 for _, p in rows], np.float32).reshape(
            -1, 2
        ),
        n_frames=np.int64(n_frames),
        frame_size=np.array(size, np.int64),
        fps=np.float64(fps),
        complete=np.bool_(complete),
        params=json.dumps(params, default=str),
    )


def extract_video(
    path: str | os.PathLike[str],
    out_npz: str | os.PathLike[str],
    max_frames: int | None = None,
    train_frames: int = 30,
    progress: Callable[[int, int], None] | None = None,
    **params: Any,
) -> dict[str, Any]:
    """Run ``SilhouetteExtractor(**params)`` over a video file and save every person of every frame.

    The frames come from :func:`iter_video` (with the Horprasert backend, the background is first
    fitted on the first ``train_frames`` frames, so all frames get results). Writes ``out_npz``
    (np.savez_compressed), one row per person and frame, P rows in total:

      frame (P,) int32, id (P,) int32, side (P,) str, bbox (P, 4) int32 [x, y, w, h],
      area (P,) int32, centroid (P, 2) float32 [x, y], height (P,) float32, merged (P,) bool,
      ctrl (P, n_ctrl, 2) float32 and ref_point (P, 2) float32 (NaN where no outline),
      n_frames () int, frame_size (2,) int [H, W], fps () float, params () str (JSON),
      complete () bool: False when the run was interrupted (KeyboardInterrupt) or failed after
      some frames: the file then holds the frames done.

    Parameters
    ----------
    path : str or os.PathLike
        The video file, or a folder of numbered PNG or JPEG frames.
    out_npz : str or os.PathLike
        The file to write.
    max_frames : int or None, default=None
        Frames to process at most (None: all).
    train_frames : int, default=30
        Frames the Horprasert background is fitted on.
    progress : callable or None, default=None
        Called after every frame with (frames done, frames the file declares or 0).
    **params
        Keyword parameters of :class:`SilhouetteExtractor`.

    Returns
    -------
    dict
        Summary: n_frames, n_rows, max_people, fps, frame_size, out_npz.

    Raises
    ------
    FileNotFoundError
        For a missing file or folder.
    ValueError
        For one OpenCV cannot decode.
    """
    extractor = SilhouetteExtractor(**params)
    rows: list[tuple[int, Person]] = []
    n_frames = 0
    max_people = 0
    size: tuple[int, int] | None = None
    fps, declared = video_info(path)
    complete = False
    try:
        for frame, result in iter_video(path, extractor, max_frames, train_frames):
            size = frame.shape[:2]
            rows.extend((result.index, p) for p in result.people)
            max_people = max(max_people, len(result.people))
            n_frames += 1
            if progress is not None:
                progress(n_frames, declared)
        complete = True
    finally:
        if size is not None:
            _save_people(
                out_npz, rows, extractor.n_ctrl, n_frames, size, fps, complete, {"train_frames": train_frames, **params}
            )
    return {
        "n_frames": n_frames,
        "n_rows": len(rows),
        "max_people": max_people,
        "fps": fps,
        "frame_size": list(size),
        "out_npz": os.fspath(out_npz),
    }
