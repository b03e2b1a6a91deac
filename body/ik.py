"""Inverse kinematics: 14 joint positions -> pose vectors, and body dimensions from joints.

Closed-form, vectorised over N frames. Used to turn motion capture (``counterpart.body.bvh``) or any
``TwoPersonTrajectory`` into pose vectors (``counterpart.body.pose``) for learning dynamics priors and for
re-rendering captured motion with the cone model.

The 14 joints do not determine every DOF, so the solver fixes what it cannot see:

* pelvis pitch is 0: the hip line gives yaw and roll only; any forward lean of the trunk is
  put into ``torso_flex``;
* ``head_turn`` is 0 (one head point gives nod and tilt only);
* the upper-arm / thigh axial rotation comes from the forearm / shin direction and is set to 0
  where the elbow / knee is nearly straight (it is undefined there);
* the torso frame is the pelvis->neck axis with the shoulder line as its left axis; shoulders
  of real people move relative to the neck (clavicles), ours do not, so arm positions are
  matched in direction, not exactly in place.

The decompositions invert the chain in ``counterpart.body.kinematics``:
``Ry(a) Rx(b) Rz(c)``: b = asin(-R12), a = atan2(R02, R22), c = atan2(R10, R11);
limb direction ``Rx(-f) Rz(p) (0,-1,0) = (sin p, -cos p cos f, cos p sin f)``.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.kinematics import cross3, norm3, rot_x, rot_z
from counterpart.body.pose import DOF, DOF_INDEX
from counterpart.body.skeleton import DEFAULT_DIMS, JOINT_INDEX, BodyDims

J = JOINT_INDEX


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(norm3(v), 1e-12)


def _frame(left: np.ndarray, up: np.ndarray) -> np.ndarray:
    """(N,3) left and up hints -> (N,3,3) rotation with columns (left, up, forward), up exact."""
    y = _unit(up)
    z = _unit(cross3(left, y))
    x = cross3(y, z)
    return np.stack([x, y, z], axis=-1)


def _yxz(R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angles (a, b, c) with R = Ry(a) Rx(b) Rz(c)."""
    b = np.arcsin(np.clip(-R[:, 1, 2], -1.0, 1.0))
    a = np.arctan2(R[:, 0, 2], R[:, 2, 2])
    c = np.arctan2(R[:, 1, 0], R[:, 1, 1])
    return a, b, c


def _limb(
    R_parent: np.ndarray,
    top: np.ndarray,
    mid: np.ndarray,
    end: np.ndarray,
    sign: float | np.ndarray,
    knee: bool | np.ndarray,
) -> tuple[np.ndarray, ...]:
    """flex, abd, rot, bend of a limb top->mid->end under parent rotation (N,3,3); ``sign`` and
    ``knee`` per row (N,) or for all rows.
    """
    u = np.einsum("nji,nj->ni", R_parent, _unit(mid - top))  # parent frame
    p = np.arcsin(np.clip(u[:, 0], -1.0, 1.0))
    f = np.arctan2(u[:, 2], -u[:, 1])
    R_a = R_parent @ rot_x(-f) @ rot_z(p)
    w = np.einsum("nji,nj->ni", R_a, _unit(end - mid))
    bend = np.arccos(np.clip(-w[:, 1], -1.0, 1.0))
    beta = np.where(knee, np.arctan2(-w[:, 0], -w[:, 2]), np.arctan2(w[:, 0], w[:, 2]))
    beta = np.where(np.sin(bend) > 1e-3, beta, 0.0)
    return f, sign * p, -sign * beta, bend


