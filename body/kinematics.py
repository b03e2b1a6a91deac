"""Forward kinematics of the 14-joint body, vectorised over N poses.

Conventions (see also ``counterpart.body.pose``): world frame in metres, Y up, ground y = 0. The body frame
has x = the person's own left, y = up, z = forward; at yaw 0 it coincides with the world frame,
so the body faces +Z (towards a camera at +Z looking towards -Z) and its left is +X.

With ``Rx, Ry, Rz`` the usual right-handed rotations about the frame axes (column vectors), the
chain is (P = pose vector, names from ``counterpart.body.pose.DOF_NAMES``)::

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

Every function is vectorised over the leading N axis (no Python loop over poses); ``anchor_points``,
which the tracker's likelihood calls many times a frame, runs the chain as a compiled loop over
the poses (``kinematics_kernel.anchor_kernel``, the numpy chain's numbers to the last bit).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from counterpart.body.pose import DOF, DOF_INDEX
from counterpart.body.skeleton import (
    ANCHOR_INDEX,
    ANCHORS,
    DEFAULT_DIMS,
    N_JOINTS,
    SEGMENT_ANCHORS,
    BodyDims,
)


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of 3-vectors: numpy's operations in numpy's order, so the same bits, without its
    axis handling, which costs more than the arithmetic on a body's few vectors (the renderer fits
    a body to every partner it draws).

    Parameters
    ----------
    a, b : ndarray of shape (..., 3)
        The vectors (broadcast against each other).

    Returns
    -------
    ndarray of shape (..., 3)
        ``a x b``.
    """
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def norm3(v: np.ndarray) -> np.ndarray:
    """``np.linalg.norm(v, axis=-1, keepdims=True)`` of 3-vectors: the squares added in the order
    numpy's reduction adds them, so the same bits, for less overhead.

    Parameters
    ----------
    v : ndarray of shape (..., 3)
        The vectors.

    Returns
    -------
    ndarray of shape (..., 1)
        Their lengths.
    """
    sq = v * v
    return np.sqrt(sq[..., 0] + sq[..., 1] + sq[..., 2])[..., None]


def rot_x(a: np.ndarray) -> np.ndarray:
    """(N,) radians -> (N, 3, 3) right-handed rotations about X.

    Parameters
    ----------
    a : ndarray of shape (N,)
        Angles, radians (any shape S gives shape S + (3, 3)).

    Returns
    -------
    ndarray of shape (N, 3, 3)
        The rotations.
    """
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack([o, z, z, z, c, -s, z, s, c], axis=-1).reshape(*np.shape(a), 3, 3)


def rot_y(a: np.ndarray) -> np.ndarray:
    """(N,) radians -> (N, 3, 3) right-handed rotations about Y.

    Parameters
    ----------
    a : ndarray of shape (N,)
        Angles, radians (any shape S gives shape S + (3, 3)).

    Returns
    -------
    ndarray of shape (N, 3, 3)
        The rotations.
    """
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack([c, z, s, z, o, z, -s, z, c], axis=-1).reshape(*np.shape(a), 3, 3)


def rot_z(a: np.ndarray) -> np.ndarray:
    """(N,) radians -> (N, 3, 3) right-handed rotations about Z.

    Parameters
    ----------
    a : ndarray of shape (N,)
        Angles, radians (any shape S gives shape S + (3, 3)).

    Returns
    -------
    ndarray of shape (N, 3, 3)
        The rotations.
    """
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


# A rotation R is carried as its three columns (each (N, 3)): right-multiplying by an elementary
# rotation mixes two columns with cos and sin, and R v = v0 col0 + v1 col1 + v2 col2. This avoids
# stacking (N, 3, 3) matrices and multiplying them batch by batch, which dominated the cost of the
# tracker's likelihood (N = 256 poses per call).
Columns = tuple[np.ndarray, np.ndarray, np.ndarray]


