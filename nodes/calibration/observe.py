"""Head and foot points of the people in view, gathered over frames for the camera estimate
(``counterpart.nodes.calibration.estimate``): what the calibration node, ``counterpart calibrate`` and the
bench share.

A person region (the silhouette node's ``PersonShape``, or ``counterpart.nodes.silhouette.regions.Person``:
anything with ``id``, ``bbox``, ``ctrl``, ``ref_point``, ``merged``) gives one observation when it
can be an upright person (``estimate.usable``). A region that cannot because it is too wide (two
people joined by an arm, a shadow or a faint line of the room; a person with an arm held out) gives
the standing bodies in its pixels when the frame's label image is given (``upright.upright_parts``),
each under an id of its own. A region shared between two tracks (``merged``) gives none: its pixels
were split between them by their previous shapes, not by what they are now (on the tuning seeds
its bodies made more estimates worse than better). The store is bounded: past ``max_observations`` it
keeps every second observation of the older half, so a long run keeps its whole span at a lower
density and each estimate costs about the same.

People who barely move (a conversation) are absorbed into the background and give no region that
can be an upright person. On a frame without any, and on every few frames with one (a still person
beside one who moves: their boxes on the upright regions left out), the people detector's boxes
give the head and foot points (:meth:`PeopleObservations.add_detections`: OpenCV's HOG people detector,
``counterpart.body.people_detector.PeopleDetector``, which finds a person from its shape alone,
moving or not). The detector's window holds a person at a fixed share of its height (Dalal & Triggs
2005: a 96-pixel person in a 128-pixel window), so the head and the feet lie at fixed shares of its
box (:data:`HEAD_IN_BOX`, :data:`FOOT_IN_BOX`); its smallest window is 128 pixels tall, so the
frame is enlarged first (:func:`detect_people`) for people a fifth of a small frame's height, and
while the runs at a fifth find no one, the runs take turns with people 0.15 of it (standing still
far from the camera) and 0.3 of it (standing still near it, whom the frame enlarged for a fifth
may show the detector as no one or as their upper half alone; on a still scene the runs at one
scale all find the same people). On a frame where neither the regions nor the detector gave anyone,
the people standing still are grown from where the frames changed lately (their gestures) down to
their feet (:meth:`PeopleObservations.add_still`, ``still.StillPeople``): the detector misses many
people seen side on or far away.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import cv2
import numpy as np

from counterpart.body.people_detector import PeopleDetector

from .estimate import CalibrationConfig, CameraEstimate, estimate_camera, head_foot, usable
from .lines import LineFamilies, scene_lines
from .still import StillPeople
from .upright import upright_parts

#: the head's and the feet's rows in a box of ``PeopleDetector.detect``, as shares of its height
#: from its top: where the top and the bottom of a person's outline lie in it (measured on the
#: simulator's tuning seeds 0-49 against the true crown and ankles, outline's excess added; the
#: detector's training windows put them at 0.13 and 0.92 of such a box)
HEAD_IN_BOX = 0.108
FOOT_IN_BOX = 0.92
#: height over width of a whole box of ``PeopleDetector.detect`` (its 64 x 128 window, of which a box
#: is 0.8 of the width and 0.95 of the height)
BOX_ASPECT = 2.375
#: the least detector score a box needs to count as a person's view
MIN_DETECTION_SCORE = 0.3
#: a box reaching within this share of its height of the frame's top or bottom is taken as cut by
#: it: the detector gives a person cut off at the knees by the frame's bottom a box of a whole,
#: smaller person, its feet on the last rows
EDGE_SHARE = 0.03
#: ids of the detector's people start here (negated), apart from the silhouettes' ids and their bodies'
DETECTION_ID = 1_000_000
#: a detection continues a person seen this many frames before at most, when its centre is within
#: this share of the box height of theirs and its height within this share of theirs
TRACK_GAP_FRAMES = 10
TRACK_SHARE = 0.3
#: a detection also continues a person last seen longer ago when it stands where they stood: its
#: centre and its height within this share of the box height of theirs (a person standing still,
#: found again after frames the detector missed them; as a new person, each spell of theirs would
#: have too few views to count)
STILL_SHARE = 0.1
#: the detector's people remembered at most, the least recently seen forgotten first
MAX_TRACKS = 32


def detect_people(detector: PeopleDetector, frame: np.ndarray, smallest: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    """People in a frame by the HOG detector, on the frame enlarged so that a person ``smallest`` of
    its height tall fills the detector's smallest window.

    Parameters
    ----------
    detector : PeopleDetector
        The detector.
    frame : ndarray of shape (H, W, 3)
        uint8 BGR frame.
    smallest : float, default=0.2
        Height of the smallest person sought, as a share of the frame's height.

    Returns
    -------
    boxes : ndarray of shape (K, 4)
        float64 (x, y, w, h) of each person's box, pixels of ``frame``.
    scores : ndarray of shape (K,)
        Detector scores.
    """
    # the detector's window is 128 px for a 96 px person: enlarge the frame so that such a person
    # comes out at least that tall
    up = max(1.0, 96.0 / (smallest * frame.shape[0]))
    big = frame if up == 1.0 else cv2.resize(frame, None, fx=up, fy=up, interpolation=cv2.INTER_LINEAR)
    boxes, scores = detector.detect(big)
    return np.asarray(boxes, np.float64).reshape(-1, 4) / up, np.asarray(scores, np.float64).reshape(-1)


class PeopleObservations:
    """Head/foot points of upright people over time, for frames of one size.

    Parameters
    ----------
    width, height : int
        Frame size, pixels.
    max_observations : int, default=1500
        Bound of the store (see the module docstring).
    max_detections : int, default=60
        Frames the people detector may be run on at most (:meth:`wants_detections`; it costs about
        0.15 s of one core a frame).
    detect_every : int or None, default=3
        The detector also runs on every this many frames that do give an upright person (its boxes
        on those people left out): a person who stands still beside one who moves is absorbed
        into the background and gives no region, and is seen only through the detector. None:
        only on frames without an upright person.
    smallest : tuple of float, default=(0.2, 0.15, 0.3)
        Height of the smallest person the detector seeks (:func:`detect_people`), as a share of the
        frame's height (:attr:`next_smallest`): the first value; while the last run at it found no
        one, the runs take turns over all the values. On a still scene every run at one scale finds
        the same people, so where they find no one the others are tried. People standing still far
        from the camera are smaller than a fifth of the frame (0.15; a run there costs about
        (0.2 / 0.15)^2 = 1.8 times one at a fifth, and finds fewer of the people it can see at a
        fifth, so it is not used while those runs find someone). For people standing still near
        the camera, most of the frame tall, the runs at a fifth may give no box or only their upper
        half's, and the runs at 0.3 (the frame enlarged less) their whole one: whether the detector
        finds a still person depends on how much the frame is enlarged, as its windows then fall
        elsewhere on them.
    still : bool, default=True
        Grow the people standing still from where the frames changed (:meth:`add_still`) on the
        frames the detector runs on and finds no one.
    """

    def __init__(
        self,
        width: int,
        height: int,
        max_observations: int = 1500,
        max_detections: int = 60,
        detect_every: int | None = 3,
        smallest: tuple[float, ...] = (0.2, 0.15, 0.3),
        still: bool = True,
    ) -> None:
        self.size = (int(width), int(height))
        self.max_observations = int(max_observations)
        self.max_detections = int(max_detections)
        self.detect_every = None if detect_every is None else int(detect_every)
        self.smallest = tuple(float(v) for v in smallest)
        if not self.smallest or not all(0.0 < v <= 1.0 for v in self.smallest):
            raise ValueError(f"smallest must be shares of the frame height in (0, 1], got {smallest}")
        #: boxes (x, y, w, h) of the upright people of the frame last given to :meth:`add`, and the
        #: detector's people on it
        self._upright: list[tuple[float, float, float, float]] = []
        self.detections_run = 0
        #: whether the detector's last run at ``smallest[0]`` found anyone
        self._found_at_first = True
        self._rows: list[tuple[float, float, float, float, int, float]] = []
        #: the detector's people last seen: (centre x, box height, id, frame number)
        self._tracks: list[tuple[float, float, int, int]] = []
        self._next_track = 0
        self._frame = 0
        #: people's regions given to :meth:`add`, and those of them cut off by the frame's bottom edge
        self.regions_seen = 0
        self.feet_out = 0
        self.still = StillPeople(width, height) if still else None
        #: the last estimate and what it was made from: (rows, config, lines, estimate)
        self._last: tuple[tuple, CalibrationConfig, LineFamilies | None, CameraEstimate | None] | None = None

    def __len__(self) -> int:
        return len(self._rows)

    def feet_out_hint(self, share: float = 0.5) -> str:
        """Why the people gave too little to calibrate from, where it is that their feet were out of
        the picture (a camera near them, or looking over their heads): in at least ``share`` of
        the regions seen. Empty otherwise.

        Returns
        -------
        str
            A sentence to add to a message, starting with "; ", or "".
        """
        if not self.regions_seen or self.feet_out < share * self.regions_seen:
            return ""
        return (
            f"; the people's feet were out of the picture in {100 * self.feet_out / self.regions_seen:.0f}% "
            "of their views (a camera near them, or looking over their heads), and the camera is "
            "estimated from where people stand: give a calibration file, e.g. from `counterpart "
            "calibrate` on a recording of this camera where people stand or walk in full view"
        )

    @property
    def span_s(self) -> float:
        """Seconds between the first and the last observation."""
        return self._rows[-1][5] - self._rows[0][5] if self._rows else 0.0

    def add(self, people: Iterable[Any], time_s: float, labels: np.ndarray | None = None) -> int:
        """Add the usable people of one frame.

        Parameters
        ----------
        people : iterable
            Person regions (anything with ``id``, ``bbox``, ``ctrl``, ``ref_point``, ``merged``).
        time_s : float
            Time the frame was seen, seconds.
        labels : ndarray of shape (H, W) or None, default=None
            The frame's label image (0 background, id + 1 on each person's pixels); with it, a
            region too wide for one upright person (not ``merged``) gives the standing bodies in it (id
            ``-(8 id + k + 1)`` for its k-th body from the left). None or another size: not used.

        Returns
        -------
        int
            How many observations were added.
        """
        n = 0
        self._frame += 1
        self._upright = []
        with_labels = labels is not None and np.shape(labels) == (self.size[1], self.size[0])
        for p in people:
            self.regions_seen += 1
            self.feet_out += int(p.bbox[1]) + int(p.bbox[3]) >= self.size[1]
            if not usable(p.bbox, *self.size, merged=bool(p.merged)):
                if with_labels and not p.merged:
                    for k, (h, f) in enumerate(upright_parts(labels, int(p.id) + 1, p.bbox, self.size)):
                        self._rows.append((h[0], h[1], f[0], f[1], -(8 * int(p.id) + k + 1), float(time_s)))
                        n += 1
                continue
            ctrl = p.ctrl if p.ctrl is not None and np.size(p.ctrl) else None
            ref = p.ref_point if p.ref_point is not None and np.size(p.ref_point) == 2 else None
            h, f = head_foot(p.bbox, ctrl, ref)
            self._upright.append(tuple(float(v) for v in p.bbox))
            self._rows.append((h[0], h[1], f[0], f[1], int(p.id), float(time_s)))
            n += 1
        self._bound()
        return n

    @property
    def next_smallest(self) -> float:
        """Height of the smallest person the detector's next run should seek, as a share of the
        frame's height (see ``smallest``; pass it to :func:`detect_people`, then the boxes to
        :meth:`add_detections`).
        """
        if self._found_at_first:
            return self.smallest[0]
        return self.smallest[self.detections_run % len(self.smallest)]

    def wants_detections(self, added: int) -> bool:
        """Whether to run the people detector on the frame last given to :meth:`add`.

        Parameters
        ----------
        added : int
            What :meth:`add` returned for it.

        Returns
        -------
        bool
            True when the detector has run on fewer than ``max_detections`` frames and the frame
            gave no observation or is one of every ``detect_every``.
        """
        every = self.detect_every is not None and self._frame % self.detect_every == 0
        return (added == 0 or every) and self.detections_run < self.max_detections

    def add_detections(
        self, boxes: np.ndarray, scores: np.ndarray, time_s: float, min_score: float = MIN_DETECTION_SCORE
    ) -> int:
        """Add the people detector's boxes of the frame last given to :meth:`add` (one where no
        region could be an upright person).

        A box counts when its score is ``min_score`` or more, it does not touch the left or right
        border, and its head and foot points, at :data:`HEAD_IN_BOX` and :data:`FOOT_IN_BOX` of its
        height in its middle column, are inside the frame (a box cut by the top or the bottom of the
        frame, or within :data:`EDGE_SHARE` of its height of them, has the height :data:`BOX_ASPECT`
        times its width: the detector's window reaches past the frame where the person's head or
        feet are near its border). A box continues the detector's person whose last box (at most
        ``TRACK_GAP_FRAMES`` frames before) is nearest in x within ``TRACK_SHARE`` of the box height
        and of a height within that share, or, seen longer ago, within ``STILL_SHARE`` (a person
        standing still whom the detector missed for a while); others start a new person (ids
        ``-(DETECTION_ID + k)``).

        Parameters
        ----------
        boxes : ndarray of shape (K, 4)
            (x, y, w, h) pixels (:func:`detect_people`).
        scores : ndarray of shape (K,)
            Their scores.
        time_s : float
            Time the frame was seen, seconds.
        min_score : float, default=MIN_DETECTION_SCORE
            Least score.

        Returns
        -------
        int
            How many observations were added.
        """
        at_first = self.next_smallest == self.smallest[0]
        self.detections_run += 1
        W, H = self.size
        b = np.asarray(boxes, np.float64).reshape(-1, 4)
        sc = np.asarray(scores, np.float64).reshape(-1)
        x, y, w, h = b.T
        # a box cut by the top or the bottom of the frame keeps its width, which gives its height
        at_top, at_bottom = y <= EDGE_SHARE * h, y + h >= H - EDGE_SHARE * h
        full = np.where(at_top | at_bottom, BOX_ASPECT * w, h)
        top = np.where(at_top, y + h - full, y)
        ok = (sc >= min_score) & (x > 0) & (x + w < W) & (full >= 20)
        ok &= (top + HEAD_IN_BOX * full > 0) & (top + FOOT_IN_BOX * full < H - 1)
        if at_first:
            self._found_at_first = bool(ok.any())
        # a box on an upright person of this frame: already seen, as a region
        for ux, uy, uw, uh in self._upright:
            ok &= ~(
                (np.abs(x + w / 2 - (ux + uw / 2)) < 0.5 * np.maximum(w, uw))
                & (np.abs(top + full / 2 - (uy + uh / 2)) < 0.5 * np.maximum(full, uh))
            )
        n = self._add_found(
            [
                (np.array([cx, y0 + HEAD_IN_BOX * bh]), np.array([cx, y0 + FOOT_IN_BOX * bh]))
                for cx, y0, bh in zip(x[ok] + w[ok] / 2, top[ok], full[ok])
            ],
            time_s,
        )
        self._upright.extend(zip(x[ok], top[ok], w[ok], full[ok]))
        return n

    def add_frame(self, frame: np.ndarray, time_s: float, added: int, detector: PeopleDetector | None) -> int:
        """What a frame's pixels give, after :meth:`add` gave ``added`` observations of its
        regions: where it changed is noted (``still.StillPeople.observe``); where
        :meth:`wants_detections`, the people detector's boxes (:func:`detect_people` at
        :attr:`next_smallest`) are added, and where neither its regions nor the detector gave
        anyone, the people standing still (:meth:`add_still`).

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3)
            uint8 BGR frame, the one last given to :meth:`add`.
        time_s : float
            Time the frame was seen, seconds.
        added : int
            What :meth:`add` returned for it.
        detector : PeopleDetector or None
            The people detector; None: neither it nor the still people are looked for.

        Returns
        -------
        int
            How many observations were added.
        """
        if self.still is not None:
            self.still.observe(frame, time_s)
        if detector is None or not self.wants_detections(added):
            return 0
        n = self.add_detections(*detect_people(detector, frame, self.next_smallest), time_s)
        return n + self.add_still(frame, time_s)

    def add_still(self, frame: np.ndarray, time_s: float) -> int:
        """Add the people standing still grown from where the frames changed lately
        (``still.StillPeople``) on the frame last given to :meth:`add` and :meth:`add_frame`, where
        neither its regions nor the detector's boxes of it (:meth:`add_detections`) gave anyone: where
        they did, what moved is mostly the people they gave, and a body grown from it often their
        trail or their raised arm.

        Returns
        -------
        int
            How many observations were added.
        """
        if self.still is None or self._upright:
            return 0
        return self._add_found(self.still.find(frame, time_s), time_s)

    def _add_found(self, found: list[tuple[np.ndarray, np.ndarray]], time_s: float) -> int:
        """Add people found on the frame last given to :meth:`add` by their head and foot points,
        each continuing the found person before it who stood where they stand (see
        :meth:`add_detections`; a person's size is the detector's box height that holds them).
        """
        known = list(self._tracks)
        seen: list[tuple[float, float, int, int]] = []
        for head, foot in found:
            cx, bh = 0.5 * (head[0] + foot[0]), (foot[1] - head[1]) / (FOOT_IN_BOX - HEAD_IN_BOX)
            share = [TRACK_SHARE if self._frame - t[3] <= TRACK_GAP_FRAMES else STILL_SHARE for t in known]
            near = [t for t, s in zip(known, share) if abs(t[0] - cx) < s * bh and abs(t[1] - bh) < s * bh]
            if near:
                pid = min(near, key=lambda t: abs(t[0] - cx))[2]
                known = [t for t in known if t[2] != pid]
            else:
                pid = -(DETECTION_ID + self._next_track)
                self._next_track += 1
            seen.append((float(cx), float(bh), pid, self._frame))
            self._rows.append((head[0], head[1], foot[0], foot[1], pid, float(time_s)))
        self._tracks = (seen + known)[:MAX_TRACKS]
        self._bound()
        return len(seen)

    def _bound(self) -> None:
        if len(self._rows) > self.max_observations:
            half = len(self._rows) // 2
            self._rows = self._rows[:half:2] + self._rows[half:]

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The observations as arrays.

        Returns
        -------
        head : ndarray of shape (N, 2)
            Head points, pixels.
        foot : ndarray of shape (N, 2)
            Foot points, pixels.
        track : ndarray of shape (N,)
            int64 person ids.
        time : ndarray of shape (N,)
            Times, seconds.
        """
        a = np.array(self._rows, np.float64).reshape(-1, 6)
        return a[:, 0:2], a[:, 2:4], a[:, 4].astype(np.int64), a[:, 5]

    def estimate(
        self, config: CalibrationConfig | None = None, lines: LineFamilies | None = None
    ) -> CameraEstimate | None:
        """The camera from what was gathered so far (and the scene's ``lines``).

        Parameters
        ----------
        config : CalibrationConfig or None, default=None
            Estimation settings; None: the defaults.
        lines : LineFamilies or None, default=None
            The scene's straight-line families, if known.

        Returns
        -------
        CameraEstimate or None
            The estimate; None with too few observations.
        """
        config = config or CalibrationConfig()
        rows = tuple(self._rows)
        # the node estimates every few frames, the same observations again where no one new was
        # seen (people merged, out of view): the fit is a function of them alone
        if self._last is not None and self._last[0] == rows and self._last[1] == config and self._last[2] is lines:
            return self._last[3]
        head, foot, track, t = self.arrays()
        est = estimate_camera(head, foot, track, self.size, t, config, lines)
        self._last = (rows, config, lines, est)
        return est