def inverse_kinematics(X: np.ndarray) -> np.ndarray:
    """Pose vectors from joint positions.

    Args:
        X: (N, 14, 3) or (14, 3) joint positions, metres, ``JOINTS`` order.

    Returns
    -------
        (N, DOF) poses; ``forward_kinematics(P, dims_from_joints(X))`` reproduces the limb
        directions of X (see the module docstring for what is fixed).
    """
    X = np.asarray(X, dtype=np.float64)
    if X.ndim == 2:
        X = X[None]
    if X.ndim != 3 or X.shape[1:] != (14, 3):
        raise ValueError(f"joints have shape {X.shape}; expected (N, 14, 3) metres")
    N = X.shape[0]
    P = np.zeros((N, DOF))
    g = DOF_INDEX
    pelvis = 0.5 * (X[:, J["l_hip"]] + X[:, J["r_hip"]])
    P[:, 0:3] = pelvis

    hip_line = X[:, J["l_hip"]] - X[:, J["r_hip"]]
    # Pelvis: yaw from the hip line, roll from its tilt, no pitch.
    yaw = np.arctan2(-hip_line[:, 2], hip_line[:, 0])
    roll = np.arctan2(-hip_line[:, 1], np.hypot(hip_line[:, 0], hip_line[:, 2]))
    P[:, g["root_yaw"]], P[:, g["root_roll"]] = yaw, roll
    c, s = np.cos(yaw), np.sin(yaw)
    Ry = np.zeros((N, 3, 3))
    Ry[:, 0, 0], Ry[:, 0, 2], Ry[:, 1, 1], Ry[:, 2, 0], Ry[:, 2, 2] = c, s, 1.0, -s, c
    R_pelvis = Ry @ rot_z(-roll)

    R_torso = _frame(X[:, J["l_shoulder"]] - X[:, J["r_shoulder"]], X[:, J["neck"]] - pelvis)
    twist, flex, minus_lat = _yxz(np.swapaxes(R_pelvis, 1, 2) @ R_torso)
    P[:, g["torso_twist"]], P[:, g["torso_flex"]], P[:, g["torso_lateral"]] = twist, flex, -minus_lat

    d = np.einsum("nji,nj->ni", R_torso, _unit(X[:, J["head"]] - X[:, J["neck"]]))
    P[:, g["head_tilt"]] = np.arcsin(np.clip(d[:, 0], -1.0, 1.0))
    P[:, g["head_nod"]] = np.arctan2(d[:, 2], d[:, 1])

    # the four limbs as one batch of 4N rows (left arms, right arms, left legs, right legs), as
    # kinematics._chain does: the same operations on every row, a quarter of the calls (the
    # renderer fits every partner it draws, one at a time)
    limbs = (("l", "shoulder", "elbow", "wrist"), ("r", "shoulder", "elbow", "wrist"))
    limbs += (("l", "hip", "knee", "ankle"), ("r", "hip", "knee", "ankle"))
    top, mid, end = (np.concatenate([X[:, J[f"{lb[0]}_{lb[k]}"]] for lb in limbs]) for k in (1, 2, 3))
    vals = _limb(
        np.concatenate([R_torso, R_torso, R_pelvis, R_pelvis]),
        top,
        mid,
        end,
        np.repeat([1.0, -1.0, 1.0, -1.0], N),
        np.repeat([False, False, True, True], N),
    )
    names = (("shoulder_flex", "shoulder_abd", "shoulder_rot", "elbow_flex"),) * 2
    names += (("hip_flex", "hip_abd", "hip_rot", "knee_flex"),) * 2
    for k, (lb, dofs) in enumerate(zip(limbs, names)):
        for name, v in zip(dofs, vals):
            P[:, g[f"{lb[0]}_{name}"]] = v[k * N : (k + 1) * N]
    return P


#: the joint pairs whose distance :func:`dims_from_joints` measures
_LENGTHS = (
    ("l_hip", "l_knee"),
    ("r_hip", "r_knee"),
    ("l_knee", "l_ankle"),
    ("r_knee", "r_ankle"),
    ("l_hip", "r_hip"),
    ("l_shoulder", "r_shoulder"),
    ("neck", "head"),
    ("l_shoulder", "l_elbow"),
    ("r_shoulder", "r_elbow"),
    ("l_elbow", "l_wrist"),
    ("r_elbow", "r_wrist"),
)


