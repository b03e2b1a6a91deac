"""People found by their shape alone: OpenCV's shipped HOG people detector (Dalal & Triggs 2005).

Shared by the silhouette node (people in view while the background is learnt) and the calibration
node (head and foot points of people absorbed into the background), so it lives below the nodes.
The default SVM ships with OpenCV; nothing is downloaded.

Image coordinates are pixels, x = column, y = row; boxes are (x, y, w, h) int.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["PeopleDetector", "box_iou"]

#: the person inside a detection window of OpenCV's HOG people detector (trained on 64 x 128
#: INRIA windows, the person about 96 pixels tall in the middle): (x0, y0, x1, y1) as fractions
#: of the window, generous in x for arms held out
_PERSON_IN_WINDOW = (0.1, 0.0, 0.9, 0.95)
#: the least share of a person found in the frame continued below (``below_frac``) that lies below
#: the frame, for them to be cut off by it: the box of someone who stands on its bottom rows
#: reaches a little past them (that person is the plain search's to find, or not)
_CUT_OFF = 0.1
#: the most rows of the frame in which people cut off by it are looked for: a bigger frame is
#: shrunk to this first (its people near the camera are large; at 1080 rows the search would cost
#: several times the plain one)
_CUT_OFF_ROWS = 360
#: rows of the detector's window: no one shorter than its person (``_PERSON_IN_WINDOW``) is found
#: in a frame at its own scale
_WINDOW_ROWS = 128
#: the most rows of a frame enlarged to find people too short for the window (``enlarge``): a
#: bigger frame is enlarged less, or not at all (the search's cost grows with its pixels)
_ENLARGED_ROWS = 720


class PeopleDetector:
    """OpenCV's HOG people detector (``cv2.HOGDescriptor_getDefaultPeopleDetector``).

    Parameters
    ----------
    hit_threshold : float, default=0.0
        SVM margin a window must pass (``detectMultiScale``'s hitThreshold); lower finds more
        people and more clutter.
    min_score : float, default=0.3
        Smallest grouped detection weight kept.
    scale : float, default=1.05
        Step between the pyramid's scales; > 1.
    stride : int, default=8
        Window step, pixels (multiple of 8, the HOG cell).
    pad_frac : float, default=0.15
        Padding added on every side, as a fraction of the frame height, with the frame's median
        colour (a replicated or mirrored border draws false edges); in [0, 1].
    below_frac : float, default=0.0
        People cut off by the frame's bottom edge (near the camera: their legs out of the
        picture) are looked for again in the frame continued below by this fraction of its
        height, its last row repeated, so that their legs go on as they leave the picture (the
        detector's window needs legs; a frame of more than 360 rows is shrunk to 360 first, as
        such people are large). Only the people found there who reach well below the frame (a
        tenth of their height) and overlap no one found in the frame as it is are added, their
        boxes cut at the frame's bottom; 0: not looked for (the detector's cost is then one
        pass); in [0, 2].
    enlarge : float, default=1.0
        In a frame where no one is found, the frame enlarged by this factor is searched again for
        people too short for the detector's window at the frame's own scale (under about 120
        pixels: people far from the camera, or a small video), at those sizes only; 1: not
        searched. In [1, 4].

    Raises
    ------
    ValueError
        If ``scale``, ``stride``, ``pad_frac``, ``below_frac`` or ``enlarge`` is out of range.
    """

    def __init__(
        self,
        hit_threshold: float = 0.0,
        min_score: float = 0.3,
        scale: float = 1.05,
        stride: int = 8,
        pad_frac: float = 0.15,
        below_frac: float = 0.0,
        enlarge: float = 1.0,
    ) -> None:
        if scale <= 1.0:
            raise ValueError(f"scale must be > 1, got {scale}")
        if stride < 1 or stride % 8:
            raise ValueError(f"stride must be a positive multiple of 8 pixels, got {stride}")
        if not 0.0 <= pad_frac <= 1.0:
            raise ValueError(f"pad_frac must be in [0, 1], got {pad_frac}")
        if not 0.0 <= below_frac <= 2.0:
            raise ValueError(f"below_frac must be in [0, 2], got {below_frac}")
        if not 1.0 <= enlarge <= 4.0:
            raise ValueError(f"enlarge must be in [1, 4], got {enlarge}")
        self.hit_threshold = hit_threshold
        self.min_score = min_score
        self.scale = scale
        self.stride = stride
        self.pad_frac = pad_frac
        self.below_frac = below_frac
        self.enlarge = enlarge
        self._hog = _people_hog()
        # the enlarged frame's pyramid stops where its scale reaches the frame's own: the sizes the
        # plain search covers are not searched twice
        self._small_hog = _people_hog(int(np.ceil(np.log(enlarge) / np.log(scale)))) if enlarge > 1.0 else None

    def detect(self, frame: np.ndarray, plain: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """People in a frame.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3)
            uint8 BGR frame.
        plain : bool, default=False
            Search the frame as it is only: neither the frame continued below (``below_frac``) nor
            the frame enlarged (``enlarge``), which cost two to four times as much as it.

        Returns
        -------
        boxes : ndarray of shape (K, 4)
            int32 (x, y, w, h) pixels of each person, clipped to the frame: the person's part of the
            detection window.
        scores : ndarray of shape (K,)
            float32 detector scores.

        Raises
        ------
        ValueError
            If ``frame`` is not uint8 (H, W, 3).
        """
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
            raise ValueError(f"frame must be uint8 (H, W, 3) BGR, got {frame.shape} {frame.dtype}")
        colour = [float(v) for v in np.median(frame[::4, ::4].reshape(-1, 3), axis=0)]
        boxes, scores = self._people(frame, colour)
        if plain:
            return boxes, scores
        if self.below_frac > 0:
            more, more_scores = self._cut_off(frame, colour)
            new = np.array([all(box_iou(b, o) < 0.3 for o in boxes) for b in more], bool).reshape(-1)
            boxes = np.concatenate([boxes, more[new]])
            scores = np.concatenate([scores, more_scores[new]])
        if not len(boxes) and self._small_hog is not None:
            boxes, scores = self._small(frame, colour)
        return boxes, scores

    def _small(self, frame: np.ndarray, colour: list[float]) -> tuple[np.ndarray, np.ndarray]:
        """The people too short for the detector's window (``enlarge``), found in the frame enlarged:
        boxes (K, 4) int32 in the frame's pixels, scores (K,) float32.
        """
        s = min(self.enlarge, _ENLARGED_ROWS / frame.shape[0])
        if s <= 1.0:
            return np.zeros((0, 4), np.int32), np.zeros(0, np.float32)
        big = cv2.resize(frame, None, fx=s, fy=s, interpolation=cv2.INTER_LINEAR)
        boxes, scores = self._people(big, colour, self._small_hog)
        boxes = np.round(boxes / s).astype(np.int32)
        # a window the frame's own pyramid holds would have been found there
        short = boxes[:, 3] < (_PERSON_IN_WINDOW[3] - _PERSON_IN_WINDOW[1]) * _WINDOW_ROWS
        return boxes[short].reshape(-1, 4), scores[short]

    def _cut_off(self, frame: np.ndarray, colour: list[float]) -> tuple[np.ndarray, np.ndarray]:
        """The people cut off by the frame's bottom edge (``below_frac``): boxes (K, 4) int32, cut at
        the frame's bottom, and scores (K,) float32. Found on the frame shrunk to at most
        ``_CUT_OFF_ROWS`` rows: they are near the camera, and so large.
        """
        h, w = frame.shape[:2]
        s = min(1.0, _CUT_OFF_ROWS / h)
        small = frame if s == 1.0 else cv2.resize(frame, None, fx=s, fy=s, interpolation=cv2.INTER_AREA)
        hs = small.shape[0]
        continued = cv2.copyMakeBorder(small, 0, int(round(self.below_frac * hs)), 0, 0, cv2.BORDER_REPLICATE)
        more, scores = self._people(continued, colour)
        cut = (more[:, 1] + more[:, 3] - hs >= _CUT_OFF * more[:, 3]) & (more[:, 1] < hs - 1)
        more, scores = more[cut].astype(np.float64) / s, scores[cut]
        x0, y0 = np.clip(more[:, 0], 0, w), np.clip(more[:, 1], 0, h)
        x1, y1 = np.clip(more[:, 0] + more[:, 2], 0, w), np.full(len(more), float(h))
        return np.stack([x0, y0, x1 - x0, y1 - y0], axis=1).round().astype(np.int32).reshape(-1, 4), scores

    def _people(
        self, frame: np.ndarray, colour: list[float], hog: cv2.HOGDescriptor | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`detect` of one image, padded with ``colour``, by ``hog`` (None: the plain
        search's): boxes (K, 4) int32 clipped to it, scores (K,) float32.
        """
        h, w = frame.shape[:2]
        pad = int(round(self.pad_frac * h))
        padded = cv2.copyMakeBorder(frame, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=colour)
        if min(padded.shape[:2]) < _WINDOW_ROWS or padded.shape[1] < 64:
            return np.zeros((0, 4), np.int32), np.zeros(0, np.float32)
        rects, weights = (hog or self._hog).detectMultiScale(
            padded,
            hitThreshold=self.hit_threshold,
            winStride=(self.stride, self.stride),
            padding=(0, 0),
            scale=self.scale,
        )
        rects = np.asarray(rects, np.float64).reshape(-1, 4)
        scores = np.asarray(weights, np.float32).reshape(-1)
        keep = scores >= self.min_score
        rects, scores = rects[keep], scores[keep]
        fx0, fy0, fx1, fy1 = _PERSON_IN_WINDOW
        x0 = rects[:, 0] + fx0 * rects[:, 2] - pad
        y0 = rects[:, 1] + fy0 * rects[:, 3] - pad
        x1 = rects[:, 0] + fx1 * rects[:, 2] - pad
        y1 = rects[:, 1] + fy1 * rects[:, 3] - pad
        x0, x1 = np.clip(x0, 0, w), np.clip(x1, 0, w)
        y0, y1 = np.clip(y0, 0, h), np.clip(y1, 0, h)
        boxes = np.stack([x0, y0, x1 - x0, y1 - y0], axis=1).round().astype(np.int32)
        ok = (boxes[:, 2] > 0) & (boxes[:, 3] > 0)
        return boxes[ok], scores[ok]


def _people_hog(levels: int | None = None) -> cv2.HOGDescriptor:
    """OpenCV's HOG with its default people SVM, its scale pyramid cut to ``levels`` (None: the
    default 64, every scale down to the window's).
    """
    hog = cv2.HOGDescriptor()
    if levels is not None:
        hog = cv2.HOGDescriptor(
            hog.winSize,
            hog.blockSize,
            hog.blockStride,
            hog.cellSize,
            hog.nbins,
            hog.derivAperture,
            hog.winSigma,
            hog.histogramNormType,
            hog.L2HysThreshold,
            hog.gammaCorrection,
            levels,
            hog.signedGradient,
        )
    hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    return hog


def box_iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two boxes (x, y, w, h); 0 for two empty ones."""
    x0, y0 = max(a[0], b[0]), max(a[1], b[1])
    x1, y1 = min(a[0] + a[2], b[0] + b[2]), min(a[1] + a[3], b[1] + b[3])
    inter = float(max(0, x1 - x0) * max(0, y1 - y0))
    union = float(a[2] * a[3] + b[2] * b[3]) - inter
    return inter / union if union > 0 else 0.0
