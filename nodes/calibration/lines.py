"""Straight lines of the scene for the camera estimate: families of parallel scene lines and their
vanishing points (the ground's horizon, the vertical).

Line segments of a frame (OpenCV's LSD, von Gioi et al. 2010), without those on the people, are
grouped by the vanishing point they converge to (sequential RANSAC over pairs of segments,
vectorised; a segment agrees with a vanishing point when the line from its midpoint to that point
is within ``angle_deg`` of its own direction). A family whose segments are mostly steep (within
``vertical_deg`` of the image vertical) is taken as the world's vertical; the others as horizontal
directions, whose vanishing points lie on the horizon (the vanishing line of the ground plane).
``counterpart.nodes.calibration.estimate`` fits the camera to them together with the people: each horizontal
family adds only its unknown direction on the ground, so it says where the horizon is (tilt and
roll) without any assumption about the angles between the families.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np


@dataclass(frozen=True)
class LineFamilies:
    """Scene line segments grouped by vanishing point.

    Parameters
    ----------
    segments : ndarray of shape (N, 4), dtype float64
        Pixels, x1, y1, x2, y2.
    family : ndarray of shape (N,), dtype int
        The family of each segment (index into ``vertical`` and ``vp``).
    vertical : ndarray of shape (F,), dtype bool
        Whether each family is the world's vertical.
    vp : ndarray of shape (F, 3)
        Homogeneous vanishing points found (pixels; last coordinate 0 at infinity).
    """

    segments: np.ndarray
    family: np.ndarray
    vertical: np.ndarray
    vp: np.ndarray

    @property
    def n_horizontal(self) -> int:
        return int((~self.vertical).sum())


def detect_segments(
    image: np.ndarray, boxes: Iterable[Any] = (), min_length: float = 20.0, scale: float = 0.6
) -> np.ndarray:
    """LSD segments of an image, without those on the people.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3) or (H, W), dtype uint8
        BGR or grey image.
    boxes : iterable of (x, y, w, h), default=()
        Boxes in pixels (the people); a segment with both ends in one box is dropped (it lies on the
        person). Segments that reach out of the box are kept: the floor's and the wall's lines
        passing behind a person are the horizon's best evidence, and a box grown around the people
        or a midpoint test cut most of them in the simulator's rooms.
    min_length : float, default=20.0
        Shortest segment kept, pixels.
    scale : float, default=0.6
        LSD's own resampling of the image before it looks for lines (its Gaussian sub-sampling, von
        Gioi et al. 2010, section 4; OpenCV's default 0.8). Smaller scales smooth more: the faint,
        aliased edges of a floor's boards receding from a low-resolution camera (320x240) come out
        as long segments instead of broken pieces, and these give the ground's second vanishing
        point (the horizon's position, and the focal length through the right-angle prior).

    Returns
    -------
    ndarray of shape (N, 4), dtype float64
        Segments x1, y1, x2, y2, pixels.
    """
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    if not 0.0 < scale <= 1.0:
        raise ValueError(f"scale must be in (0, 1], got {scale}")
    found = cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD, scale).detect(grey)[0]
    if found is None:
        return np.zeros((0, 4))
    s = found.reshape(-1, 4).astype(np.float64)
    s = s[np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]) >= min_length]
    keep = np.ones(len(s), bool)
    for x, y, w, h in boxes:
        inside = (s[:, [0, 2]] >= x) & (s[:, [0, 2]] <= x + w) & (s[:, [1, 3]] >= y) & (s[:, [1, 3]] <= y + h)
        keep &= ~inside.all(axis=1)
    return s[keep]


def segment_angles(segments: np.ndarray, vp: np.ndarray) -> np.ndarray:
    """Sine of the angle between each segment and the line from its midpoint to its vanishing point.

    Parameters
    ----------
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.
    vp : ndarray of shape (3,) or (N, 3)
        Homogeneous vanishing point for all segments, or one per segment (at infinity a direction).

    Returns
    -------
    ndarray of shape (N,)
        Signed sine of the angle.
    """
    d = segments[:, 2:] - segments[:, :2]
    mid = 0.5 * (segments[:, :2] + segments[:, 2:])
    vp = np.broadcast_to(vp, (len(segments), 3))
    to = vp[:, :2] - vp[:, 2:3] * mid
    cross = d[:, 0] * to[:, 1] - d[:, 1] * to[:, 0]
    return cross / np.maximum(np.linalg.norm(d, axis=1) * np.linalg.norm(to, axis=1), 1e-12)


def find_families(
    segments: np.ndarray,
    centre_row: float,
    max_families: int = 3,
    angle_deg: float = 1.5,
    min_segments: int = 5,
    vertical_deg: float = 25.0,
    iters: int = 400,
    seed: int = 0,
) -> LineFamilies:
    """Group segments by vanishing point (sequential RANSAC; see the module docstring).

    Parameters
    ----------
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.
    centre_row : float
        The principal point's row, pixels (the image's middle row).
    max_families : int, default=3
        Vanishing points sought at most.
    angle_deg : float, default=1.5
        Agreement of a segment with a vanishing point, degrees.
    min_segments : int, default=5
        Segments each family needs.
    vertical_deg : float, default=25.0
        A family whose length-weighted segments are within this of the image vertical (degrees) and
        whose vanishing point is below ``centre_row`` (or at infinity) is the world's vertical (at
        most one: the steepest).
    iters : int, default=400
        Pairs tried per vanishing point.
    seed : int, default=0
        Seed of their draw.

    Returns
    -------
    LineFamilies
        The segments that joined a family, their families and vanishing points.
    """
    rng = np.random.default_rng(seed)
    s = np.asarray(segments, np.float64).reshape(-1, 4)
    length = np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1])
    lines = np.cross(np.column_stack([s[:, :2], np.ones(len(s))]), np.column_stack([s[:, 2:], np.ones(len(s))]))
    family = np.full(len(s), -1)
    vps: list[np.ndarray] = []
    tol = np.sin(np.radians(angle_deg))
    for f in range(max_families):
        free = np.flatnonzero(family < 0)
        if len(free) < min_segments:
            break
        i, j = rng.choice(free, (2, iters)) if len(free) > 1 else (free, free)
        cand = np.cross(lines[i], lines[j])
        cand = cand[np.linalg.norm(cand, axis=1) > 1e-12]
        cand /= np.linalg.norm(cand, axis=1, keepdims=True)
        if not len(cand):
            break
        d = s[free, 2:] - s[free, :2]
        mid = 0.5 * (s[free, :2] + s[free, 2:])
        to = cand[:, None, :2] - cand[:, None, 2:3] * mid[None]  # (C, n, 2)
        sin = (d[None, :, 0] * to[..., 1] - d[None, :, 1] * to[..., 0]) / np.maximum(
            np.linalg.norm(d, axis=1)[None] * np.linalg.norm(to, axis=2), 1e-12
        )
        score = ((np.abs(sin) < tol) * length[free][None]).sum(axis=1)
        best = cand[int(np.argmax(score))]
        members = free[np.abs(segment_angles(s[free], best)) < tol]
        if len(members) < min_segments:
            break
        family[members] = f
        vps.append(best)
    keep = family >= 0
    n = len(vps)
    steep = np.zeros(n)
    for f in range(n):
        m = family == f
        d = s[m, 2:] - s[m, :2]
        steep[f] = np.average(np.abs(d[:, 0]) / np.maximum(np.linalg.norm(d, axis=1), 1e-12), weights=length[m])
    # the vertical: steep segments whose vanishing point is below the image centre (a camera level or
    # looking down) or at infinity; steep families converging upwards are ground lines running away
    # from the camera, whose vanishing point is on the horizon above
    vertical = np.zeros(n, bool)
    vp = np.array(vps).reshape(-1, 3)
    below = (np.abs(vp[:, 2]) < 1e-9 * np.linalg.norm(vp[:, :2], axis=1)) | (
        vp[:, 1] * np.sign(vp[:, 2]) > centre_row * np.abs(vp[:, 2])
    )
    ok = (steep < np.sin(np.radians(vertical_deg))) & below
    if ok.any():
        vertical[int(np.argmin(np.where(ok, steep, np.inf)))] = True
    return LineFamilies(s[keep], family[keep], vertical, vp)


__all__ = ["LineFamilies", "detect_segments", "find_families", "segment_angles"]
