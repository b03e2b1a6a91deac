"""People in view while the background is learnt: find them, and learn the room around them.

A robust (median) fit learns whatever stays put for most of the training frames, so two people
standing and talking become part of the background: later they come out as fragments and the
room where they stood as ghosts. Here they are found first and kept out of the statistics:

1. ``PeopleDetector`` (``counterpart.body.people_detector``, shared with the calibration): OpenCV's shipped HOG people detector (Dalal & Triggs 2005, the default
   SVM; no downloaded weights) on every training frame: it misses a still person on most frames
   of some clips and finds them on one or two, which a search of every fifth frame can miss. The
   frame is padded with its median colour first, so that people whose head or feet touch the
   image border, the usual case for an elevated camera close to the people, still fit the
   detector's window with its margins. People cut off by the frame's bottom edge (near the
   camera, their legs out of the picture) are looked for again in the frame continued below
   (``CUT_OFF_BELOW``): the detector's window needs legs. A frame in which no one is found is
   searched again enlarged (``ENLARGE``), for people too short for the detector's window (a
   small video, people far from the camera).
2. ``fit_around_people``: a first fit leaves the people's boxes out of the frames near those they
   were found in, and out of every frame that still shows a person who stands still
   (``HorprasertBackground.fit`` with ``exclude``; the room seen behind them in too few frames is
   filled in from around it). The model then separates each person from the rest of their box,
   frame by frame, and a second fit leaves out only the people themselves (grown by a rim), so
   the room beside them is learnt from its own pixels. Walkers need none of this (the median
   copes with them), and a walker's box is kept to the frames near its own (``_walked_off``: a
   loose box on a thin walker, carried to every frame, took the road they crossed out of the
   room), and so is a detection the detector owes to a walker beside a thing of the room, such as a
   lamp post (``_found_on_passers_by``: on the frame with the walker put back to the room, no one
   is found there); a detection on the still room is not trusted without a sure score or movement
   in its box.

Image coordinates are pixels, x = column, y = row; boxes are (x, y, w, h) int.
"""

from __future__ import annotations

import hashlib
from concurrent.futures import Future, ThreadPoolExecutor

import cv2
import numpy as np

from counterpart.body.people_detector import PeopleDetector, box_iou

from .background import FOREGROUND, HorprasertBackground, NoRoomSeen, as_frame_stack

#: in a box whose room was filled in from around it, a pixel this much darker or brighter than
#: the filled-in room (raw brightness distortion) is taken for the person: the guess is good to
#: a few percent on a plain floor, a person is rarely that close to it in brightness and colour
_PERSON_BRIGHTNESS = 0.2
#: a detection is taken for a person when the detector is sure of it (score) or something in its
#: box moves during the training frames: a fraction of its pixels change by more than the grey
#: levels below from their median at least once (a standing person sways, breathes, turns their
#: head; a false detection on the room, a parked car or a barrier does none of that)
_SURE_SCORE = 1.0
_MOVED_GREY = 30
_MOVED_FRAC = 0.01
#: a box found in one frame holds the same still person in another frame when fewer than this
#: fraction of its pixels changed between the two (a person fills about half of their box: a
#: walker who has left it changes far more)
_SAME_FRAC = 0.2
#: the least share of a box that must differ from its temporal median for those pixels to be taken
#: as the person in it, and the share of them back to the median that shows the person has left
#: (``_walked_off``)
_PERSON_SHARE = 0.05
_GONE_FRAC = 0.5
#: the least share of a still person's box a passer-by's pixels must fill for the detector to be
#: asked whether it found the passer-by (``_found_on_passers_by``): someone standing still who
#: moves a hand changes less of their box
_PASSER_SHARE = 0.025
#: the bottom fraction of a person's box that holds their feet, and their shadow on the ground
_FEET_BAND = 0.25
#: the score a still person (``_still_person``) reaches at least once
_STILL_SCORE = 0.75
#: how far below the frame people cut off by its bottom edge are looked for, as a fraction of its
#: height (``PeopleDetector``'s ``below_frac``)
CUT_OFF_BELOW = 0.8
#: how much a frame in which no one is found is enlarged to look for people too short for the
#: detector's window (``PeopleDetector``'s ``enlarge``): 2 finds people down to about 60 pixels
ENLARGE = 2.0
#: the largest share of the frame hinted boxes may cover: more is a whole room taken for people (a
#: model that no longer fitted the room), and carried to every frame it would leave too little room
_MAX_HINTED_SHARE = 0.5
#: one frame's confirmed detections: boxes (K, 4), scores (K,), moved (K,) bool (``_confirmed``)
_Found = tuple[np.ndarray, np.ndarray, np.ndarray]
#: training frames are searched with every search of the detector on every this many-th frame
#: (``fit_around_people``'s ``detect_every``), at their own scale only between
DETECT_EVERY = 5


