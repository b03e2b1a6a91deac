"""The actor-centred frame: joints relative to one person's ground point and facing.

For a person with joints X (14, 3) (metres, world, Y up) the frame has its origin at the pelvis
(mid-hip point) dropped to the floor, r = (p_x, 0, p_z); its +Z axis is the person's horizontal
facing f and +X their own left. The left direction is the mean of the hip line (l_hip - r_hip) and
the shoulder line, projected on the floor; facing f = left x up (right-handed, Y up). With the
heading angle theta = atan2(f_x, f_z)::

    local = R_y(theta)^T (X - r),     X = R_y(theta) local + r,

R_y(theta) = [[cos, 0, sin], [0, 1, 0], [-sin, 0, cos]]. Models learnt in this frame do not depend
on where the pair stands or which way it faces.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.skeleton import JOINT_INDEX

_LH, _RH = JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]
_LS, _RS = JOINT_INDEX["l_shoulder"], JOINT_INDEX["r_shoulder"]


def actor_frame(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Origin and heading of a person's frame.

    Parameters
    ----------
    X : ndarray of shape (..., 14, 3)
        Joints, metres, world frame (Y up).

    Returns
    -------
    origin : ndarray of shape (..., 3)
        The frame's origin in metres, with y = 0.
    theta : ndarray of shape (...)
        Heading angle in radians.

    Raises
    ------
    ValueError
        If ``X`` is not of shape (..., 14, 3).
    """
    X = np.asarray(X, np.float64)
    if X.shape[-2:] != (14, 3):
        raise ValueError(f"joints must be (..., 14, 3) metres, got shape {X.shape}")
    origin = 0.5 * (X[..., _LH, :] + X[..., _RH, :])
    origin[..., 1] = 0.0
    left = (X[..., _LH, :] - X[..., _RH, :]) + (X[..., _LS, :] - X[..., _RS, :])
    # facing = left x up with up = +Y: (lx, ly, lz) x (0, 1, 0) = (-lz, 0, lx)
    theta = np.arctan2(-left[..., 2], left[..., 0])
    return origin, theta


def _rot(theta: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations by ``theta`` (radians) about +Y, filled in place (the responder builds
    several per frame: nested stacks cost more than the arithmetic).
    """
    c, s = np.cos(theta), np.sin(theta)
    R = np.zeros((*np.shape(c), 3, 3))
    R[..., 0, 0], R[..., 0, 2], R[..., 1, 1], R[..., 2, 0], R[..., 2, 2] = c, s, 1.0, -s, c
    return R


def to_local(Y: np.ndarray, origin: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """World points into the frame.

    Parameters
    ----------
    Y : ndarray of shape (..., J, 3)
        World points, metres.
    origin : ndarray of shape (..., 3)
        The frame's origin, metres.
    theta : ndarray of shape (...)
        The frame's heading, radians.

    Returns
    -------
    ndarray of shape (..., J, 3)
        The points in the frame, metres.
    """
    R = _rot(np.asarray(theta, np.float64))
    d = np.asarray(Y, np.float64) - np.asarray(origin, np.float64)[..., None, :]
    return np.einsum("...ji,...kj->...ki", R, d)  # R^T d per point


def to_world(L: np.ndarray, origin: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Local points of the frame back to world coordinates.

    Parameters
    ----------
    L : ndarray of shape (..., J, 3)
        Points in the frame, metres.
    origin : ndarray of shape (..., 3)
        The frame's origin, metres.
    theta : ndarray of shape (...)
        The frame's heading, radians.

    Returns
    -------
    ndarray of shape (..., J, 3)
        World points, metres.
    """
    R = _rot(np.asarray(theta, np.float64))
    return np.einsum("...ij,...kj->...ki", R, np.asarray(L, np.float64)) + np.asarray(origin, np.float64)[..., None, :]


def relative_pair(observed: np.ndarray, partner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both people in the observed person's frame, frame by frame.

    Parameters
    ----------
    observed, partner : ndarray of shape (T, 14, 3)
        Joints, metres, world frame.

    Returns
    -------
    obs_local, partner_local : ndarray of shape (T, 14, 3)
        Both people in the observed person's frame, metres.
    """
    o, th = actor_frame(observed)
    return to_local(observed, o, th), to_local(partner, o, th)