def _rx(R: Columns, c: np.ndarray, s: np.ndarray) -> Columns:
    """R Rx(a) from R's columns and cos a, sin a (each (N, 1))."""
    a0, a1, a2 = R
    return a0, a1 * c + a2 * s, a2 * c - a1 * s


def _ry(R: Columns, c: np.ndarray, s: np.ndarray) -> Columns:
    """R Ry(a)."""
    a0, a1, a2 = R
    return a0 * c - a2 * s, a1, a0 * s + a2 * c


def _rz(R: Columns, c: np.ndarray, s: np.ndarray) -> Columns:
    """R Rz(a)."""
    a0, a1, a2 = R
    return a0 * c + a1 * s, a1 * c - a0 * s, a2


#: the limbs, in the order of their DOFs in ``body.pose`` (four each: the shoulder's or hip's
#: flex, abd, rot, then the elbow's or knee's flex): their chains run as one batch of 4N rows
_LIMBS = ("l_arm", "r_arm", "l_leg", "r_leg")
_LIMB_DOF0 = DOF_INDEX["l_shoulder_flex"]
assert [DOF_INDEX[n] for n in ("r_shoulder_flex", "l_hip_flex", "r_hip_flex", "r_knee_flex")] == [
    _LIMB_DOF0 + 4,
    _LIMB_DOF0 + 8,
    _LIMB_DOF0 + 12,
    DOF - 1,
]
#: the anchors of the limbs' chains, limb by limb, each from its root (shoulder, hip) outwards
_LIMB_ANCHORS = np.array(
    [
        ANCHOR_INDEX[f"{sd}_{n}"]
        for names, sides in (
            (("shoulder", "elbow", "wrist", "hand_end"), "lr"),
            (("hip", "knee", "ankle", "toe"), "lr"),
        )
        for sd in sides
        for n in names
    ],
    dtype=np.intp,
)


#: the lengths of BodyDims the chain reads
_LENGTHS = (
    "ankle_height",
    "shin",
    "thigh",
    "hip_width",
    "torso_length",
    "shoulder_width",
    "shoulder_drop",
    "neck_to_head",
    "head_half_height",
    "upper_arm",
    "forearm",
    "hand_length",
    "foot_length",
    "chest_drop",
    "torso_bottom_drop",
    "r_toe",
)


class _Limbs:
    """The per-row constants of the limbs' batch of 4N rows (left arms, right arms, left legs,
    right legs, N rows each), each as an (4N, 1) array or (arms or legs alone) (2N, 1): the side's
    sign, the bones' lengths and the offsets of the roots, computed as the chain did per call.
    """

    def __init__(self, d: BodyDims | RowDims, n: int) -> None:
        def rows(*per_limb: object) -> np.ndarray:
            return np.concatenate([np.broadcast_to(np.asarray(v, np.float64), (n, 1)) for v in per_limb])

        sign = np.repeat(np.array([1.0, -1.0]), n)[:, None]  # (2N, 1): +1 left, -1 right
        self.sign = np.concatenate([sign, sign])  # (4N, 1)
        self.neg_sign = -self.sign
        # the elbow bends with -sin, the knee with +sin
        self.bend = np.repeat(np.array([-1.0, 1.0]), 2 * n)[:, None]
        self.shoulder = sign * rows(d.shoulder_width, d.shoulder_width) / 2  # (2N, 1)
        self.shoulder_drop = rows(d.shoulder_drop, d.shoulder_drop)
        self.hip = sign * rows(d.hip_width, d.hip_width) / 2
        self.bone1 = rows(d.upper_arm, d.upper_arm, d.thigh, d.thigh)  # (4N, 1)
        self.bone2 = rows(d.forearm, d.forearm, d.shin, d.shin)
        self.hand = rows(d.hand_length, d.hand_length)  # (2N, 1)
        self.toe_drop = rows(d.ankle_height - d.r_toe, d.ankle_height - d.r_toe)
        self.foot = rows(d.foot_length, d.foot_length)


