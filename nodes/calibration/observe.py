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
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from .estimate import CalibrationConfig, CameraEstimate, estimate_camera, head_foot, usable
from .lines import LineFamilies, detect_segments, find_families
from .upright import upright_parts


class PeopleObservations:
    """Head/foot points of upright people over time, for frames of one size.

    Parameters
    ----------
    width, height : int
        Frame size, pixels.
    max_observations : int, default=1500
        Bound of the store (see the module docstring).
    """

    def __init__(self, width: int, height: int, max_observations: int = 1500) -> None:
        self.size = (int(width), int(height))
        self.max_observations = int(max_observations)
        self._rows: list[tuple[float, float, float, float, int, float]] = []

    def __len__(self) -> int:
        return len(self._rows)

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
        with_labels = labels is not None and np.shape(labels) == (self.size[1], self.size[0])
        for p in people:
            if not usable(p.bbox, *self.size, merged=bool(p.merged)):
                if with_labels and not p.merged:
                    for k, (h, f) in enumerate(upright_parts(labels, int(p.id) + 1, p.bbox, self.size)):
                        self._rows.append((h[0], h[1], f[0], f[1], -(8 * int(p.id) + k + 1), float(time_s)))
                        n += 1
                continue
            ctrl = p.ctrl if p.ctrl is not None and np.size(p.ctrl) else None
            ref = p.ref_point if p.ref_point is not None and np.size(p.ref_point) == 2 else None
            h, f = head_foot(p.bbox, ctrl, ref)
            self._rows.append((h[0], h[1], f[0], f[1], int(p.id), float(time_s)))
            n += 1
        if len(self._rows) > self.max_observations:
            half = len(self._rows) // 2
            self._rows = self._rows[:half:2] + self._rows[half:]
        return n

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
        head, foot, track, t = self.arrays()
        return estimate_camera(head, foot, track, self.size, t, config or CalibrationConfig(), lines)


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
            image = np.median(np.stack(self.frames), axis=0).astype(np.uint8)
            self._families = find_families(detect_segments(image, self.boxes), (image.shape[0] - 1) / 2.0)
        return self._families


__all__ = ["PeopleObservations", "SceneFrames"]
