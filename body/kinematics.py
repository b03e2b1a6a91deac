"""Forward kinematics of the 14-joint body, vectorised over N poses.

Conventions (see also ``body.pose``): world frame in metres, Y up, ground y = 0. The body frame
has x = the person's own left, y = up, z = forward; at yaw 0 it coincides with the world frame,
so the body faces +Z (towards a camera at +Z looking towards -Z) and its left is +X.

With ``Rx, Ry, Rz`` the usual right-handed rotations about the frame axes (column vectors), the
chain is (P = pose vector, names from ``body.pose.DOF_NAMES``)::

    R_pelvis   = Ry(root_yaw) Rx(root_pitch) Rz(-root_roll)
    R_torso    = R_pelvis Ry(torso_twist) Rx(torso_flex) Rz(-torso_lateral)
    R_head     = R_torso  Ry(head_turn)   Rx(head_nod)   Rz(-head_tilt)
    R_l_uarm   = R_torso  Rx(-l_shoulder_flex) Rz(+l_shoulder_abd) Ry(-l_shoulder_rot)
    R_r_uarm   = R_torso  Rx(-r_shoulder_flex) Rz(-r_shoulder_abd) Ry(+r_shoulder_rot)
    R_s_farm   = R_s_uarm Rx(-s_elbow_flex)
    R_l_thigh  = R_pelvis Rx(-l_hip_flex) Rz(+l_hip_abd) Ry(-l_hip_rot)
    R_r_thigh  = R_pelvis Rx(-r_hip_flex) Rz(-r_hip_abd) Ry(+r_hip_rot)
    R_s_shin   = R_s_thigh Rx(+s_knee_flex)

and the points (d = BodyDims, s = +1 for left, -1 for right)::

    pelvis   = (root_x, root_y, root_z)
    s_hip    = pelvis + R_pelvis (s d.hip_width/2, 0, 0)
    s_knee   = s_hip + R_s_thigh (0, -d.thigh, 0);  s_ankle = s_knee + R_s_shin (0, -d.shin, 0)
    s_toe    = s_ankle + R_s_shin (0, -(d.ankle_height - d.r_toe), d.foot_length)
    neck     = pelvis + R_torso (0, d.torso_length, 0)
    s_shoulder = neck + R_torso (s d.shoulder_width/2, -d.shoulder_drop, 0)
    s_elbow  = s_shoulder + R_s_uarm (0, -d.upper_arm, 0)
    s_wrist  = s_elbow + R_s_farm (0, -d.forearm, 0); s_hand_end = s_wrist + R_s_farm (0, -d.hand_length, 0)
    head     = neck + R_head (0, d.neck_to_head, 0); chin/crown = head -/+ R_head (0, d.head_half_height, 0)
    chest    = neck - R_torso (0, d.chest_drop, 0); torso_bottom = pelvis - R_torso (0, d.torso_bottom_drop, 0)

Every function is vectorised over the leading N axis (no Python loop over poses).
"""

from __future__ import annotations

import numpy as np

from body.pose import DOF, DOF_INDEX
from body.skeleton import (
    ANCHOR_INDEX, ANCHORS, DEFAULT_DIMS, N_JOINTS, SEGMENT_ANCHORS, BodyDims,
)


def rot_x(a: np.ndarray) -> np.ndarray:
    """(N,) radians -> (N, 3, 3) right-handed rotations about X."""
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack([o, z, z, z, c, -s, z, s, c], axis=-1).reshape(*np.shape(a), 3, 3)


def rot_y(a: np.ndarray) -> np.ndarray:
    """(N,) radians -> (N, 3, 3) right-handed rotations about Y."""
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack([c, z, s, z, o, z, -s, z, c], axis=-1).reshape(*np.shape(a), 3, 3)


def rot_z(a: np.ndarray) -> np.ndarray:
    """(N,) radians -> (N, 3, 3) right-handed rotations about Z."""
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack([c, -s, z, s, c, z, z, z, o], axis=-1).reshape(*np.shape(a), 3, 3)


def _as_poses(P: np.ndarray) -> np.ndarray:
    P = np.asarray(P, dtype=np.float64)
    if P.ndim == 1:
        P = P[None]
    if P.ndim != 2 or P.shape[1] != DOF:
        raise ValueError(f"poses have shape {P.shape}; expected (N, {DOF}) or ({DOF},)")
    return P