class RowDims:
    """Body dimensions per pose of a batch that holds several people's poses (their particles
    evaluated at once): each length of :class:`BodyDims` the chain reads, as an (N, 1) array.

    Parameters
    ----------
    dims : sequence of BodyDims
        Each person's dimensions.
    counts : sequence of int
        Each person's poses, in the batch's order.
    """

    def __init__(self, dims: Sequence[BodyDims], counts: Sequence[int]) -> None:
        for name in _LENGTHS:
            setattr(self, name, np.repeat(np.array([getattr(d, name) for d in dims], np.float64), counts)[:, None])
        self._limbs: _Limbs | None = None
        self._rows: tuple[np.ndarray, np.ndarray] | None = None

    def kernel_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """The lengths (N, len(_LENGTHS)) of these rows, in ``_LENGTHS``' order, and the row of
        each pose (N,): ``kinematics_kernel.anchor_kernel``'s tables.
        """
        if self._rows is None:
            lengths = np.hstack([getattr(self, name) for name in _LENGTHS])
            self._rows = (np.ascontiguousarray(lengths), np.arange(len(lengths), dtype=np.int64))
        return self._rows

    def limbs(self) -> _Limbs:
        """The limbs' batch constants of these rows, made once."""
        if self._limbs is None:
            self._limbs = _Limbs(self, len(self.thigh))
        return self._limbs


@lru_cache(maxsize=16)
def row_dims(dims: tuple[BodyDims, ...], counts: tuple[int, ...]) -> RowDims:
    """:class:`RowDims` of these people and counts, made once: a tracker calls the chain with the
    same bodies and particle counts frame after frame (a body changes when its track starts).

    Parameters
    ----------
    dims : tuple of BodyDims
        Each person's dimensions.
    counts : tuple of int
        Each person's poses, in the batch's order.

    Returns
    -------
    RowDims
        The rows (shared: not to be changed).
    """
    return RowDims(dims, counts)


@lru_cache(maxsize=16)
def _body_limbs(d: BodyDims, n: int) -> _Limbs:
    """The limbs' batch constants of one body for N poses (the likelihood calls the chain with
    the same body and count many times a frame).
    """
    return _Limbs(d, n)


@lru_cache(maxsize=16)
def _pelvis_up(n: int) -> np.ndarray:
    """(N, 3) rows (0, 1, 0), read-only: the pelvis's second column before its pitch and roll."""
    return np.broadcast_to(np.array([0.0, 1.0, 0.0]), (n, 3))


