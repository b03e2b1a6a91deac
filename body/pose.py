"""Pose parameterisation: one flat vector of 28 degrees of freedom per body.

World frame: metres, Y up, ground plane y = 0. At yaw 0 the body faces +Z (towards a camera
placed at +Z looking back towards -Z); the person's own left is then +X.

Layout of a pose vector ``P`` (angles in radians; "left" is always the person's own left)::

    idx name              positive means
     0  root_x            pelvis root (mid-point of the hip joints) position, metres
     1  root_y            pelvis height above the ground, metres
     2  root_z
     3  root_yaw          turn towards own left (about world +Y); 0 faces +Z; wraps to [-pi, pi)
     4  root_pitch        lean the whole body forward
     5  root_roll         lean the whole body towards own left
     6  torso_flex        bend the trunk forward (about the pelvis)
     7  torso_lateral     bend the trunk towards own left
     8  torso_twist       twist the shoulders towards own left
     9  head_nod          chin down (nod forward), about the neck joint
    10  head_tilt         ear towards own left shoulder
    11  head_turn         look towards own left
    12  l_shoulder_flex   raise the arm forward (pi/2: pointing forward)
    13  l_shoulder_abd    raise the arm sideways, away from the body (pi/2: horizontal)
    14  l_shoulder_rot    internal rotation about the upper-arm axis
    15  l_elbow_flex      bend the elbow (0: straight)
    16-19 r_shoulder_flex, r_shoulder_abd, r_shoulder_rot, r_elbow_flex   (mirror of the left)
    20  l_hip_flex        raise the thigh forward
    21  l_hip_abd         move the leg sideways, away from the body
    22  l_hip_rot         internal rotation about the thigh axis (toes inwards)
    23  l_knee_flex       bend the knee (0: straight), shin goes backwards
    24-27 r_hip_flex, r_hip_abd, r_hip_rot, r_knee_flex                    (mirror of the left)

All angles zero is standing straight with arms hanging down along the body. The exact rotation
matrices are in ``counterpart.body.kinematics``.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.skeleton import DEFAULT_DIMS, BodyDims

DOF_NAMES: tuple[str, ...] = (
    "root_x",
    "root_y",
    "root_z",
    "root_yaw",
    "root_pitch",
    "root_roll",
    "torso_flex",
    "torso_lateral",
    "torso_twist",
    "head_nod",
    "head_tilt",
    "head_turn",
    "l_shoulder_flex",
    "l_shoulder_abd",
    "l_shoulder_rot",
    "l_elbow_flex",
    "r_shoulder_flex",
    "r_shoulder_abd",
    "r_shoulder_rot",
    "r_elbow_flex",
    "l_hip_flex",
    "l_hip_abd",
    "l_hip_rot",
    "l_knee_flex",
    "r_hip_flex",
    "r_hip_abd",
    "r_hip_rot",
    "r_knee_flex",
)
DOF: int = len(DOF_NAMES)
DOF_INDEX: dict[str, int] = {n: i for i, n in enumerate(DOF_NAMES)}

# Index slices for groups other modules tend to need.
ROOT_POS = slice(0, 3)
ROOT_ROT = slice(3, 6)
JOINT_ANGLES = slice(6, DOF)
YAW = DOF_INDEX["root_yaw"]

_LIMITS_DEG: dict[str, tuple[float, float]] = {
    "root_pitch": (-30, 80),
    "root_roll": (-30, 30),
    "torso_flex": (-30, 90),
    "torso_lateral": (-40, 40),
    "torso_twist": (-50, 50),
    "head_nod": (-50, 60),
    "head_tilt": (-40, 40),
    "head_turn": (-80, 80),
    "shoulder_flex": (-60, 180),
    "shoulder_abd": (-20, 180),
    "shoulder_rot": (-90, 90),
    "elbow_flex": (0, 150),
    "hip_flex": (-30, 120),
    "hip_abd": (-25, 60),
    "hip_rot": (-40, 40),
    "knee_flex": (0, 150),
}


def _limits() -> tuple[np.ndarray, np.ndarray]:
    lo = np.empty(DOF)
    hi = np.empty(DOF)
    for i, name in enumerate(DOF_NAMES):
        if name in ("root_x", "root_z"):
            lo[i], hi[i] = -20.0, 20.0
        elif name == "root_y":
            lo[i], hi[i] = 0.2, 2.5
        elif name == "root_yaw":
            lo[i], hi[i] = -np.pi, np.pi
        else:
            key = name if name in _LIMITS_DEG else name[2:]
            lo[i], hi[i] = np.deg2rad(_LIMITS_DEG[key])
    lo.setflags(write=False)
    hi.setflags(write=False)
    return lo, hi


# (DOF,) lower and upper limits: metres for root_x/y/z, radians for the rest.
LOWER, UPPER = _limits()


def _check(P: np.ndarray) -> np.ndarray:
    P = np.asarray(P, dtype=np.float64)
    if P.shape[-1:] != (DOF,):
        raise ValueError(f"pose array has shape {P.shape}; expected (..., {DOF}) (see DOF_NAMES)")
    return P


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angles wrapped into [-pi, pi).

    Parameters
    ----------
    a : array_like
        Angles, radians.

    Returns
    -------
    ndarray
        The angles in [-pi, pi), radians, of the shape of ``a``.
    """
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def clip_to_limits(P: np.ndarray) -> np.ndarray:
    """Clip poses into [LOWER, UPPER]; the yaw is wrapped, not clipped.

    Parameters
    ----------
    P : ndarray of shape (..., DOF)
        Pose vectors (metres for root_x/y/z, radians for the rest).

    Returns
    -------
    ndarray of shape (..., DOF), dtype float64
        A clipped copy.

    Raises
    ------
    ValueError
        If the last axis of ``P`` is not of length ``DOF``.
    """
    P = _check(P)
    out = np.clip(P, LOWER, UPPER)
    out[..., YAW] = wrap_angle(P[..., YAW])
    return out


