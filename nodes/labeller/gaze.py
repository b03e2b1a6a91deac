"""Gaze target: "at the other person" or "away", from head orientation (Okwechime et al. label
gaze direction from head pose).

Facing direction of the body is the normal of the shoulder line in the ground plane: with Y up, the
shoulder vector ``s = l_shoulder - r_shoulder`` points to the person's left, and the forward
direction is ``s x up = (-s_z, 0, s_x)``; at yaw 0 a person faces +Z (left shoulder at +X). The
gaze yaw is that body yaw plus the head yaw relative to the torso when the tracker gives one::

    gaze_yaw   = atan2(-s_z, s_x) + head_yaw_rel
    target_yaw = atan2(o_x - h_x, o_z - h_z)          (o: other person, h: own head)
    delta      = wrap(gaze_yaw - target_yaw) in (-pi, pi]
    score      = (1 + cos(delta)) / 2,   label = |delta| <= threshold

Yaw only: looking up or down is not modelled. Without a head yaw the head is assumed to face where
the shoulders face, so a head turned while the shoulders stay put is missed (the tracker's head
yaw fixes that). A silhouette alone does not support gaze: the labeller reports UNKNOWN there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from counterpart.nodes.labeller.signals import UNKNOWN


def facing_yaw_from_shoulders(l_shoulder: np.ndarray, r_shoulder: np.ndarray) -> np.ndarray:
    """Body yaw from the shoulders.

    Parameters
    ----------
    l_shoulder, r_shoulder : ndarray of shape (..., 3)
        Left and right shoulder positions, metres, world frame (Y up).

    Returns
    -------
    ndarray of shape (...,)
        Yaw in radians about +Y (0 faces +Z); nan where the shoulders coincide in the ground plane.

    Raises
    ------
    ValueError
        If the shoulders' last axis is not of length 3.
    """
    s = np.asarray(l_shoulder, dtype=np.float64) - np.asarray(r_shoulder, dtype=np.float64)
    if s.shape[-1] != 3:
        raise ValueError(f"shoulders must be (...,3) metres, got {s.shape}")
    yaw = np.arctan2(-s[..., 2], s[..., 0])
    return np.where(np.hypot(s[..., 0], s[..., 2]) > 1e-9, yaw, np.nan)


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Wrap radians to (-pi, pi].

    Parameters
    ----------
    a : array_like of float
        Angles, radians, any shape.

    Returns
    -------
    ndarray of float64
        The angles wrapped to (-pi, pi], same shape as ``a``.
    """
    return np.pi - np.mod(np.pi - np.asarray(a, dtype=np.float64), 2 * np.pi)


@dataclass(frozen=True)
class GazeResult:
    """Per-frame gaze at the other person.

    Attributes
    ----------
    score : ndarray of shape (T,)
        ``(1 + cos(delta)) / 2``, in [0, 1].
    label : ndarray of shape (T,)
        int8: 1 at the other, 0 away, UNKNOWN.
    delta : ndarray of shape (T,)
        Gaze yaw minus target yaw, radians, wrapped to (-pi, pi].
    """

    score: np.ndarray
    label: np.ndarray
    delta: np.ndarray


def gaze_at_other(
    head: np.ndarray,
    l_shoulder: np.ndarray,
    r_shoulder: np.ndarray,
    other: np.ndarray,
    head_yaw_rel: np.ndarray | float | None = None,
    threshold: float = float(np.radians(30.0)),
) -> GazeResult:
    """Per-frame gaze at the other person.

    Frames with a missing (nan) input, or the other person at the own head's position, are UNKNOWN.

    Parameters
    ----------
    head, l_shoulder, r_shoulder : ndarray of shape (T, 3) or (3,)
        Own head and shoulder positions, metres, world frame.
    other : ndarray of shape (T, 3) or (3,)
        The other person's head or any target point, metres, world frame.
    head_yaw_rel : ndarray of shape (T,) or float or None, default=None
        Head yaw relative to the torso, radians, positive turns towards the person's left; None: the
        head faces where the shoulders face.
    threshold : float, default=radians(30)
        The largest ``|delta|`` (radians) still counted as "at the other"; in (0, pi).

    Returns
    -------
    GazeResult
        Per-frame score, label and delta.

    Raises
    ------
    ValueError
        If ``threshold`` is not in (0, pi), or the positions are not (T, 3).
    """
    if not 0 < threshold < np.pi:
        raise ValueError(f"threshold must be in (0, pi) radians, got {threshold}")
    head = np.atleast_2d(np.asarray(head, dtype=np.float64))
    other = np.atleast_2d(np.asarray(other, dtype=np.float64))
    yaw = np.atleast_1d(facing_yaw_from_shoulders(l_shoulder, r_shoulder))
    if head_yaw_rel is not None:
        yaw = yaw + np.asarray(head_yaw_rel, dtype=np.float64)
    d = other - head
    if d.shape[-1] != 3:
        raise ValueError(f"head and other must be (T,3) metres, got {head.shape} and {other.shape}")
    dist = np.hypot(d[..., 0], d[..., 2])
    target = np.arctan2(d[..., 0], d[..., 2])
    delta = wrap_angle(yaw - target)
    delta = np.where(dist > 1e-6, delta, np.nan)
    score = 0.5 * (1.0 + np.cos(delta))
    label = (np.abs(delta) <= threshold).astype(np.int8)
    label[np.isnan(delta)] = UNKNOWN
    return GazeResult(score, label, delta)


def gaze_accuracy(pred: np.ndarray, truth: np.ndarray) -> float:
    """Fraction of frames where ``pred == truth``, over frames where both are known (not UNKNOWN).

    Parameters
    ----------
    pred, truth : ndarray of shape (T,)
        Predicted and true labels (1, 0 or UNKNOWN).

    Returns
    -------
    float
        The accuracy in [0, 1]; nan if no frame is known in both.

    Raises
    ------
    ValueError
        If ``pred`` and ``truth`` differ in shape.
    """
    pred = np.asarray(pred)
    truth = np.asarray(truth)
    if pred.shape != truth.shape:
        raise ValueError(f"pred and truth must have the same shape, got {pred.shape} and {truth.shape}")
    known = (pred != UNKNOWN) & (truth != UNKNOWN)
    if not known.any():
        return float("nan")
    return float(np.mean(pred[known] == truth[known]))