def people_detector() -> PeopleDetector:
    """The detector of the people in the training frames: OpenCV's HOG people detector, people cut
    off by the frame's bottom edge (``CUT_OFF_BELOW``) and people too short for its window
    (``ENLARGE``) included.
    """
    return PeopleDetector(below_frac=CUT_OFF_BELOW, enlarge=ENLARGE)


class PrefetchDetector:
    """A people detector that starts on each training frame as it comes (``submit``), in a worker
    thread, so that a live graph finds the people of its training frames while the frames are
    still coming instead of all at once after the last one (OpenCV lets go of the GIL while it
    detects). Each frame is searched as :func:`fit_around_people` will ask: fully on every
    ``every``-th frame submitted from the first, at its own scale only on the others
    (:func:`searched_fully`). ``detect`` of a frame submitted before, searched so, waits for its
    result; of another, it detects at once. The results are those of the wrapped detector, frame for
    frame.

    Parameters
    ----------
    detector : PeopleDetector or None, default=None
        The detector; None: :func:`people_detector`.
    every : int, default=DETECT_EVERY
        :func:`fit_around_people`'s ``detect_every``.
    """

    def __init__(self, detector: PeopleDetector | None = None, every: int = DETECT_EVERY) -> None:
        self.detector = detector or people_detector()
        self.every = every
        self._pool: ThreadPoolExecutor | None = None
        #: (frame content digest, plain) -> its detection
        self._pending: dict[tuple[bytes, bool], Future] = {}
        #: frames submitted since the last ``clear``
        self._submitted = 0

    @staticmethod
    def _key(frame: np.ndarray, plain: bool) -> tuple[bytes, bool]:
        # by content: the background model stacks copies of the frames it was given
        digest = hashlib.blake2b(np.ascontiguousarray(frame).data, digest_size=16).digest()
        return digest + bytes(str(frame.shape), "ascii"), plain

    def submit(self, frame: np.ndarray) -> None:
        """Start the detection of the next training frame in the worker thread.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3)
            uint8 BGR frame (copied).
        """
        # the last training frame is searched fully too, but which one is last is not known yet:
        # the fit searches it again if it was searched at its own scale only
        key = self._key(frame, plain=not searched_fully(self._submitted, None, self.every))
        self._submitted += 1
        if key not in self._pending:
            if self._pool is None:
                self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="people")
            self._pending[key] = self._pool.submit(self.detector.detect, frame.copy(), key[1])

    def detect(self, frame: np.ndarray, plain: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """People in a frame, waiting for a submitted frame's result.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3)
            uint8 BGR frame.
        plain : bool, default=False
            As ``PeopleDetector.detect``'s.

        Returns
        -------
        tuple of ndarray
            ``(boxes (K, 4), scores (K,))``, as ``PeopleDetector.detect``.
        """
        # kept until ``clear``: a clip's repeated frames (a frame rate doubled by duplicates)
        # are asked for once each and detected once
        key = self._key(frame, plain)
        fut = self._pending.get(key)
        if fut is None:
            fut = Future()
            fut.set_result(self.detector.detect(frame, plain))
            self._pending[key] = fut
        return fut.result()

    def clear(self) -> None:
        """Forget the frames submitted and their results (detections still running finish unread)."""
        self._pending.clear()
        self._submitted = 0


def searched_fully(k: int, n: int | None, every: int = DETECT_EVERY) -> bool:
    """Whether :func:`fit_around_people` searches training frame ``k`` of ``n`` (None: not known
    yet) with every search of the detector, or at its own scale only
    (``PeopleDetector.detect(plain=True)``): fully on every ``every``-th frame from the first and
    on the last.

    Parameters
    ----------
    k : int
        Index of the frame among the training frames, from 0.
    n : int or None
        Number of training frames; None: frame ``k`` is not taken for the last.
    every : int, default=DETECT_EVERY
        The schedule's step (``detect_every``); < 1 counts as 1.

    Returns
    -------
    bool
        True for a full search.
    """
    return k % max(1, int(every)) == 0 or (n is not None and k == n - 1)


def moving_fraction(frames: np.ndarray, box: np.ndarray) -> float:
    """Fraction of the pixels of a box whose colour (any channel) differs by more than
    ``_MOVED_GREY`` grey levels from its temporal median in at least one frame.

    Parameters
    ----------
    frames : ndarray of shape (N, H, W, 3)
        uint8 frames.
    box : ndarray of shape (4,)
        (x, y, w, h) pixels.

    Returns
    -------
    float
        The fraction in [0, 1]; 0 for an empty box.
    """
    x, y, w, h = (int(v) for v in box)
    blk = frames[:, y : y + h, x : x + w].astype(np.int16)
    if blk.size == 0:
        return 0.0
    dev = np.abs(blk - np.median(blk, axis=0).astype(np.int16)).max(axis=(0, 3))
    return float(np.mean(dev > _MOVED_GREY))


def _confirmed(frames: np.ndarray, boxes: np.ndarray, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The boxes (K, 4) and scores (K,) of the detections that are sure or hold movement
    (``_SURE_SCORE``, ``_MOVED_FRAC``), and whether each holds movement (K,) bool: measured on the
    unsure ones only (False on the sure ones, which the detector finds again as a rule).
    """
    sure = scores >= _SURE_SCORE
    moved = np.array([not s and moving_fraction(frames, b) >= _MOVED_FRAC for b, s in zip(boxes, sure)], bool)
    keep = sure | moved
    return boxes[keep], scores[keep], moved[keep]


def _with_hints(found: _Found, hints: np.ndarray) -> _Found:
    """A frame's confirmed detections with the hinted boxes (K, 4) that none of them holds (IoU <
    0.5) added as sure ones (score 1, moved: a still person whether or not found again).
    """
    boxes, scores, moved = found
    new = hints[[all(box_iou(h, b) < 0.5 for b in boxes) for h in hints]]
    return (
        np.concatenate([boxes.reshape(-1, 4), new]).astype(np.int32),
        np.concatenate([scores, np.ones(len(new), scores.dtype)]),
        np.concatenate([moved, np.ones(len(new), bool)]),
    )


def _boxes_for(
    frames: np.ndarray,
    j: int,
    found: dict[int, _Found],
    step: int,
    walkers: set[tuple[int, int]],
    hinted: frozenset[tuple[int, int]] = frozenset(),
) -> tuple[np.ndarray, np.ndarray]:
    """The boxes (K, 4) in which frame j is searched for people, and whether each holds a person
    standing still (K,) bool. They are the boxes detected within ``step`` frames of j, and the
    boxes of a still person (``_still_person``) detected further away whose content frame j
    still shows (fewer than ``_SAME_FRAC`` of the box's pixels changed by more than
    ``_MOVED_GREY``), unless the person walked off (``walkers``: (frame, index) of the boxes
    ``_walked_off`` holds). ``found``: detection frame -> (boxes (K, 4), scores (K,), moved (K,)).
    ``hinted``: (frame, index) of the hints' boxes, carried to every frame: someone kicking or
    waving changes much of their box while they stay in it.
    """
    out, still = [], []
    for k, (boxes, scores, moved) in found.items():
        for i, (b, s, m) in enumerate(zip(boxes, scores, moved)):
            stays = (
                (k, i) not in walkers
                and _still_person(found, k, b, s, m)
                and ((k, i) in hinted or _changed_fraction(frames[j], frames[k], b) < _SAME_FRAC)
            )
            if abs(j - k) <= step or stays:
                out.append(b)
                still.append(stays)
    return np.array(out, np.int32).reshape(-1, 4), np.array(still, bool)


def _walked_off(
    frames: np.ndarray, found: dict[int, _Found], k: int, box: np.ndarray, step: int, min_share: float = _PERSON_SHARE
) -> bool:
    """Whether the person in box (x, y, w, h) of frame k walked through it: no detection more than
    ``step`` frames away is on the same place (IoU >= 0.5), and the room behind them is back on every
    frame that far away (at least ``step`` of them).

    The person's pixels are those of the box that differ from its temporal median in frame k (by
    more than ``_MOVED_GREY``, any channel; eroded by a pixel: the rim of someone swaying about
    their median outline is not a body); the room is back on a frame where at least
    ``_GONE_FRAC`` of them are within ``_MOVED_GREY`` of the median again. A walker fills a small
    part of a box found on them and leaves it within a second: over the whole box their leaving
    changes too few pixels to tell (``_SAME_FRAC``), and their box, carried to every frame as a
    still person's, took the road they crossed out of the room. Someone found on the same place
    again later (or earlier) stays there, however they moved in between (the median there can be
    their usual pose, which their pixels in a turn differ from). Someone who came before k and
    stays is not back to the room after it (and the frames before they came show the room, which
    their box need not be carried to), and someone who stood in the median differs from it in too
    few pixels (``min_share`` of the box, ``_PERSON_SHARE`` unless the caller asks) to be judged.
    """
    x, y, w, h = (int(v) for v in box)
    far = [j for j in range(len(frames)) if abs(j - k) > step]
    if len(far) < step or any(
        abs(j - k) > step and box_iou(box, other) >= 0.5 for j, (boxes, _, _) in found.items() for other in boxes
    ):
        return False
    blk = frames[:, y : y + h, x : x + w]
    if blk.size == 0:
        return False
    median, off = _off_median(blk, k)
    person = cv2.erode(off.view(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    if person.mean() < min_share:
        return False
    back = np.abs(blk[far].astype(np.int16) - median.astype(np.int16)).max(axis=3) <= _MOVED_GREY
    return bool((back[:, person].mean(axis=1) >= _GONE_FRAC).all())


def _off_median(blk: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """A box's pixels over the training frames ``blk`` (N, h, w, 3) uint8: their temporal median
    (h, w, 3) uint8, and those of frame k off it by more than ``_MOVED_GREY`` (any channel), (h, w)
    bool.
    """
    median = np.median(blk, axis=0).astype(np.uint8)
    return median, cv2.absdiff(blk[k], median).max(axis=2) > _MOVED_GREY


def _found_on_passers_by(
    detector: PeopleDetector, frames: np.ndarray, found: dict[int, _Found], step: int, judged: set[tuple[int, int]]
) -> set[tuple[int, int]]:
    """(frame, index) of the still people's detections (``_still_person``) that the detector owes to
    someone passing through their box. ``judged``: the detections left as they are (walkers, hints).

    A lamp post or a sign that the detector takes for a person with a walker beside it is sure
    enough and moves enough to pass for a still person, and carried to every frame it would be
    learnt as a hole in the room, filled in from around it: a ghost for as long as the camera runs.
    The walker may fill too little of the large box for ``_walked_off`` to judge (under
    ``_PERSON_SHARE``). Such a detection is the walker's when the walker's pixels, down to
    ``_PASSER_SHARE`` of the box, are the room again on every frame away from it, and on its frame
    with those pixels put back to the box's temporal median the detector no longer finds anyone
    there (IoU >= 0.5). A person standing still who moved an arm is in the median too, and found
    on it; the search runs for such detections only.
    """
    out: set[tuple[int, int]] = set()
    for k, (boxes, scores, moved) in found.items():
        for i, (b, s, m) in enumerate(zip(boxes, scores, moved)):
            if (
                (k, i) in judged
                or not _still_person(found, k, b, s, m)
                or not _walked_off(frames, found, k, b, step, _PASSER_SHARE)
            ):
                continue
            x, y, w, h = (int(v) for v in b)
            median, off = _off_median(frames[:, y : y + h, x : x + w], k)
            still = frames[k].copy()
            still[y : y + h, x : x + w][off] = median[off]
            if not any(box_iou(b, o) >= 0.5 for o in detector.detect(still)[0]):
                out.add((k, i))
    return out


def _still_person(found: dict[int, _Found], k: int, box: np.ndarray, score: float, moved: bool) -> bool:
    """Whether a box found in frame k holds someone standing still: found again (IoU >= 0.5) in
    another frame or moving a little in the training frames (swaying, breathing, turning their
    head: the detector misses people now and then, and may find a still one only once), and
    surely (score >= ``_STILL_SCORE``) in at least one of them. A weak detection on the room's
    clutter, which would be carried to every frame and learnt as a hole in the room, may be
    found twice too, but not surely, and does not move.
    """
    again = [
        s
        for j, (boxes, scores, _) in found.items()
        if j != k
        for other, s in zip(boxes, scores)
        if box_iou(box, other) >= 0.5
    ]
    return (bool(again) or bool(moved)) and max(again + [score]) >= _STILL_SCORE


def _changed_fraction(a: np.ndarray, b: np.ndarray, box: np.ndarray) -> float:
    """Fraction of box (x, y, w, h) pixels whose colour (any channel) differs by more than
    ``_MOVED_GREY`` grey levels between frames a and b (H, W, 3) uint8.
    """
    x, y, w, h = (int(v) for v in box)
    d = cv2.absdiff(a[y : y + h, x : x + w], b[y : y + h, x : x + w])
    if d is None or not d.size:  # OpenCV gives None for an empty crop
        return 1.0
    # the largest channel per pixel (OpenCV's reduce over each pixel's 3 values), counted
    big = cv2.reduce(d.reshape(-1, 3), 1, cv2.REDUCE_MAX)
    return int(np.count_nonzero(big > _MOVED_GREY)) / big.shape[0]


def _feet_bands(boxes: np.ndarray) -> np.ndarray:
    """The bottom ``_FEET_BAND`` of each box (K, 4) (x, y, w, h), grown down by the same, (K, 4)."""
    b = np.asarray(boxes, np.float64).reshape(-1, 4)
    band = _FEET_BAND * b[:, 3]
    return np.stack([b[:, 0], b[:, 1] + b[:, 3] - band, b[:, 2], 2.0 * band], axis=1)


def box_mask(shape: tuple[int, int], boxes: np.ndarray, grow: float = 0.0) -> np.ndarray:
    """Mask of the inside of boxes, each grown on every side by ``grow`` times its height.

    Parameters
    ----------
    shape : tuple of int (H, W)
        Image size, pixels.
    boxes : ndarray of shape (K, 4)
        (x, y, w, h) pixels.
    grow : float, default=0.0
        Growth on every side as a fraction of each box's height.

    Returns
    -------
    ndarray of shape (H, W)
        bool, True inside any of the grown boxes (clipped to the image).
    """
    h, w = shape
    out = np.zeros((h, w), bool)
    for x, y, bw, bh in np.asarray(boxes).reshape(-1, 4):
        g = grow * bh
        xa, ya = int(max(0, np.floor(x - g))), int(max(0, np.floor(y - g)))
        xb, yb = int(min(w, np.ceil(x + bw + g))), int(min(h, np.ceil(y + bh + g)))
        out[ya:yb, xa:xb] = True
    return out


def fit_around_people(
    model: HorprasertBackground,
    frames: np.ndarray | list[np.ndarray],
    detector: PeopleDetector | None = None,
    detect_every: int = DETECT_EVERY,
    box_grow: float = 0.05,
    person_grow: float = 0.03,
    hints: np.ndarray | None = None,
) -> np.ndarray:
    """Fit ``model`` (robustly) on training frames in which people may stand still.

    Parameters
    ----------
    model : HorprasertBackground
        The background model to fit (its parameters are kept).
    frames : ndarray of shape (N, H, W, 3) or list of ndarray of shape (H, W, 3)
        uint8 BGR training frames, N >= 2.
    detector : PeopleDetector or None, default=None
        People detector (``detect(frame, plain)``); None: :func:`people_detector`.
    detect_every : int, default=DETECT_EVERY
        The detector's boxes on every this many-th frame (and the last) are used; on the other
        frames (searched too, at their own scale only: ``plain``) only those of someone these frames
        did not show. A frame is searched for
        people in the boxes found within this many frames of it, and in any other box whose
        content it shares (someone standing there still: the detector misses people now and then,
        in a turn or with an arm across the body), but not where a walker was.
    box_grow : float, default=0.05
        The first fit leaves out each box grown by this fraction of its height.
    person_grow : float, default=0.03
        The second fit leaves out each person's pixels grown by this fraction of their box height
        (the model's outline of a person misses a blurred rim).
    hints : ndarray of shape (K, 4) or None, default=None
        Boxes (x, y, w, h) of people known to stand in the first frame, whatever the detector finds
        (the people found just before the background had to be learnt again,
        ``SilhouetteExtractor.restart_background``): sure detections of frame 0, taken for a still
        person's and carried to every frame (the second fit then leaves out the pixels that are
        theirs there, and learns the room in the rest of the box); none where together they cover
        over ``_MAX_HINTED_SHARE`` of the frame.

    Returns
    -------
    ndarray of shape (N, H, W)
        bool, the samples left out of the final fit (the people found; their boxes when no one
        stood still long enough to need the second fit). With no one detected it is all False and
        the fit is the plain robust one.
    """
    stack = as_frame_stack(frames)
    n, h, w = stack.shape[:3]
    det = detector or people_detector()
    step = max(1, int(detect_every))
    at = [k for k in range(n) if searched_fully(k, n, step)]
    found = {k: _confirmed(stack, *det.detect(stack[k])) for k in at}  # k -> (boxes, scores, moved)
    hinted: frozenset[tuple[int, int]] = frozenset()
    if hints is not None and len(hints) and box_mask((h, w), np.asarray(hints)).mean() <= _MAX_HINTED_SHARE:
        before = len(found[0][0])
        found[0] = _with_hints(found[0], np.asarray(hints, np.int32).reshape(-1, 4))
        hinted = frozenset((0, i) for i in range(before, len(found[0][0])))
    # The frames between are searched too, for someone the schedule's frames did not show: the
    # detector may find a still person on a frame or two only. Only those new boxes are kept (more
    # boxes of the people already found would only widen the holes in the room). At the frame's
    # own scale only: the searches of the frame continued below and enlarged, three quarters of the
    # detector's time, changed what was learnt on none of the 60 real clips as they come (on 6 of
    # the 120 cut off above the knees or shrunk to a third, no worse over them).
    # Walkers need none of them (the median copes), so a new box is kept only for a still person.
    known = [b for boxes, _, _ in found.values() for b in boxes]
    extra: dict[int, _Found] = {}
    for k in sorted(set(range(n)) - set(at)):
        boxes, scores, moved = _confirmed(stack, *det.detect(stack[k], plain=True))
        new = np.array([all(box_iou(b, o) < 0.5 for o in known) for b in boxes], bool)
        if new.any():
            extra[k] = (boxes[new], scores[new], moved[new])
    every = {**found, **extra}
    for k, (boxes, scores, moved) in extra.items():
        still = np.array([_still_person(every, k, *f) for f in zip(boxes, scores, moved)], bool)
        if still.any():
            found[k] = (boxes[still], scores[still], moved[still])
    # a hinted person is never taken for a walker: someone kicking or dancing on the spot stays,
    # though the pixels that tell a walker (those off the box's median) all move
    walkers = {
        (k, i)
        for k, (boxes, _, _) in found.items()
        for i, b in enumerate(boxes)
        if (k, i) not in hinted and _walked_off(stack, found, k, b, step)
    }
    walkers |= _found_on_passers_by(det, stack, found, step, walkers | hinted)
    near = [_boxes_for(stack, j, found, step, walkers, hinted) for j in range(n)]
    if not any(len(b) for b, _ in near):
        model.fit(stack, robust=True)
        return np.zeros((n, h, w), bool)
    boxes = np.stack([box_mask((h, w), b, box_grow) for b, _ in near])
    try:
        model.fit(stack, robust=True, exclude=boxes)
    except NoRoomSeen:
        # boxes over the whole frame in most frames (people standing still across a narrow frame, a
        # crowd) leave no room to learn around them: the plain robust fit, as with no one found
        model.fit(stack, robust=True)
        return np.zeros((n, h, w), bool)
    if not model.unseen_.any():
        # everyone found moved enough for the room behind them to be seen in most frames (the
        # robust median copes with them): the fit without their boxes is the answer
        return boxes
    people = np.stack(
        [
            _person_pixels(model, stack[j], boxes[j], box_mask((h, w), b[still], box_grow), b, person_grow)
            for j, (b, still) in enumerate(near)
        ]
    )
    model.fit(stack, robust=True, exclude=people)
    return people


def _person_pixels(
    model: HorprasertBackground,
    frame: np.ndarray,
    boxes: np.ndarray,
    still: np.ndarray,
    box_list: np.ndarray,
    grow: float,
) -> np.ndarray:
    """(H, W) bool: the pixels of one training frame, inside the people's (grown) boxes, that the
    first fit does not explain as the room, as solid regions grown by ``grow`` times the typical
    box height. ``boxes``, ``still``: (H, W) bool masks of all boxes and of those of people
    standing still; ``box_list`` (K, 4) the boxes.

    Where the first fit saw the room, it is right, and what differs from it is a person. Where it
    saw no room (the boxes filled in from around them), a thing the fill does not continue (a
    sign, a bin) differs too: there only a person standing still, who has to be left out, is
    taken. And as the fill is a guess, a pixel counts there when it is foreground or differs in
    brightness by more than ``_PERSON_BRIGHTNESS``: a darker or lighter shade of the floor's
    colour is more likely a grey shirt than the room.
    """
    if not boxes.any():
        return boxes
    alpha_hat, cd_hat = model.distortions(frame)
    alpha = 1.0 + alpha_hat * model.a_
    fg = model.apply(frame) == FOREGROUND
    changed = fg | (np.abs(alpha - 1.0) > _PERSON_BRIGHTNESS)
    # At the feet, a darker shade of the floor (its chromaticity, no darker than a shadow can be)
    # is the person's cast shadow: it is not left out, so that it stays a shadow there. The room
    # under it is learnt shadowed; when it is uncovered the model absorbs the ghost.
    feet = box_mask(frame.shape[:2], _feet_bands(box_list), 0.0)
    shade = feet & (alpha < 1.0) & (alpha >= model.shadow_bounds()[0]) & (cd_hat <= model.thresholds_["tau_cd"])
    changed &= ~shade
    r = max(1, int(round(grow * float(np.median(box_list[:, 3])))))
    return _solid_regions(changed & boxes & (~model.unseen_ | still), r) & boxes


def _solid_regions(mask: np.ndarray, r: int) -> np.ndarray:
    """A person's (H, W) bool pixels made solid: speckle opened away, thin horizontal runs removed
    (the edges of the room the fill did not continue, a skirting board or a kerb, not a standing
    person: an opening with a vertical line of 2r + 1 pixels), gaps closed and holes filled (disk
    of radius r), and the result grown by r pixels.
    """
    m = cv2.morphologyEx(mask.view(np.uint8), cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    m = cv2.morphologyEx(m, cv2.MORPH_OPEN, np.ones((2 * r + 1, 1), np.uint8))
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, disk)
    contours, _ = cv2.findContours(m, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    m = np.zeros_like(m)
    cv2.drawContours(m, contours, -1, 1, thickness=cv2.FILLED)
    return cv2.dilate(m, disk).astype(bool)
