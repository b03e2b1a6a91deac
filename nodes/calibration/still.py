"""People who stand still, segmented from the frame where they moved a little: the head and foot
points of people the background model has absorbed and the people detector does not find.

Two people talking keep their feet where they are for minutes; the background model learns them,
and only their gestures (a hand, a nodding head, the edge of a swaying body) reach the silhouettes,
as fragments. The people detector finds some of them and misses others (a body seen side on, a
person far from the camera). Where something moved is where someone is: the pixels that changed
over the last seconds mark part of each person (:class:`StillPeople` keeps, for every pixel, when
it last changed), and GrabCut (Rother, Kolmogorov & Blake 2004, "GrabCut": colour models of the
person and of the scene, and a graph cut between them) given a band around each moving part, from
well above it (the head over a moving hand) down to the frame's bottom, grows it to the whole body,
down to the feet that never moved: the floor beside and the wall behind them are the scene's
colours, seen outside the band. The standing bodies in what it grows (``upright.upright_parts``:
tall and narrow, whole) give the head and foot points, but for a body that moved as a whole (a
walker: what grows from the trail is the trail) and one whose gestures reach below its feet (cut
at the waist, the legs taken for the scene).

Image coordinates are pixels, x = column, y = row; boxes are (x, y, w, h).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .upright import upright_parts


@dataclass(frozen=True)
class StillConfig:
    """Parameters of :class:`StillPeople`.

    Parameters
    ----------
    window_s : float, default=2.0
        A pixel counts as moved for this long after it last changed, seconds.
    reference_s : float, default=1.0
        A frame is compared with one seen up to this long before it (the reference is renewed
        then), seconds: a slow gesture changes a pixel by little from one frame to the next.
    threshold : float, default=40.0
        Least change of a pixel, the sum over its three channels (0-765), for it to have moved:
        above a camera's noise.
    min_part_share : float, default=0.04
        Least height of a moving part, as a share of the frame's height.
    spread : float, default=0.5
        The band given to GrabCut around a moving part of width w reaches this many times w on
        either side of it.
    above : float, default=3.0
        The band starts this many times the moving part's height above its top (a hand that moved
        at the waist has the head above it), and reaches the frame's bottom (the feet never moved).
    max_moved_share : float, default=0.6
        A body grown from the moving parts is left out where more of its pixels than this share
        moved: one who moved as a whole walked, and is the silhouettes' to find (grown from the
        trail a walker leaves, the body is the trail).
    max_below : float, default=0.1
        A body is left out where a moving part it was grown from reaches below its feet by more
        than this share of its height: what GrabCut kept of that person ends above their gestures
        (at the waist, the legs taken for the scene).
    iterations : int, default=3
        GrabCut's iterations.
    rows : int, default=240
        Frames taller than this are shrunk to it first (GrabCut's cost grows with the pixels).
    """

    window_s: float = 2.0
    reference_s: float = 1.0
    threshold: float = 40.0
    min_part_share: float = 0.04
    spread: float = 0.5
    above: float = 3.0
    max_moved_share: float = 0.6
    max_below: float = 0.1
    iterations: int = 3
    rows: int = 240

    def __post_init__(self) -> None:
        if not (self.window_s > 0 and self.reference_s > 0 and self.threshold > 0 and self.rows >= 32):
            raise ValueError(f"StillConfig: window_s, reference_s and threshold must be > 0 and rows >= 32, got {self}")


class StillPeople:
    """Where the frames changed lately, and the standing people grown from there.

    Parameters
    ----------
    width, height : int
        Frame size, pixels.
    config : StillConfig or None
        Parameters (None: the defaults).
    """

    def __init__(self, width: int, height: int, config: StillConfig | None = None) -> None:
        self.config = config or StillConfig()
        #: frames are worked on shrunk by this factor
        self.scale = min(1.0, self.config.rows / float(height))
        #: (width, height) of the frames worked on, pixels
        self.size = (max(1, int(round(width * self.scale))), max(1, int(round(height * self.scale))))
        #: time each pixel last changed, seconds (-inf: never)
        self._moved = np.full((self.size[1], self.size[0]), -np.inf, np.float32)
        self._reference: np.ndarray | None = None
        self._reference_s = 0.0
        #: GrabCut runs so far
        self.runs = 0

    def _shrunk(self, frame: np.ndarray) -> np.ndarray:
        if self.scale == 1.0:
            return frame
        return cv2.resize(frame, self.size, interpolation=cv2.INTER_AREA)

    def observe(self, frame: np.ndarray, time_s: float) -> None:
        """Note which pixels of a frame changed.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3)
            uint8 BGR frame of the size given.
        time_s : float
            Time the frame was seen, seconds.
        """
        small = self._shrunk(frame)
        if self._reference is not None:
            change = cv2.absdiff(small, self._reference).astype(np.int16).sum(axis=2) > self.config.threshold
            # a lone pixel over the threshold is noise, not a body's edge
            change = cv2.morphologyEx(change.astype(np.uint8), cv2.MORPH_OPEN, np.ones((2, 2), np.uint8))
            self._moved[change.astype(bool)] = time_s
        if self._reference is None or time_s - self._reference_s > self.config.reference_s:
            self._reference, self._reference_s = small, float(time_s)

    def moved(self, time_s: float) -> np.ndarray:
        """Pixels (of the frames as worked on) that changed within ``window_s`` of ``time_s``.

        Returns
        -------
        ndarray of shape (h, w)
            bool.
        """
        return (time_s - self._moved) <= self.config.window_s

    def moving_parts(self, time_s: float) -> np.ndarray:
        """Boxes of the parts that moved within ``window_s`` of ``time_s``, pixels of the frames as
        worked on.

        Returns
        -------
        ndarray of shape (K, 4)
            int (x, y, w, h) of each part at least ``min_part_share`` of the frame tall.
        """
        return self._parts(self.moved(time_s))

    def _parts(self, moved: np.ndarray) -> np.ndarray:
        H = self.size[1]
        k = max(3, H // 40)
        joined = cv2.morphologyEx(moved.astype(np.uint8), cv2.MORPH_CLOSE, np.ones((k, k), np.uint8))
        _, _, stats, _ = cv2.connectedComponentsWithStats(joined, connectivity=8)
        boxes = stats[1:, :4]
        return boxes[boxes[:, 3] >= self.config.min_part_share * H]

    def find(self, frame: np.ndarray, time_s: float) -> list[tuple[np.ndarray, np.ndarray]]:
        """The standing people grown from the parts that moved lately.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3)
            uint8 BGR frame (the last one given to :meth:`observe`).
        time_s : float
            Its time, seconds.

        Returns
        -------
        list of (head, foot)
            Each person's head and foot points, ndarrays of shape (2,), pixels of ``frame``, left to
            right.
        """
        W, H = self.size
        moved = self.moved(time_s)
        parts = self._parts(moved)
        if not len(parts):
            return []
        mask = np.full((H, W), cv2.GC_BGD, np.uint8)
        for x, y, w, h in parts:
            s = int(round(self.config.spread * w))
            mask[max(0, y - int(self.config.above * h)) :, max(0, x - s) : min(W, x + w + s)] = cv2.GC_PR_FGD
        # GrabCut's colour model of the scene needs some of it on every side: the band and a margin
        ys, xs = np.nonzero(mask == cv2.GC_PR_FGD)
        m = max(8, H // 10)
        x0, x1, y0, y1 = max(0, xs.min() - m), min(W, xs.max() + 1 + m), max(0, ys.min() - m), min(H, ys.max() + 1)
        crop = np.ascontiguousarray(mask[y0:y1, x0:x1])
        if (crop == cv2.GC_BGD).sum() < 64:
            return []
        self.runs += 1
        bgd, fgd = np.zeros((1, 65)), np.zeros((1, 65))
        image = np.ascontiguousarray(self._shrunk(frame)[y0:y1, x0:x1])
        # GrabCut starts its colour models by k-means from OpenCV's global random state: seeded, the
        # same frames give the same bodies whatever ran before in the process
        cv2.setRNGSeed(0)
        cv2.grabCut(image, crop, None, bgd, fgd, self.config.iterations, cv2.GC_INIT_WITH_MASK)
        grown = np.zeros((H, W), np.uint8)
        grown[y0:y1, x0:x1] = (crop == cv2.GC_FGD) | (crop == cv2.GC_PR_FGD)
        n, cc, stats, _ = cv2.connectedComponentsWithStats(grown, connectivity=8)
        out: list[tuple[np.ndarray, np.ndarray]] = []
        for j in range(1, n):
            bx, by, bw, bh = stats[j, :4]
            # grown from a moving part: it holds one's top (a head, a raised hand)
            mine = parts[(bx <= parts[:, 0] + parts[:, 2] / 2) & (parts[:, 0] + parts[:, 2] / 2 <= bx + bw)]
            mine = mine[(by <= mine[:, 1] + 1) & (mine[:, 1] + 1 <= by + bh)]
            if not len(mine) or moved[cc == j].mean() > self.config.max_moved_share:
                continue
            lowest = float((mine[:, 1] + mine[:, 3]).max())
            for head, foot in upright_parts(cc, j, (bx, by, bw, bh), self.size):
                # a moving part reaching below the body: the body was cut above it (at the waist),
                # its legs taken for the scene
                if lowest - foot[1] <= self.config.max_below * (foot[1] - head[1]):
                    out.append((head, foot))
        return sorted(((h / self.scale, f / self.scale) for h, f in out), key=lambda hf: float(hf[1][0]))
