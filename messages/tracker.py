"""Messages of the tracker node (Deutscher, Blake & Reid 2000; Zheng et al. 2006)."""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message, struct


@struct
class TrackedBody:
    """One tracked person.

    Attributes
    ----------
    id : int
        Track identifier.
    side : str
        Side of the frame the person stands on (``"left"``, ``"right"`` or ``"centre"``).
    joints : ndarray of shape (14, 3)
        float32, metres in the world frame (counterpart.body.skeleton.JOINTS order, Y up).
    pose : ndarray of shape (DOF,)
        float64 pose vector (body.pose), the weighted mean of the particles.
    best_pose : ndarray of shape (DOF,)
        float64 pose vector (body.pose) of the best particle.
    ess : float
        Effective sample size of the final weighted particle set (un-annealed weights, before
        resampling: 1 to the particle count).
    log_likelihood : float
        Log-likelihood of the mean pose.
    lost : bool
        True when the track collapsed and is re-initialising.
    """

    id: int = 0
    side: str = "left"
    joints: np.ndarray = EMPTY
    pose: np.ndarray = EMPTY
    best_pose: np.ndarray = EMPTY
    ess: float = 0.0
    log_likelihood: float = 0.0
    lost: bool = False


@message("tracker.Pose3D", 1)
class Pose3D:
    """The tracked people of one frame.

    Attributes
    ----------
    people : list of TrackedBody
        The tracked people.
    fps : float
        The source's frame rate (the frame's; 0: unknown), so that consumers of poses alone (the
        responder) know the time between frames.
    """

    people: list[TrackedBody] = ()
    fps: float = 0.0
