"""Foreground clean-up into person regions, and identities kept over time.

``clean_mask`` turns a raw foreground mask into solid regions (morphological opening against
speckle, closing across small gaps, holes filled, regions below a minimum area dropped).
``PersonTracker`` gives each region a stable identity: regions are matched to the people of the
previous frame by the overlap of each person's motion-predicted mask and, for the rest, by a
Hungarian assignment on position and size. When people touch (a handshake) and their regions
merge into one, the merged region is split between them: every pixel goes to the person whose
predicted mask it lies deepest inside or, outside all of them, nearest to (distance
transforms). Both keep their ids and are flagged ``merged``; identities are never exchanged
between tracks. Image coordinates are pixels, x = column, y = row.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

from . import kernels

LEFT = "left"
RIGHT = "right"
_INFEASIBLE = 1e6
#: newcomer check (see PersonTracker): frames a person must have been seen; growth past the usual
#: area that keeps their template; frames it is kept before the new size is accepted; the rate of
#: the usual area's running mean per frame
NEWCOMER_MIN_AGE = 25
NEWCOMER_FREEZE = 1.3
NEWCOMER_PATIENCE = 10
_USUAL_AREA_RATE = 0.2
#: cost of leaving a track or a region out of the assignment; a pair costs its distance in person
#: heights + size term - overlap, and is kept when cheaper than leaving both out (2 x this)
UNMATCHED_COST = 1.0
#: a person slower than this many of their heights per frame (0.3 heights/s at 30 fps, about 0.5
#: m/s) is not walking: their "velocity" is the sway of a changing outline, or the last steps
#: before they stopped to embrace someone. When a merge hides them (their piece is small) it is
#: not extrapolated, so the prediction does not wander off the merged region; a walker passing
#: behind someone keeps theirs
WALK_SPEED = 0.01
#: a left-over region below a person is their legs or feet (``PersonTracker._stacked_owner``)
#: when this share of its width lies in their columns, the rows between it and them are at most
#: this share of their height (trousers of the floor's colour leave a gap), and it is at most this
#: share of their height tall (as long as the rest of them when their template lacks the legs)
STACK_OVERLAP = 0.5
STACK_GAP = 0.35
STACK_MAX_BELOW = 1.0
#: widest union of a person and a region above them, as a share of its height, that is one
#: person (``group_stacked``'s bound)
STACK_UPRIGHT = 0.45
#: a new region whose bottom is within this share of a tracked person's height of their feet'
#: row, and shorter than this share of their height, is a part of someone (``_ground_owner``)
FEET_ROW = 0.1
FRAGMENT_HEIGHT = 0.4
#: a new region less than ``FRAGMENT_HEIGHT`` of a tracked person's height tall, within their rows
#: and at most this share of their height of columns from their box, is torn off them
#: (``PersonTracker._beside_owner``)
BESIDE_GAP = 0.1
#: someone who was part of a merged region last frame still claims it with this share of their
#: predicted pixels on it (``min_overlap`` otherwise): hidden in a hug, their template, of their
#: shape before the people met, overlaps the merged region less and less as it changes shape
MERGE_KEEP_OVERLAP = 0.05
#: a left-over region with this share of its box in the box of a person's piece, and at most
#: this share of their height tall, is a part of them (``PersonTracker._enclosing_owner``)
ENCLOSED_SHARE = 0.8
ENCLOSED_MAX_HEIGHT = 0.5
#: a left-over region at least this share of a person's piece tall, its feet on their feet row
#: (``FEET_ROW``) and at least ``APART_GAP`` of their height of columns away from them, is a
#: person of their own even inside their predicted mask (``_stands_apart``)
WHOLE_HEIGHT = 0.75
APART_GAP = 0.15


@dataclass(frozen=True, eq=False)
class Person:
    """One person in one frame.

    Parameters
    ----------
    id : int
        Stable identity (>= 0); the label image uses id + 1.
    side : {"left", "right"}
        The image half of the centroid when first seen; a person who joins the one person seen
        takes their side of them, and that person the other side (``PersonTracker._pair_sides``):
        the only change of a side.
    bbox : tuple of int
        (x, y, w, h), pixels.
    area : int
        Pixels.
    centroid : tuple of float
        (x, y), pixels.
    height : float
        Bbox height, pixels.
    merged : bool, default=False
        The region was shared with another person this frame and split between them.
    ctrl : ndarray of shape (n, 2) or None, default=None
        B-spline control points, pixels; filled in by the pipeline, None from the tracker alone.
    ref_point : ndarray of shape (2,) or None, default=None
        The reference point at the top of the head, pixels; filled in by the pipeline, None from
        the tracker alone.
    """

    id: int
    side: str
    bbox: tuple[int, int, int, int]
    area: int
    centroid: tuple[float, float]
    height: float
    merged: bool = False
    ctrl: np.ndarray | None = None
    ref_point: np.ndarray | None = None


def _disk(size: int) -> np.ndarray:
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size))


def label_type(height: int, width: int) -> int:
    """The OpenCV label type for the 8-connected regions of a ``height`` x ``width`` mask:
    ``cv2.CV_16U`` where 16 bits hold every label, else ``cv2.CV_32S``.

    OpenCV labels with 16-bit labels by the same algorithm, so to the same values, in less time,
    and what reads the labels moves half the memory. A mask has at most
    ceil(H / 2) ceil(W / 2) regions (one pixel in each 2 x 2 block): 16 bits hold them for frames
    up to about 510 x 510.

    Parameters
    ----------
    height, width : int
        The mask's size, pixels.

    Returns
    -------
    int
        ``cv2.CV_16U`` or ``cv2.CV_32S``.
    """
    return cv2.CV_16U if ((height + 1) // 2) * ((width + 1) // 2) < 65535 else cv2.CV_32S


def components_with_stats(m8: np.ndarray) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """``cv2.connectedComponentsWithStats(m8, connectivity=8)`` with uint16 labels where they fit.

    With ``label_type``'s labels: OpenCV computes the stats of 16-bit labels in a fraction of the
    time it takes with 32-bit ones, and the labels, stats and centroids are the same.

    Parameters
    ----------
    m8 : ndarray of shape (H, W), dtype uint8
        The mask (non-zero: foreground).

    Returns
    -------
    n : int
        Labels, background (0) included.
    labels : ndarray of shape (H, W), dtype uint16 or int32
        Region labels, 0 = background.
    stats : ndarray of shape (n, 5), dtype int32
        x, y, width, height, area of each label (``cv2.CC_STAT_*``).
    centroids : ndarray of shape (n, 2), dtype float64
        x, y of each label's centroid.
    """
    return cv2.connectedComponentsWithStats(m8, connectivity=8, ltype=label_type(*m8.shape))


def components_in_box(m8: np.ndarray) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """``components_with_stats`` of a mask, labelled inside the bounding box of its set pixels
    (the people, often a third of the frame): the same labels, and the same stats and centroids of
    every region; row 0 (the background) is the box's, not the frame's.

    OpenCV labels 2 x 2 blocks in raster order and numbers the regions by the first block of
    each, so a box whose corner is on even coordinates keeps the frame's blocks and the labels'
    order. The centroids are OpenCV's sums over the pixels' coordinates divided by the area: the
    box's sums (whole numbers, recovered exactly from its centroids) are shifted by the box's
    corner and divided again, the same quotient as over the frame.

    Parameters
    ----------
    m8 : ndarray of shape (H, W), dtype uint8
        The mask (non-zero: foreground).

    Returns
    -------
    As ``components_with_stats``, labels (H, W) of the whole frame.
    """
    h, w = m8.shape
    x, y, bw, bh = cv2.boundingRect(m8)
    x0, y0 = x & ~1, y & ~1
    if bw == 0 or (x + bw - x0) * (y + bh - y0) > 0.75 * h * w:  # empty, or nothing to gain
        return components_with_stats(m8)
    n, lab, stats, cents = cv2.connectedComponentsWithStats(
        m8[y0 : y + bh, x0 : x + bw], connectivity=8, ltype=label_type(h, w)
    )
    comp = np.zeros((h, w), lab.dtype)
    comp[y0 : y + bh, x0 : x + bw] = lab
    stats[1:, cv2.CC_STAT_LEFT] += x0
    stats[1:, cv2.CC_STAT_TOP] += y0
    area = stats[1:, cv2.CC_STAT_AREA].astype(np.float64)
    sums = np.rint(cents[1:] * area[:, None])  # exact: the sums are whole numbers far below 2^52
    cents[1:, 0] = (sums[:, 0] + area * x0) / area
    cents[1:, 1] = (sums[:, 1] + area * y0) / area
    return n, comp, stats, cents


def _as_u8(m: np.ndarray) -> np.ndarray:
    """A mask (H, W) (non-zero: set) as 0 / 1 uint8: a contiguous bool mask as a view of its bytes
    (no pass over the frame), any other as a new array.
    """
    if m.dtype == bool and m.flags.c_contiguous:
        return m.view(np.uint8)
    return (m != 0).astype(np.uint8)


def clean_mask(
    mask: np.ndarray,
    open_px: int = 3,
    close_px: int = 7,
    fill_holes: bool = True,
    min_area: int = 0,
) -> np.ndarray:
    """Clean a foreground mask into solid regions.

    Parameters
    ----------
    mask : ndarray of shape (H, W)
        The foreground mask (non-zero: foreground).
    open_px : int, default=3
        Diameter (pixels) of the elliptical opening (removes speckle); <= 1 skips the step.
    close_px : int, default=7
        Diameter (pixels) of the elliptical closing (bridges small gaps, e.g. between a leg and the
        body); <= 1 skips the step.
    fill_holes : bool, default=True
        Fill every enclosed background hole (the outer contour is what we model).
    min_area : int, default=0
        Drop connected regions (8-connected) smaller than this many pixels.

    Returns
    -------
    ndarray of shape (H, W), dtype bool
        The cleaned mask.

    Raises
    ------
    ValueError
        ``mask`` is not 2-D, or a negative ``open_px``, ``close_px`` or ``min_area``.
    """
    m = np.asarray(mask)
    if m.ndim != 2:
        raise ValueError(f"mask must be 2-D (H, W), got shape {m.shape}")
    if open_px < 0 or close_px < 0 or min_area < 0:
        raise ValueError(f"open_px, close_px and min_area must be >= 0, got {open_px}, {close_px}, {min_area}")
    # a bool mask is read as its 0 / 1 bytes (no pass over the frame); the steps below write new arrays
    m8 = _as_u8(m)
    steps = open_px > 1 or close_px > 1 or fill_holes or min_area > 0
    if open_px > 1:
        m8 = cv2.morphologyEx(m8, cv2.MORPH_OPEN, _disk(open_px))
    # the steps after the opening work on the box of what is left (the people, often half the
    # frame or less) and paste it back: nothing outside that box is set by them
    full, box = None, (0, 0, 0, 0)
    if close_px > 1 and close_px % 2 == 1 and (box := cv2.boundingRect(m8))[2] > 0:
        full = m8
        m8, box = _close_in_box(m8, close_px, box)
    elif close_px > 1:
        m8 = cv2.morphologyEx(m8, cv2.MORPH_CLOSE, _disk(close_px))
    if fill_holes or min_area > 0:
        contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        if fill_holes:
            out = np.zeros_like(m8)
            cv2.drawContours(out, contours, -1, 1, thickness=cv2.FILLED)
            m8 = out
        if min_area > 0:
            n, labels, stats, _ = components_with_stats(m8)
            keep = stats[:, cv2.CC_STAT_AREA] >= min_area
            keep[0] = False
            m8 = keep[labels].view(np.uint8)
    if full is not None:
        x, y, w, h = box
        out = np.zeros_like(full)
        out[y : y + h, x : x + w] = m8
        m8 = out
    # 0 / 1 bytes of the steps' own arrays: viewed as bool (without a step: a copy of the input)
    return m8.view(bool) if steps else m8.astype(bool)


def _close_in_box(
    m8: np.ndarray, size: int, box: tuple[int, int, int, int]
) -> tuple[np.ndarray, tuple[int, int, int, int]]:
    """The closing of ``m8`` (H, W) uint8 by ``_disk(size)`` (odd ``size``) inside the box where it
    can set pixels, given ``box`` (x, y, w, h), the bounding box of its non-zero pixels (not empty).

    The closing by a symmetric disk of radius r = size // 2 sets nothing outside ``box`` but
    next to the frame's edge: a pixel left of the box has a pixel r further left that the
    dilation leaves unset, unless that pixel is off the frame, where the erosion reads set
    pixels (OpenCV's default border). So the closing's box is ``box`` stretched to each edge of
    the frame that it comes within r of. Inside that box the closing reads the dilation up to r
    pixels out, which the foreground (all in ``box``) fixes within r pixels more: worked out on
    ``box`` grown by r (clipped to the frame, whose edges stay the image's edges), it is the
    closing of the whole frame.

    Returns
    -------
    closed : ndarray of shape (h', w'), dtype uint8
        The closing in the closing's box (a new array).
    out_box : tuple of int
        That box, x, y, w', h'.
    """
    x, y, w, h = box
    r = size // 2
    hh, ww = m8.shape
    ox0, oy0 = (0 if x <= r else x), (0 if y <= r else y)
    ox1, oy1 = (ww if x + w >= ww - r else x + w), (hh if y + h >= hh - r else y + h)
    x0, y0, x1, y1 = max(x - r, 0), max(y - r, 0), min(x + w + r, ww), min(y + h + r, hh)
    closed = cv2.morphologyEx(m8[y0:y1, x0:x1], cv2.MORPH_CLOSE, _disk(size))
    return np.ascontiguousarray(closed[oy0 - y0 : oy1 - y0, ox0 - x0 : ox1 - x0]), (ox0, oy0, ox1 - ox0, oy1 - oy0)


@dataclass
class _Track:
    """A person's state. ``crop``/``origin`` is their shape template: the mask of the last frame
    in which they were seen on their own (not merged); prediction places it at the predicted
    centroid, so a long merge cannot erode or grow anyone's shape.
    """

    id: int
    side: str
    centroid: np.ndarray  # (2,) x, y
    velocity: np.ndarray  # (2,) pixels per frame
    crop: np.ndarray  # bool template mask within its bbox
    origin: np.ndarray  # (2,) int x0, y0 of the template when it was taken
    area: int  # template area, pixels
    height: float  # template height, pixels
    offset: np.ndarray  # (2,) template centroid - origin
    missed: int = 0
    seen: int = 0  # frames this person was observed in
    usual_area: float = 0.0  # running mean of the template area (newcomer check)
    frozen: int = 0  # consecutive frames the template was kept through a growth (newcomer check)
    in_merge: bool = False  # the last observation was a piece of a merged region

    def predicted_centroid(self) -> np.ndarray:
        return self.centroid + self.velocity

    def predicted_origin(self) -> np.ndarray:
        return np.rint(self.predicted_centroid() - self.offset).astype(np.int64)


def _paste(track: _Track, x0: int, y0: int, h: int, w: int) -> np.ndarray:
    """The track's predicted mask in the window (x0, y0, w, h): (h, w) bool."""
    out = np.zeros((h, w), bool)
    ox, oy = track.predicted_origin()
    ch, cw = track.crop.shape
    ax0, ay0 = max(ox, x0), max(oy, y0)
    ax1, ay1 = min(ox + cw, x0 + w), min(oy + ch, y0 + h)
    if ax1 > ax0 and ay1 > ay0:
        out[ay0 - y0 : ay1 - y0, ax0 - x0 : ax1 - x0] = track.crop[ay0 - oy : ay1 - oy, ax0 - ox : ax1 - ox]
    return out


@dataclass(frozen=True, eq=False)
class _Regions:
    """One mask's connected regions (``components_with_stats``): comp (H, W) labels (uint16 or int32),
    stats (n, 5), cents (n, 2) x, y; regions the labels of those of at least min_area pixels;
    counts (T, n) pixels of each track's predicted mask in each region (0 for small regions),
    frac_track (T, n) the same over the track's area; region_area (n,) pixels.
    """

    comp: np.ndarray
    stats: np.ndarray
    cents: np.ndarray
    regions: list[int]
    counts: np.ndarray
    frac_track: np.ndarray
    region_area: np.ndarray


#: a person's piece of this frame: (crop (h, w) bool, x0, y0, merged)
_Piece = tuple[np.ndarray, int, int, bool]


@dataclass
class _Matching:
    """What the steps of ``PersonTracker.update`` decided so far: track index -> its piece,
    regions taken, tracks hidden in a merge, the bbox (x, y, w, h) of the merged region each
    claimant of a merge is in, and the regions (crop, x0, y0) that start new people.
    """

    assigned: dict[int, _Piece] = field(default_factory=dict)
    used_regions: set[int] = field(default_factory=set)
    occluded: set[int] = field(default_factory=set)
    within: dict[int, tuple[int, int, int, int]] = field(default_factory=dict)  # track -> merged bbox
    fresh: list[tuple[np.ndarray, int, int]] = field(default_factory=list)


class PersonTracker:
    """Keeps person identities over frames of cleaned foreground masks.

    Parameters
    ----------
    min_area : int, default=50
        Regions smaller than this (pixels) are ignored; >= 1.
    max_missed : int, default=10
        Frames a person may go unseen (occluded, left the view) before the track ends; >= 0.
    max_distance : float, default=0.75
        Gate of the Hungarian assignment: a region further than this many person heights from a
        person's predicted centroid cannot be theirs.
        A person or a region may also stay unassigned (``UNMATCHED_COST`` each), so the
        assignment never pairs them up wrongly only to match everyone; regions left over
        that stand one above the other with an upright union are one new person
        (``group_stacked``).
    size_weight : float, default=0.5
        Weight of |log(area ratio)| against the normalised distance in the cost.
    min_overlap : float, default=0.2
        Fraction of a person's predicted pixels that must fall in a region for the person to
        claim it, in (0, 1]; a region claimed by two or more people is a merge and is split.
    velocity_smoothing : float, default=0.5
        Exponential smoothing factor of the per-frame velocity, in [0, 1) (0 = last step).
    newcomer_growth : float, default=1.6
        Someone who stood still through the background model's training frames is
        part of the background, and when they move they appear already touching their neighbour,
        in that neighbour's region. So, for an established person (seen ``NEWCOMER_MIN_AGE``
        frames, clear of the image border): a region ``newcomer_growth`` times their usual area
        or more is checked for a newcomer, and the part further than ``newcomer_margin`` person
        heights from their predicted mask, if it is at least ``newcomer_min_frac`` of their usual
        area, is split off as a new person. Their template is not updated from a region grown past
        ``NEWCOMER_FREEZE`` times the usual area, so that it keeps their own shape while the
        newcomer emerges (0 disables all of this).
    newcomer_margin : float, default=0.1
        Person heights beyond their predicted mask from which a newcomer's part starts; >= 0.
    newcomer_min_frac : float, default=0.4
        Least size of a newcomer's part, as a fraction of the person's usual area; > 0.
    min_upright : float, default=1.0
        A region that no one claims starts a new person only when its height is at
        least this many times its width (after ``group_stacked`` has joined the parts of one
        person): people stand upright, cars, barriers and ghost strips lie wide (0: any region).

    Raises
    ------
    ValueError
        A parameter out of its range.
    """

    def __init__(
        self,
        min_area: int = 50,
        max_missed: int = 10,
        max_distance: float = 0.75,
        size_weight: float = 0.5,
        min_overlap: float = 0.2,
        velocity_smoothing: float = 0.5,
        newcomer_growth: float = 1.6,
        newcomer_margin: float = 0.1,
        newcomer_min_frac: float = 0.4,
        min_upright: float = 1.0,
    ) -> None:
        if min_area < 1:
            raise ValueError(f"min_area must be >= 1 pixel, got {min_area}")
        if max_missed < 0:
            raise ValueError(f"max_missed must be >= 0 frames, got {max_missed}")
        if max_distance <= 0:
            raise ValueError(f"max_distance must be > 0 (person heights), got {max_distance}")
        if not 0.0 < min_overlap <= 1.0:
            raise ValueError(f"min_overlap must be in (0, 1], got {min_overlap}")
        if not 0.0 <= velocity_smoothing < 1.0:
            raise ValueError(f"velocity_smoothing must be in [0, 1), got {velocity_smoothing}")
        self.min_area = min_area
        self.max_missed = max_missed
        self.max_distance = max_distance
        self.size_weight = size_weight
        self.min_overlap = min_overlap
        self.velocity_smoothing = velocity_smoothing
        if newcomer_growth < 0 or newcomer_margin < 0 or newcomer_min_frac <= 0:
            raise ValueError(
                f"newcomer_growth={newcomer_growth} and newcomer_margin={newcomer_margin} must be "
                f">= 0, newcomer_min_frac={newcomer_min_frac} > 0"
            )
        self.newcomer_growth = newcomer_growth
        self.newcomer_margin = newcomer_margin
        self.newcomer_min_frac = newcomer_min_frac
        if min_upright < 0:
            raise ValueError(f"min_upright must be >= 0 (height / width), got {min_upright}")
        self.min_upright = min_upright
        self.reset()

    def reset(self) -> None:
        """Forget all people; the next id is 0 again."""
        self._tracks: list[_Track] = []
        self._next_id = 0

    @property
    def active_ids(self) -> list[int]:
        """Ids of the people currently tracked (seen, or unseen for at most max_missed frames)."""
        return [t.id for t in self._tracks]

    def update(self, mask: np.ndarray) -> tuple[np.ndarray, list[Person]]:
        """Track people in one cleaned foreground mask.

        Parameters
        ----------
        mask : ndarray of shape (H, W), dtype bool
            The cleaned foreground mask (non-zero: foreground).

        Returns
        -------
        labels : ndarray of shape (H, W), dtype int32
            0 = background and id + 1 per person.
        people : list of Person
            The people seen in this frame, sorted by id.

        Raises
        ------
        ValueError
            ``mask`` is not 2-D.
        """
        m = np.asarray(mask)
        if m.ndim != 2:
            raise ValueError(f"mask must be 2-D (H, W), got shape {m.shape}")
        frame = self._label_regions(m)
        match = _Matching()
        self._split_merges(frame, match)
        self._assign_by_position(frame, match)
        self._take_leftovers(frame, match)
        return self._commit(frame, match)

    # ------------------------------------------------------------------ the steps of update
    def _label_regions(self, m: np.ndarray) -> _Regions:
        """The mask's connected regions and their overlap with each track's predicted mask."""
        h_img, w_img = m.shape
        n, comp, stats, cents = components_in_box(_as_u8(m))
        regions = [r for r in range(1, n) if stats[r, cv2.CC_STAT_AREA] >= self.min_area]
        tracks = self._tracks
        counts = np.zeros((len(tracks), n), np.int64)
        for i, t in enumerate(tracks):
            x0, y0 = t.predicted_origin()
            ch, cw = t.crop.shape
            ax0, ay0, ax1, ay1 = max(x0, 0), max(y0, 0), min(x0 + cw, w_img), min(y0 + ch, h_img)
            if ax1 > ax0 and ay1 > ay0:
                # one compiled pass over the template (a gather and a bincount in numpy)
                counts[i] = kernels.overlap_counts(comp, t.crop, int(x0), int(y0), n)
        # regions below min_area are no one's: as if the clean-up had removed them (the pipeline
        # leaves that to this one labelling pass instead of labelling the mask twice)
        small = stats[:, cv2.CC_STAT_AREA] < self.min_area
        small[0] = True
        counts[:, small] = 0
        frac_track = counts / np.maximum([t.area for t in tracks], 1)[:, None] if tracks else counts.astype(float)
        return _Regions(
            comp=comp,
            stats=stats,
            cents=cents,
            regions=regions,
            counts=counts,
            frac_track=frac_track,
            region_area=stats[:, cv2.CC_STAT_AREA].astype(np.float64),
        )

    def _split_merges(self, frame: _Regions, match: _Matching) -> None:
        """A region that is the main region of two or more tracks is split between them."""
        tracks = self._tracks
        if not (tracks and frame.regions):
            return
        best = np.argmax(frame.frac_track, axis=1)
        need = np.array([MERGE_KEEP_OVERLAP if t.in_merge else self.min_overlap for t in tracks])
        # someone unseen since last frame who was not hidden in a merge has left or was a
        # passing fragment: where they were, a person who walks there must not be split with them
        # (someone hidden behind others was in a merge and keeps their claim)
        back = np.array([t.missed == 0 or t.in_merge for t in tracks])
        top = frame.frac_track[np.arange(len(tracks)), best]
        second = np.sort(frame.frac_track, axis=1)[:, -2] if frame.frac_track.shape[1] > 1 else np.zeros(len(tracks))
        # A merge breaking up: the prediction of a track that was in it (its share of the merged
        # region, pulled toward the others) lies on several of the pieces. A weak overlap, under
        # min_overlap and not twice its next-best region's, says nothing about which piece is
        # theirs: it is no claim, and position and size decide (``_assign_by_position``).
        decisive = (top >= self.min_overlap) | (top >= 2 * second)
        strong = (top >= need) & back & decisive
        for r in frame.regions:
            claim = [i for i in range(len(tracks)) if strong[i] and best[i] == r]
            if len(claim) >= 2:
                match.used_regions.add(r)
                # A claimant left with no pixels is hidden behind the others: it sits out
                # the assignment below rather than grab someone else's region.
                match.occluded.update(claim)
                box = tuple(int(v) for v in frame.stats[r, :4])
                match.within.update({i: box for i in claim})
                for i, piece in self._split(frame.comp, frame.stats, r, [tracks[i] for i in claim]).items():
                    match.assigned[claim[i]] = (*piece, True)

    def _assign_by_position(self, frame: _Regions, match: _Matching) -> None:
        """Hungarian assignment of the remaining tracks and regions on position and size; a
        region grown past an established track's usual area may give a newcomer away.
        """
        tracks = self._tracks
        h_img, w_img = frame.comp.shape
        free_t = [i for i in range(len(tracks)) if i not in match.assigned and i not in match.occluded]
        free_r = [r for r in frame.regions if r not in match.used_regions]
        if not (free_t and free_r):
            return
        cost = np.empty((len(free_t), len(free_r)))
        for a, i in enumerate(free_t):
            t = tracks[i]
            scale = max(t.height, 10.0)
            d = np.hypot(*(frame.cents[free_r] - t.predicted_centroid()).T) / scale
            size = np.abs(np.log(frame.region_area[free_r] / max(t.area, 1)))
            c = d + self.size_weight * size - frame.frac_track[i, free_r]
            ok = (d <= self.max_distance) | (frame.frac_track[i, free_r] >= self.min_overlap)
            cost[a] = np.where(ok, c, _INFEASIBLE)
        rows, cols = linear_sum_assignment(_with_unmatched(cost, UNMATCHED_COST))
        for a, b in zip(rows, cols):
            if a < len(free_t) and b < len(free_r) and cost[a, b] < _INFEASIBLE:
                r = free_r[b]
                t = tracks[free_t[a]]
                split = None
                if self._established(t, w_img, h_img) and frame.region_area[r] >= self.newcomer_growth * t.usual_area:
                    split = self._split_newcomer(frame.comp, frame.stats, r, t)
                if split is not None and not self._emerging(split, t):
                    split = None
                if split is None:
                    match.assigned[free_t[a]] = (*self._region_crop(frame.comp, frame.stats, r), False)
                else:
                    match.assigned[free_t[a]] = (*split[0], True)
                    match.fresh.append(split[1])
                match.used_regions.add(r)

    def _take_leftovers(self, frame: _Regions, match: _Matching) -> None:
        """Left-over regions: the legs or feet of an assigned person (``_stacked_owner``) or a
        fragment of one (mostly inside their predicted mask, unless it stands apart from them as a
        whole person: ``_stands_apart``) join them; the rest start new people when they look like
        one and are not a short piece on someone's feet row (``_ground_owner``) or at their side
        (``_beside_owner``).
        """
        unowned: list[tuple[np.ndarray, int, int]] = []  # left-over regions no one claims
        for r in frame.regions:
            if r in match.used_regions:
                continue
            crop, x0, y0 = self._region_crop(frame.comp, frame.stats, r)
            # the person it stands under first: a template can hold someone else's feet, taken
            # in while the two touched, and would keep them for good
            owner = self._stacked_owner(crop, x0, y0, match)
            if owner < 0 and self._tracks:
                frac_region = frame.counts[:, r] / frame.region_area[r]
                i = int(np.argmax(frac_region))
                if (
                    frac_region[i] >= 0.5
                    and i in match.assigned
                    and not _stands_apart((crop, x0, y0), match.assigned[i])
                ):
                    owner = i
            if owner < 0:
                owner = self._enclosing_owner(crop, x0, y0, match)
            if owner >= 0:
                match.assigned[owner] = (*_union(match.assigned[owner][:3], (crop, x0, y0)), match.assigned[owner][3])
            else:
                unowned.append((crop, x0, y0))
        # a new person must look like one: a standing person, or two side by side, is taller than
        # wide; a car, a barrier, the strip of a ghost along a skirting board or a kerb is not
        for g in group_stacked(unowned):
            if g[0].shape[0] < self.min_upright * g[0].shape[1]:
                continue
            owner = self._ground_owner(*g, match)
            if owner is None:
                owner = self._beside_owner(*g, match)
            if owner is None:
                match.fresh.append(g)
            elif owner >= 0:
                match.assigned[owner] = (*_union(match.assigned[owner][:3], g), match.assigned[owner][3])

    def _ground_owner(self, crop: np.ndarray, x0: int, y0: int, match: _Matching) -> int | None:
        """Whether an upright left-over group (crop (h, w), x0, y0) is a whole new person (None),
        a part of the assigned track whose index is returned, or a fragment of no one (-1).

        People stand on the ground: someone whose feet are on the same image row as a tracked
        person's (within ``FEET_ROW`` of their height) is about as far from the camera and so
        about as tall. A group that ends there but is less than ``FRAGMENT_HEIGHT`` of their
        height tall is a part of a person (a leg stepping back in a push, an arm), not a
        person: it joins the person it lies beside (``STACK_GAP`` of their height at most
        between them), or is dropped.
        """
        h, w = crop.shape
        best, best_gap = None, np.inf
        for i, (pc, px, py, _) in match.assigned.items():
            ph, pw = pc.shape
            height = max(self._tracks[i].height, float(ph))
            if not _shorter_on_same_row((crop, x0, y0), py + ph, height):
                continue
            gap = max(px - (x0 + w), x0 - (px + pw), 0)
            if gap < best_gap:
                best, best_gap = (i if gap <= STACK_GAP * height else -1), gap
        return best

    def _beside_owner(self, crop: np.ndarray, x0: int, y0: int, match: _Matching) -> int | None:
        """Whether an upright left-over group (crop (h, w), x0, y0) that stands on no one's feet
        row is a whole new person (None) or a piece torn off one beside it (-1: dropped).

        The background model tears pieces off people at their sides: an arm held out, the shadow
        at their side, the blocks a heavily compressed video smears round their outline. Such a
        piece lies within a person's rows (``FEET_ROW`` of their height above their top to as
        much below their feet), at most ``BESIDE_GAP`` of their height of columns from their box,
        and is less than ``FRAGMENT_HEIGHT`` of their height tall. As a person of its own it would
        keep a track for as long as pieces come off there. It is not joined to them: a shadow or
        a codec's blocks would then be theirs.
        """
        h, w = crop.shape
        for i, (pc, px, py, _) in match.assigned.items():
            ph, pw = pc.shape
            height = max(self._tracks[i].height, float(ph))
            within_rows = y0 >= py - FEET_ROW * height and y0 + h <= py + ph + FEET_ROW * height
            gap = max(px - (x0 + w), x0 - (px + pw), 0)
            if h < FRAGMENT_HEIGHT * height and within_rows and gap <= BESIDE_GAP * height:
                return -1
        return None

    def _stacked_owner(self, crop: np.ndarray, x0: int, y0: int, match: _Matching) -> int:
        """The index of the assigned track whose legs or feet, or head and shoulders, a left-over
        region (crop (h, w), x0, y0) is, or -1.

        Legs in trousers of the floor's colour come out as a region of their own below a gap;
        once the person has moved, it lies outside their predicted mask and would start a new
        "person". It is theirs when its middle lies in their lower half or under them, within their columns
        (``STACK_OVERLAP`` of its width), at most ``STACK_GAP`` of their height below it, and is
        no taller than ``STACK_MAX_BELOW`` of their height (someone standing nearer the camera,
        lower in the picture, is taller than the person further back).

        Likewise the head and shoulders of someone whose upper body was given to the person they
        touched (a push, a handshake) come out above their legs when the two part: a region above
        a person, in their columns, at most ``STACK_GAP`` of their height above them and no taller
        than them, whose union with them stands upright as one person does (``_upright_pair``),
        is theirs.
        """
        h, w = crop.shape
        best, best_overlap = -1, 0
        for i, (pc, px, py, _) in match.assigned.items():
            ph, pw = pc.shape
            overlap = min(x0 + w, px + pw) - max(x0, px)
            height = max(self._tracks[i].height, float(ph))
            gap = y0 - (py + ph)  # rows between them; < 0 where they share rows
            below = y0 + 0.5 * h > py + 0.5 * ph  # its middle in their lower half, or under them
            if below:
                stacked = gap <= STACK_GAP * height and h <= STACK_MAX_BELOW * height
            else:
                stacked = (
                    py - (y0 + h) <= STACK_GAP * height
                    and h <= height
                    and _upright_pair((pc, px, py), (crop, x0, y0), STACK_UPRIGHT)
                )
            if stacked and overlap >= STACK_OVERLAP * w and overlap > best_overlap:
                best, best_overlap = i, overlap
        return best

    def _enclosing_owner(self, crop: np.ndarray, x0: int, y0: int, match: _Matching) -> int:
        """The index of the assigned track a small left-over region (crop (h, w), x0, y0) lies
        within, or -1.

        A raised arm, a turned head or a hand torn off a person by the background model comes out
        as a small region of its own inside their outline's box, away from their template's
        pixels; as a new "person" it would then claim a share of them in every merge that
        follows. It is theirs when ``ENCLOSED_SHARE`` of its box lies in the box of their piece
        of this frame and it is at most ``ENCLOSED_MAX_HEIGHT`` of their height tall: another
        person inside someone's box is about as tall as them, or further back and smaller but
        standing on the ground, below their middle (``_stacked_owner`` and the assignment see to
        the people who stand one behind the other).
        """
        h, w = crop.shape
        best, best_share = -1, 0.0
        for i, (pc, px, py, _) in match.assigned.items():
            ph, pw = pc.shape
            ox = min(x0 + w, px + pw) - max(x0, px)
            oy = min(y0 + h, py + ph) - max(y0, py)
            share = max(ox, 0) * max(oy, 0) / float(h * w)
            height = max(self._tracks[i].height, float(ph))
            if share >= ENCLOSED_SHARE and h <= ENCLOSED_MAX_HEIGHT * height and share > best_share:
                best, best_share = i, share
        return best

    def _commit(self, frame: _Regions, match: _Matching) -> tuple[np.ndarray, list[Person]]:
        """Update the tracks, start new ones, retire the long unseen; paint the labels."""
        h_img, w_img = frame.comp.shape
        labels = np.zeros((h_img, w_img), np.int32)
        people: list[Person] = []
        alive: list[_Track] = []
        # before anyone's record of this frame is made: it may change the side of the one seen
        pair_side = self._pair_sides(match)
        for i, t in enumerate(self._tracks):
            piece = match.assigned.get(i)
            if piece is None or not piece[0].any():
                t.missed += 1
                t.centroid = t.predicted_centroid()
                if t.missed <= self.max_missed:
                    alive.append(t)
                continue
            crop, x0, y0, merged = piece
            # a region grown well past the person's usual size may hold an emerging newcomer:
            # keep the template of their own shape until it is split off or the size settles
            grown = (
                not merged
                and self._established(t, w_img, h_img)
                and np.count_nonzero(crop) > NEWCOMER_FREEZE * t.usual_area
            )
            t.frozen = t.frozen + 1 if grown else 0
            if t.frozen > NEWCOMER_PATIENCE:  # no newcomer after all: they did change size
                t.frozen, t.usual_area = 0, float(np.count_nonzero(crop))
            person = self._observe(t, crop, x0, y0, merged, t.frozen > 0, match.within.get(i))
            people.append(person)
            alive.append(t)
            _paint(labels, crop, x0, y0, t.id + 1)
        # New people are numbered left to right, so ids do not depend on the labelling order.
        match.fresh.sort(key=lambda f: f[1] + 0.5 * f[0].shape[1])
        for crop, x0, y0 in match.fresh:
            t = self._new_track(crop, x0, y0, w_img, pair_side)
            people.append(self._observe(t, crop, x0, y0, False))
            alive.append(t)
            _paint(labels, crop, x0, y0, t.id + 1)
        self._tracks = alive
        people.sort(key=lambda p: p.id)
        return labels, people

    def _pair_sides(self, match: _Matching) -> str | None:
        """The side of the one newcomer beside the one person seen this frame, by where they stand
        beside them (None otherwise: a new person's side is their half of the frame).

        A pair is left and right of each other: two people first seen as one region (already
        together when the camera started) are one track until they part, and both may then stand
        in the same half of the frame. The person seen before takes the side opposite the
        newcomer's: the only time a side changes, before the two were ever told apart.
        """
        seen = [i for i, piece in match.assigned.items() if piece[0].any()]
        if len(seen) != 1 or len(match.fresh) != 1:
            return None
        crop, x0, _ = match.fresh[0]
        pc, px, _, _ = match.assigned[seen[0]]
        newcomer_left = x0 + 0.5 * crop.shape[1] < px + 0.5 * pc.shape[1]
        self._tracks[seen[0]].side = RIGHT if newcomer_left else LEFT
        return LEFT if newcomer_left else RIGHT

    def _new_track(self, crop: np.ndarray, x0: int, y0: int, w_img: int, side: str | None = None) -> _Track:
        """A new person's track from their first region (crop, x0, y0), with the next id; ``side``
        None: their half of the frame.
        """
        ys, xs = np.nonzero(crop)
        c = np.array([xs.mean() + x0, ys.mean() + y0])
        t = _Track(
            id=self._next_id,
            side=side or (LEFT if c[0] < w_img / 2.0 else RIGHT),
            centroid=c,
            velocity=np.zeros(2),
            crop=crop,
            origin=np.array([x0, y0], np.int64),
            area=int(crop.sum()),
            height=float(crop.shape[0]),
            offset=c - np.array([x0, y0]),
            missed=-1,  # no previous position: no velocity from the first observation
        )
        self._next_id += 1
        return t

    # ------------------------------------------------------------------ internals
    @staticmethod
    def _region_crop(comp: np.ndarray, stats: np.ndarray, r: int) -> tuple[np.ndarray, int, int]:
        x, y, w, h = (int(v) for v in stats[r, :4])
        return comp[y : y + h, x : x + w] == r, x, y

    @staticmethod
    def _split(
        comp: np.ndarray, stats: np.ndarray, r: int, claim: list[_Track]
    ) -> dict[int, tuple[np.ndarray, int, int]]:
        """Share region r between the claiming tracks; returns claim index -> (crop, x0, y0)."""
        x, y, w, h = (int(v) for v in stats[r, :4])
        region = comp[y : y + h, x : x + w] == r
        # Signed distance to each predicted mask: negative inside (depth), positive outside.
        signed = np.empty((len(claim), h, w), np.float32)
        for k, t in enumerate(claim):
            pred = _paste(t, x, y, h, w).astype(np.uint8)
            outside = cv2.distanceTransform(1 - pred, cv2.DIST_L2, 5)
            inside = cv2.distanceTransform(pred, cv2.DIST_L2, 5)
            signed[k] = outside - inside
        # np.argmin(signed, axis=0) (the first claim on ties) in whole-plane passes: argmin along
        # the stacked axis is a slow strided reduction
        owner = np.zeros((h, w), np.intp)
        best = signed[0]
        for k in range(1, len(claim)):
            closer = signed[k] < best
            np.copyto(owner, k, where=closer)
            best = np.where(closer, signed[k], best)
        pieces: dict[int, tuple[np.ndarray, int, int]] = {}
        for k in range(len(claim)):
            part = region & (owner == k)
            if part.any():
                pieces[k] = _crop_box(part, x, y)
        return pieces

    def _established(self, t: _Track, w_img: int, h_img: int) -> bool:
        """Whether track t's usual size is known well enough for the newcomer check: seen long
        enough, and its template clear of the image border (someone walking in grows fast).
        """
        if not self.newcomer_growth or t.seen < NEWCOMER_MIN_AGE:
            return False
        (x0, y0), (h, w) = t.origin, t.crop.shape
        return x0 > 1 and y0 > 1 and x0 + w < w_img - 1 and y0 + h < h_img - 1

    @staticmethod
    def _emerging(split: tuple[tuple[np.ndarray, int, int], tuple[np.ndarray, int, int]], t: _Track) -> bool:
        """Whether the newcomer's piece of a grown region ((t's piece, the newcomer's piece), each
        (crop, x0, y0)) can be a person: one who stood beside track t stands on the ground too,
        their feet below t's middle, and is not much shorter than t when their feet are on t's
        row (``_shorter_on_same_row``). What floats above t's middle is t's own head and
        shoulders (given to someone t touched, back now); what is short on t's row is a leg
        stepping out.
        """
        (mine, mx, my), (new, nx, ny) = split
        top = min(my, ny)
        feet = max(my + mine.shape[0], ny + new.shape[0])
        if ny + new.shape[0] < 0.5 * (top + feet):
            return False
        return not _shorter_on_same_row(split[1], my + mine.shape[0], t.height)

    def _split_newcomer(
        self, comp: np.ndarray, stats: np.ndarray, r: int, t: _Track
    ) -> tuple[tuple[np.ndarray, int, int], tuple[np.ndarray, int, int]] | None:
        """Region r, grown well past track t's usual area: (t's piece, the newcomer's piece), each
        (crop, x0, y0), or None when what lies outside t's predicted mask is too small to be a
        person (an arm stretched out, a step forward).
        """
        x, y, w, h = (int(v) for v in stats[r, :4])
        region = comp[y : y + h, x : x + w] == r
        pred = _paste(t, x, y, h, w).astype(np.uint8)
        outside = cv2.distanceTransform(1 - pred, cv2.DIST_L2, 5)
        far = (region & (outside > self.newcomer_margin * t.height)).view(np.uint8)
        n, comp_far, st, _ = components_with_stats(far)
        if n < 2:
            return None
        k = 1 + int(np.argmax(st[1:, cv2.CC_STAT_AREA]))
        if st[k, cv2.CC_STAT_AREA] < max(self.min_area, self.newcomer_min_frac * t.usual_area):
            return None
        new = comp_far == k
        mine = region & ~new
        if not mine.any():
            return None
        return _crop_box(mine, x, y), _crop_box(new, x, y)

    def _observe(
        self,
        t: _Track,
        crop: np.ndarray,
        x0: int,
        y0: int,
        merged: bool,
        keep_template: bool = False,
        within: tuple[int, int, int, int] | None = None,
    ) -> Person:
        """Update track t from its piece (crop (h, w) bool at x0, y0) of this frame; ``within``:
        the bbox (x, y, w, h) of the merged region the piece comes from, if any.
        """
        # the centroid from the pixel sums (whole numbers, exact in float64: the means of the
        # pixels' coordinates to the last bit), without listing the pixels
        m00, m10, m01 = kernels.mask_moments(crop)  # cv2.moments' first three, to the bit
        area = int(m00)
        c = np.array([m10 / m00 + x0, m01 / m00 + y0])
        # In a merge, a piece much smaller than the person's template (they are mostly hidden or
        # the split is uncertain) says little about where they are: keep the prediction then.
        # A grown region kept out of the template: its centroid is pulled by what joined it.
        trusted = (not merged and not keep_template) or (merged and area >= 0.5 * t.area)
        s = self.velocity_smoothing
        if trusted:
            if t.missed == 0:
                t.velocity = s * t.velocity + (1.0 - s) * (c - t.centroid)
            t.centroid = c
        else:
            t.centroid = t.predicted_centroid()
            if np.hypot(*t.velocity) < WALK_SPEED * t.height:
                t.velocity = np.zeros(2)
            if within is not None:
                # someone hidden in a merged region is in it: a velocity taken from the jumping
                # centroids of their pieces must not carry them out of it
                bx, by, bw, bh = within
                inside = np.clip(t.centroid, [bx, by], [bx + bw - 1, by + bh - 1])
                t.velocity = np.where(inside != t.centroid, 0.0, t.velocity)
                t.centroid = inside
        t.in_merge = merged
        if not merged and not keep_template:
            t.crop, t.origin, t.offset = crop, np.array([x0, y0], np.int64), c - np.array([x0, y0])
            t.area, t.height = area, float(crop.shape[0])
            t.usual_area = t.area if t.seen == 0 else t.usual_area + _USUAL_AREA_RATE * (t.area - t.usual_area)
        t.seen += 1
        t.missed = 0
        return Person(
            id=t.id,
            side=t.side,
            bbox=(int(x0), int(y0), int(crop.shape[1]), int(crop.shape[0])),
            area=area,
            centroid=(float(c[0]), float(c[1])),
            height=float(crop.shape[0]),
            merged=merged,
        )


def _shorter_on_same_row(part: tuple[np.ndarray, int, int], feet_row: float, height: float) -> bool:
    """Whether a region (crop (h, w), x0, y0) ends within ``FEET_ROW`` of ``height`` of a
    person's feet row (pixels) and is less than ``FRAGMENT_HEIGHT`` of their height tall: on
    the ground as far away as they are, a whole person would be about as tall.
    """
    h = part[0].shape[0]
    return abs(part[2] + h - feet_row) <= FEET_ROW * height and h < FRAGMENT_HEIGHT * height


def _stands_apart(part: tuple[np.ndarray, int, int], piece: _Piece) -> bool:
    """Whether a left-over region (crop (h, w), x0, y0) is a whole person beside a person's piece
    (crop, x0, y0, merged) of this frame: at least ``WHOLE_HEIGHT`` of the piece's height tall, its
    feet on the piece's feet row (within ``FEET_ROW`` of that height) and ``APART_GAP`` of that
    height or more of columns between them. A part of someone (an arm, a leg, a torn-off hand) is
    shorter or touches them; a second person inside a template that held two people who came as
    one region (a handshake when the camera started) stands beside them once they part.
    """
    crop, x0, y0 = part
    pc, px, py, _ = piece
    ph = pc.shape[0]
    gap = max(px - (x0 + crop.shape[1]), x0 - (px + pc.shape[1]))
    return (
        crop.shape[0] >= WHOLE_HEIGHT * ph
        and abs((y0 + crop.shape[0]) - (py + ph)) <= FEET_ROW * ph
        and gap >= APART_GAP * ph
    )


def _crop_box(part: np.ndarray, x: int, y: int) -> tuple[np.ndarray, int, int]:
    """A non-empty mask (h, w) placed at (x, y) -> (its bbox crop, x0, y0)."""
    # OpenCV's bounding box of the set bytes: no index arrays
    x0, y0, w, h = cv2.boundingRect(np.ascontiguousarray(part).view(np.uint8))
    return part[y0 : y0 + h, x0 : x0 + w], x + x0, y + y0


def _union(a: tuple[np.ndarray, int, int], b: tuple[np.ndarray, int, int]) -> tuple[np.ndarray, int, int]:
    """Union of two bbox-cropped masks (crop, x0, y0)."""
    (ca, xa, ya), (cb, xb, yb) = a, b
    x0, y0 = min(xa, xb), min(ya, yb)
    x1 = max(xa + ca.shape[1], xb + cb.shape[1])
    y1 = max(ya + ca.shape[0], yb + cb.shape[0])
    out = np.zeros((y1 - y0, x1 - x0), bool)
    out[ya - y0 : ya - y0 + ca.shape[0], xa - x0 : xa - x0 + ca.shape[1]] |= ca
    out[yb - y0 : yb - y0 + cb.shape[0], xb - x0 : xb - x0 + cb.shape[1]] |= cb
    return out, x0, y0


def _with_unmatched(cost: np.ndarray, unmatched: float) -> np.ndarray:
    """(T, R) assignment costs -> (T + R, R + T): each track and each region may also stay
    unmatched at ``unmatched``. Without this, a full matching prefers two feasible but wrong pairs
    (a stale track takes someone's region, who then takes a stray fragment) to one right pair.
    """
    T, R = cost.shape
    out = np.full((T + R, R + T), _INFEASIBLE)
    out[:T, :R] = cost
    out[np.arange(T), R + np.arange(T)] = unmatched
    out[T + np.arange(R), np.arange(R)] = unmatched
    out[T:, R:] = 0.0
    return out


def group_stacked(
    parts: list[tuple[np.ndarray, int, int]], max_aspect: float = STACK_UPRIGHT
) -> list[tuple[np.ndarray, int, int]]:
    """Join first-sight regions that are parts of one standing person.

    Someone who stood still while the background was learnt is partly background; when they move,
    the parts of them that differ from it (head and shoulders, legs) come out as separate regions,
    one above the other. Two regions whose column ranges overlap are one person when their union
    is no wider than ``max_aspect`` times its height (a standing person, seen from any side, is
    narrower than half their height; two people side by side are wider).

    Parameters
    ----------
    parts : list of (ndarray of shape (h, w), int, int)
        (crop (bool), x0, y0) per region, pixels.
    max_aspect : float, default=0.45
        Widest union, as a fraction of its height, that is one person.

    Returns
    -------
    list of (ndarray of shape (h, w), int, int)
        The groups' unions, in the same form.
    """
    groups = list(parts)
    while True:
        pair = next(
            (
                (i, j)
                for i in range(len(groups))
                for j in range(i + 1, len(groups))
                if _upright_pair(groups[i], groups[j], max_aspect)
            ),
            None,
        )
        if pair is None:
            return groups
        groups[pair[0]] = _union(groups[pair[0]], groups.pop(pair[1]))


def _upright_pair(a: tuple[np.ndarray, int, int], b: tuple[np.ndarray, int, int], max_aspect: float) -> bool:
    """Whether two bbox-cropped masks overlap in columns and their union is upright."""
    (ca, xa, ya), (cb, xb, yb) = a, b
    overlap = min(xa + ca.shape[1], xb + cb.shape[1]) - max(xa, xb)
    width = max(xa + ca.shape[1], xb + cb.shape[1]) - min(xa, xb)
    height = max(ya + ca.shape[0], yb + cb.shape[0]) - min(ya, yb)
    return overlap > 0 and width <= max_aspect * height


def _paint(labels: np.ndarray, crop: np.ndarray, x0: int, y0: int, value: int) -> None:
    window = labels[y0 : y0 + crop.shape[0], x0 : x0 + crop.shape[1]]
    window[crop] = value