def within_limits(P: np.ndarray) -> np.ndarray:
    """Where every DOF lies inside [LOWER, UPPER] (a finite yaw always does).

    Parameters
    ----------
    P : ndarray of shape (..., DOF)
        Pose vectors.

    Returns
    -------
    ndarray of shape (...), dtype bool
        True where the pose is within its limits.

    Raises
    ------
    ValueError
        If the last axis of ``P`` is not of length ``DOF``.
    """
    P = _check(P)
    ok = (P >= LOWER) & (P <= UPPER)
    ok[..., YAW] = np.isfinite(P[..., YAW])
    return ok.all(axis=-1)


def neutral_pose(dims: BodyDims = DEFAULT_DIMS, x: float = 0.0, z: float = 0.0, yaw: float = 0.0) -> np.ndarray:
    """Relaxed standing pose: feet on y = 0, arms slightly away from the body, elbows slightly bent.

    Parameters
    ----------
    dims : BodyDims, default=DEFAULT_DIMS
        Body dimensions (the pelvis height is ``dims.hip_height``).
    x, z : float, default=0.0
        Where the pelvis stands on the ground, metres.
    yaw : float, default=0.0
        Rotation of the facing from +Z, radians.

    Returns
    -------
    ndarray of shape (DOF,)
        The pose vector.
    """
    P = np.zeros(DOF)
    P[DOF_INDEX["root_x"]] = x
    P[DOF_INDEX["root_y"]] = dims.hip_height
    P[DOF_INDEX["root_z"]] = z
    P[YAW] = wrap_angle(yaw)
    for side in ("l", "r"):
        P[DOF_INDEX[f"{side}_shoulder_abd"]] = np.deg2rad(10)
        P[DOF_INDEX[f"{side}_elbow_flex"]] = np.deg2rad(10)
    return P