#: (bone, 2) joint indices of ``_LENGTHS``
_LENGTH_ENDS = np.array([(J[a], J[b]) for a, b in _LENGTHS])
#: the fraction between the two values that ``np.percentile(values, 5)`` of two values takes (its
#: linear method's weight, as numpy computes it: the same bits, see :func:`_low_ankle`)
_P5_OF_TWO = float(np.percentile([0.0, 1.0], 5))


def _low_ankle(y: np.ndarray) -> float:
    """``np.percentile(y, 5)`` of the ankle heights (N, 2); of one frame, numpy's linear
    interpolation between its two values written out (the same operations on the same numbers:
    ``lo + (hi - lo) * t``), at a fraction of its cost: the renderer fits one frame at a time.
    """
    if y.shape[0] != 1:
        return float(np.percentile(y, 5))
    lo, hi = sorted(y[0].tolist())
    return lo + (hi - lo) * _P5_OF_TWO


def _median0(a: np.ndarray) -> np.ndarray:
    """The median over the first axis; of one frame, that frame's values as they are (which is what
    ``np.median`` returns for them, at a fraction of its cost: the renderer fits one frame at a time).
    """
    return a[0] if len(a) == 1 else np.median(a, axis=0)


def dims_from_joints(X: np.ndarray, base: BodyDims = DEFAULT_DIMS) -> BodyDims:
    """Body dimensions fitted to joint positions (median bone lengths over frames).

    Args:
        X: (N, 14, 3) metres.
        base: proportions for what the joints do not show (radii, hand, foot, head size),
            scaled by the ratio of the fitted leg length to the base leg length.

    Returns
    -------
        BodyDims whose ``height`` is the implied stature (ankle height + legs + torso + neck to
        head + half the head).
    """
    X = np.asarray(X, dtype=np.float64).reshape(-1, 14, 3)
    # every bone's median length over the frames in one call (per bone, the small numpy calls
    # cost more than the arithmetic: the renderer fits each partner it draws)
    ends = _LENGTH_ENDS
    med = _median0(norm3(X[:, ends[:, 0]] - X[:, ends[:, 1]])[..., 0])
    lengths = dict(zip(_LENGTHS, med.tolist()))

    def length(a: str, b: str) -> float:
        return lengths[a, b]

    thigh = 0.5 * (length("l_hip", "l_knee") + length("r_hip", "r_knee"))
    shin = 0.5 * (length("l_knee", "l_ankle") + length("r_knee", "r_ankle"))
    k = (thigh + shin) / (base.thigh + base.shin)
    out = base.scaled(base.height * k)
    pelvis = 0.5 * (X[:, J["l_hip"]] + X[:, J["r_hip"]])
    torso = float(_median0(norm3(X[:, J["neck"]] - pelvis)[..., 0]))
    # Ankles are lowest while the foot is planted; a low percentile ignores the swing phase.
    ankle = _low_ankle(X[:, [J["l_ankle"], J["r_ankle"]], 1])
    ankle = max(ankle, 0.5 * out.ankle_height)
    vals = dict(
        thigh=thigh,
        shin=shin,
        hip_width=length("l_hip", "r_hip"),
        torso_length=torso,
        shoulder_width=length("l_shoulder", "r_shoulder"),
        neck_to_head=length("neck", "head"),
        upper_arm=0.5 * (length("l_shoulder", "l_elbow") + length("r_shoulder", "r_elbow")),
        forearm=0.5 * (length("l_elbow", "l_wrist") + length("r_elbow", "r_wrist")),
        ankle_height=ankle,
    )
    sh = 0.5 * (X[:, J["l_shoulder"]] + X[:, J["r_shoulder"]])
    drop = float(_median0(np.einsum("ni,ni->n", X[:, J["neck"]] - sh, _unit(X[:, J["neck"]] - pelvis))))
    vals["shoulder_drop"] = max(drop, 0.0)
    vals["chest_drop"] = 0.5 * torso
    vals["height"] = ankle + shin + thigh + torso + vals["neck_to_head"] + out.head_half_height
    from dataclasses import replace

    return replace(out, **vals)
