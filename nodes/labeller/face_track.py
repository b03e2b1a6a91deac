"""Faces tracked from frame to frame: a head point that is still when the face is still.

A Haar cascade box (:func:`counterpart.nodes.labeller.face.detect_face`) jumps by several per cent of its size
from frame to frame on real video, even on a face that does not move, which is as large as a
small nod. So the box is not the head point. Each tracked face instead carries:

- **motion from optical flow**: corners of the upper face (eyes, brows, nose: the mouth is left out
  so that speech does not move the point) followed by pyramidal Lucas-Kanade with a
  forward-backward check (Bouguet 2000); the point moves by the median displacement of the points
  that pass. A still face gives a still point (sub-pixel noise), a nod or shake moves it by the
  motion of the features;
- **the features' motion relative to the head's outline** (``tilt``): a nod rotates the head, so
  the eyes and nose move up and down over the skull while the top of the head (hair against the
  background, high above the neck's pivot) hardly moves with the rotation; a body bouncing on its
  knees or leaning moves both alike. The top edge's vertical shift is one Lucas-Kanade step
  (Lucas and Kanade 1981) on the row profile of a strip above the face (:func:`outline_shift`);
  ``tilt`` accumulates the features' downward motion minus it (px), a rotation cue that a
  translation of the whole head leaves still;
- **a slow pull towards the detections**: every detected box pulls the point by
  ``1 - exp(-1 / (anchor_s * fps))`` of the difference, so the flow's drift is corrected over about
  ``anchor_s`` seconds while the box's frame-to-frame jitter is attenuated by about
  ``sqrt(1 / (2 anchor_s fps))``; the face size (the box width) is smoothed the same way with
  ``size_s``;
- **bridging**: a detection missed for up to ``max_miss_s`` seconds (a blink of the detector,
  a quick turn) is carried by the flow alone, and for up to ``max_flow_s`` seconds while the flow
  keeps following the face's points (a look away past the frontal detector's reach: the eyes and
  brows stay in view and trackable, and a nod or shake made then is still measured); only a
  longer miss ends the track.

A face turned too far aside for the frontal cascade (a person who looks away when the video
starts, or while a nod or shake is made) is looked for with OpenCV's profile cascade
(``haarcascade_profileface.xml``, trained on faces turned one way; the mirrored image gives the
other) where the frontal one finds nothing and the flow cannot carry the face: in the whole-frame
search while no face is tracked, and around a new face being confirmed or a tracked face whose
flow failed (the flow bridges a tracked face's look-away by itself, see ``max_flow_s``, so a
look-away costs no profile search). A profile detection starts, confirms and keeps a track, but
its box (the side of the head, not the face's front) pulls neither the face size nor, while the
flow follows the face, the head point.

While a face is tracked it is searched for only around its last position (one face width
around it, at the scale of its size: cheap); new faces are searched for, at the scale that makes
``min_face_px`` the cascade's 24 px window, every ``search_every_s`` seconds, whether or not a
face is tracked (a first face and new ones: a face that appears waits up to that long to be
found, and a stream without a face costs a search only that often). Where the people in view are
known (their boxes, e.g. the silhouettes'), that search looks only at their head regions
(:func:`head_regions`): the top half of each box whose person is tall enough to have a face of
``min_face_px`` (a face is at most ``1 / BODY_FACE_RATIO`` of its person's height), or the whole
box of one cut by the frame's bottom edge (its height says nothing of its face's size); small
people far from the camera cost nothing. The whole frame is then searched only every
``full_search_every_s`` seconds (a face the boxes miss: a person absorbed into the background, a
close-up whose motion gives only fragments), and every ``search_every_s`` where no boxes are
known (no people, or a caller that gives none). Tracks are
numbered by slot (0 .. ``max_faces`` - 1): a face that is lost and found again takes the lowest
free slot, with a new ``track_id``. A new face must be detected again on each of its next
``CONFIRM`` frames, or it is dropped (most false detections on a textured background are not
found twice running).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import count

import cv2
import numpy as np

#: the cascade's detection window (px): a face is found at scale s when its width is >= 24 / s
HAAR_WINDOW_PX = 24
#: face width (px) the search region around a tracked face is scaled to
ROI_FACE_PX = 64
#: frames after its first detection on which a new face must be detected again to be kept
CONFIRM = 2
#: a face (the cascade's box, about the head's width) is at most 1 / BODY_FACE_RATIO of the height of
#: its person's box: a standing adult's head is about 1/7.5 of their height, their face box narrower
#: still; a seated person's box, chair aside, is shorter, so theirs comes closer to it
BODY_FACE_RATIO = 7.0
#: the top share of a person's box that holds their head (standing, sitting, bending, arms raised)
HEAD_SHARE = 0.5
#: the strip whose row profile follows the top of the head, in face widths from the head point:
#: from OUTLINE_TOP to OUTLINE_BOTTOM above it, OUTLINE_W wide (the hairline and the head's top edge)
OUTLINE_TOP, OUTLINE_BOTTOM, OUTLINE_W = 0.95, 0.45, 0.5


@dataclass(frozen=True)
class FaceTrackParams:
    """Parameters of face tracking.

    Parameters
    ----------
    fps : float
        Frame rate (Hz), > 0.
    min_face_px : int, default=40
        Smallest face width tracked (px), at least ``HAAR_WINDOW_PX``.
    max_miss_s : float, default=0.5
        Longest run of missed detections bridged by the flow (s).
    anchor_s : float, default=1.0
        Time constant of the pull of the head point towards the detected box (s).
    size_s : float, default=1.0
        Time constant of the face size smoothing (s).
    search_every_s : float, default=0.5
        Period of the whole-frame search for new faces (s), with or without a tracked face.
    max_faces : int, default=2
        Most faces tracked at once.
    n_points : int, default=40
        Optical-flow points per face (>= 8).
    max_jump : float, default=0.5
        Largest distance (face widths) from the tracked point at which a detection is taken as this face
        (beyond it the track is ended and restarted there).
    max_flow_s : float, default=2.0
        Longest run of missed detections bridged while the flow follows the face (s; at least
        ``max_miss_s``).
    profile_faces : bool, default=True
        Look for faces turned aside with the profile cascade where the frontal one finds none
        (:class:`FaceTracker`'s ``profile``).
    full_search_every_s : float, default=2.0
        Period of the whole-frame search for new faces (s) while people's boxes are given to
        :meth:`FaceTracker.update` (their head regions are searched every ``search_every_s``); at
        least ``search_every_s``.

    Raises
    ------
    ValueError
        Naming the first parameter out of range.
    """

    fps: float
    min_face_px: int = 40
    max_miss_s: float = 0.5
    anchor_s: float = 1.0
    size_s: float = 1.0
    search_every_s: float = 0.5
    max_faces: int = 2
    n_points: int = 40
    max_jump: float = 0.5
    max_flow_s: float = 2.0
    profile_faces: bool = True
    full_search_every_s: float = 2.0

    def __post_init__(self) -> None:
        checks = {
            "fps": (self.fps > 0, "must be > 0 Hz"),
            "min_face_px": (
                self.min_face_px >= HAAR_WINDOW_PX,
                f"must be >= {HAAR_WINDOW_PX} px (the cascade's window)",
            ),
            "max_miss_s": (self.max_miss_s >= 0, "must be >= 0 s"),
            "anchor_s": (self.anchor_s > 0, "must be > 0 s"),
            "size_s": (self.size_s > 0, "must be > 0 s"),
            "search_every_s": (self.search_every_s > 0, "must be > 0 s"),
            "max_faces": (self.max_faces >= 1, "must be >= 1"),
            "n_points": (self.n_points >= 8, "must be >= 8"),
            "max_jump": (self.max_jump > 0, "must be > 0 face widths"),
            "max_flow_s": (self.max_flow_s >= self.max_miss_s, "must be >= max_miss_s (s)"),
            "full_search_every_s": (
                self.full_search_every_s >= self.search_every_s,
                "must be >= search_every_s (s)",
            ),
        }
        for name, (ok, why) in checks.items():
            if not ok:
                raise ValueError(f"{name}={getattr(self, name)!r}: {why}")

    def alpha(self, seconds: float) -> float:
        """Per-frame gain of a first-order smoother.

        Parameters
        ----------
        seconds : float
            Time constant (s).

        Returns
        -------
        float
            ``1 - exp(-1 / (seconds * fps))``, in (0, 1).
        """
        return float(1.0 - np.exp(-1.0 / (seconds * self.fps)))

    @property
    def max_miss(self) -> int:
        """Missed detections bridged, in frames."""
        return int(round(self.max_miss_s * self.fps))

    @property
    def max_flow_miss(self) -> int:
        """Missed detections bridged while the flow follows the face, in frames."""
        return int(round(self.max_flow_s * self.fps))


_ids = count()


@dataclass
class FaceTrack:
    """One tracked face.

    Attributes
    ----------
    center : ndarray of shape (2,)
        Head point (px, x right, y down).
    size : float
        Smoothed face width (px).
    slot : int
        Its place among the tracked faces.
    track_id : int
        Unique over the run.
    detected : bool
        The last search found it with the frontal cascade (the search runs on every other frame while the flow follows a
        confirmed face, so this is that of the last search).
    missed : int
        Frames since the last detection (frontal or profile).
    age : int
        Frames since the track started.
    flow_ok : bool
        The optical flow followed the face into this frame.
    tilt : float
        The features' downward motion relative to the head's top edge, accumulated since the track
        started (px; see the module docstring): moves with a nod's rotation, not with the head's
        translation.
    points : ndarray of shape (n, 1, 2), dtype float32
        Optical-flow points (px).
    box : tuple of float
        The smoothed box (x, y, w, h) px.
    """

    center: np.ndarray
    size: float
    slot: int
    track_id: int = field(default_factory=lambda: next(_ids))
    detected: bool = True
    missed: int = 0
    age: int = 0
    flow_ok: bool = False
    tilt: float = 0.0
    points: np.ndarray = field(default_factory=lambda: np.empty((0, 1, 2), np.float32))

    @property
    def confirmed(self) -> bool:
        """Detected on its first frame and the ``CONFIRM`` after it (see the module docstring)."""
        return self.age >= CONFIRM

    @property
    def box(self) -> tuple[float, float, float, float]:
        w = self.size
        return (float(self.center[0] - w / 2), float(self.center[1] - w / 2), float(w), float(w))


def _detect(
    gray: np.ndarray,
    cascade: cv2.CascadeClassifier,
    scale: float,
    min_px: float,
    max_px: float | None,
    min_neighbors: int,
    x0: int = 0,
    y0: int = 0,
    scale_factor: float = 1.1,
    mirror: bool = False,
) -> np.ndarray:
    """Faces (K, 4) float (x, y, w, h) in full-image px of ``gray`` searched at ``scale``; with
    ``mirror`` searched in the mirror image (a profile cascade finds faces turned one way only),
    the boxes mirrored back.
    """
    width = gray.shape[1]
    if mirror:
        gray = cv2.flip(gray, 1)
    if scale < 1.0:
        gray = cv2.resize(
            gray,
            (max(1, int(round(gray.shape[1] * scale))), max(1, int(round(gray.shape[0] * scale)))),
            interpolation=cv2.INTER_AREA,
        )
    else:
        scale = 1.0
    mn = max(HAAR_WINDOW_PX, int(min_px * scale))
    if gray.shape[0] < mn or gray.shape[1] < mn:
        return np.empty((0, 4))
    kw = {"maxSize": (int(max_px * scale), int(max_px * scale))} if max_px else {}
    f = cascade.detectMultiScale(gray, scaleFactor=scale_factor, minNeighbors=min_neighbors, minSize=(mn, mn), **kw)
    if len(f) == 0:
        return np.empty((0, 4))
    f = np.asarray(f, dtype=np.float64) / scale
    if mirror:
        f[:, 0] = width - f[:, 0] - f[:, 2]
    f[:, 0] += x0
    f[:, 1] += y0
    return f


def head_regions(
    boxes: list[tuple[float, float, float, float]], shape: tuple[int, ...], min_face_px: float
) -> list[tuple[int, int, int, int]]:
    """The image regions that can hold the face of min_face_px or more of a person with a known box.

    A box whose bottom is inside the image holds the whole person (x, y, w, h): its face is at most
    ``h / BODY_FACE_RATIO`` wide, so a box shorter than ``BODY_FACE_RATIO * min_face_px`` gives no
    region, a taller one its top ``HEAD_SHARE``. A box cut by the image's bottom edge (the person
    may go on below it: a close-up, someone near the camera) gives its whole self. Each region is
    widened by half the largest face the box can hold to the sides and top (a head whose outline
    the box missed), and cut at the image's edges.

    Parameters
    ----------
    boxes : list of tuple of float
        People's boxes (x, y, w, h), px.
    shape : tuple of int
        The image's shape (H, W, ...).
    min_face_px : float
        The smallest face looked for, px.

    Returns
    -------
    list of tuple of int
        Regions (x0, y0, x1, y1), px, end exclusive; each at least ``min_face_px`` a side.
    """
    img_h, img_w = shape[0], shape[1]
    out = []
    for x, y, w, h in boxes:
        cut = y + h >= img_h - 1
        if w <= 0 or h <= 0 or (not cut and h < BODY_FACE_RATIO * min_face_px):
            continue
        m = 0.5 * max(h, w) / BODY_FACE_RATIO if cut else 0.5 * h / BODY_FACE_RATIO
        x0, x1 = max(0, int(x - m)), min(img_w, int(np.ceil(x + w + m)))
        y0 = max(0, int(y - m))
        y1 = min(img_h, int(np.ceil(y + (h if cut else HEAD_SHARE * h))))
        if x1 - x0 >= min_face_px and y1 - y0 >= min_face_px:
            out.append((x0, y0, x1, y1))
    return out


def outline_shift(prev: np.ndarray, gray: np.ndarray, center: np.ndarray, size: float) -> float | None:
    """Vertical shift of the top of a head between two frames.

    The strip ``OUTLINE_W`` face widths wide, from ``OUTLINE_TOP`` to ``OUTLINE_BOTTOM`` face widths
    above the head point (cut at the image's edges), is averaged over its columns in both frames;
    one Lucas-Kanade step on the two row profiles ``p0, p1`` gives the shift
    ``dy = -sum(g (p1 - p0)) / sum(g^2)`` with ``g`` the mean profile's gradient (Lucas and Kanade
    1981, eq. 2 in one dimension): the strongest horizontal edges (the head's top against the
    background, the hairline) weigh most.

    Parameters
    ----------
    prev, gray : ndarray of shape (H, W), dtype uint8
        The previous and the current frame.
    center : ndarray of shape (2,)
        The head point in the current frame (x, y), px.
    size : float
        The face width, px.

    Returns
    -------
    float or None
        The shift (px, image down), or None when the strip is under 8 rows or columns or flat.
    """
    x0, x1 = max(0, int(center[0] - OUTLINE_W / 2 * size)), min(gray.shape[1], int(center[0] + OUTLINE_W / 2 * size))
    y0 = max(0, int(center[1] - OUTLINE_TOP * size))
    y1 = min(gray.shape[0], int(center[1] - OUTLINE_BOTTOM * size))
    if x1 - x0 < 8 or y1 - y0 < 8:
        return None
    p0 = prev[y0:y1, x0:x1].mean(axis=1, dtype=np.float64)
    p1 = gray[y0:y1, x0:x1].mean(axis=1, dtype=np.float64)
    g = np.gradient(0.5 * (p0 + p1))
    gg = float(g @ g)
    return -float(g @ (p1 - p0)) / gg if gg > 1e-6 else None


class FaceTracker:
    """Tracks up to ``max_faces`` frontal faces through a video (see the module docstring).

    Call :meth:`update` once per frame.

    Parameters
    ----------
    params : FaceTrackParams
        Tracking parameters.
    cascade : cv2.CascadeClassifier
        The frontal face detector.
    profile : cv2.CascadeClassifier or None, default=None
        The profile face detector, tried where the frontal one finds nothing; None: frontal faces only.
    """

    def __init__(
        self, params: FaceTrackParams, cascade: cv2.CascadeClassifier, profile: cv2.CascadeClassifier | None = None
    ) -> None:
        self.params = params
        self.cascade = cascade
        self.profile = profile
        self.tracks: list[FaceTrack] = []
        self._prev: np.ndarray | None = None
        self._frame = 0
        self._a_pos = params.alpha(params.anchor_s)
        self._a_size = params.alpha(params.size_s)
        self._search_every = max(1, int(round(params.search_every_s * params.fps)))
        self._full_every = max(1, int(round(params.full_search_every_s * params.fps)))
        self._lk = dict(
            winSize=(15, 15), maxLevel=2, criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 0.03)
        )

    def reset(self) -> None:
        """Forget every face (a cut, a gap in the stream)."""
        self.tracks = []
        self._prev = None

    def _seed(self, gray: np.ndarray, tr: FaceTrack) -> None:
        """Corners of the upper face (eyes, brows, nose; not the mouth) for the flow."""
        w = tr.size
        x0, x1 = int(tr.center[0] - 0.35 * w), int(tr.center[0] + 0.35 * w)
        y0, y1 = int(tr.center[1] - 0.35 * w), int(tr.center[1] + 0.12 * w)
        x0, y0 = max(0, x0), max(0, y0)
        x1, y1 = min(gray.shape[1], x1), min(gray.shape[0], y1)
        if x1 - x0 < 8 or y1 - y0 < 8:
            tr.points = np.empty((0, 1, 2), np.float32)
            return
        pts = cv2.goodFeaturesToTrack(gray[y0:y1, x0:x1], self.params.n_points, 0.01, max(2.0, w / 40))
        if pts is None:
            tr.points = np.empty((0, 1, 2), np.float32)
            return
        tr.points = (pts.reshape(-1, 1, 2) + np.array([x0, y0], np.float32)).astype(np.float32)

    def _flow(self, gray: np.ndarray, tr: FaceTrack) -> np.ndarray | None:
        """Median displacement (2,) px of the face's points from the last frame, or None."""
        if self._prev is None or len(tr.points) < 4:
            return None
        nxt, st, _ = cv2.calcOpticalFlowPyrLK(self._prev, gray, tr.points, None, **self._lk)
        back, st2, _ = cv2.calcOpticalFlowPyrLK(gray, self._prev, nxt, None, **self._lk)
        ok = (st.ravel() == 1) & (st2.ravel() == 1) & (np.linalg.norm((back - tr.points).reshape(-1, 2), axis=1) < 0.5)
        if ok.sum() < 4:
            tr.points = np.empty((0, 1, 2), np.float32)
            return None
        d = (nxt - tr.points).reshape(-1, 2)[ok]
        tr.points = nxt[ok]
        return np.median(d, axis=0)

    def _profiles(self, gray: np.ndarray, *args: float | None) -> np.ndarray:
        """Profile faces turned either way: :func:`_detect` (arguments after the cascade) with the
        profile cascade on ``gray`` and on its mirror image.
        """
        return np.concatenate([_detect(gray, self.profile, *args, mirror=m) for m in (False, True)])  # type: ignore[arg-type]

    def _around(self, gray: np.ndarray, tr: FaceTrack, profile: bool = False) -> tuple[np.ndarray | None, bool]:
        """The detection nearest the tracked point within ``max_jump`` face widths, or None; and
        whether it is a profile's (looked for, when ``profile``, where no frontal face is found).
        """
        w = tr.size
        m = 0.75 * w
        x0, y0 = max(0, int(tr.center[0] - w / 2 - m)), max(0, int(tr.center[1] - w / 2 - m))
        x1 = min(gray.shape[1], int(tr.center[0] + w / 2 + m))
        y1 = min(gray.shape[0], int(tr.center[1] + w / 2 + m))
        if x1 - x0 < HAAR_WINDOW_PX or y1 - y0 < HAAR_WINDOW_PX:
            return None, False
        args = (min(1.0, ROI_FACE_PX / w), max(self.params.min_face_px, 0.7 * w), 1.45 * w, 3, x0, y0)
        f = _detect(gray[y0:y1, x0:x1], self.cascade, *args)
        profile = profile and len(f) == 0 and self.profile is not None
        if profile:
            f = self._profiles(gray[y0:y1, x0:x1], *args)
        if len(f) == 0:
            return None, False
        c = f[:, :2] + f[:, 2:] / 2
        d = np.linalg.norm(c - tr.center, axis=1)
        i = int(np.argmin(d))
        return (f[i], profile) if d[i] <= self.params.max_jump * w else (None, False)

    def update(self, gray: np.ndarray, boxes: list[tuple[float, float, float, float]] | None = None) -> list[FaceTrack]:
        """Track the faces into a frame.

        Parameters
        ----------
        gray : ndarray of shape (H, W), dtype uint8
            The frame, grey.
        boxes : list of tuple of float or None, default=None
            The boxes (x, y, w, h) px of the people in view, when known: new faces are searched
            for in their head regions, and in the whole frame only every
            ``full_search_every_s`` (see the module docstring); None or empty: in the whole frame
            every ``search_every_s``.

        Returns
        -------
        list of FaceTrack
            The tracks alive on this frame, in slot order.
        """
        p = self.params
        alive: list[FaceTrack] = []
        for tr in self.tracks:
            d = self._flow(gray, tr)
            tr.flow_ok = d is not None
            if d is not None:
                tr.center = tr.center + d
                top = outline_shift(self._prev, gray, tr.center, tr.size)  # type: ignore[arg-type]
                if top is not None:
                    tr.tilt += float(d[1]) - top
            # the pull towards the detections is slow, so a confirmed face that the flow follows is
            # searched for on every other frame only (half the cost); a miss counts its frames
            attempt = d is None or tr.age < CONFIRM or tr.missed > 0 or tr.age % 2 == 1
            # a profile is looked for where the flow cannot carry the face or a new face is being
            # confirmed; the flow bridges a look-away of a tracked face by itself (max_flow_s)
            det, profile = self._around(gray, tr, d is None or tr.age < CONFIRM) if attempt else (None, False)
            tr.age += 1
            if not attempt:
                pass
            elif det is None:
                tr.detected = False
                tr.missed += 1
                # a new face must be found again on its next CONFIRM frames: the cascade's false
                # positives on a textured background rarely are
                if tr.missed > (p.max_miss if d is None else p.max_flow_miss) or tr.age <= CONFIRM:
                    continue
            elif profile:
                # the face is there, turned aside: the track lives on; the box is the side of the
                # head, so it carries the point only where the flow does not
                tr.detected, tr.missed = False, 0
                if d is None:
                    tr.center = tr.center + max(self._a_pos, p.alpha(0.1)) * (det[:2] + det[2:] / 2 - tr.center)
            else:
                tr.detected, tr.missed = True, 0
                dc = det[:2] + det[2:] / 2
                # without the flow (no points) the detections alone must carry the point: a
                # faster pull, still smoothing their jitter over a few frames
                a = self._a_pos if d is not None else max(self._a_pos, p.alpha(0.1))
                tr.center = tr.center + a * (dc - tr.center)
                tr.size += self._a_size * (float(det[2]) - tr.size)
            if len(tr.points) < p.n_points // 2 or tr.age % self._search_every == 0:
                self._seed(gray, tr)
            alive.append(tr)
        self.tracks = alive
        if len(self.tracks) < p.max_faces and self._frame % self._search_every == 0:
            if not boxes or self._frame % self._full_every == 0:
                self._search(gray)
            else:
                for region in head_regions(boxes, gray.shape, p.min_face_px):
                    self._search(gray, region)
        self._prev = gray
        self._frame += 1
        return sorted(self.tracks, key=lambda t: t.slot)

    def _search(self, gray: np.ndarray, region: tuple[int, int, int, int] | None = None) -> None:
        """Search of the whole frame or of a ``region`` (x0, y0, x1, y1) px of it; faces away from
        every track start new tracks (largest first).
        """
        p = self.params
        x0, y0, x1, y1 = region or (0, 0, gray.shape[1], gray.shape[0])
        part = gray[y0:y1, x0:x1]
        args = (min(1.0, HAAR_WINDOW_PX / p.min_face_px), p.min_face_px, None, 5, x0, y0)
        found = _detect(part, self.cascade, *args)
        if len(found) == 0 and not self.tracks and self.profile is not None:
            found = self._profiles(part, *args)
        for f in sorted(found, key=lambda f: -f[2]):
            if len(self.tracks) >= p.max_faces:
                break
            c = f[:2] + f[2:] / 2
            if any(np.linalg.norm(c - t.center) < max(t.size, f[2]) for t in self.tracks):
                continue
            used = {t.slot for t in self.tracks}
            tr = FaceTrack(center=c.astype(np.float64), size=float(f[2]), slot=min(set(range(p.max_faces)) - used))
            self._seed(gray, tr)
            self.tracks.append(tr)
