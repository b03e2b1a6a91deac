"""Constructed joint streams with planted social signals and known truth: fixtures for the labeller's
tests and bench/labeller.py (the simulator's conversation scenarios give rendered, labelled ones).

- :func:`standing_pose`: a (14,3) standing skeleton in the project joint order.
- :func:`conversation`: two people facing each other with planted nods, shakes, torso sway and
  turns away, plus per-frame truth.
- :func:`planted_label_streams`: speaker/listener label streams where each planted rule
  ``S:x -> L:y`` holds with a known confidence at a known offset.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from counterpart.body.skeleton import JOINT_INDEX, JOINTS

_STAND = np.array(
    [
        [0.00, 1.62, 0.02],  # head (centre)
        [0.00, 1.45, 0.00],  # neck
        [0.18, 1.42, 0.00],  # l_shoulder (+X is the person's left when facing +Z)
        [0.20, 1.15, 0.00],  # l_elbow
        [0.20, 0.90, 0.05],  # l_wrist
        [-0.18, 1.42, 0.00],  # r_shoulder
        [-0.20, 1.15, 0.00],  # r_elbow
        [-0.20, 0.90, 0.05],  # r_wrist
        [0.10, 0.95, 0.00],  # l_hip
        [0.10, 0.50, 0.00],  # l_knee
        [0.10, 0.08, 0.00],  # l_ankle
        [-0.10, 0.95, 0.00],  # r_hip
        [-0.10, 0.50, 0.00],  # r_knee
        [-0.10, 0.08, 0.00],  # r_ankle
    ]
)
assert len(_STAND) == len(JOINTS)

#: joints that move with the upper body (everything above the hips)
UPPER = np.array([JOINT_INDEX[j] for j in JOINTS[:8]])


def standing_pose(position: Sequence[float] = (0.0, 0.0, 0.0), yaw: float = 0.0) -> np.ndarray:
    """A person standing (feet on y = 0), in the project joint order.

    Parameters
    ----------
    position : sequence of float, default=(0.0, 0.0, 0.0)
        Where the person stands, metres, world frame.
    yaw : float, default=0.0
        Facing, radians (0 = +Z).

    Returns
    -------
    ndarray of shape (14, 3)
        Joints, metres, world frame.
    """
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])  # rotation about +Y: +Z -> (sin, 0, cos)
    return _STAND @ rot.T + np.asarray(position, dtype=np.float64)


def rotate_about_y(points: np.ndarray, yaw: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """Rotate points about the vertical axis through pivots.

    Parameters
    ----------
    points : ndarray of shape (T, J, 3)
        Points, metres.
    yaw : ndarray of shape (T,)
        Rotation per frame, radians.
    pivot : ndarray of shape (T, 3)
        Pivot per frame, metres.

    Returns
    -------
    ndarray of shape (T, J, 3)
        The rotated points, metres.
    """
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    d = points - pivot[:, None]
    x = c * d[..., 0] + s * d[..., 2]
    z = -s * d[..., 0] + c * d[..., 2]
    return np.stack([x, d[..., 1], z], axis=-1) + pivot[:, None]


@dataclass(frozen=True)
class Conversation:
    """Two people's joint streams with their planted signals' truth.

    Parameters
    ----------
    fps : float
        Frames per second.
    joints_a, joints_b : ndarray of shape (T, 14, 3)
        Joints, metres, world frame.
    head_yaw_a, head_yaw_b : ndarray of shape (T,)
        Head yaw relative to the torso, radians.
    truth_a, truth_b : dict of str to ndarray of shape (T,), dtype bool
        Truth of "nod", "shake", "gaze_at_other" and "activity" (sway or turning).
    """

    fps: float
    joints_a: np.ndarray
    joints_b: np.ndarray
    head_yaw_a: np.ndarray
    head_yaw_b: np.ndarray
    truth_a: dict[str, np.ndarray]
    truth_b: dict[str, np.ndarray]


def _segments(
    rng: np.random.Generator, t: int, fps: float, n: int, dur: tuple[float, float], busy: np.ndarray
) -> np.ndarray:
    """Up to n random non-overlapping segments (bool mask) avoiding `busy` (+0.8 s margin)."""
    mask = np.zeros(t, dtype=bool)
    margin = int(0.8 * fps)
    for _ in range(20 * n):
        if mask.sum() and (np.diff(mask.astype(int)) == 1).sum() >= n:
            break
        length = int(rng.uniform(*dur) * fps)
        start = int(rng.integers(margin, max(margin + 1, t - length - margin)))
        lo, hi = max(0, start - margin), min(t, start + length + margin)
        if not (busy[lo:hi].any() or mask[lo:hi].any()):
            mask[start : start + length] = True
    return mask


def _person(
    rng: np.random.Generator, t: int, fps: float, position: Sequence[float], yaw0: float, noise_m: float
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], np.ndarray]:
    tt = np.arange(t) / fps
    busy = np.zeros(t, dtype=bool)
    # about one nod per 15 s, one shake per 20 s, one turn and one sway per 25 s
    nod = _segments(rng, t, fps, max(1, t // int(15 * fps)), (1.5, 3.0), busy)
    shake = _segments(rng, t, fps, max(1, t // int(20 * fps)), (1.5, 3.0), nod)
    turn = _segments(rng, t, fps, max(1, t // int(25 * fps)), (2.0, 4.0), nod | shake)
    sway = _segments(rng, t, fps, max(1, t // int(25 * fps)), (2.0, 4.0), nod | shake | turn)
    # body yaw: turned 70 degrees away during `turn`, ramped over 0.4 s
    ramp = int(0.4 * fps)
    k = np.convolve(turn.astype(float), np.ones(ramp) / ramp, mode="same")
    side = np.where(rng.random() < 0.5, 1.0, -1.0)
    yaw = yaw0 + side * np.radians(70.0) * k
    j = np.broadcast_to(standing_pose(position, 0.0), (t, 14, 3)).copy()
    pivot = np.broadcast_to(np.asarray(position, dtype=np.float64), (t, 3))
    j = rotate_about_y(j, yaw, pivot)
    fwd = np.stack([np.sin(yaw), np.zeros(t), np.cos(yaw)], axis=-1)
    left = np.stack([np.cos(yaw), np.zeros(t), -np.sin(yaw)], axis=-1)
    head = JOINT_INDEX["head"]
    f_nod = rng.uniform(1.6, 2.6)
    a_nod = rng.uniform(0.02, 0.03)
    j[:, head, 1] += np.where(nod, a_nod * np.sin(2 * np.pi * f_nod * tt), 0.0)
    j[:, head] += fwd * np.where(nod, 0.3 * a_nod * np.sin(2 * np.pi * f_nod * tt), 0.0)[:, None]
    f_sh = rng.uniform(1.8, 3.0)
    yaw_head = np.where(shake, np.radians(20.0) * np.sin(2 * np.pi * f_sh * tt), 0.0)
    j[:, head] += left * (0.02 / np.radians(20.0) * yaw_head)[:, None]
    # torso sway: the whole upper body and hips rock sideways 5 cm at ~1 Hz
    f_sw = rng.uniform(0.8, 1.4)
    sw = np.where(sway, 0.05 * np.sin(2 * np.pi * f_sw * tt), 0.0)
    moving = np.r_[UPPER, [JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]]
    j[:, moving] += (left * sw[:, None])[:, None]
    j += rng.normal(0.0, noise_m, j.shape)
    # activity truth: the torso sways, or the body is turning (the torso moves in both)
    turning = np.abs(np.gradient(yaw)) * fps > 0.2
    truth = {"nod": nod, "shake": shake, "activity": sway | turning}
    return j, yaw_head, truth, yaw


def conversation(
    duration_s: float = 60.0, fps: float = 25.0, seed: int = 0, distance_m: float = 1.5, noise_m: float = 0.002
) -> Conversation:
    """Two people facing each other (A at the origin facing +Z, B facing -Z),
    each with random nods (1.6-2.6 Hz, 2-3 cm), shakes (1.8-3 Hz, 20 degrees head yaw with 2 cm
    sideways head motion), turns away (70 degrees, whole body) and torso sway (5 cm, ~1 Hz), never
    overlapping, plus Gaussian joint noise. Truth of gaze_at_other is geometric:
    facing within 30 degrees of the other's head.

    Parameters
    ----------
    duration_s : float, default=60.0
        Length, seconds.
    fps : float, default=25.0
        Frames per second.
    seed : int, default=0
        Random seed.
    distance_m : float, default=1.5
        Distance between the two people, metres.
    noise_m : float, default=0.002
        Standard deviation of the Gaussian joint noise, metres.

    Returns
    -------
    Conversation
        The joint streams and their truth.
    """
    rng = np.random.default_rng(seed)
    t = int(round(duration_s * fps))
    ja, hya, tra, yaw_a = _person(rng, t, fps, (0.0, 0.0, 0.0), 0.0, noise_m)
    jb, hyb, trb, yaw_b = _person(rng, t, fps, (0.0, 0.0, distance_m), np.pi, noise_m)
    h = JOINT_INDEX["head"]
    for tr, me, other, yaw in ((tra, ja, jb, yaw_a), (trb, jb, ja, yaw_b)):
        d = other[:, h] - me[:, h]
        target = np.arctan2(d[:, 0], d[:, 2])
        delta = np.angle(np.exp(1j * (yaw - target)))
        tr["gaze_at_other"] = np.abs(delta) <= np.radians(30.0)
    return Conversation(fps, ja, jb, hya, hyb, tra, trb)


def planted_label_streams(
    n_frames: int,
    n_signals: int,
    rules: Sequence[tuple[int, int, float]],
    offset: int = 10,
    base_rate: tuple[float, float] = (0.03, 0.12),
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Speaker and listener label streams (n_frames, n_signals) bool with planted rules.

    Every speaker signal and every listener signal not named in ``rules`` is on independently per
    frame with a rate drawn from ``base_rate``. For each planted rule ``(x, y, c)``, listener signal
    ``y`` is on at frame ``t + offset`` exactly when speaker signal ``x`` is on at ``t`` and a coin of
    probability ``c`` lands; ``y`` has no other source, so rule ``S:x -> L:y`` has confidence ``c`` in
    expectation.

    Parameters
    ----------
    n_frames : int
        Frames.
    n_signals : int
        Signals per stream.
    rules : sequence of (int, int, float)
        Planted rules ``(x, y, c)``; each listener signal may be planted by one rule only.
    offset : int, default=10
        Frames from a speaker signal to the listener's response.
    base_rate : tuple of (float, float), default=(0.03, 0.12)
        Range of the per-frame rates of the independent signals.
    seed : int, default=0
        Random seed.

    Returns
    -------
    speaker, listener : ndarray of shape (n_frames, n_signals), dtype bool
        The label streams.
    names : list of str
        Signal names "sig00", "sig01", ...

    Raises
    ------
    ValueError
        If a listener signal is planted by more than one rule.
    """
    ys = [y for _, y, _ in rules]
    if len(set(ys)) != len(ys):
        raise ValueError(f"each listener signal may be planted by one rule only, got {ys}")
    rng = np.random.default_rng(seed)
    rates_s = rng.uniform(*base_rate, n_signals)
    rates_l = rng.uniform(*base_rate, n_signals)
    sp = rng.random((n_frames, n_signals)) < rates_s
    li = rng.random((n_frames, n_signals)) < rates_l
    for x, y, c in rules:
        li[:, y] = False
        li[offset:, y] = sp[: -offset or None, x] & (rng.random(n_frames - offset) < c)
    return sp, li, [f"sig{i:02d}" for i in range(n_signals)]
