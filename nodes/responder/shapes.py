"""Silhouette B-spline shapes of two-person trajectories, for the joint-shape model.

Each person is turned into cone-model poses (``counterpart.body.ik``), rasterised alone through the camera
(``counterpart.body.raster.rasterise_silhouettes``: one mask per person, as the silhouette node separates
people) and fitted with a closed B-spline of ``n`` control points
(``counterpart.body.spline.silhouette_spline``), giving per frame the control points (n, 2)
pixels, the region centroid (2,) pixels and the height (pixels, bounding box).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from counterpart.body.camera import Camera, default_camera
from counterpart.body.ik import dims_from_joints, inverse_kinematics
from counterpart.body.raster import rasterise_silhouettes
from counterpart.body.trajectory import TwoPersonTrajectory


@dataclass
class ShapeTrack:
    """One person's silhouette over T frames.

    Attributes
    ----------
    ctrl : ndarray of shape (T, n, 2)
        B-spline control points, pixels.
    pos : ndarray of shape (T, 2)
        Region centroid, pixels.
    height : ndarray of shape (T,)
        Height of the bounding box, pixels.
    valid : ndarray of shape (T,), dtype bool
        False where the person is out of view (the other fields are zero there).
    """

    ctrl: np.ndarray
    pos: np.ndarray
    height: np.ndarray
    valid: np.ndarray


def silhouette_track(joints: np.ndarray, camera: Camera, n: int = 32) -> ShapeTrack:
    """The person's silhouette splines through ``camera``.

    Parameters
    ----------
    joints : ndarray of shape (T, 14, 3)
        One person's joints, metres, world frame.
    camera : Camera
        The camera the person is rasterised through.
    n : int, default=32
        Control points per spline.

    Returns
    -------
    ShapeTrack
        The silhouette per frame; frames with fewer than 20 pixels of the person are not valid.
    """
    from counterpart.body.spline import silhouette_spline  # the spline convention shared with the silhouette node

    X = np.asarray(joints, np.float64)
    P = inverse_kinematics(X)
    masks = rasterise_silhouettes(P, dims_from_joints(X), camera)
    T = len(X)
    ctrl, pos = np.zeros((T, n, 2)), np.zeros((T, 2))
    height, valid = np.zeros(T), np.zeros(T, bool)
    for t, m in enumerate(masks):  # a few thousand small masks: OpenCV per mask
        ys, xs = np.nonzero(m)
        if len(xs) < 20:
            continue
        ctrl[t], _ = silhouette_spline(m, n)
        pos[t] = xs.mean(), ys.mean()
        height[t] = ys.max() - ys.min() + 1
        valid[t] = True
    return ShapeTrack(ctrl, pos, height, valid)


def trajectory_shapes(
    traj: TwoPersonTrajectory, camera: Camera | None = None, n: int = 32
) -> tuple[ShapeTrack, ShapeTrack]:
    """Both people's silhouette tracks of a trajectory.

    Parameters
    ----------
    traj : TwoPersonTrajectory
        The two people's joints.
    camera : Camera or None, default=None
        The camera; ``None`` for the default camera at 160 x 120 pixels.
    n : int, default=32
        Control points per spline.

    Returns
    -------
    a, b : ShapeTrack
        The silhouette tracks of person A and person B.
    """
    cam = camera or default_camera(160, 120)
    return silhouette_track(traj.a, cam, n), silhouette_track(traj.b, cam, n)


def mirror_ctrl(ctrl: np.ndarray) -> np.ndarray:
    """Mirror control points left-right (x -> -x) keeping the ordering convention: point 0 stays at
    the head, and the order is reversed so the curve stays counter-clockwise.

    Parameters
    ----------
    ctrl : ndarray of shape (..., n, 2)
        Control points, x relative to the mirror axis.

    Returns
    -------
    ndarray of shape (..., n, 2), dtype float64
        The mirrored control points (a copy).
    """
    c = np.asarray(ctrl, np.float64).copy()
    c[..., 0] *= -1
    n = c.shape[-2]
    return c[..., np.r_[0, n - 1 : 0 : -1], :]
