"""Activity: how much the torso moves (Okwechime et al.: "activity" from body motion).

Only the torso points are used (3D: shoulders and hips; 2D: the upper-body control points of the
silhouette's spline), so that head nods and leg swing do not count. Velocities are finite
differences over ``lag`` frames (``v_t = (p_t - p_{t-lag}) * fps / lag``; a lag of a few frames
keeps tracker jitter from dominating). Over a window of ``W`` frames the score is the mean-scaled
standard deviation of those velocities::

    score_t = sqrt( mean_j sum_d var_{t-W < u <= t}( v_{u,j,d} ) ) / s_t

with ``s_t`` the mean torso length over the window (3D: mid-shoulder to mid-hip distance, metres;
2D: ``torso_fraction * silhouette height``, pixels). The score is therefore in torso lengths per
second and does not depend on the person's size or distance to the camera. Constant-velocity
translation (walking at a steady pace) has zero velocity variance and is not activity; gesturing,
swaying, bending and turning are. Label: ``score >= threshold``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from counterpart.nodes.labeller.signals import JOINT_INDEX, UNKNOWN, threshold_labels

_TORSO_IDX = np.array([JOINT_INDEX[j] for j in ("l_shoulder", "r_shoulder", "l_hip", "r_hip")])

#: silhouette spline control points (of 32, index 0 at the top of the head) treated as upper body
UPPER_BODY_POINTS_32 = np.r_[np.arange(24, 32), np.arange(0, 9)]


@dataclass(frozen=True)
class ActivityParams:
    """Parameters of the activity score.

    Parameters
    ----------
    fps : float
        Frame rate, Hz (> 0).
    window_s : float, default=1.0
        Window of the velocity statistics, seconds (at least 2 frames).
    lag_s : float, default=0.12
        Finite-difference step, seconds.
    threshold : float, default=0.15
        Label threshold, torso lengths per second.

    Raises
    ------
    ValueError
        If ``fps`` is not positive or the window is under 2 frames.
    """

    fps: float
    window_s: float = 1.0
    lag_s: float = 0.12
    threshold: float = 0.15

    def __post_init__(self) -> None:
        if not self.fps > 0:
            raise ValueError(f"fps must be > 0, got {self.fps}")
        if self.w < 2:
            raise ValueError(f"window_s * fps must give >= 2 frames, got window_s={self.window_s}")

    @property
    def w(self) -> int:
        """Window in frames."""
        return int(round(self.window_s * self.fps))

    @property
    def lag(self) -> int:
        """Finite-difference lag in frames (>= 1)."""
        return max(1, int(round(self.lag_s * self.fps)))


def torso_points_3d(joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Torso points and torso length from joints.

    Parameters
    ----------
    joints : ndarray of shape (T, 14, 3)
        Joints, metres, in the project joint order.

    Returns
    -------
    points : ndarray of shape (T, 4, 3)
        Shoulders and hips (l_shoulder, r_shoulder, l_hip, r_hip), metres.
    torso : ndarray of shape (T,)
        Mid-shoulder to mid-hip distance, metres.

    Raises
    ------
    ValueError
        If ``joints`` is not of shape (T, 14, 3).
    """
    joints = np.asarray(joints, dtype=np.float64)
    if joints.ndim != 3 or joints.shape[1:] != (14, 3):
        raise ValueError(f"joints must be (T,14,3) metres in the project joint order, got {joints.shape}")
    pts = joints[:, _TORSO_IDX]
    mid_sh = 0.5 * (pts[:, 0] + pts[:, 1])
    mid_hip = 0.5 * (pts[:, 2] + pts[:, 3])
    return pts, np.linalg.norm(mid_sh - mid_hip, axis=-1)