class SceneFrames:
    """A few frames of the scene for its straight lines: frames whose number is a multiple of
    ``every``, up to ``keep`` of them, with the boxes of the people on them. :meth:`families` takes
    the per-pixel median of the frames (people who move are gone from it) and leaves out the
    segments on any person's box.

    Parameters
    ----------
    every : int, default=8
        Keep frames whose number is a multiple of this.
    keep : int, default=9
        The most frames kept.
    """

    def __init__(self, every: int = 8, keep: int = 9) -> None:
        self.every, self.keep = int(every), int(keep)
        self.frames: list[np.ndarray] = []
        self.boxes: list[tuple[int, int, int, int]] = []
        self._families: LineFamilies | None = None

    def wants(self, index: int) -> bool:
        """Whether frame number ``index`` is one to :meth:`add`.

        Parameters
        ----------
        index : int
            Frame number.

        Returns
        -------
        bool
            True while fewer than ``keep`` frames are kept and ``index`` is a multiple of ``every``.
        """
        return len(self.frames) < self.keep and index % self.every == 0

    def add(self, frame: np.ndarray, people: Iterable[Any]) -> None:
        """Keep a frame and its people (ignored once ``keep`` frames are kept).

        Parameters
        ----------
        frame : ndarray of shape (H, W) or (H, W, 3)
            uint8 image.
        people : iterable
            The people on the frame (anything with ``bbox``, (x, y, w, h) pixels).
        """
        if len(self.frames) >= self.keep:
            return
        self.frames.append(np.asarray(frame))
        self.boxes.extend(tuple(int(v) for v in p.bbox) for p in people)
        self._families = None

    def families(self) -> LineFamilies | None:
        """The line families of the frames kept so far.

        Returns
        -------
        LineFamilies or None
            The families; None before the first frame.
        """
        if not self.frames:
            return None
        if self._families is None:
            self._families = scene_lines(self.image(), self.boxes)
        return self._families

    def image(self) -> np.ndarray | None:
        """The per-pixel median of the frames kept (people who move are gone from it).

        Returns
        -------
        ndarray of shape (H, W) or (H, W, 3), dtype uint8, or None
            The image; None before the first frame.
        """
        if not self.frames:
            return None
        return np.median(np.stack(self.frames), axis=0).astype(np.uint8)


__all__ = ["FOOT_IN_BOX", "HEAD_IN_BOX", "PeopleObservations", "SceneFrames", "detect_people"]