def _chain(P: np.ndarray, dims: BodyDims | RowDims, rotations: bool = True) -> tuple[np.ndarray, dict[str, Columns]]:
    """The chain of the module docstring: anchor points (N, len(ANCHORS), 3) and (with
    ``rotations``) the columns of every body part's rotation.

    The four limbs go through their chains as one batch of 4N rows (left arms, right arms, left
    legs, right legs), with the side's sign per row: the same operations on every row as one
    limb at a time, so the same numbers, at a quarter of the calls (the tracker's likelihood runs
    it on few poses many times a frame, where the cost of a call, not of a pose, dominates).
    """
    d = dims
    N = len(P)
    Cf, Sf = np.cos(P), np.sin(P)  # (N, DOF)
    C, S = Cf[:, :, None], Sf[:, :, None]
    ix = DOF_INDEX

    def cs(n: str) -> tuple[np.ndarray, np.ndarray]:
        return C[:, ix[n]], S[:, ix[n]]

    def neg(n: str) -> tuple[np.ndarray, np.ndarray]:
        return C[:, ix[n]], -S[:, ix[n]]

    z = np.zeros((N, 1))
    c, s = cs("root_yaw")
    R: dict[str, Columns] = {}
    pel = R["pelvis"] = _rz(
        _rx((np.concatenate([c, z, -s], 1), _pelvis_up(N), np.concatenate([s, z, c], 1)), *cs("root_pitch")),
        *neg("root_roll"),
    )
    tor = R["torso"] = _rz(_rx(_ry(pel, *cs("torso_twist")), *cs("torso_flex")), *neg("torso_lateral"))
    if rotations:
        hed = R["head"] = _rz(_rx(_ry(tor, *cs("head_turn")), *cs("head_nod")), *neg("head_tilt"))
        head_up = hed[1]
    else:  # the points read the head's second column alone: _rz's second of _rx's first two
        h0, h1, h2 = _ry(tor, *cs("head_turn"))
        c, s = cs("head_nod")
        h1 = h1 * c + h2 * s
        c, s = neg("head_tilt")
        head_up = h1 * c - h0 * s

    pts = np.empty((N, len(ANCHORS), 3))
    ax = ANCHOR_INDEX
    pelvis = P[:, 0:3]
    pts[:, ax["pelvis"]] = pelvis
    neck = pelvis + d.torso_length * tor[1]
    pts[:, ax["neck"]] = neck
    pts[:, ax["chest"]] = neck - d.chest_drop * tor[1]
    pts[:, ax["torso_bottom"]] = pelvis - d.torso_bottom_drop * tor[1]
    head = neck + d.neck_to_head * head_up
    pts[:, ax["head"]] = head
    half = d.head_half_height * head_up
    pts[:, ax["chin"]] = head - half
    pts[:, ax["crown"]] = head + half

    # The four limbs at once, 4N rows. Arms and legs mirrored so that every positive angle means
    # the same movement on both sides: sign +1 on the left rows, -1 on the right ones.
    lim = d.limbs() if isinstance(d, RowDims) else _body_limbs(d, N)
    n2 = 2 * N
    C4 = Cf[:, _LIMB_DOF0:].reshape(N, 4, 4).transpose(1, 0, 2).reshape(4 * N, 4, 1)
    S4 = Sf[:, _LIMB_DOF0:].reshape(N, 4, 4).transpose(1, 0, 2).reshape(4 * N, 4, 1)
    root = tuple(np.concatenate([t, t, p, p]) for t, p in zip(tor, pel))  # each limb's parent
    (c1, c2, c3, c4), (s1, s2, s3, s4) = (C4[:, k] for k in range(4)), (S4[:, k] for k in range(4))
    # upper arms and thighs, then forearms and shins
    if rotations:
        up = _ry(_rz(_rx(root, c1, -s1), c2, lim.sign * s2), c3, lim.neg_sign * s3)
    else:  # the points and the forearms' and shins' columns read its last two columns alone
        a0, a1, a2 = _rz(_rx(root, c1, -s1), c2, lim.sign * s2)
        s3 = lim.neg_sign * s3
        up = (a0, a1, a0 * s3 + a2 * c3)  # _ry's columns 1 and 2; its column 0 left unturned, unread
    lo = _rx(up, c4, lim.bend * s4)
    # each limb's four anchors from its root outwards, (4 anchors, 4N rows, 3)
    J = np.empty((4, 4 * N, 3))
    arm, leg = J[0, :n2], J[0, n2:]
    np.add(np.concatenate([neck, neck]), lim.shoulder * root[0][:n2], out=arm)
    arm -= lim.shoulder_drop * root[1][:n2]
    np.add(np.concatenate([pelvis, pelvis]), lim.hip * root[0][n2:], out=leg)
    np.subtract(J[0], lim.bone1 * up[1], out=J[1])  # elbows, knees
    np.subtract(J[1], lim.bone2 * lo[1], out=J[2])  # wrists, ankles
    np.subtract(J[2, :n2], lim.hand * lo[1][:n2], out=J[3, :n2])  # hand ends
    toe = np.subtract(J[2, n2:], lim.toe_drop * lo[1][n2:], out=J[3, n2:])
    toe += lim.foot * lo[2][n2:]
    pts[:, _LIMB_ANCHORS] = J.reshape(4, 4, N, 3).transpose(2, 1, 0, 3).reshape(N, 16, 3)
    if rotations:
        for k, sd in enumerate("lr"):
            for part, cols, at in (("upper_arm", up, 0), ("forearm", lo, 0), ("thigh", up, 2), ("shin", lo, 2)):
                rows = slice((at + k) * N, (at + k + 1) * N)
                R[f"{sd}_{part}"] = tuple(a[rows] for a in cols)
    return pts, R


