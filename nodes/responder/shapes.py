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
    """One person's silhouette over T frames: ctrl (T, n, 2), pos (T, 2), height (T,), pixels;
    valid (T,) bool (False where the person is out of view).
    """

    ctrl: np.ndarray
    pos: np.ndarray
    height: np.ndarray
    valid: np.ndarray


def silhouette_track(joints: np.ndarray, camera: Camera, n: int = 32) -> ShapeTrack:
    """(T, 14, 3) joints (metres, world) -> the person's silhouette splines through ``camera``."""
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
    """Both people's silhouette tracks (A, B) of a trajectory; default camera 160 x 120 pixels."""
    cam = camera or default_camera(160, 120)
    return silhouette_track(traj.a, cam, n), silhouette_track(traj.b, cam, n)


def mirror_ctrl(ctrl: np.ndarray) -> np.ndarray:
    """Mirror control points (..., n, 2) left-right (x -> -x) keeping the ordering convention: point
    0 stays at the head, and the order is reversed so the curve stays counter-clockwise.
    """
    c = np.asarray(ctrl, np.float64).copy()
    c[..., 0] *= -1
    n = c.shape[-2]
    return c[..., np.r_[0, n - 1 : 0 : -1], :]
