"""Fast anchor points of the body for the likelihood: ``body.kinematics.frames`` without the
rotation matrices' stacking.

Same chain and points as ``body.kinematics`` (see its docstring). A rotation is kept as its three
columns, each (N, 3); right-multiplying by an elementary rotation Rx/Ry/Rz(a) mixes two columns
with cos a and sin a, and R (0, L, 0) is just L times the middle column. This avoids building
(N, 3, 3) matrices by ``np.stack`` and multiplying them batch by batch, which dominated the cost
of a likelihood evaluation at the tracker's N = 256.
"""
from __future__ import annotations

import numpy as np

from body.pose import DOF, DOF_INDEX
from body.skeleton import ANCHOR_INDEX, ANCHORS, DEFAULT_DIMS, BodyDims

_I = DOF_INDEX


def _rx(R, c, s):
    a0, a1, a2 = R
    return a0, a1 * c + a2 * s, a2 * c - a1 * s


def _ry(R, c, s):
    a0, a1, a2 = R
    return a0 * c - a2 * s, a1, a0 * s + a2 * c


def _rz(R, c, s):
    a0, a1, a2 = R
    return a0 * c + a1 * s, a1 * c - a0 * s, a2


def anchor_points(P: np.ndarray, dims: BodyDims = DEFAULT_DIMS) -> np.ndarray:
    """(N, 28) poses -> (N, len(ANCHORS), 3) anchor points in metres, equal (to rounding) to
    ``body.kinematics.frames(P, dims)[0]``."""
    P = np.asarray(P, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != DOF:
        raise ValueError(f"poses have shape {P.shape}; expected (N, {DOF})")
    d = dims
    C = np.cos(P)[:, :, None]                                     # (N, DOF, 1)
    S = np.sin(P)[:, :, None]
    cs = {n: (C[:, i], S[:, i]) for n, i in _I.items()}

    def neg(n):
        c, s = cs[n]
        return c, -s

    N = len(P)
    z = np.zeros((N, 1))
    c, s = cs["root_yaw"]
    pel = (np.concatenate([c, z, -s], 1), np.broadcast_to(np.array([0.0, 1.0, 0.0]), (N, 3)),
           np.concatenate([s, z, c], 1))
    pel = _rz(_rx(pel, *cs["root_pitch"]), *neg("root_roll"))
    tor = _rz(_rx(_ry(pel, *cs["torso_twist"]), *cs["torso_flex"]), *neg("torso_lateral"))
    hed = _rz(_rx(_ry(tor, *cs["head_turn"]), *cs["head_nod"]), *neg("head_tilt"))

    pts = np.empty((N, len(ANCHORS), 3))
    ix = ANCHOR_INDEX
    pelvis = P[:, 0:3]
    pts[:, ix["pelvis"]] = pelvis
    neck = pelvis + d.torso_length * tor[1]
    pts[:, ix["neck"]] = neck
    pts[:, ix["chest"]] = neck - d.chest_drop * tor[1]
    pts[:, ix["torso_bottom"]] = pelvis - d.torso_bottom_drop * tor[1]
    head = neck + d.neck_to_head * hed[1]
    pts[:, ix["head"]] = head
    half = d.head_half_height * hed[1]
    pts[:, ix["chin"]] = head - half
    pts[:, ix["crown"]] = head + half
    for sd, sign in (("l", 1.0), ("r", -1.0)):
        c, s = cs[f"{sd}_shoulder_abd"]
        cr, sr = cs[f"{sd}_shoulder_rot"]
        ua = _ry(_rz(_rx(tor, *neg(f"{sd}_shoulder_flex")), c, sign * s), cr, -sign * sr)
        fa = _rx(ua, *neg(f"{sd}_elbow_flex"))
        sh = neck + (sign * d.shoulder_width / 2) * tor[0] - d.shoulder_drop * tor[1]
        el = sh - d.upper_arm * ua[1]
        wr = el - d.forearm * fa[1]
        pts[:, ix[f"{sd}_shoulder"]] = sh
        pts[:, ix[f"{sd}_elbow"]] = el
        pts[:, ix[f"{sd}_wrist"]] = wr
        pts[:, ix[f"{sd}_hand_end"]] = wr - d.hand_length * fa[1]
        c, s = cs[f"{sd}_hip_abd"]
        cr, sr = cs[f"{sd}_hip_rot"]
        th = _ry(_rz(_rx(pel, *neg(f"{sd}_hip_flex")), c, sign * s), cr, -sign * sr)
        sn = _rx(th, *cs[f"{sd}_knee_flex"])
        hp = pelvis + (sign * d.hip_width / 2) * pel[0]
        kn = hp - d.thigh * th[1]
        an = kn - d.shin * sn[1]
        pts[:, ix[f"{sd}_hip"]] = hp
        pts[:, ix[f"{sd}_knee"]] = kn
        pts[:, ix[f"{sd}_ankle"]] = an
        pts[:, ix[f"{sd}_toe"]] = an - (d.ankle_height - d.r_toe) * sn[1] + d.foot_length * sn[2]
    return pts


__all__ = ["anchor_points"]
