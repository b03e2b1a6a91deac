"""Motion capture as a scenario: a BVH pair (two people of one take) driving the renderer.

``scenario_from_bvh(path_a, path_b, fps=25)``: read both files (``counterpart.body.trajectory``), turn the
pair about the vertical so that the line between the two people at their closest approach runs
along +X with A on the left (the camera looks along -Z), recentre the pair at the origin, fit each
person's body (``counterpart.body.ik.dims_from_joints``) and poses (``counterpart.body.ik.inverse_kinematics``), and lift
each person by one constant so that the body's lowest point over the take sits on the floor (the
5th percentile of the per-frame lowest points: feet on y = 0, any jump kept).

Labels: phase 0 before the closest approach window (pelvis distance within 5 cm of its
minimum), 1 inside it, 2 after; gaze and activity measured as in ``counterpart.sim.scenarios``; nod, shake
and talking unknown (-1): the capture does not say.
"""

from __future__ import annotations

import os

import numpy as np

from counterpart.body.ik import dims_from_joints, inverse_kinematics
from counterpart.body.kinematics import lowest_point
from counterpart.body.pose import DOF_INDEX
from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.sim.scenarios import SIGNAL_INDEX, SIGNAL_NAMES, Scenario, _gaze_and_activity

#: where the project's development data keeps the CMU handshake (subjects 18 and 19, trial 1)
CMU_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "..", "shared", "data", "cmu")


def default_cmu_pair() -> tuple[str, str]:
    """Paths of the CMU handshake pair in the shared data folder.

    Returns
    -------
    path_a, path_b : str
        The BVH files of subjects 18 and 19, trial 1.

    Raises
    ------
    FileNotFoundError
        When either file is absent.
    """
    a, b = (os.path.normpath(os.path.join(CMU_DIR, f)) for f in ("18_01.bvh", "19_01.bvh"))
    for p in (a, b):
        if not os.path.exists(p):
            raise FileNotFoundError(f"{p}: CMU BVH file not found; give --bvh-a/--bvh-b (bvh_a=, bvh_b=) paths")
    return a, b


def _rot_y(points: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return points @ R.T


def scenario_from_bvh(
    path_a: str | os.PathLike, path_b: str | os.PathLike, fps: float = 25.0, label: str = "handshake", seed: int = 0
) -> Scenario:
    """A :class:`counterpart.sim.scenarios.Scenario` from two BVH files of one take (see the module docstring).

    Parameters
    ----------
    path_a, path_b : str or os.PathLike
        BVH files of the two people of one take.
    fps : float, default=25.0
        Frame rate of the scenario (Hz).
    label : str, default="handshake"
        Interaction label.
    seed : int, default=0
        Recorded in the scenario's metadata.

    Returns
    -------
    Scenario
        Poses, body dimensions, phases and social signals of both people, rotated so that they meet
        along +X and centred on their meeting point.
    """
    traj = TwoPersonTrajectory.from_bvh_pair(path_a, path_b, fps=fps, label=label)
    A, B = traj.a.astype(np.float64), traj.b.astype(np.float64)
    pa = 0.5 * (A[:, 8] + A[:, 11])
    pb = 0.5 * (B[:, 8] + B[:, 11])
    dist = np.linalg.norm((pb - pa)[:, [0, 2]], axis=1)
    k = int(np.argmin(dist))
    d = (pb - pa)[k]
    angle = np.arctan2(d[0], d[2]) - np.pi / 2  # rotate d onto +X
    A, B = _rot_y(A, -angle), _rot_y(B, -angle)
    pa, pb = 0.5 * (A[:, 8] + A[:, 11]), 0.5 * (B[:, 8] + B[:, 11])
    centre = 0.5 * (pa[k] + pb[k])
    A[..., [0, 2]] -= centre[[0, 2]]
    B[..., [0, 2]] -= centre[[0, 2]]
    poses, dims = [], []
    for X in (A, B):
        dm = dims_from_joints(X)
        P = inverse_kinematics(X)
        P[:, DOF_INDEX["root_y"]] -= float(np.percentile(lowest_point(P, dm), 5))
        poses.append(P)
        dims.append(dm)
    T = len(A)
    near = dist <= dist.min() + 0.05
    first, last = np.flatnonzero(near)[[0, -1]]
    phase = np.where(np.arange(T) < first, 0, np.where(np.arange(T) <= last, 1, 2)).astype(np.int32)
    gaze, act = _gaze_and_activity(poses[0], poses[1], dims[0], dims[1], fps)
    sig = []
    for p in range(2):
        s = np.full((T, len(SIGNAL_NAMES)), -1, np.int8)
        s[:, SIGNAL_INDEX["gaze_at_other"]] = gaze[:, p]
        s[:, SIGNAL_INDEX["activity"]] = act[:, p]
        sig.append(s)
    meta = {
        "scenario": "cmu",
        "seed": int(seed),
        "emotion": None,
        "strength": None,
        "initiator": None,
        "interested": None,
        "source": traj.meta.get("source"),
        "rotation_rad": float(angle),
        "licence": "CMU Graphics Lab Motion Capture Database (mocap.cs.cmu.edu), NSF EIA-0196217",
    }
    return Scenario(poses[0], poses[1], dims[0], dims[1], float(fps), label, phase, sig[0], sig[1], SIGNAL_NAMES, meta)
