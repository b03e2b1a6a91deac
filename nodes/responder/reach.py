"""Hand contact: the partner's hand meets the observed person's hand where it is offered.

A model learnt from pairs puts the partner's hand where the training pairs' hands met, relative to
the observed person's body; on another person (another height, reach, or a tracker's estimate of
them) the hands then miss each other by a few centimetres to decimetres. As animation systems do
for contacts, the hand that the model already brings near the observed hand is pulled onto it by
two-bone inverse kinematics of the partner's arm (shoulder fixed, bone lengths kept):

    w = clip((r_engage - d) / (r_engage - r_contact), 0, 1),   target = W + w (H - W),

d the distance between the model's wrist W and the nearest observed wrist H (metres). w grows
smoothly from 0 at ``r_engage`` to 1 at ``r_contact``, so the hand is never thrown across; beyond
reach of the shoulder the arm stretches towards the target without leaving its shoulder.

A hand the observed person holds out (``offered``: where their silhouette says it is,
:attr:`.staging.Stage.offered_`; tracked wrists are the least reliable joints on real video) is
taken by the partner's arm whose shoulder is nearer, with d the distance of the hand beyond that
arm's length from its shoulder: a hand within the partner's reach is met (w = 1), whatever the
model's arm was doing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from counterpart.body.skeleton import JOINT_INDEX

#: (shoulder, elbow, wrist) joint indices of each arm
ARMS = tuple((JOINT_INDEX[f"{s}_shoulder"], JOINT_INDEX[f"{s}_elbow"], JOINT_INDEX[f"{s}_wrist"]) for s in ("l", "r"))
_WRISTS = [w for _, _, w in ARMS]


@dataclass(frozen=True)
class ReachConfig:
    """Distances between the model's wrist and the observed wrist at which the pull starts and ends.

    Parameters
    ----------
    r_engage : float, default=0.45
        Distance at which the pull starts (w = 0), metres.
    r_contact : float, default=0.1
        Distance at which the pull is complete (w = 1), metres; ``0 <= r_contact < r_engage``.

    Raises
    ------
    ValueError
        If not ``0 <= r_contact < r_engage``.
    """

    r_engage: float = 0.45
    r_contact: float = 0.1

    def __post_init__(self) -> None:
        if not 0.0 <= self.r_contact < self.r_engage:
            raise ValueError(
                f"reach distances r_contact={self.r_contact}, r_engage={self.r_engage}: need 0 <= r_contact < r_engage"
            )


def two_bone_ik(
    shoulder: np.ndarray, elbow: np.ndarray, wrist: np.ndarray, target: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Put the wrist on ``target`` (or as near as the arm reaches), both bone lengths kept.

    The elbow is bent in the plane of the shoulder, the target and the old elbow (the law of
    cosines in that plane).

    Parameters
    ----------
    shoulder, elbow, wrist : ndarray of shape (3,)
        The arm's joints, metres, world frame; the shoulder stays fixed.
    target : ndarray of shape (3,)
        Where the wrist should go, metres, world frame.

    Returns
    -------
    elbow : ndarray of shape (3,)
        New elbow, metres.
    wrist : ndarray of shape (3,)
        New wrist, metres.
    """
    a = float(np.linalg.norm(elbow - shoulder))
    b = float(np.linalg.norm(wrist - elbow))
    to = target - shoulder
    dist = float(np.linalg.norm(to))
    if dist < 1e-9 or a < 1e-9 or b < 1e-9:
        return elbow.copy(), wrist.copy()
    dist_c = float(np.clip(dist, abs(a - b) + 1e-6, a + b - 1e-6))
    axis = to / dist
    # the bend direction: the old elbow's offset from the shoulder-target line
    bend = (elbow - shoulder) - np.dot(elbow - shoulder, axis) * axis
    n = float(np.linalg.norm(bend))
    if n < 1e-9:  # a straight arm: bend it downwards, or sideways when it points straight down
        for hint in (np.array([0.0, -1.0, 0.0]), np.array([1.0, 0.0, 0.0])):
            bend = hint - np.dot(hint, axis) * axis
            n = float(np.linalg.norm(bend))
            if n > 1e-6:
                break
    bend = bend / n
    along = (a * a - b * b + dist_c * dist_c) / (2 * dist_c)
    up = np.sqrt(max(a * a - along * along, 0.0))
    new_elbow = shoulder + along * axis + up * bend
    new_wrist = shoulder + dist_c * axis
    return new_elbow, new_wrist


def reach(
    observed: np.ndarray,
    partner: np.ndarray,
    config: ReachConfig = ReachConfig(),
    offered: np.ndarray | None = None,
) -> tuple[np.ndarray, float]:
    """The partner with the hand nearest an observed hand pulled onto it; and the pull w.

    Parameters
    ----------
    observed : ndarray of shape (14, 3)
        The observed person's joints, metres, world frame.
    partner : ndarray of shape (14, 3)
        The model's partner joints, metres, world frame.
    config : ReachConfig, default=ReachConfig()
        The engage and contact distances.
    offered : ndarray of shape (3,) or None, default=None
        A hand the observed person holds out, metres, world frame (see the module): it is met
        before the tracked wrists are looked at.

    Returns
    -------
    partner : ndarray of shape (14, 3)
        A new array, the dtype of ``partner``, with the pulled arm.
    w : float
        The pull, in [0, 1].
    """
    X = np.asarray(observed, np.float64)
    P = np.asarray(partner, np.float64).copy()
    if offered is not None and np.isfinite(offered).all():
        goal = np.asarray(offered, np.float64)
        arm = int(np.argmin([np.linalg.norm(P[s] - goal) for s, _, _ in ARMS]))
        s, e, wr = ARMS[arm]
        length = float(np.linalg.norm(P[e] - P[s]) + np.linalg.norm(P[wr] - P[e]))
        beyond = max(float(np.linalg.norm(goal - P[s])) - length, 0.0)
        w = float(np.clip((config.r_engage - beyond) / (config.r_engage - config.r_contact), 0.0, 1.0))
        if w > 0.0:
            P[e], P[wr] = two_bone_ik(P[s], P[e], P[wr], P[wr] + w * (goal - P[wr]))
            return P.astype(np.asarray(partner).dtype), w
    d = np.linalg.norm(P[_WRISTS][:, None] - X[_WRISTS][None], axis=-1)  # (partner arm, observed wrist)
    arm, hand = np.unravel_index(int(np.argmin(d)), d.shape)
    w = float(np.clip((config.r_engage - d[arm, hand]) / (config.r_engage - config.r_contact), 0.0, 1.0))
    if w > 0.0:
        s, e, wr = ARMS[arm]
        goal = P[wr] + w * (X[_WRISTS[hand]] - P[wr])
        P[e], P[wr] = two_bone_ik(P[s], P[e], P[wr], goal)
    return P.astype(np.asarray(partner).dtype), w