def _apply(R: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(N,3,3) x (3,) -> (N,3)."""
    return R @ np.asarray(v, dtype=np.float64)


def frames(P: np.ndarray, dims: BodyDims = DEFAULT_DIMS) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """All anchor points and segment frames.

    Args:
        P: (N, DOF) or (DOF,) poses.
        dims: body dimensions.
    Returns:
        points: (N, len(ANCHORS), 3) metres, the 14 joints then ``EXTRA_ANCHORS``.
        rotations: name -> (N, 3, 3) world rotation of each body part's frame
            ("pelvis", "torso", "head", "l_upper_arm", "l_forearm", "r_...", "l_thigh",
            "l_shin", "r_...").
    """
    P = _as_poses(P)
    d = dims
    g = {name: P[:, i] for name, i in DOF_INDEX.items()}
    R = {}
    R["pelvis"] = rot_y(g["root_yaw"]) @ rot_x(g["root_pitch"]) @ rot_z(-g["root_roll"])
    R["torso"] = R["pelvis"] @ rot_y(g["torso_twist"]) @ rot_x(g["torso_flex"]) @ rot_z(-g["torso_lateral"])
    R["head"] = R["torso"] @ rot_y(g["head_turn"]) @ rot_x(g["head_nod"]) @ rot_z(-g["head_tilt"])

    pts = np.empty((P.shape[0], len(ANCHORS), 3))
    ix = ANCHOR_INDEX
    pelvis = P[:, 0:3]
    pts[:, ix["pelvis"]] = pelvis
    neck = pelvis + _apply(R["torso"], (0.0, d.torso_length, 0.0))
    pts[:, ix["neck"]] = neck
    pts[:, ix["chest"]] = neck - _apply(R["torso"], (0.0, d.chest_drop, 0.0))
    pts[:, ix["torso_bottom"]] = pelvis - _apply(R["torso"], (0.0, d.torso_bottom_drop, 0.0))
    head = neck + _apply(R["head"], (0.0, d.neck_to_head, 0.0))
    pts[:, ix["head"]] = head
    half = _apply(R["head"], (0.0, d.head_half_height, 0.0))
    pts[:, ix["chin"]] = head - half
    pts[:, ix["crown"]] = head + half

    for s, sign in (("l", 1.0), ("r", -1.0)):
        # Arms: mirrored so that every positive angle means the same movement on both sides.
        ua = (R["torso"] @ rot_x(-g[f"{s}_shoulder_flex"]) @ rot_z(sign * g[f"{s}_shoulder_abd"])
              @ rot_y(-sign * g[f"{s}_shoulder_rot"]))
        fa = ua @ rot_x(-g[f"{s}_elbow_flex"])
        R[f"{s}_upper_arm"], R[f"{s}_forearm"] = ua, fa
        sh = neck + _apply(R["torso"], (sign * d.shoulder_width / 2, -d.shoulder_drop, 0.0))
        el = sh + _apply(ua, (0.0, -d.upper_arm, 0.0))
        wr = el + _apply(fa, (0.0, -d.forearm, 0.0))
        pts[:, ix[f"{s}_shoulder"]] = sh
        pts[:, ix[f"{s}_elbow"]] = el
        pts[:, ix[f"{s}_wrist"]] = wr
        pts[:, ix[f"{s}_hand_end"]] = wr + _apply(fa, (0.0, -d.hand_length, 0.0))

        th = (R["pelvis"] @ rot_x(-g[f"{s}_hip_flex"]) @ rot_z(sign * g[f"{s}_hip_abd"])
              @ rot_y(-sign * g[f"{s}_hip_rot"]))
        sn = th @ rot_x(g[f"{s}_knee_flex"])
        R[f"{s}_thigh"], R[f"{s}_shin"] = th, sn
        hp = pelvis + _apply(R["pelvis"], (sign * d.hip_width / 2, 0.0, 0.0))
        kn = hp + _apply(th, (0.0, -d.thigh, 0.0))
        an = kn + _apply(sn, (0.0, -d.shin, 0.0))
        pts[:, ix[f"{s}_hip"]] = hp
        pts[:, ix[f"{s}_knee"]] = kn
        pts[:, ix[f"{s}_ankle"]] = an
        pts[:, ix[f"{s}_toe"]] = an + _apply(sn, (0.0, -(d.ankle_height - d.r_toe), d.foot_length))
    return pts, R


def forward_kinematics(P: np.ndarray, dims: BodyDims = DEFAULT_DIMS) -> np.ndarray:
    """Joint positions.

    Args:
        P: (N, DOF) poses (a single (DOF,) pose is treated as N = 1).
        dims: body dimensions.
    Returns:
        (N, 14, 3) float64 world positions in metres, in ``body.skeleton.JOINTS`` order.
    """
    return frames(P, dims)[0][:, :N_JOINTS]


def cone_endpoints(P: np.ndarray, dims: BodyDims = DEFAULT_DIMS) -> tuple[np.ndarray, np.ndarray]:
    """The 16 truncated cones of N poses.

    Returns:
        ends: (N, 16, 2, 3) metres, start and end centre of each cone in ``SEGMENTS`` order.
        radii: (16, 2) metres, the matching radii (same for every pose).
    """
    pts = frames(P, dims)[0]
    return pts[:, SEGMENT_ANCHORS], dims.segment_radii()


def lowest_point(P: np.ndarray, dims: BodyDims = DEFAULT_DIMS) -> np.ndarray:
    """(N,) lowest y (metres) of the cone surfaces of each pose: rim bottoms of every cone.

    The exact lowest point of a circular rim of radius r around axis a is at
    ``y_centre - r * sqrt(1 - a_y**2)``.
    """
    ends, radii = cone_endpoints(P, dims)
    axis = ends[:, :, 1] - ends[:, :, 0]
    n = np.linalg.norm(axis, axis=-1, keepdims=True)
    ay = np.where(n[..., 0] > 0, axis[..., 1] / np.maximum(n[..., 0], 1e-12), 1.0)
    drop = radii[None] * np.sqrt(np.clip(1.0 - ay**2, 0.0, 1.0))[..., None]
    return (ends[..., 1] - drop).min(axis=(1, 2))
