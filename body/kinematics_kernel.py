"""Compiled forward kinematics of the anchor points (``kinematics.anchor_points``): the chain of
``counterpart.body.kinematics`` one pose at a time, in a loop numba compiles (the numpy chain's
few dozen array calls per batch dominated the tracker's likelihood at real-time particle counts).

A module of its own so that only the processes that compute anchor points import numba.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, inline="always")
def _kx(
    a0: tuple[float, float, float], a1: tuple[float, float, float], a2: tuple[float, float, float], c: float, s: float
) -> tuple:
    """``kinematics._rx`` of one pose's columns (3-tuples)."""
    return (
        a0,
        (a1[0] * c + a2[0] * s, a1[1] * c + a2[1] * s, a1[2] * c + a2[2] * s),
        (a2[0] * c - a1[0] * s, a2[1] * c - a1[1] * s, a2[2] * c - a1[2] * s),
    )


@numba.njit(cache=True, nogil=True, inline="always")
def _ky(
    a0: tuple[float, float, float], a1: tuple[float, float, float], a2: tuple[float, float, float], c: float, s: float
) -> tuple:
    """``_ry`` of one pose's columns."""
    return (
        (a0[0] * c - a2[0] * s, a0[1] * c - a2[1] * s, a0[2] * c - a2[2] * s),
        a1,
        (a0[0] * s + a2[0] * c, a0[1] * s + a2[1] * c, a0[2] * s + a2[2] * c),
    )


@numba.njit(cache=True, nogil=True, inline="always")
def _kz(
    a0: tuple[float, float, float], a1: tuple[float, float, float], a2: tuple[float, float, float], c: float, s: float
) -> tuple:
    """``_rz`` of one pose's columns."""
    return (
        (a0[0] * c + a1[0] * s, a0[1] * c + a1[1] * s, a0[2] * c + a1[2] * s),
        (a1[0] * c - a0[0] * s, a1[1] * c - a0[1] * s, a1[2] * c - a0[2] * s),
        a2,
    )