#: the DOFs the chain reads, in the order of ``kinematics_kernel.anchor_kernel``'s ``ix`` (then the limbs' first)
_KERNEL_DOFS = (
    "root_yaw",
    "root_pitch",
    "root_roll",
    "torso_twist",
    "torso_flex",
    "torso_lateral",
    "head_turn",
    "head_nod",
    "head_tilt",
)
#: the anchors of the torso and the head, in the order of ``kinematics_kernel.anchor_kernel``'s ``at``
_KERNEL_ANCHORS = ("pelvis", "neck", "chest", "torso_bottom", "head", "chin", "crown")


_KIX = np.array([DOF_INDEX[n] for n in _KERNEL_DOFS], np.int64)
_KAT = np.array([ANCHOR_INDEX[n] for n in _KERNEL_ANCHORS], np.int64)
_KLIMB_AT = _LIMB_ANCHORS.astype(np.int64)


@lru_cache(maxsize=16)
def _body_rows(d: BodyDims, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``kinematics_kernel.anchor_kernel``'s lengths (1, len(_LENGTHS)) of one body and its rows (N,) of zeros."""
    return np.array([[getattr(d, name) for name in _LENGTHS]], np.float64), np.zeros(n, np.int64)


#: the fewest poses whose anchor points ``anchor_points`` computes with the compiled kernel (a
#: tracker's particles); fewer go through the numpy chain
KERNEL_MIN_POSES = 16


def anchor_points(P: np.ndarray, dims: BodyDims | RowDims = DEFAULT_DIMS) -> np.ndarray:
    """Anchor points: ``frames`` without building the rotation matrices (the tracker's likelihood
    needs the points alone), by the compiled ``kinematics_kernel.anchor_kernel`` from
    ``KERNEL_MIN_POSES`` poses on: the numbers of ``_chain``.

    Parameters
    ----------
    P : ndarray of shape (N, DOF) or (DOF,)
        Poses (a single pose is treated as N = 1), metres and radians as in ``counterpart.body.pose``.
    dims : BodyDims or RowDims
        Body dimensions, metres (RowDims: per pose, for a batch of several people's poses).

    Returns
    -------
    ndarray of shape (N, len(ANCHORS), 3)
        Anchor points, metres, world frame.

    Raises
    ------
    ValueError
        If ``P`` is not of shape (N, DOF) or (DOF,).
    """
    P = np.ascontiguousarray(_as_poses(P), dtype=np.float64)
    if len(P) < KERNEL_MIN_POSES:
        # the same numbers; a few bodies a frame (the renderer, the simulator, the responder) never
        # wait for numba's import and the kernel's load
        return _chain(P, dims, rotations=False)[0]
    lengths, row = dims.kernel_rows() if isinstance(dims, RowDims) else _body_rows(dims, len(P))
    out = np.empty((len(P), len(ANCHORS), 3))
    # imported here: numba's slow import is paid by the processes that compute anchor points, not by
    # every one that imports the body
    from counterpart.body.kinematics_kernel import anchor_kernel

    # numpy's cos and sin (the kernel's own may differ in the last bit)
    anchor_kernel(P, np.cos(P), np.sin(P), lengths, row, _KIX, _LIMB_DOF0, _KAT, _KLIMB_AT, out)
    return out


def frames(P: np.ndarray, dims: BodyDims = DEFAULT_DIMS) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """All anchor points and segment frames.

    Parameters
    ----------
    P : ndarray of shape (N, DOF) or (DOF,)
        Poses (a single pose is treated as N = 1), metres and radians as in ``counterpart.body.pose``.
    dims : BodyDims
        Body dimensions, metres.

    Returns
    -------
    points : ndarray of shape (N, len(ANCHORS), 3)
        Metres, world frame: the 14 joints then ``EXTRA_ANCHORS``.
    rotations : dict of str to ndarray of shape (N, 3, 3)
        Name -> world rotation of each body part's frame ("pelvis", "torso", "head", "l_upper_arm",
        "l_forearm", "r_...", "l_thigh", "l_shin", "r_...").

    Raises
    ------
    ValueError
        If ``P`` is not of shape (N, DOF) or (DOF,).
    """
    pts, cols = _chain(_as_poses(P), dims)
    return pts, {name: np.stack(c, axis=-1) for name, c in cols.items()}


def forward_kinematics(P: np.ndarray, dims: BodyDims = DEFAULT_DIMS) -> np.ndarray:
    """Joint positions.

    Parameters
    ----------
    P : ndarray of shape (N, DOF) or (DOF,)
        Poses (a single pose is treated as N = 1), metres and radians as in ``counterpart.body.pose``.
    dims : BodyDims
        Body dimensions, metres.

    Returns
    -------
    ndarray of shape (N, 14, 3), dtype float64
        World positions in metres, in ``counterpart.body.skeleton.JOINTS`` order.

    Raises
    ------
    ValueError
        If ``P`` is not of shape (N, DOF) or (DOF,).
    """
    return _chain(_as_poses(P), dims, rotations=False)[0][:, :N_JOINTS]


def cone_endpoints(P: np.ndarray, dims: BodyDims = DEFAULT_DIMS) -> tuple[np.ndarray, np.ndarray]:
    """The 16 truncated cones of N poses.

    Parameters
    ----------
    P : ndarray of shape (N, DOF) or (DOF,)
        Poses (a single pose is treated as N = 1), metres and radians as in ``counterpart.body.pose``.
    dims : BodyDims
        Body dimensions, metres.

    Returns
    -------
    ends : ndarray of shape (N, 16, 2, 3)
        Metres, world frame: start and end centre of each cone in ``SEGMENTS`` order.
    radii : ndarray of shape (16, 2)
        Metres: the matching radii (same for every pose).

    Raises
    ------
    ValueError
        If ``P`` is not of shape (N, DOF) or (DOF,).
    """
    return anchor_points(P, dims)[:, SEGMENT_ANCHORS], dims.segment_radii()


def lowest_point(P: np.ndarray, dims: BodyDims = DEFAULT_DIMS) -> np.ndarray:
    """(N,) lowest y (metres) of the cone surfaces of each pose: rim bottoms of every cone.

    The exact lowest point of a circular rim of radius r around axis a is at
    ``y_centre - r * sqrt(1 - a_y**2)``.

    Parameters
    ----------
    P : ndarray of shape (N, DOF) or (DOF,)
        Poses (a single pose is treated as N = 1), metres and radians as in ``counterpart.body.pose``.
    dims : BodyDims
        Body dimensions, metres.

    Returns
    -------
    ndarray of shape (N,)
        The lowest y of each pose, metres.

    Raises
    ------
    ValueError
        If ``P`` is not of shape (N, DOF) or (DOF,).
    """
    ends, radii = cone_endpoints(P, dims)
    axis = ends[:, :, 1] - ends[:, :, 0]
    n = np.linalg.norm(axis, axis=-1, keepdims=True)
    ay = np.where(n[..., 0] > 0, axis[..., 1] / np.maximum(n[..., 0], 1e-12), 1.0)
    drop = radii[None] * np.sqrt(np.clip(1.0 - ay**2, 0.0, 1.0))[..., None]
    return (ends[..., 1] - drop).min(axis=(1, 2))
