"""The body model: 14 joints, 16 truncated-cone segments, body dimensions.

Follows the articulated model of Zheng et al. 2006 ("Virtual friend"): 14 joints linked into a
kinematic tree rooted at the pelvis (the mid-point of the two hip joints), fleshed out by 16
truncated cones.

Joints (index: name)::

     0 head        centre of the head (about eye level)
     1 neck        base of the neck, between the shoulders
     2 l_shoulder  3 l_elbow  4 l_wrist         (the person's own left)
     5 r_shoulder  6 r_elbow  7 r_wrist
     8 l_hip       9 l_knee  10 l_ankle
    11 r_hip      12 r_knee  13 r_ankle

``PARENT[j]`` is the index of joint ``j``'s parent, or ``-1`` where the parent is the pelvis root
(which is not one of the 14 joints: it is the mid-point of ``l_hip`` and ``r_hip``).

Segments are true truncated cones (flat circular ends, no caps) between two *anchor points*.
Anchors are the 14 joints plus a few points at a fixed offset from a joint in that joint's
frame (``ANCHORS``, see ``counterpart.body.kinematics``): the pelvis root, the chest and the bottom of the
torso, the chin and crown of the head, the ends of the hands and the toes.

All lengths are metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import NamedTuple

import numpy as np

JOINTS: tuple[str, ...] = (
    "head",
    "neck",
    "l_shoulder",
    "l_elbow",
    "l_wrist",
    "r_shoulder",
    "r_elbow",
    "r_wrist",
    "l_hip",
    "l_knee",
    "l_ankle",
    "r_hip",
    "r_knee",
    "r_ankle",
)
JOINT_INDEX: dict[str, int] = {name: i for i, name in enumerate(JOINTS)}
N_JOINTS: int = len(JOINTS)

# -1: attached to the pelvis root (mid-hip point), which is not one of the 14 joints.
PARENT: tuple[int, ...] = (1, -1, 1, 2, 3, 1, 5, 6, -1, 8, 9, -1, 11, 12)

# Bones between joints (child, parent) that keep a fixed length under every pose.
BONES: tuple[tuple[int, int], ...] = tuple((j, p) for j, p in enumerate(PARENT) if p >= 0)

#: the joints in an order in which every parent comes before its children (the pelvis root first)
TREE_ORDER: tuple[int, ...] = (1, 8, 11, 0, 2, 5, 9, 12, 3, 6, 10, 13, 4, 7)


def bone_lengths(X: np.ndarray) -> np.ndarray:
    """Each joint's distance from its parent (from the pelvis root, the mid-hip point, where ``PARENT``
    is -1).

    Parameters
    ----------
    X : ndarray of shape (..., 14, 3)
        Joints, metres.

    Returns
    -------
    ndarray of shape (..., 14)
        Lengths, metres.
    """
    X = np.asarray(X, np.float64)
    return np.linalg.norm(X - _parents(X), axis=-1)


def with_bone_lengths(X: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """The same pose on other bones: every bone keeps its direction and takes the given length,
    from the pelvis root (the mid-hip point, which stays where it is) out to the hands and feet.

    Parameters
    ----------
    X : ndarray of shape (..., 14, 3)
        Joints, metres.
    lengths : ndarray of shape (14,) or (..., 14)
        Each joint's distance from its parent, metres (:func:`bone_lengths`).

    Returns
    -------
    ndarray of shape (..., 14, 3)
        New joints, metres. A bone of zero length in ``X`` keeps zero length.
    """
    X = np.asarray(X, np.float64)
    L = np.broadcast_to(np.asarray(lengths, np.float64), X.shape[:-1])
    d = X - _parents(X)
    n = np.linalg.norm(d, axis=-1, keepdims=True)
    unit = np.divide(d, n, out=np.zeros_like(d), where=n > 0)
    out = np.empty_like(X)
    root = 0.5 * (X[..., JOINT_INDEX["l_hip"], :] + X[..., JOINT_INDEX["r_hip"], :])
    for j in TREE_ORDER:
        base = root if PARENT[j] < 0 else out[..., PARENT[j], :]
        out[..., j, :] = base + unit[..., j, :] * L[..., j, None]
    return out


def _parents(X: np.ndarray) -> np.ndarray:
    """Each joint's parent's position (the pelvis root for the root's children), shape of ``X``."""
    root = 0.5 * (X[..., JOINT_INDEX["l_hip"], :] + X[..., JOINT_INDEX["r_hip"], :])
    idx = np.maximum(np.asarray(PARENT), 0)
    return np.where((np.asarray(PARENT) < 0)[:, None], root[..., None, :], X[..., idx, :])


# Extra anchor points used by the cones, after the 14 joints in the FK point array.
EXTRA_ANCHORS: tuple[str, ...] = (
    "pelvis",  # root: mid-point of the hip joints
    "chest",  # on the torso axis, `chest_drop` below the neck
    "torso_bottom",  # on the torso axis, `torso_bottom_drop` below the pelvis
    "chin",  # head axis, `head_half_height` below the head centre
    "crown",  # head axis, `head_half_height` above the head centre
    "l_hand_end",
    "r_hand_end",  # along the forearm, `hand_length` beyond the wrist
    "l_toe",
    "r_toe",  # foot tip, in the shin frame
)
ANCHORS: tuple[str, ...] = JOINTS + EXTRA_ANCHORS
ANCHOR_INDEX: dict[str, int] = {name: i for i, name in enumerate(ANCHORS)}


class Segment(NamedTuple):
    """One truncated cone: from anchor ``start`` (radius ``r_start``) to ``end`` (``r_end``).

    Attributes
    ----------
    name : str
        Segment name.
    start, end : str
        Names of the anchors (``ANCHORS``) at the cone's two ends.
    r_start, r_end : str
        Names of the :class:`BodyDims` fields that give the radii at ``start`` and ``end``.
    """

    name: str
    start: str
    end: str
    r_start: str
    r_end: str


SEGMENTS: tuple[Segment, ...] = (
    Segment("head", "chin", "crown", "r_chin", "r_crown"),
    Segment("neck", "neck", "head", "r_neck", "r_neck_top"),
    Segment("upper_torso", "neck", "chest", "r_shoulders", "r_chest"),
    Segment("lower_torso", "chest", "torso_bottom", "r_chest", "r_pelvis"),
    Segment("l_upper_arm", "l_shoulder", "l_elbow", "r_upper_arm", "r_elbow"),
    Segment("l_forearm", "l_elbow", "l_wrist", "r_elbow", "r_wrist"),
    Segment("l_hand", "l_wrist", "l_hand_end", "r_wrist", "r_hand"),
    Segment("r_upper_arm", "r_shoulder", "r_elbow", "r_upper_arm", "r_elbow"),
    Segment("r_forearm", "r_elbow", "r_wrist", "r_elbow", "r_wrist"),
    Segment("r_hand", "r_wrist", "r_hand_end", "r_wrist", "r_hand"),
    Segment("l_thigh", "l_hip", "l_knee", "r_thigh", "r_knee"),
    Segment("l_shin", "l_knee", "l_ankle", "r_knee", "r_ankle"),
    Segment("l_foot", "l_ankle", "l_toe", "r_ankle", "r_toe"),
    Segment("r_thigh", "r_hip", "r_knee", "r_thigh", "r_knee"),
    Segment("r_shin", "r_knee", "r_ankle", "r_knee", "r_ankle"),
    Segment("r_foot", "r_ankle", "r_toe", "r_ankle", "r_toe"),
)
SEGMENT_NAMES: tuple[str, ...] = tuple(s.name for s in SEGMENTS)
N_SEGMENTS: int = len(SEGMENTS)
# (16, 2) anchor indices of each cone's two ends.
SEGMENT_ANCHORS: np.ndarray = np.array([[ANCHOR_INDEX[s.start], ANCHOR_INDEX[s.end]] for s in SEGMENTS], dtype=np.intp)


@dataclass(frozen=True)
class BodyDims:
    """Body dimensions in metres. The default is an adult of 1.75 m.

    Lengths follow anthropometric proportions of stature (Drillis & Contini): hip joints at
    0.53 h, knees at 0.285 h, shoulders at 0.82 h, eyes at 0.936 h.

    Parameters
    ----------
    height : float, default=1.75
        The stature (sole to crown) in the neutral standing pose, metres.
    ankle_height, shin, thigh, hip_width, torso_length, shoulder_width, shoulder_drop, \
neck_to_head, head_half_height, upper_arm, forearm, hand_length, foot_length, chest_drop, \
torso_bottom_drop : float
        Lengths, metres: joint to joint along each bone (each field's comment names its ends).
    r_chin, r_crown, r_neck, r_neck_top, r_shoulders, r_chest, r_pelvis, r_upper_arm, r_elbow, \
r_wrist, r_hand, r_thigh, r_knee, r_ankle, r_toe : float
        Radii (``r_*``), metres: radius of the cone at that place.

    Raises
    ------
    ValueError
        If a field is not a finite length >= 0, or ``height`` is not > 0.
    """

    height: float = 1.75
    # lengths
    ankle_height: float = 0.07  # sole to ankle joint
    shin: float = 0.43  # knee to ankle
    thigh: float = 0.43  # hip to knee
    hip_width: float = 0.18  # between the two hip joint centres
    torso_length: float = 0.52  # pelvis (mid-hip) to neck
    shoulder_width: float = 0.36  # between the two shoulder joint centres
    shoulder_drop: float = 0.02  # shoulders below the neck joint
    neck_to_head: float = 0.19  # neck joint to head centre
    head_half_height: float = 0.11  # head centre to crown (and to chin)
    upper_arm: float = 0.30  # shoulder to elbow
    forearm: float = 0.25  # elbow to wrist
    hand_length: float = 0.12  # wrist to end of the hand cone
    foot_length: float = 0.16  # ankle to toe end, forward
    chest_drop: float = 0.26  # neck to the chest anchor (upper/lower torso boundary)
    torso_bottom_drop: float = 0.08  # pelvis to the bottom of the lower torso
    # radii
    r_chin: float = 0.075
    r_crown: float = 0.09
    r_neck: float = 0.06
    r_neck_top: float = 0.055
    r_shoulders: float = 0.17
    r_chest: float = 0.14
    r_pelvis: float = 0.16
    r_upper_arm: float = 0.05
    r_elbow: float = 0.04
    r_wrist: float = 0.033
    r_hand: float = 0.035
    r_thigh: float = 0.08
    r_knee: float = 0.055
    r_ankle: float = 0.04
    r_toe: float = 0.03

    def __post_init__(self) -> None:
        # the field names listed once (dataclasses.fields builds the list on every call) and
        # math.isfinite (numpy's call on one number costs far more): the renderer fits a body to
        # every partner it draws
        for name in _DIM_NAMES:
            v = getattr(self, name)
            if not math.isfinite(v) or v < 0:
                raise ValueError(f"BodyDims.{name}={v!r}: must be a finite length >= 0 metres")
        if self.height <= 0:
            raise ValueError(f"BodyDims.height={self.height!r}: must be > 0 metres")

    def scaled(self, height: float) -> BodyDims:
        """The same proportions scaled uniformly to a stature.

        Parameters
        ----------
        height : float
            The new stature, metres.

        Returns
        -------
        BodyDims
            Every length and radius multiplied by ``height / self.height``.

        Raises
        ------
        ValueError
            If ``height`` is not a positive finite number.
        """
        if not np.isfinite(height) or height <= 0:
            raise ValueError(f"height={height!r}: must be a positive number of metres")
        k = float(height) / self.height
        return replace(self, **{name: getattr(self, name) * k for name in _DIM_NAMES})

    @property
    def hip_height(self) -> float:
        """Height of the pelvis root above the ground in the neutral pose (metres)."""
        return self.ankle_height + self.shin + self.thigh

    def segment_radii(self) -> np.ndarray:
        """Cone radii of every segment.

        Returns
        -------
        ndarray of shape (16, 2)
            float64 radii in metres, in ``SEGMENTS`` order: (start, end).
        """
        return np.array([[getattr(self, s.r_start), getattr(self, s.r_end)] for s in SEGMENTS])


#: the fields of BodyDims, in order
_DIM_NAMES: tuple[str, ...] = tuple(f.name for f in fields(BodyDims))
DEFAULT_DIMS = BodyDims()
