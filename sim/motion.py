"""Motion building blocks for the scenarios: keyframe tracks, overlays, arm reaching, ground contact.

Everything works on pose arrays ``P`` of shape (T, 28) (``counterpart.body.pose`` layout, radians and metres)
sampled at ``fps`` frames per second.

* :class:`Track` holds keyframes of one person and samples them with minimum-jerk interpolation
  between consecutive keys (Flash & Hogan 1985: ``s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5``), so
  velocity and acceleration are zero at every key: human-like point-to-point movements.
* :func:`add_gait` adds leg swing driven by the distance the pelvis travels (walking).
* :func:`bump` / :func:`oscillation` add windowed movements (nods, shakes, waving, pumping).
* :func:`reach` solves the arm (shoulder flex/abd/rot, elbow flex) so that the wrist lies on a
  world target, vectorised over frames: a two-bone analytic solution for the elbow position,
  then ``counterpart.body.ik.inverse_kinematics`` for the angles; :func:`apply_reach` blends it in by a
  per-frame weight.
* :func:`ground` shifts ``root_y`` so that the lowest point of the body touches y = 0.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.ik import inverse_kinematics
from counterpart.body.kinematics import forward_kinematics, lowest_point
from counterpart.body.pose import DOF, DOF_INDEX, clip_to_limits
from counterpart.body.skeleton import JOINT_INDEX, BodyDims

ARM_DOFS: dict[str, list[int]] = {
    s: [DOF_INDEX[f"{s}_{n}"] for n in ("shoulder_flex", "shoulder_abd", "shoulder_rot", "elbow_flex")]
    for s in ("l", "r")
}


def min_jerk(tau: np.ndarray) -> np.ndarray:
    """Minimum-jerk profile on [0, 1] (Flash & Hogan 1985), clipped outside.

    Parameters
    ----------
    tau : ndarray
        Normalised time, any shape; clipped to [0, 1].

    Returns
    -------
    ndarray
        ``10 tau^3 - 15 tau^4 + 6 tau^5``, in [0, 1], same shape as ``tau``.
    """
    t = np.clip(tau, 0.0, 1.0)
    return t * t * t * (10.0 - 15.0 * t + 6.0 * t * t)


def ramp(times: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """0 before ``t0``, 1 after ``t1``, minimum-jerk in between.

    Parameters
    ----------
    times : ndarray of shape (T,)
        Sample times, seconds.
    t0, t1 : float
        Start and end of the rise, seconds; ``t1 <= t0``: a step at ``t0``.

    Returns
    -------
    ndarray of shape (T,)
        float64 in [0, 1].
    """
    if t1 <= t0:
        return (times >= t0).astype(np.float64)
    return min_jerk((times - t0) / (t1 - t0))


def window(times: np.ndarray, t0: float, t1: float, edge: float) -> np.ndarray:
    """Smooth plateau: rises over ``edge`` s from ``t0``, falls over ``edge`` s to ``t1``.

    Parameters
    ----------
    times : ndarray of shape (T,)
        Sample times, seconds.
    t0, t1 : float
        Start of the rise and end of the fall, seconds.
    edge : float
        Duration of the rise and of the fall, seconds.

    Returns
    -------
    ndarray of shape (T,)
        float64 in [0, 1].
    """
    return ramp(times, t0, t0 + edge) * (1.0 - ramp(times, t1 - edge, t1))


class Track:
    """Keyframes of one person's pose; sampled with minimum-jerk interpolation.

    Keys must be added in increasing time. ``set(t, name=value, ...)`` copies the previous key
    and changes the named DOFs (``counterpart.body.pose.DOF_NAMES``), so a key only says what moves.

    Parameters
    ----------
    P0 : ndarray of shape (DOF,)
        The pose at time 0 (``counterpart.body.pose`` layout, radians and metres).

    Raises
    ------
    ValueError
        If ``P0`` is not of shape (DOF,).
    """

    def __init__(self, P0: np.ndarray) -> None:
        P0 = np.asarray(P0, dtype=np.float64)
        if P0.shape != (DOF,):
            raise ValueError(f"Track: initial pose has shape {P0.shape}; expected ({DOF},)")
        self.times: list[float] = [0.0]
        self.poses: list[np.ndarray] = [P0.copy()]

    @property
    def last(self) -> np.ndarray:
        return self.poses[-1].copy()

    @property
    def end(self) -> float:
        return self.times[-1]

    def key(self, t: float, P: np.ndarray) -> Track:
        """Add a key.

        Parameters
        ----------
        t : float
            Time of the key, seconds; not before the last key.
        P : ndarray of shape (DOF,)
            The pose at ``t``.

        Returns
        -------
        Track
            self, for chaining.

        Raises
        ------
        ValueError
            If ``t`` is before the last key.
        """
        if t < self.times[-1] - 1e-9:
            raise ValueError(f"Track.key: time {t:.3f} s is before the last key at {self.times[-1]:.3f} s")
        self.times.append(float(t))
        self.poses.append(np.asarray(P, dtype=np.float64).copy())
        return self

    def set(self, t: float, **dofs: float) -> Track:
        """Add a key: the previous key with the named DOFs changed.

        Parameters
        ----------
        t : float
            Time of the key, seconds; not before the last key.
        **dofs : float
            New values of DOFs by name (``counterpart.body.pose.DOF_NAMES``), radians or metres.

        Returns
        -------
        Track
            self, for chaining.

        Raises
        ------
        ValueError
            If a DOF name is unknown or ``t`` is before the last key.
        """
        P = self.last
        for name, v in dofs.items():
            if name not in DOF_INDEX:
                raise ValueError(f"Track.set: unknown DOF {name!r}; see counterpart.body.pose.DOF_NAMES")
            P[DOF_INDEX[name]] = v
        return self.key(t, P)

    def hold(self, t: float) -> Track:
        """Add a key at ``t`` (seconds) repeating the last pose; returns self."""
        return self.key(t, self.last)

    def sample(self, times: np.ndarray) -> np.ndarray:
        """Poses at the given times; before the first / after the last key: held.

        Parameters
        ----------
        times : ndarray of shape (T,)
            Sample times, seconds.

        Returns
        -------
        ndarray of shape (T, DOF)
            The interpolated poses.
        """
        kt = np.asarray(self.times)
        kp = np.stack(self.poses)
        i = np.clip(np.searchsorted(kt, times, side="right") - 1, 0, len(kt) - 1)
        j = np.minimum(i + 1, len(kt) - 1)
        span = kt[j] - kt[i]
        tau = np.where(span > 1e-9, (times - kt[i]) / np.where(span > 1e-9, span, 1.0), 0.0)
        s = min_jerk(tau)[:, None]
        return kp[i] + s * (kp[j] - kp[i])


def smooth_noise(rng: np.random.Generator, n: int, fps: float, cutoff_hz: float, k: int = 1) -> np.ndarray:
    """Low-pass Gaussian noise of unit standard deviation (Gaussian-kernel smoothed).

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of the noise.
    n : int
        Number of samples.
    fps : float
        Sample rate, frames per second.
    cutoff_hz : float
        Cut-off frequency of the smoothing, Hz.
    k : int, default=1
        Number of independent channels.

    Returns
    -------
    ndarray of shape (n, k)
        The noise, each channel of unit standard deviation.
    """
    sigma = max(fps / (2 * np.pi * cutoff_hz), 1e-3)
    half = int(np.ceil(3 * sigma))
    x = rng.standard_normal((n + 2 * half, k))
    ker = np.exp(-0.5 * (np.arange(-half, half + 1) / sigma) ** 2)
    ker /= ker.sum()
    y = np.stack([np.convolve(x[:, c], ker, mode="valid") for c in range(k)], axis=1)[:n]
    sd = y.std(axis=0, keepdims=True)
    return y / np.where(sd > 0, sd, 1.0)


def oscillation(times: np.ndarray, t0: float, t1: float, freq_hz: float, phase: float = 0.0) -> np.ndarray:
    """``sin(2 pi f (t - t0) + phase)`` under a Hann window on [t0, t1] (0 outside), so the
    movement starts and ends at rest.

    Parameters
    ----------
    times : ndarray of shape (T,)
        Sample times, seconds.
    t0, t1 : float
        Start and end of the window, seconds.
    freq_hz : float
        Oscillation frequency ``f``, Hz.
    phase : float, default=0.0
        Phase at ``t0``, radians.

    Returns
    -------
    ndarray of shape (T,)
        float64 in [-1, 1].
    """
    inside = (times >= t0) & (times <= t1)
    d = max(t1 - t0, 1e-9)
    w = 0.5 - 0.5 * np.cos(2 * np.pi * (times - t0) / d)
    return np.where(inside, w * np.sin(2 * np.pi * freq_hz * (times - t0) + phase), 0.0)


def add_gait(P: np.ndarray, fps: float, dims: BodyDims, amp: float = 1.0, arms: np.ndarray | None = None) -> np.ndarray:
    """Add walking leg swing to poses whose pelvis moves horizontally.

    The gait phase advances with the distance walked (one cycle per stride of ``0.75 * height``
    metres: two steps), and its amplitude follows the walking speed (full at >= 0.5 m/s), so feet
    barely slide and the legs rest when the pelvis stops.

    Parameters
    ----------
    P : ndarray of shape (T, DOF)
        Poses (``counterpart.body.pose`` layout).
    fps : float
        Frame rate, frames per second.
    dims : BodyDims
        Body dimensions (the stride follows ``dims.height``).
    amp : float, default=1.0
        Multiplier of the swing amplitude.
    arms : ndarray of shape (T,) or None, default=None
        In [0, 1], scales the counter-swing of the arms (0 where the arms are busy); None: full swing.

    Returns
    -------
    ndarray of shape (T, DOF)
        A new array; ``P`` is not changed.
    """
    P = P.copy()
    xz = P[:, [0, 2]]
    step = np.r_[0.0, np.linalg.norm(np.diff(xz, axis=0), axis=1)]
    speed = np.convolve(step * fps, np.ones(5) / 5, mode="same")
    a = np.clip(speed / 0.5, 0.0, 1.0) * amp
    phi = 2 * np.pi * np.cumsum(step) / (0.75 * dims.height)
    s = np.sin(phi)
    g = DOF_INDEX
    P[:, g["l_hip_flex"]] += 0.35 * a * s
    P[:, g["r_hip_flex"]] -= 0.35 * a * s
    # The knee bends while its leg swings forward (hip flexing), clearing the foot.
    P[:, g["l_knee_flex"]] += a * (0.1 + 0.5 * np.clip(np.sin(phi + 0.6), 0, None))
    P[:, g["r_knee_flex"]] += a * (0.1 + 0.5 * np.clip(-np.sin(phi + 0.6), 0, None))
    w = a if arms is None else a * arms
    P[:, g["l_shoulder_flex"]] -= 0.3 * w * s
    P[:, g["r_shoulder_flex"]] += 0.3 * w * s
    return P


def ground(P: np.ndarray, dims: BodyDims) -> np.ndarray:
    """Poses with ``root_y`` shifted so that the lowest body point of every frame is at y = 0.

    Parameters
    ----------
    P : ndarray of shape (T, DOF)
        Poses (``counterpart.body.pose`` layout).
    dims : BodyDims
        Body dimensions.

    Returns
    -------
    ndarray of shape (T, DOF)
        A new array; ``P`` is not changed.
    """
    P = P.copy()
    P[:, DOF_INDEX["root_y"]] -= lowest_point(P, dims)
    return P


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def reach(P: np.ndarray, dims: BodyDims, side: str, target: np.ndarray, reach_frac: float = 0.985) -> np.ndarray:
    """Arm angles that put the ``side`` ("l"/"r") wrist on ``target``.

    The elbow is placed in the plane of the shoulder-target line and a "down and outwards" pole,
    the way people hold their elbows when they reach.

    Parameters
    ----------
    P : ndarray of shape (T, DOF)
        Poses (the rest of the body is kept).
    dims : BodyDims
        Body dimensions.
    side : {"l", "r"}
        The person's own side.
    target : ndarray of shape (T, 3) or (3,)
        Wrist targets, metres, world frame.
    reach_frac : float, default=0.985
        Targets farther than this fraction of the arm length are pulled in along the
        shoulder-target line (the arm then points at them, nearly straight).

    Returns
    -------
    ndarray of shape (T, 4)
        shoulder_flex, shoulder_abd, shoulder_rot, elbow_flex, radians.

    Raises
    ------
    ValueError
        If ``side`` is not "l" or "r".
    """
    if side not in ("l", "r"):
        raise ValueError(f"reach: side={side!r}; use 'l' or 'r'")
    P = np.atleast_2d(np.asarray(P, dtype=np.float64))
    X = forward_kinematics(P, dims)
    T = X.shape[0]
    target = np.broadcast_to(np.asarray(target, dtype=np.float64), (T, 3))
    J = JOINT_INDEX
    S = X[:, J[f"{side}_shoulder"]]
    a, b = dims.upper_arm, dims.forearm
    d = target - S
    L = np.linalg.norm(d, axis=1, keepdims=True)
    u = _unit(d)
    L = np.clip(L, abs(a - b) + 1e-3, reach_frac * (a + b))
    x = (a * a - b * b + L * L) / (2 * L)
    h = np.sqrt(np.clip(a * a - x * x, 0.0, None))
    out = _unit(X[:, J[f"{side}_shoulder"]] - X[:, J["neck"]])
    pole = np.array([0.0, -1.0, 0.0]) + 0.6 * out
    pole = _unit(pole - np.sum(pole * u, axis=1, keepdims=True) * u)
    E = S + x * u + h * pole
    W = S + L * u
    X2 = X.copy()
    X2[:, J[f"{side}_elbow"]] = E
    X2[:, J[f"{side}_wrist"]] = W
    return inverse_kinematics(X2)[:, ARM_DOFS[side]]


def apply_reach(P: np.ndarray, dims: BodyDims, side: str, target: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Blend the ``reach`` solution into the ``side`` arm by a per-frame weight.

    Parameters
    ----------
    P : ndarray of shape (T, DOF)
        Poses.
    dims : BodyDims
        Body dimensions.
    side : {"l", "r"}
        The person's own side.
    target : ndarray of shape (T, 3) or (3,)
        Wrist targets, metres, world frame.
    weight : ndarray of shape (T,)
        Blend weight in [0, 1] (0: the pose as is, 1: the reach solution).

    Returns
    -------
    ndarray of shape (T, DOF)
        A new array, clipped to the joint limits.
    """
    P = P.copy()
    w = np.asarray(weight, dtype=np.float64)
    on = w > 1e-6
    if on.any():
        sol = reach(P[on], dims, side, np.broadcast_to(target, (len(P), 3))[on])
        idx = ARM_DOFS[side]
        P[np.ix_(on, idx)] = (1 - w[on, None]) * P[np.ix_(on, idx)] + w[on, None] * sol
    return clip_to_limits(P)
