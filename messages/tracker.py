"""Messages of the tracker node (Deutscher, Blake & Reid 2000; Zheng et al. 2006)."""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message, struct


@struct
class TrackedBody:
    """One tracked person: ``joints`` (14, 3) float32 metres in the world frame (counterpart.body.skeleton.JOINTS
    order, Y up), ``pose`` and ``best_pose`` (DOF,) float64 pose vectors (body.pose), the weighted
    mean and the best particle; ``ess`` effective sample size of the final weighted particle set
    (un-annealed weights, before resampling: 1 to the particle count); ``log_likelihood``
    of the mean pose; ``lost`` when the track collapsed and is re-initialising.
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
    """The tracked people of one frame; ``fps`` the source's frame rate (the frame's, 0: unknown),
    so that consumers of poses alone (the responder) know the time between frames.
    """

    people: list[TrackedBody] = ()
    fps: float = 0.0