def activity_from_points(
    points: np.ndarray, scale: np.ndarray, params: ActivityParams
) -> tuple[np.ndarray, np.ndarray]:
    """Batch activity over a trajectory of points, vectorised over windows (causal).

    Parameters
    ----------
    points : ndarray of shape (T, J, D)
        Positions (any unit).
    scale : ndarray of shape (T,)
        Torso length in the same unit.
    params : ActivityParams
        Frame rate, window, lag and threshold.

    Returns
    -------
    score : ndarray of shape (T,)
        Activity, torso lengths per second; NaN where unknown.
    label : ndarray of shape (T,), dtype int8
        ``score >= threshold`` (1/0), UNKNOWN (-1) where the score is NaN.
        The first ``W + lag - 1`` frames and windows with a missing (NaN) point are UNKNOWN.

    Raises
    ------
    ValueError
        If the shapes do not match.
    """
    pts = np.asarray(points, dtype=np.float64)
    sc = np.asarray(scale, dtype=np.float64)
    if pts.ndim != 3 or sc.shape != (pts.shape[0],):
        raise ValueError(f"points must be (T,J,D) and scale (T,); got {pts.shape} and {sc.shape}")
    t, lag, w = pts.shape[0], params.lag, params.w
    score = np.full(t, np.nan)
    if t >= w + lag:
        v = (pts[lag:] - pts[:-lag]) * (params.fps / lag)  # (T-lag, J, D)
        vw = sliding_window_view(v, w, axis=0)  # (M, J, D, W)
        var = vw.var(axis=-1).sum(axis=-1).mean(axis=-1)  # (M,)
        sw = sliding_window_view(sc[lag:], w).mean(axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            s = np.sqrt(var) / sw
        s[~(sw > 0)] = np.nan
        score[w + lag - 1 :] = s
    return score, threshold_labels(score, params.threshold)


def activity_3d(joints: np.ndarray, fps: float, **params: object) -> tuple[np.ndarray, np.ndarray]:
    """Activity over 3D joints.

    Parameters
    ----------
    joints : ndarray of shape (T, 14, 3)
        Joints, metres, in the project joint order.
    fps : float
        Frame rate, Hz.
    **params
        Other fields of :class:`ActivityParams` (``window_s``, ``lag_s``, ``threshold``).

    Returns
    -------
    score : ndarray of shape (T,)
        Activity, torso lengths per second; NaN where unknown.
    label : ndarray of shape (T,), dtype int8
        ``score >= threshold`` (1/0), UNKNOWN (-1) where the score is NaN.
    """
    p = ActivityParams(fps=fps, **params)  # type: ignore[arg-type]
    pts, sc = torso_points_3d(joints)
    return activity_from_points(pts, sc, p)


def activity_2d(
    control_points: np.ndarray, height_px: np.ndarray | float, fps: float, torso_fraction: float = 0.3, **params: object
) -> tuple[np.ndarray, np.ndarray]:
    """Activity from silhouette splines, on :data:`UPPER_BODY_POINTS_32`.

    Crude: arm gestures move the outline as much as the torso does, and they count.

    Parameters
    ----------
    control_points : ndarray of shape (T, 32, 2)
        Spline control points, pixels, ordered from the top of the head.
    height_px : ndarray of shape (T,) or float
        Silhouette height, pixels.
    fps : float
        Frame rate, Hz.
    torso_fraction : float, default=0.3
        Torso length as a fraction of the silhouette height.
    **params
        Other fields of :class:`ActivityParams` (``window_s``, ``lag_s``, ``threshold``).

    Returns
    -------
    score : ndarray of shape (T,)
        Activity, torso lengths per second; NaN where unknown.
    label : ndarray of shape (T,), dtype int8
        ``score >= threshold`` (1/0), UNKNOWN (-1) where the score is NaN.

    Raises
    ------
    ValueError
        If ``control_points`` is not of shape (T, 32, 2).
    """
    cp = np.asarray(control_points, dtype=np.float64)
    if cp.ndim != 3 or cp.shape[1:] != (32, 2):
        raise ValueError(f"control_points must be (T,32,2) pixels, got {cp.shape}")
    p = ActivityParams(fps=fps, **params)  # type: ignore[arg-type]
    h = np.broadcast_to(np.asarray(height_px, dtype=np.float64), (cp.shape[0],))
    return activity_from_points(cp[:, UPPER_BODY_POINTS_32], torso_fraction * h, p)


class ActivityDetector:
    """Streaming activity for one person: gives :func:`activity_from_points` values frame by frame.

    ``update(points (J,D), scale) -> (score, label)``; use :meth:`update_3d` for (14,3) joints and
    :meth:`update_2d` for a (32,2) silhouette spline.

    Parameters
    ----------
    fps : float
        Frame rate, Hz.
    window_s : float, default=1.0
        Window of the velocity statistics, seconds.
    lag_s : float, default=0.12
        Finite-difference step, seconds.
    threshold : float, default=0.15
        Label threshold, torso lengths per second.
    torso_fraction : float, default=0.3
        Torso length as a fraction of the silhouette height (2D).
    """

    def __init__(
        self,
        fps: float,
        window_s: float = 1.0,
        lag_s: float = 0.12,
        threshold: float = 0.15,
        torso_fraction: float = 0.3,
    ) -> None:
        self.params = ActivityParams(fps=fps, window_s=window_s, lag_s=lag_s, threshold=threshold)
        self.torso_fraction = torso_fraction
        self._n = self.params.w + self.params.lag
        self._pts: np.ndarray | None = None
        self._sc = np.full(2 * self._n, np.nan)
        self._i = 0
        self._count = 0

    def reset(self) -> None:
        """Forget the history."""
        self._pts = None
        self._sc.fill(np.nan)
        self._i = 0
        self._count = 0

    def update(self, points: np.ndarray, scale: float) -> tuple[float, int]:
        """Add one frame.

        Parameters
        ----------
        points : ndarray of shape (J, D)
            Torso points (any unit).
        scale : float
            Torso length, same unit.

        Returns
        -------
        score : float
            Activity, torso lengths per second; NaN until the window is full or when unknown.
        label : int
            1/0, or UNKNOWN (-1).
        """
        pts = np.asarray(points, dtype=np.float64)
        n = self._n
        if self._pts is None or self._pts.shape[1:] != pts.shape:
            self._pts = np.full((2 * n,) + pts.shape, np.nan)
            self._count = 0
        self._pts[self._i] = pts
        self._pts[self._i + n] = pts
        self._sc[self._i] = scale
        self._sc[self._i + n] = scale
        self._i = (self._i + 1) % n
        self._count += 1
        if self._count < n:
            return float("nan"), UNKNOWN
        p = self.params
        buf = self._pts[self._i : self._i + n]
        v = (buf[p.lag :] - buf[: -p.lag]) * (p.fps / p.lag)
        sw = self._sc[self._i + p.lag : self._i + n].mean()
        if not sw > 0:
            return float("nan"), UNKNOWN
        s = float(np.sqrt(v.var(axis=0).sum(axis=-1).mean()) / sw)
        if s != s:
            return s, UNKNOWN
        return s, int(s >= p.threshold)

    def update_3d(self, joints: np.ndarray) -> tuple[float, int]:
        """Add one frame of 3D joints.

        Parameters
        ----------
        joints : ndarray of shape (14, 3)
            Joints, metres, in the project joint order.

        Returns
        -------
        score : float
            Activity, torso lengths per second (NaN when unknown).
        label : int
            1/0, or UNKNOWN (-1).

        Raises
        ------
        ValueError
            If ``joints`` is not of shape (14, 3).
        """
        j = np.asarray(joints, dtype=np.float64)
        if j.shape != (14, 3):
            raise ValueError(f"joints must be (14,3) metres, got {j.shape}")
        pts = j[_TORSO_IDX]
        torso = float(np.linalg.norm(0.5 * (pts[0] + pts[1] - pts[2] - pts[3])))
        return self.update(pts, torso)

    def update_2d(self, control_points: np.ndarray, height_px: float) -> tuple[float, int]:
        """Add one frame of a silhouette spline.

        Parameters
        ----------
        control_points : ndarray of shape (32, 2)
            Spline control points, pixels, from the top of the head.
        height_px : float
            Silhouette height, pixels.

        Returns
        -------
        score : float
            Activity, torso lengths per second (NaN when unknown).
        label : int
            1/0, or UNKNOWN (-1).

        Raises
        ------
        ValueError
            If ``control_points`` is not of shape (32, 2).
        """
        cp = np.asarray(control_points, dtype=np.float64)
        if cp.shape != (32, 2):
            raise ValueError(f"control_points must be (32,2) pixels, got {cp.shape}")
        return self.update(cp[UPPER_BODY_POINTS_32], self.torso_fraction * float(height_px))
