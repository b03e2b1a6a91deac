"""A track carried through a refined camera: the same picture, read by another camera.

The calibration node refines the graph's camera while the tracks go on: it publishes the default
camera first and then steps towards its estimate (``nodes.calibration.smooth``), so on a real video
the camera a track began under can be far from the one it ends under. The picture does not change
with the camera; what changes is where and how large a body must be to look as it does. A body
carried over unchanged keeps the stature it was measured at under the first camera, which under
the refined one is the size of someone else: the search then fits it to the person's outline by
its head and arms, its legs reaching past their feet, and the partner, built on its bones, is drawn
at that wrong size too.

So a body is moved with the camera (:class:`GroundMove`): its feet go to where the new camera puts
the pixel they stood on (``init.stand_at``), its size changes as the stature the new camera reads
between the same head and foot rows over the old one's, and it turns as the line of sight to that
place turns, about the vertical through its feet. Its pose (the joint angles, its lean) is kept.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from counterpart.body.camera import Camera
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import YAW, wrap_angle
from counterpart.body.skeleton import JOINT_INDEX, BodyDims

from .init import stand_at

_HEAD = JOINT_INDEX["head"]
_ANKLES = [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]


@dataclass(frozen=True)
class GroundMove:
    """A move of bodies on the ground plane from one camera's reading of a picture to another's.

    A ground point q (x, z) goes to ``target + scale * Ry(turn) (q - origin)``; the pelvis height
    is multiplied by the scale, the heading turned by ``turn``.

    Attributes
    ----------
    origin : ndarray of shape (2,)
        The feet's ground point (x, z) under the old camera, metres.
    target : ndarray of shape (2,)
        The same pixel's ground point under the new camera, metres.
    turn : float
        The change of the bearing of the line of sight to the feet (``root_yaw``'s sense: about +Y,
        0 along +Z), radians.
    stature_ratio : float
        The stature the new camera reads between the body's head and foot rows over the old
        camera's (> 0).
    """

    origin: np.ndarray
    target: np.ndarray
    turn: float
    stature_ratio: float

    def apply(self, P: np.ndarray, scale: float) -> np.ndarray:
        """Move poses.

        Parameters
        ----------
        P : ndarray of shape (..., 28)
            Poses (``counterpart.body.pose``), metres and radians.
        scale : float
            The ratio of the body's new size to its old (the stature ratio, or less where the
            stature is bounded).

        Returns
        -------
        ndarray of shape (..., 28)
            The moved poses (a new array).
        """
        Q = np.array(P, dtype=np.float64, copy=True)
        dx, dz = Q[..., 0] - self.origin[0], Q[..., 2] - self.origin[1]
        c, s = np.cos(self.turn), np.sin(self.turn)
        Q[..., 0] = self.target[0] + scale * (c * dx + s * dz)
        Q[..., 2] = self.target[1] + scale * (-s * dx + c * dz)
        Q[..., 1] *= scale
        Q[..., YAW] = wrap_angle(Q[..., YAW] + self.turn)
        return Q


def _bearing(ground: np.ndarray, camera: Camera) -> float:
    c = camera.centre
    return float(np.arctan2(ground[0] - c[0], ground[2] - c[2]))


def ground_move(pose: np.ndarray, dims: BodyDims, old: Camera, new: Camera) -> GroundMove:
    """How a body seen through ``old`` must move to look the same through ``new``.

    Parameters
    ----------
    pose : ndarray of shape (28,)
        The body's pose under the old camera.
    dims : BodyDims
        Its dimensions.
    old, new : Camera
        The camera it was fitted through, and the refined one (the same frames).

    Returns
    -------
    GroundMove
        The move, read at the column of the mid-ankle: the feet at the lower ankle's row, the top
        at the head joint's.

    Raises
    ------
    PlacementError
        When the feet's pixel lies at or above either camera's horizon.
    """
    joints = forward_kinematics(pose, dims)[0]
    uv = old.project(joints)
    u = float(uv[_ANKLES, 0].mean())
    top, bottom = float(uv[_HEAD, 1]), float(uv[_ANKLES, 1].max())
    g_old, h_old = stand_at(u, top, bottom, old)
    g_new, h_new = stand_at(u, top, bottom, new)
    ratio = h_new / h_old if h_old > 1e-6 and h_new > 1e-6 else 1.0
    return GroundMove(
        origin=g_old[[0, 2]],
        target=g_new[[0, 2]],
        turn=_bearing(g_new, new) - _bearing(g_old, old),
        stature_ratio=float(ratio),
    )


__all__ = ["GroundMove", "ground_move"]
