"""Planted two-person interactions for the responder tests (built with the real body model)."""

from __future__ import annotations

import numpy as np

from counterpart.body.camera import Camera
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import DOF_INDEX, neutral_pose
from counterpart.body.trajectory import TwoPersonTrajectory


def smooth(rng: np.random.Generator, T: int, lo: float, hi: float, knots: int = 6) -> np.ndarray:
    """A smooth random curve (T,) between lo and hi."""
    k = rng.uniform(lo, hi, knots)
    return np.interp(np.linspace(0, knots - 1, T), np.arange(knots), k)


def planted_pair(seed: int, T: int = 120, fps: float = 25.0) -> TwoPersonTrajectory:
    """A raises the right arm along a random smooth curve a(t); B, facing A 1.3 m away, answers by
    raising the LEFT arm by a(t) and bending forward by a(t)/4. The pair stands at a random place
    with a random heading, so only an actor-centred model can generalise across seeds.
    """
    rng = np.random.default_rng(seed)
    a = smooth(rng, T, 0.0, 2.2)
    x0, z0, yaw = rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.0), rng.uniform(-np.pi, np.pi)
    fwd = np.array([np.sin(yaw), np.cos(yaw)])
    PA = np.tile(neutral_pose(x=x0, z=z0, yaw=yaw), (T, 1))
    PB = np.tile(neutral_pose(x=x0 + 1.3 * fwd[0], z=z0 + 1.3 * fwd[1], yaw=yaw + np.pi), (T, 1))
    PA[:, DOF_INDEX["r_shoulder_flex"]] = a
    PB[:, DOF_INDEX["l_shoulder_flex"]] = a
    PB[:, DOF_INDEX["torso_flex"]] = a / 4
    return TwoPersonTrajectory(a=forward_kinematics(PA), b=forward_kinematics(PB), fps=fps, label="planted")


def mpjpe_mm(x: np.ndarray, y: np.ndarray) -> float:
    """Mean per-joint position error in millimetres of (T, 14, 3) metres arrays."""
    return float(np.linalg.norm(np.asarray(x) - np.asarray(y), axis=-1).mean() * 1e3)


#: the camera of the staging tests: the simulator's default, 320x240
CAM = Camera.look_at([0.0, 1.6, 4.0], [0.0, 0.9, 0.0], 55.0, 320, 240)


def box_overlap(P: np.ndarray, box: tuple[float, float, float, float]) -> tuple[float, float]:
    """Intersection over union of joints P's (n, 3) box in ``CAM`` with ``box`` ``(x, y, w, h)``, pixels,
    and the share of P's box inside it.
    """
    q = CAM.project(P)
    a = np.r_[q.min(0), q.max(0)]
    w = max(0.0, min(a[2], box[0] + box[2]) - max(a[0], box[0]))
    h = max(0.0, min(a[3], box[1] + box[3]) - max(a[1], box[1]))
    own = (a[2] - a[0]) * (a[3] - a[1])
    return w * h / (own + box[2] * box[3] - w * h), w * h / own
