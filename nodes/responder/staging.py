"""Where the generated partner stands: on the ground, at a partner's distance, never jumping.

An interaction model places the partner relative to the observed person's frame
(:mod:`.frames`); on real tracking that frame is noisy (a person bending over turns their
estimated facing, a tracker's jump moves their origin), and a model's placement that is right
for the training pairs can then put the partner inside the observed person or metres away.
:class:`Stage` corrects the generated pose as a whole, a rigid move on the ground plane, so the
model's posture and gestures are kept:

1. the partner's ground offset from the observed person, p - o (p, o the mid-hips dropped to the
   floor, :func:`.frames.actor_frame`), is clipped to a length in [``min_distance_m``,
   ``max_distance_m``] (along the observed person's facing when p lies on o);
2. that offset changes by at most ``max_speed_m_s`` times the time between frames, in polar
   coordinates about the person (the partner walks round them, never through them; it never
   jumps), so the distance holds on every frame. The offset is relative to the observed person:
   where the tracker's estimate of the person jumps, the partner stays beside them in the picture
   rather than walking after them;
3. the partner recoils when pushed: when a wrist of the observed person comes within
   ``contact_m`` of the partner's torso axis (neck to mid-hip) the partner's distance grows by
   ``recoil_m``, which then fades with time constant ``recoil_s`` (the step back, then the
   return; still within the limits and the speed of 1 and 2);
4. the lowest ankle is brought into [0, ``max_ankle_m``] above the ground plane y = 0 (a partner
   may hop, never sink into the floor or float).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from counterpart.body.skeleton import JOINT_INDEX

from .frames import actor_frame

_ANKLES = [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]
_WRISTS = [JOINT_INDEX["l_wrist"], JOINT_INDEX["r_wrist"]]
_NECK, _HIPS = JOINT_INDEX["neck"], [JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]


@dataclass(frozen=True)
class StageConfig:
    """Limits of the partner's placement (metres, metres per second).

    Parameters
    ----------
    min_distance_m, max_distance_m : float, default=0.5, 1.2
        The range of the partner's ground distance from the observed person, metres.
    max_speed_m_s : float, default=2.5
        The most the partner's ground offset changes per second, metres per second.
    max_ankle_m : float, default=0.3
        The highest the lowest ankle may be above the ground plane, metres.
    contact_m : float, default=0.2
        A wrist within this distance of the partner's torso axis is a push, metres.
    recoil_m : float, default=0.3
        The distance a push adds, metres.
    recoil_s : float, default=0.8
        Time constant of the recoil's fading, seconds.

    Raises
    ------
    ValueError
        If the limits are inconsistent (min > max, negative values, non-positive speed or time constant).
    """

    min_distance_m: float = 0.5
    max_distance_m: float = 1.2
    max_speed_m_s: float = 2.5
    max_ankle_m: float = 0.3
    contact_m: float = 0.2
    recoil_m: float = 0.3
    recoil_s: float = 0.8

    def __post_init__(self) -> None:
        if not 0.0 <= self.min_distance_m <= self.max_distance_m:
            raise ValueError(
                f"partner distance limits [{self.min_distance_m}, {self.max_distance_m}] m: need 0 <= min <= max"
            )
        if self.max_speed_m_s <= 0 or self.max_ankle_m < 0:
            raise ValueError(f"max_speed_m_s={self.max_speed_m_s} must be > 0 and max_ankle_m={self.max_ankle_m} >= 0")
        if self.contact_m < 0 or self.recoil_m < 0 or self.recoil_s <= 0:
            raise ValueError(
                f"contact_m={self.contact_m}, recoil_m={self.recoil_m} must be >= 0 and recoil_s={self.recoil_s} > 0"
            )


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances (N,) of points (N, 3) from the segment a-b (3,) each, metres."""
    ab = b - a
    t = np.clip((points - a) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


def _clip_length(d: np.ndarray, facing: float, lo: float, hi: float) -> np.ndarray:
    """Ground vector d (2,) (x, z) with its length clipped to [lo, hi]; the facing direction
    (heading ``facing``, radians) where d is too short to have one.
    """
    r = float(np.hypot(*d))
    u = d / r if r > 1e-6 else np.array([np.sin(facing), np.cos(facing)])
    return u * min(max(r, lo), hi)


def _walk(start: np.ndarray, goal: np.ndarray, limit: float) -> np.ndarray:
    """Ground offset (2,) from ``start`` towards ``goal`` (both (2,), metres, non-zero), moved at most
    about ``limit`` metres: in polar coordinates about the person, so that a partner going to the
    other side walks round them rather than through them.
    """
    r0, r1 = float(np.hypot(*start)), float(np.hypot(*goal))
    a0, a1 = np.arctan2(start[1], start[0]), np.arctan2(goal[1], goal[0])
    da = (a1 - a0 + np.pi) % (2 * np.pi) - np.pi
    dr = r1 - r0
    length = float(np.hypot(0.5 * (r0 + r1) * da, dr))
    if length <= limit:
        return goal
    f = limit / length
    r, a = r0 + f * dr, a0 + f * da
    return np.array([r * np.cos(a), r * np.sin(a)])


class Stage:
    """Keeps a generated partner where a partner would stand, frame by frame.

    Parameters
    ----------
    config : StageConfig
        the limits.

    Attributes
    ----------
    corrected : int
        Frames on which the model's placement was moved.
    pushes : int
        Pushes the partner recoiled from.
    """

    def __init__(self, config: StageConfig = StageConfig()) -> None:
        self.config = config
        self.corrected = 0  # frames on which the model's placement was moved
        self.reset()

    def reset(self) -> None:
        """Forget the last placement (another person observed, or a new stream)."""
        self._last: np.ndarray | None = None  # the last ground offset from the observed person
        self._recoil = 0.0  # metres added to the partner's distance by a push, fading
        self._touching = False
        self.pushes = 0  # pushes the partner recoiled from

    def __call__(self, observed: np.ndarray, partner: np.ndarray, dt: float) -> np.ndarray:
        """The partner's joints, world metres, moved rigidly to a valid place.

        Parameters
        ----------
        observed, partner : ndarray of shape (14, 3)
            World joints (metres, Y up, ground y = 0) of the observed person and of the model's partner.
        dt : float
            Seconds since the last call (the speed limit is per second).

        Returns
        -------
        ndarray of shape (14, 3)
            A new array of ``partner``'s dtype, world metres.
        """
        c = self.config
        X = np.asarray(observed, np.float64)
        P = np.asarray(partner, np.float64)
        o3, facing = actor_frame(X)
        p3, _ = actor_frame(P)
        o, p = o3[[0, 2]], p3[[0, 2]]
        self._recoil *= float(np.exp(-max(float(dt), 0.0) / c.recoil_s))
        touching = False
        if self._last is not None:  # the hands against the partner where it stands (last frame's offset)
            at = np.zeros(3)
            at[[0, 2]] = o + self._last - p
            touching = bool(
                (_segment_distance(X[_WRISTS], P[_NECK] + at, P[_HIPS].mean(axis=0) + at) < c.contact_m).any()
            )
        if touching and not self._touching:
            self._recoil += c.recoil_m
            self.pushes += 1
        self._touching = touching
        d = p - o
        r = float(np.hypot(*d))
        if r > 1e-6:
            d = d * (r + self._recoil) / r
        offset = _clip_length(d, float(facing), c.min_distance_m, c.max_distance_m)
        if self._last is not None:
            offset = _walk(self._last, offset, c.max_speed_m_s * max(float(dt), 0.0))
        self._last = offset
        shift = np.zeros(3)
        shift[[0, 2]] = o + offset - p
        ankle = float(P[_ANKLES, 1].min())
        shift[1] = min(max(ankle, 0.0), c.max_ankle_m) - ankle
        if np.abs(shift).max() > 1e-3:
            self.corrected += 1
        return (P + shift).astype(np.asarray(partner).dtype)