@numba.njit(cache=True, nogil=True)
def anchor_kernel(
    P: np.ndarray,
    C: np.ndarray,
    S: np.ndarray,
    lengths: np.ndarray,
    row: np.ndarray,
    ix: np.ndarray,
    limb_dof0: int,
    at: np.ndarray,
    limb_at: np.ndarray,
    out: np.ndarray,
) -> None:
    """The chain of the module docstring for the anchor points alone, one pose at a time.

    The same operations in the same order as ``kinematics._chain(..., rotations=False)`` (float64, each
    rotation carried as its three columns), so the same numbers to the last bit.

    Parameters
    ----------
    P : ndarray of shape (N, DOF), dtype float64
        Poses, metres and radians.
    C, S : ndarray of shape (N, DOF), dtype float64
        ``np.cos(P)``, ``np.sin(P)`` (numpy's, so that they are numpy's to the last bit).
    lengths : ndarray of shape (R, len(_LENGTHS)), dtype float64
        Rows of body lengths, metres, in the order of ``kinematics._LENGTHS``.
    row : ndarray of shape (N,), dtype int64
        Each pose's row of ``lengths``.
    ix : ndarray of shape (len(_KERNEL_DOFS),), dtype int64
        Where the DOFs of ``kinematics._KERNEL_DOFS`` are in a pose.
    limb_dof0 : int
        The first limb DOF (left shoulder flex; four per limb: arms then legs, left then right).
    at : ndarray of shape (len(_KERNEL_ANCHORS),), dtype int64
        The anchors of ``kinematics._KERNEL_ANCHORS``.
    limb_at : ndarray of shape (16,), dtype int64
        ``kinematics._LIMB_ANCHORS``: each limb's four anchors from its root outwards.
    out : ndarray of shape (N, A, 3), dtype float64
        Filled with the anchor points, metres.
    """
    zero, one = 0.0, 1.0
    for n in range(P.shape[0]):
        d = lengths[row[n]]
        ankle_h, shin, thigh, hip_w, torso_l = d[0], d[1], d[2], d[3], d[4]
        sh_w, sh_drop, neck_head, head_half, uarm = d[5], d[6], d[7], d[8], d[9]
        farm, hand, foot, chest_drop, tb_drop, r_toe = d[10], d[11], d[12], d[13], d[14], d[15]
        c, s = C[n, ix[0]], S[n, ix[0]]
        pel = _kx((c, zero, -s), (zero, one, zero), (s, zero, c), C[n, ix[1]], S[n, ix[1]])
        pel = _kz(pel[0], pel[1], pel[2], C[n, ix[2]], -S[n, ix[2]])
        tor = _ky(pel[0], pel[1], pel[2], C[n, ix[3]], S[n, ix[3]])
        tor = _kx(tor[0], tor[1], tor[2], C[n, ix[4]], S[n, ix[4]])
        tor = _kz(tor[0], tor[1], tor[2], C[n, ix[5]], -S[n, ix[5]])
        h0, h1, h2 = _ky(tor[0], tor[1], tor[2], C[n, ix[6]], S[n, ix[6]])
        c, s = C[n, ix[7]], S[n, ix[7]]
        h1 = (h1[0] * c + h2[0] * s, h1[1] * c + h2[1] * s, h1[2] * c + h2[2] * s)
        c, s = C[n, ix[8]], -S[n, ix[8]]
        up = (h1[0] * c - h0[0] * s, h1[1] * c - h0[1] * s, h1[2] * c - h0[2] * s)
        t1 = tor[1]
        for k in range(3):
            pelvis = P[n, k]
            neck = pelvis + torso_l * t1[k]
            head = neck + neck_head * up[k]
            half = head_half * up[k]
            out[n, at[0], k] = pelvis
            out[n, at[1], k] = neck
            out[n, at[2], k] = neck - chest_drop * t1[k]
            out[n, at[3], k] = pelvis - tb_drop * t1[k]
            out[n, at[4], k] = head
            out[n, at[5], k] = head - half
            out[n, at[6], k] = head + half
        for limb in range(4):  # left arm, right arm, left leg, right leg
            sign = 1.0 if limb % 2 == 0 else -1.0
            arm = limb < 2
            root = tor if arm else pel
            q = limb_dof0 + 4 * limb
            c1, c2, c3, c4 = C[n, q], C[n, q + 1], C[n, q + 2], C[n, q + 3]
            s1, s2, s3, s4 = S[n, q], S[n, q + 1], S[n, q + 2], S[n, q + 3]
            a = _kx(root[0], root[1], root[2], c1, -s1)
            a = _kz(a[0], a[1], a[2], c2, sign * s2)
            s3 = -sign * s3
            u1, u2 = (
                a[1],
                (
                    a[0][0] * s3 + a[2][0] * c3,
                    a[0][1] * s3 + a[2][1] * c3,
                    a[0][2] * s3 + a[2][2] * c3,
                ),
            )
            s4 = (-1.0 if arm else 1.0) * s4  # the elbow bends with -sin, the knee with +sin
            l1 = (u1[0] * c4 + u2[0] * s4, u1[1] * c4 + u2[1] * s4, u1[2] * c4 + u2[2] * s4)
            l2 = (u2[0] * c4 - u1[0] * s4, u2[1] * c4 - u1[1] * s4, u2[2] * c4 - u1[2] * s4)
            bone1, bone2 = (uarm, farm) if arm else (thigh, shin)
            r0, r1 = root[0], root[1]
            for k in range(3):
                if arm:
                    j0 = (out[n, at[1], k] + sign * sh_w / 2 * r0[k]) - sh_drop * r1[k]
                else:
                    j0 = out[n, at[0], k] + sign * hip_w / 2 * r0[k]
                j1 = j0 - bone1 * u1[k]
                j2 = j1 - bone2 * l1[k]
                j3 = j2 - hand * l1[k] if arm else (j2 - (ankle_h - r_toe) * l1[k]) + foot * l2[k]
                out[n, limb_at[4 * limb], k] = j0
                out[n, limb_at[4 * limb + 1], k] = j1
                out[n, limb_at[4 * limb + 2], k] = j2
                out[n, limb_at[4 * limb + 3], k] = j3


__all__ = ["anchor_kernel"]
