"""Seeded two-person scenarios: pose trajectories, per-frame labels and planted listener rules.

Every generator ``NAME(seed=0, fps=25.0, emotion=None, strength=None, initiator=None, **kw)``
returns a :class:`Scenario`: two people's pose trajectories (``counterpart.body.pose`` vectors, T x 28), their
body sizes, an interaction label, a per-frame phase and per-frame social-signal labels.

Scene layout: world metres, Y up, floor y = 0, camera of ``counterpart.body.camera.default_camera`` at
z = +4 m. Person A stands on the left (x < 0) facing +X (``root_yaw`` = +pi/2), person B on the
right (x > 0) facing -X (``root_yaw`` = -pi/2), both around z = 0 (jittered by the seed).

Motion is keyframed (``counterpart.sim.motion.Track``, minimum-jerk between keys) with overlays for gait,
nods, shakes, gestures and emotional style, then grounded (lowest body point on y = 0 every
frame); hands that must meet a target (handshake, high five, pull, push) are solved per frame
with a two-bone arm inverse kinematics (``counterpart.sim.motion.reach``), so contacts are exact.

Seeded variation (``numpy.random.default_rng(seed)`` only): timing, positions, body heights
(``BodyDims.scaled``, 1.55-1.92 m), who initiates, emotion and its strength, and the listener's
interest in conversations.

Phase codes (``PHASES``): 0 approach (before contact), 1 contact (hands joined / touching, or
the main exchange: waving, talking), 2 retreat (after contact). A conversation is phase 1 all
through.

Signals (``SIGNAL_NAMES``), int8 per person and frame, 1 present, 0 absent, -1 unknown:
``nod`` and ``shake`` (head movements planted by the generator, frames where the movement
runs), ``gaze_at_other`` (head facing within 0.3 rad of the other's head in the horizontal
plane, measured on the final poses), ``talking`` (the speaker's turn in a conversation; 0 in
the other scenarios: nobody talks there), ``activity`` (mean speed of shoulders and hips above
0.15 m/s, measured on the final poses).

Emotion (``EMOTIONS``) with ``strength`` s in [0, 1] changes both people's style (see
:func:`style`): angry is faster (x(1 + 0.5 s)) and larger (x(1 + 0.5 s)); sad slower
(x(1 - 0.4 s)), smaller (x(1 - 0.45 s)), head down (+0.35 s rad) and slumped; happy faster
(x(1 + 0.25 s)), larger (x(1 + 0.3 s)) and bouncy (knee bounce at 2.2 Hz); neutral ignores s.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from counterpart.body.kinematics import forward_kinematics, frames
from counterpart.body.pose import DOF_INDEX, clip_to_limits, neutral_pose
from counterpart.body.skeleton import ANCHOR_INDEX, DEFAULT_DIMS, JOINT_INDEX, BodyDims
from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.messages import EMOTIONS
from counterpart.sim.motion import Track, add_gait, apply_reach, ground, oscillation, ramp, smooth_noise, window

SIGNAL_NAMES: tuple[str, ...] = ("nod", "shake", "gaze_at_other", "talking", "activity")
SIGNAL_INDEX: dict[str, int] = {n: i for i, n in enumerate(SIGNAL_NAMES)}
UNKNOWN: int = -1
PHASES: dict[int, str] = {0: "approach", 1: "contact", 2: "retreat"}

#: Listener responses planted in ``conversation``: when the speaker starts signal ``antecedent``
#: (an event of ``d`` frames starting at frame t), the listener performs ``consequent`` over frames
#: [t + offset, t + offset + d) with probability ``p_interested`` (meta["interested"] True) or
#: ``p_uninterested``. ``offset_s`` is in seconds; in frames it is ``round(offset_s * fps)``
#: (10 at 25 fps). Events are placed so responses never overlap other events of the listener, and
#: spontaneous listener events never fall where a response could, so per frame
#: P(listener consequent at t + offset | speaker antecedent at t) equals the probability.
PLANTED_RULES: tuple[dict[str, Any], ...] = (
    {
        "antecedent": "nod",
        "consequent": "nod",
        "offset_s": 0.4,
        "offset_frames_at_25fps": 10,
        "p_interested": 0.8,
        "p_uninterested": 0.3,
    },
    {
        "antecedent": "shake",
        "consequent": "shake",
        "offset_s": 0.4,
        "offset_frames_at_25fps": 10,
        "p_interested": 0.6,
        "p_uninterested": 0.2,
    },
)


@dataclass(frozen=True)
class Style:
    """Emotional style: multipliers of speed (1/duration) and amplitude, offsets in radians.

    Parameters
    ----------
    emotion : str, default="neutral"
        One of ``EMOTIONS``.
    strength : float, default=0.0
        Strength in [0, 1].
    speed : float, default=1.0
        Speed multiplier (1/duration).
    amp : float, default=1.0
        Amplitude multiplier.
    head_down : float, default=0.0
        Head pitch offset, radians.
    slump : float, default=0.0
        Torso slump offset, radians.
    bounce : float, default=0.0
        Knee bounce at 2.2 Hz: peak hip flexion, radians (the knees twice that).
    """

    emotion: str = "neutral"
    strength: float = 0.0
    speed: float = 1.0
    amp: float = 1.0
    head_down: float = 0.0
    slump: float = 0.0
    bounce: float = 0.0


def style(emotion: str, strength: float) -> Style:
    """The :class:`Style` of an emotion at a strength.

    Parameters
    ----------
    emotion : str
        One of ``EMOTIONS``.
    strength : float
        Strength in [0, 1].

    Returns
    -------
    Style
        The style.

    Raises
    ------
    ValueError
        If ``emotion`` is unknown or ``strength`` is outside [0, 1].
    """
    if emotion not in EMOTIONS:
        raise ValueError(f"emotion={emotion!r}: use one of {EMOTIONS}")
    s = float(strength)
    if not 0.0 <= s <= 1.0:
        raise ValueError(f"strength={strength!r}: must be in [0, 1]")
    if emotion == "angry":
        return Style(emotion, s, 1 + 0.5 * s, 1 + 0.5 * s, 0.1 * s, 0.05 * s, 0.0)
    if emotion == "sad":
        return Style(emotion, s, 1 - 0.4 * s, 1 - 0.45 * s, 0.35 * s, 0.15 * s, 0.0)
    if emotion == "happy":
        return Style(emotion, s, 1 + 0.25 * s, 1 + 0.3 * s, -0.08 * s, 0.0, 0.18 * s)
    return Style("neutral", s)


@dataclass
class Scenario:
    """Two people's motion with labels.

    Attributes
    ----------
    poses_a, poses_b : ndarray of shape (T, 28), dtype float64
        Pose vectors (``counterpart.body.pose``), radians and metres.
    dims_a, dims_b : BodyDims
        Body dimensions.
    fps : float
        Frames per second; frame t is at t / fps seconds.
    label : str
        Interaction name ("handshake", ...).
    phase : ndarray of shape (T,), dtype int32
        Phase codes (``PHASES``).
    signals_a, signals_b : ndarray of shape (T, 5), dtype int8
        Signal labels, columns ``signal_names``, 1/0/-1 (unknown).
    signal_names : tuple of str, default=SIGNAL_NAMES
        The signal names.
    meta : dict, default={}
        Seed, emotion, strength, initiator ("a"/"b"), interested, and scenario details.
    """

    poses_a: np.ndarray
    poses_b: np.ndarray
    dims_a: BodyDims
    dims_b: BodyDims
    fps: float
    label: str
    phase: np.ndarray
    signals_a: np.ndarray
    signals_b: np.ndarray
    signal_names: tuple[str, ...] = SIGNAL_NAMES
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return int(self.poses_a.shape[0])

    @property
    def times(self) -> np.ndarray:
        """(T,) seconds."""
        return np.arange(self.n_frames) / self.fps

    def joints(self) -> np.ndarray:
        """Joint positions of A and B.

        Returns
        -------
        ndarray of shape (T, 2, 14, 3)
            Joints, metres, world frame.
        """
        return np.stack(
            [forward_kinematics(self.poses_a, self.dims_a), forward_kinematics(self.poses_b, self.dims_b)], axis=1
        )

    def crop(self, n: int) -> Scenario:
        """The first ``n`` frames.

        Parameters
        ----------
        n : int
            Frames kept (at least 1).

        Returns
        -------
        Scenario
            A new scenario (arrays are views).

        Raises
        ------
        ValueError
            If ``n`` < 1.
        """
        n = int(n)
        if n < 1:
            raise ValueError(f"crop: n={n}; need at least one frame")
        return Scenario(
            self.poses_a[:n],
            self.poses_b[:n],
            self.dims_a,
            self.dims_b,
            self.fps,
            self.label,
            self.phase[:n],
            self.signals_a[:n],
            self.signals_b[:n],
            self.signal_names,
            dict(self.meta),
        )

    def to_trajectory(self) -> TwoPersonTrajectory:
        """The ``counterpart.body.trajectory`` form.

        Returns
        -------
        TwoPersonTrajectory
            Joints, signals as float32 with -1 unknown, phase; body dimensions in ``meta``.
        """
        X = self.joints()
        meta = dict(self.meta)
        meta["dims_a"] = _dims_dict(self.dims_a)
        meta["dims_b"] = _dims_dict(self.dims_b)
        return TwoPersonTrajectory(
            a=X[:, 0],
            b=X[:, 1],
            fps=self.fps,
            label=self.label,
            signals_a=self.signals_a.astype(np.float32),
            signals_b=self.signals_b.astype(np.float32),
            signal_names=self.signal_names,
            phase=self.phase,
            meta=json.loads(json.dumps(meta)),
        )


def _dims_dict(d: BodyDims) -> dict[str, float]:
    return {k: float(v) for k, v in d.__dict__.items()}


# --------------------------------------------------------------------------------- shared set-up
@dataclass
class _Ctx:
    name: str
    rng: np.random.Generator
    fps: float
    st: Style
    dims: dict[str, BodyDims]
    init: str
    cx: float
    cz: float
    meta: dict[str, Any]

    @property
    def other(self) -> str:
        return "b" if self.init == "a" else "a"

    def fwd(self, p: str) -> float:
        """+1 for A (faces +X), -1 for B."""
        return 1.0 if p == "a" else -1.0

    def dur(self, seconds: float) -> float:
        """A movement duration under the emotional speed."""
        return seconds / self.st.speed


def _context(
    name: str, seed: int, fps: float, emotion: str | None, strength: float | None, initiator: str | None
) -> _Ctx:
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps={fps!r}: frames per second must be > 0")
    seed = int(seed)
    rng = np.random.default_rng([seed, sum(map(ord, name))])
    emo = str(rng.choice(EMOTIONS)) if emotion is None else emotion
    s = float(rng.uniform(0.2, 1.0)) if strength is None else float(strength)
    st = style(emo, s)
    dims = {p: DEFAULT_DIMS.scaled(float(rng.uniform(1.55, 1.92))) for p in ("a", "b")}
    init = str(rng.choice(["a", "b"])) if initiator is None else initiator
    if init not in ("a", "b"):
        raise ValueError(f"initiator={initiator!r}: use 'a' (left person) or 'b' (right person)")
    cx, cz = float(rng.uniform(-0.2, 0.2)), float(rng.uniform(-0.4, 0.3))
    meta = {
        "scenario": name,
        "seed": seed,
        "emotion": emo,
        "strength": s,
        "initiator": init,
        "interested": None,
        "heights": [dims["a"].height, dims["b"].height],
    }
    return _Ctx(name, rng, float(fps), st, dims, init, cx, cz, meta)


def _start_pose(c: _Ctx, p: str, x: float) -> np.ndarray:
    yaw = c.fwd(p) * np.pi / 2 + float(c.rng.uniform(-0.06, 0.06))
    P = neutral_pose(c.dims[p], x=x, z=c.cz, yaw=yaw)
    P[DOF_INDEX["root_yaw"]] = c.fwd(p) * np.pi / 2  # keep facing along the line; jitter in twist
    P[DOF_INDEX["torso_twist"]] = yaw - c.fwd(p) * np.pi / 2
    return P


def _shoulder(dims: BodyDims, lean: float) -> np.ndarray:
    """Right shoulder (3,) of a grounded person at the origin facing +Z leaning ``lean`` rad."""
    P = neutral_pose(dims)
    P[DOF_INDEX["torso_flex"]] = lean
    P = ground(P[None], dims)
    return forward_kinematics(P, dims)[0, JOINT_INDEX["r_shoulder"]]  # right is -X here


def _contact_distance(dims: BodyDims, hand_y: float, lateral: float, lean: float, frac: float = 0.9) -> float:
    """Horizontal distance (m) from the pelvis to a right-hand target at height ``hand_y`` and
    ``lateral`` metres towards the person's right, when leaning ``lean`` rad, such that the
    shoulder-target distance is ``frac`` of the arm length.
    """
    S = _shoulder(dims, lean)
    L = frac * (dims.upper_arm + dims.forearm)
    rest = L * L - (hand_y - S[1]) ** 2 - (-lateral - S[0]) ** 2
    return float(S[2] + np.sqrt(max(rest, 0.01)))


def _comfortable_hand_height(dims: list[BodyDims], lateral: float, lean: float, frac: float, forward: float) -> float:
    """The lowest hand height (m) that every person reaches with the hand at least ``forward``
    metres in front of the shoulder (tall people set it: they would otherwise stand too close).
    """
    ys = []
    for d in dims:
        S = _shoulder(d, lean)
        L = frac * (d.upper_arm + d.forearm)
        ys.append(S[1] - np.sqrt(max(L * L - (-lateral - S[0]) ** 2 - forward**2, 0.0)))
    return float(max(ys))


def _idle(c: _Ctx, P: np.ndarray, times: np.ndarray, p: str) -> np.ndarray:
    """Style offsets, a living sway and (happy) a bounce."""
    P = P.copy()
    g = DOF_INDEX
    st = c.st
    n = smooth_noise(c.rng, len(times), c.fps, 0.3, 4)
    P[:, g["torso_lateral"]] += 0.015 * n[:, 0]
    P[:, g["torso_flex"]] += 0.01 * n[:, 1] + st.slump
    P[:, g["head_turn"]] += 0.03 * n[:, 2]
    P[:, g["head_tilt"]] += 0.02 * n[:, 3]
    P[:, g["head_nod"]] += st.head_down
    if st.bounce > 0:
        b = st.bounce * 0.5 * (1 - np.cos(2 * np.pi * 2.2 * times + c.rng.uniform(0, 6.3)))
        for s in ("l", "r"):
            P[:, g[f"{s}_knee_flex"]] += 2 * b
            P[:, g[f"{s}_hip_flex"]] += b
    for s in ("l", "r"):  # slumped shoulders when sad
        P[:, g[f"{s}_shoulder_flex"]] += 0.3 * st.slump
    return P


def _gaze_and_activity(
    Pa: np.ndarray, Pb: np.ndarray, da: BodyDims, db: BodyDims, fps: float
) -> tuple[np.ndarray, np.ndarray]:
    """(T, 2) gaze_at_other and activity labels of A and B measured on the poses."""
    pts_a, Ra = frames(Pa, da)
    pts_b, Rb = frames(Pb, db)
    h = JOINT_INDEX["head"]
    gaze, act = [], []
    for pts, R, other in ((pts_a, Ra, pts_b), (pts_b, Rb, pts_a)):
        f = R["head"][:, :, 2]
        to = other[:, h] - pts[:, h]
        ang = np.abs(np.arctan2(f[:, 0] * to[:, 2] - f[:, 2] * to[:, 0], f[:, 0] * to[:, 0] + f[:, 2] * to[:, 2]))
        gaze.append(ang < 0.3)
        tj = [JOINT_INDEX[j] for j in ("l_shoulder", "r_shoulder", "l_hip", "r_hip")]
        c = pts[:, tj].mean(axis=1)
        v = np.linalg.norm(np.gradient(c, axis=0), axis=1) * fps
        v = np.convolve(v, np.ones(5) / 5, mode="same")
        act.append(v > 0.15)
    return np.stack(gaze, 1), np.stack(act, 1)


def _finish(
    c: _Ctx, P: dict[str, np.ndarray], phase: np.ndarray, events: dict[str, dict[str, np.ndarray]] | None = None
) -> Scenario:
    Pa, Pb = clip_to_limits(P["a"]), clip_to_limits(P["b"])
    T = len(Pa)
    gaze, act = _gaze_and_activity(Pa, Pb, c.dims["a"], c.dims["b"], c.fps)
    sig = {}
    for k, p in enumerate(("a", "b")):
        s = np.zeros((T, len(SIGNAL_NAMES)), np.int8)
        s[:, SIGNAL_INDEX["gaze_at_other"]] = gaze[:, k]
        s[:, SIGNAL_INDEX["activity"]] = act[:, k]
        if events:
            for name, mask in events[p].items():
                s[:, SIGNAL_INDEX[name]] = mask
        sig[p] = s
    meta = dict(c.meta)
    meta["style"] = {"speed": c.st.speed, "amp": c.st.amp}
    return Scenario(
        Pa, Pb, c.dims["a"], c.dims["b"], c.fps, c.name, phase.astype(np.int32), sig["a"], sig["b"], SIGNAL_NAMES, meta
    )


def _times(c: _Ctx, end: float) -> np.ndarray:
    return np.arange(int(np.ceil(end * c.fps)) + 1) / c.fps


def _walk(tr: Track, t0: float, t1: float, x: float) -> None:
    tr.hold(t0)
    tr.set(t1, root_x=x)


def _legs(c: _Ctx, P: np.ndarray, p: str, busy: np.ndarray | None = None) -> np.ndarray:
    arms = None if busy is None else 1.0 - busy
    return add_gait(P, c.fps, c.dims[p], amp=min(c.st.amp, 1.3), arms=arms)


# ------------------------------------------------------------------------- meeting-hands scenarios
def _hands_meet(c: _Ctx, high: bool, hand_dy: float = 0.0) -> dict[str, Any]:
    """Shared geometry of handshake / high five / pull: distances and the meeting point (raised by
    ``hand_dy`` metres: the target height of the offered hand).
    """
    hmin = min(c.dims["a"].height, c.dims["b"].height)
    lean = 0.0 if high else 0.08
    hand_y = 0.93 * hmin if high else _comfortable_hand_height(list(c.dims.values()), 0.025, lean, 0.96, 0.3)
    hand_y += float(hand_dy)
    d = {p: _contact_distance(c.dims[p], hand_y, 0.025, lean, 0.96) for p in "ab"}
    mx = c.cx + 0.5 * (d["a"] - d["b"])
    return {"hand_y": hand_y, "lean": lean, "d": d, "mx": mx}


def _approach(c: _Ctx, tracks: dict[str, Track], x_end: dict[str, float], t_start: float) -> dict[str, float]:
    """Initiator walks 0.6-1.1 m to ``x_end``, the other 0.1-0.5 m, a little later. Returns
    each person's arrival time.
    """
    arrive = {}
    for p in (c.init, c.other):
        dist = c.rng.uniform(0.6, 1.1) if p == c.init else c.rng.uniform(0.1, 0.5)
        t0 = t_start + (0.0 if p == c.init else c.rng.uniform(0.2, 0.6))
        tracks[p].poses[0][0] = x_end[p] - c.fwd(p) * dist
        t1 = t0 + c.dur(0.6 + dist / 0.75)
        _walk(tracks[p], t0, t1, x_end[p])
        arrive[p] = t1
    return arrive


def handshake(
    seed: int = 0,
    fps: float = 25.0,
    emotion: str | None = None,
    strength: float | None = None,
    initiator: str | None = None,
    hand_dy: float = 0.0,
) -> Scenario:
    """Two people walk up to each other, shake right hands (pumping), let go and step back.

    Parameters
    ----------
    seed : int, default=0
        Seed of every random choice.
    fps : float, default=25.0
        Frames per second (> 0).
    emotion : str or None, default=None
        One of ``EMOTIONS`` (None: drawn from the seed).
    strength : float or None, default=None
        Emotion strength in [0, 1] (None: drawn from the seed in [0.2, 1]).
    initiator : str or None, default=None
        ``"a"`` (left person) or ``"b"`` (right person) (None: drawn from the seed).
    hand_dy : float, default=0.0
        Raises (lowers, < 0) the height where the hands meet, metres.

    Returns
    -------
    Scenario
        The scenario.

    Raises
    ------
    ValueError
        If ``fps``, ``emotion``, ``strength`` or ``initiator`` is invalid.
    """
    c = _context("handshake", seed, fps, emotion, strength, initiator)
    return _meeting(c, kind="handshake", hand_dy=hand_dy)


def high_five(
    seed: int = 0,
    fps: float = 25.0,
    emotion: str | None = None,
    strength: float | None = None,
    initiator: str | None = None,
    hand_dy: float = 0.0,
) -> Scenario:
    """Two people walk up, raise their right hands and slap them together above head height.

    Parameters
    ----------
    seed : int, default=0
        Seed of every random choice.
    fps : float, default=25.0
        Frames per second (> 0).
    emotion : str or None, default=None
        One of ``EMOTIONS`` (None: drawn from the seed).
    strength : float or None, default=None
        Emotion strength in [0, 1] (None: drawn from the seed in [0.2, 1]).
    initiator : str or None, default=None
        ``"a"`` (left person) or ``"b"`` (right person) (None: drawn from the seed).
    hand_dy : float, default=0.0
        Raises (lowers, < 0) the height where the hands meet, metres.

    Returns
    -------
    Scenario
        The scenario.

    Raises
    ------
    ValueError
        If ``fps``, ``emotion``, ``strength`` or ``initiator`` is invalid.
    """
    c = _context("high_five", seed, fps, emotion, strength, initiator)
    return _meeting(c, kind="high_five", hand_dy=hand_dy)


def pull(
    seed: int = 0,
    fps: float = 25.0,
    emotion: str | None = None,
    strength: float | None = None,
    initiator: str | None = None,
) -> Scenario:
    """The initiator takes the other's right hand and pulls: steps back leaning back, the other is
    drawn forward a step, leaning in; then they let go.

    Parameters
    ----------
    seed : int, default=0
        Seed of every random choice.
    fps : float, default=25.0
        Frames per second (> 0).
    emotion : str or None, default=None
        One of ``EMOTIONS`` (None: drawn from the seed).
    strength : float or None, default=None
        Emotion strength in [0, 1] (None: drawn from the seed in [0.2, 1]).
    initiator : str or None, default=None
        ``"a"`` (left person) or ``"b"`` (right person) (None: drawn from the seed).

    Returns
    -------
    Scenario
        The scenario.

    Raises
    ------
    ValueError
        If ``fps``, ``emotion``, ``strength`` or ``initiator`` is invalid.
    """
    c = _context("pull", seed, fps, emotion, strength, initiator)
    return _meeting(c, kind="pull")


def _meeting(c: _Ctx, kind: str, hand_dy: float = 0.0) -> Scenario:
    geo = _hands_meet(c, high=(kind == "high_five"), hand_dy=hand_dy)
    x_end = {"a": geo["mx"] - geo["d"]["a"], "b": geo["mx"] + geo["d"]["b"]}
    tracks = {p: Track(_start_pose(c, p, x_end[p])) for p in "ab"}
    arrive = _approach(c, tracks, x_end, float(c.rng.uniform(0.3, 0.8)))
    t_arr = max(arrive.values())
    reach_d = c.dur(0.7 if kind != "high_five" else 0.5)
    r0 = {c.init: t_arr - c.dur(0.35), c.other: t_arr - c.dur(0.35) + c.dur(float(c.rng.uniform(0.1, 0.3)))}
    t_c = max(r0.values()) + reach_d
    hold = {
        "handshake": c.dur(float(c.rng.uniform(1.2, 2.0))),
        "high_five": c.dur(0.2),
        "pull": c.dur(float(c.rng.uniform(0.9, 1.2))),
    }[kind]
    t_r = t_c + hold
    rel_d = c.dur(0.6)
    pull_d = 0.3 * c.st.amp
    for p in "ab":
        tr = tracks[p]
        tr.set(max(tr.end, r0[p]), torso_flex=0.0)
        tr.set(max(tr.end, r0[p] + reach_d), torso_flex=geo["lean"])
        if kind == "pull":
            x = tr.last[0]
            tr.hold(t_c + 0.1)
            if p == c.init:  # step back, leaning back
                tr.set(t_r, root_x=x - c.fwd(p) * pull_d, torso_flex=-0.15 * c.st.amp)
            else:  # drawn forward, leaning in
                tr.set(t_r, root_x=x + c.fwd(p) * pull_d * 1.15, torso_flex=0.3 * c.st.amp)
        tr.hold(max(tr.end, t_r))
        tr.set(t_r + rel_d, torso_flex=0.0)
    # retreat: both step back a little
    t_back = t_r + rel_d * 0.5
    for p in "ab":
        tr = tracks[p]
        tr.hold(max(tr.end, t_back))
        back = float(c.rng.uniform(0.2, 0.5))
        tr.set(t_back + c.dur(0.6 + back / 0.75), root_x=tr.last[0] - c.fwd(p) * back)
    end = max(tr.end for tr in tracks.values()) + 0.6
    times = _times(c, end)
    # hand targets
    M = np.tile([geo["mx"], geo["hand_y"], c.cz], (len(times), 1))
    if kind == "handshake":
        M[:, 1] += 0.035 * c.st.amp * oscillation(times, t_c - 0.1, t_r, 2.0 * c.st.speed)
    if kind == "pull":
        toward = c.fwd(c.init) * -1.0  # towards the puller's back
        M[:, 0] += toward * pull_d * ramp(times, t_c + 0.1, t_r)
    P = {}
    for p in "ab":
        w = ramp(times, r0[p], r0[p] + reach_d) * (1 - ramp(times, t_r, t_r + rel_d))
        base = _legs(c, _idle(c, tracks[p].sample(times), times, p), p, busy=w)
        base = ground(base, c.dims[p])
        # A's right is +Z, B's right is -Z: each hand stays on its own side of the meeting point.
        own = M + np.array([0.0, 0.0, 0.025 if p == "a" else -0.025])
        if kind == "high_five":
            ready = M + np.array([-c.fwd(p) * 0.18, -0.05, 0.1 if p == "a" else -0.1])
            k = ramp(times, t_c - c.dur(0.25), t_c) * (1 - ramp(times, t_r, t_r + c.dur(0.2)))
            own = ready + k[:, None] * (own - ready)
        P[p] = apply_reach(base, c.dims[p], "r", own, w)
    phase = np.where(times < t_c, 0, np.where(times < t_r, 1, 2))
    c.meta.update({"t_contact": [t_c, t_r], "hand_target": [geo["mx"], geo["hand_y"], c.cz]})
    return _finish(c, P, phase)


def push(
    seed: int = 0,
    fps: float = 25.0,
    emotion: str | None = None,
    strength: float | None = None,
    initiator: str | None = None,
) -> Scenario:
    """The initiator walks up and pushes the other on the chest with both hands; the pushed person
    recoils: leans back, arms flung out, head snapping back, stumbling backwards a few steps.

    Parameters
    ----------
    seed : int, default=0
        Seed of every random choice.
    fps : float, default=25.0
        Frames per second (> 0).
    emotion : str or None, default=None
        One of ``EMOTIONS`` (None: drawn from the seed).
    strength : float or None, default=None
        Emotion strength in [0, 1] (None: drawn from the seed in [0.2, 1]).
    initiator : str or None, default=None
        ``"a"`` (left person) or ``"b"`` (right person) (None: drawn from the seed).

    Returns
    -------
    Scenario
        The scenario.

    Raises
    ------
    ValueError
        If ``fps``, ``emotion``, ``strength`` or ``initiator`` is invalid.
    """
    c = _context("push", seed, fps, emotion, strength, initiator)
    I, O = c.init, c.other
    dO = c.dims[O]
    chest_y = dO.hip_height + dO.torso_length - dO.chest_drop * 0.6
    reach_I = _contact_distance(c.dims[I], chest_y, -0.12, 0.15, 0.8)
    gap = reach_I + dO.r_chest * 0.9
    x = {O: c.cx + c.fwd(I) * gap / 2, I: c.cx - c.fwd(I) * gap / 2}
    tracks = {p: Track(_start_pose(c, p, x[p])) for p in "ab"}
    dist = float(c.rng.uniform(0.6, 1.1))
    tracks[I].poses[0][0] = x[I] - c.fwd(I) * dist
    t0 = float(c.rng.uniform(0.3, 0.8))
    t_arr = t0 + c.dur(0.6 + dist / 0.8)
    _walk(tracks[I], t0, t_arr, x[I])
    reach_d = c.dur(0.4)
    r0 = t_arr - c.dur(0.25)
    t_c = r0 + reach_d
    shove = c.dur(0.35)
    t_r = t_c + shove
    a = c.st.amp
    tI = tracks[I]
    tI.set(max(tI.end, r0), torso_flex=0.05)
    tI.set(t_c, torso_flex=0.15)
    tI.set(t_r, torso_flex=0.28, root_x=x[I] + c.fwd(I) * 0.1 * a)
    tI.set(t_r + c.dur(0.8), torso_flex=0.0)
    tI.hold(t_r + c.dur(2.0))
    tO = tracks[O]
    tO.hold(t_c)
    push_in = 0.12 * a
    tO.set(
        t_r,
        root_x=x[O] + c.fwd(I) * push_in,
        torso_flex=-0.25 * a,
        head_nod=-0.3 * a,
        l_shoulder_abd=0.5 * a,
        r_shoulder_abd=0.5 * a,
        l_elbow_flex=0.6,
        r_elbow_flex=0.6,
    )
    back = float(c.rng.uniform(0.3, 0.45)) * a
    tO.set(
        t_r + c.dur(0.7),
        root_x=x[O] + c.fwd(I) * (push_in + back),
        torso_flex=-0.1 * a,
        head_nod=0.0,
        l_shoulder_abd=0.9 * a,
        r_shoulder_abd=0.9 * a,
    )
    tO.set(
        t_r + c.dur(1.4), torso_flex=0.0, l_shoulder_abd=0.17, r_shoulder_abd=0.17, l_elbow_flex=0.17, r_elbow_flex=0.17
    )
    end = max(tI.end, tO.end) + 0.6
    times = _times(c, end)
    P = {O: ground(_legs(c, _idle(c, tO.sample(times), times, O), O), dO)}
    pts, R = frames(P[O], dO)
    chest = pts[:, ANCHOR_INDEX["chest"]]
    w = ramp(times, r0, t_c) * (1 - ramp(times, t_r, t_r + c.dur(0.4)))
    base = ground(_legs(c, _idle(c, tI.sample(times), times, I), I, busy=w), c.dims[I])
    for side, sgn in (("l", 1.0), ("r", -1.0)):
        # O's left is +X of its torso frame; the pusher's left hand lands on O's right side.
        local = np.array([-sgn * 0.11, 0.02, dO.r_chest * 0.95])
        target = chest + np.einsum("tij,j->ti", R["torso"], local)
        base = apply_reach(base, c.dims[I], side, target, w)
    P[I] = base
    phase = np.where(times < t_c, 0, np.where(times < t_r, 1, 2))
    c.meta.update({"t_contact": [t_c, t_r], "pushed": O})
    return _finish(c, P, phase)


def wave(
    seed: int = 0,
    fps: float = 25.0,
    emotion: str | None = None,
    strength: float | None = None,
    initiator: str | None = None,
) -> Scenario:
    """The initiator takes a step, raises the right hand and waves; the other waves back.

    Parameters
    ----------
    seed : int, default=0
        Seed of every random choice.
    fps : float, default=25.0
        Frames per second (> 0).
    emotion : str or None, default=None
        One of ``EMOTIONS`` (None: drawn from the seed).
    strength : float or None, default=None
        Emotion strength in [0, 1] (None: drawn from the seed in [0.2, 1]).
    initiator : str or None, default=None
        ``"a"`` (left person) or ``"b"`` (right person) (None: drawn from the seed).

    Returns
    -------
    Scenario
        The scenario.

    Raises
    ------
    ValueError
        If ``fps``, ``emotion``, ``strength`` or ``initiator`` is invalid.
    """
    c = _context("wave", seed, fps, emotion, strength, initiator)
    g = DOF_INDEX
    half = float(c.rng.uniform(0.9, 1.3))
    x = {"a": c.cx - half, "b": c.cx + half}
    tracks = {p: Track(_start_pose(c, p, x[p])) for p in "ab"}
    I, O = c.init, c.other
    tracks[I].poses[0][0] = x[I] - c.fwd(I) * 0.35
    t0 = float(c.rng.uniform(0.3, 0.7))
    _walk(tracks[I], t0, t0 + c.dur(1.0), x[I])
    up = c.dur(0.6)
    start = {I: t0 + c.dur(0.8), O: t0 + c.dur(0.8) + float(c.rng.uniform(0.5, 1.0))}
    length = {I: c.dur(float(c.rng.uniform(1.8, 2.6)))}
    length[O] = max(length[I] - (start[O] - start[I]) + 0.3, c.dur(1.2))
    a = c.st.amp
    osc = {}
    for p in (I, O):
        tr = tracks[p]
        tr.hold(max(tr.end, start[p]))
        tr.set(
            start[p] + up,
            r_shoulder_abd=min(2.0 + 0.3 * (a - 1), 2.6),
            r_shoulder_flex=0.3,
            r_shoulder_rot=-1.2,
            r_elbow_flex=0.9,
        )
        tr.hold(start[p] + up + length[p])
        tr.set(
            start[p] + 2 * up + length[p],
            r_shoulder_abd=0.17,
            r_shoulder_flex=0.0,
            r_shoulder_rot=0.0,
            r_elbow_flex=0.17,
        )
        osc[p] = (start[p] + up * 0.5, start[p] + up * 1.5 + length[p])
    end = max(tr.end for tr in tracks.values()) + 0.6
    times = _times(c, end)
    P = {}
    for p in "ab":
        Q = _idle(c, tracks[p].sample(times), times, p)
        Q[:, g["r_elbow_flex"]] += 0.4 * a * oscillation(times, *osc[p], 2.0 * c.st.speed)
        P[p] = ground(_legs(c, Q, p, busy=window(times, start[p], osc[p][1] + up, up)), c.dims[p])
    t_c, t_r = start[I] + up, start[I] + up + length[I]
    phase = np.where(times < t_c, 0, np.where(times < t_r, 1, 2))
    c.meta.update({"t_contact": [t_c, t_r]})
    return _finish(c, P, phase)


# ---------------------------------------------------------------------------------- conversation
def _place_events(
    rng: np.random.Generator, lo: int, hi: int, rate_per_frame: float, dur: tuple[int, int], gap: int, busy: np.ndarray
) -> list[tuple[int, int]]:
    """Non-overlapping events (start, length) in [lo, hi) at a Poisson rate, avoiding ``busy``
    frames (and marking theirs, with ``gap`` frames of margin).
    """
    out = []
    t = lo + int(rng.exponential(1 / rate_per_frame))
    while t < hi:
        d = int(rng.integers(dur[0], dur[1] + 1))
        if t + d + gap <= hi and not busy[max(t - gap, 0) : t + d + gap].any():
            out.append((t, d))
            busy[max(t - gap, 0) : t + d + gap] = True
            t += d + gap
        t += 1 + int(rng.exponential(1 / rate_per_frame))
    return out


def conversation(
    seed: int = 0,
    fps: float = 25.0,
    emotion: str | None = None,
    strength: float | None = None,
    initiator: str | None = None,
    interested: bool | None = None,
    duration: float = 30.0,
) -> Scenario:
    """Two people standing face to face take turns talking (``duration`` seconds).

    The speaker gestures with both arms, looks away now and then (mostly at the start of a turn)
    and nods (about 2 Hz, 2-4 cm of head motion) or shakes the head; the listener mostly looks at
    the speaker, looks away more often when not ``interested``, and answers the speaker's nods and
    shakes by the ``PLANTED_RULES``. Spontaneous listener nods (0.03/s) fall only where no planted
    response can. The initiator speaks first.

    Parameters
    ----------
    seed : int, default=0
        Seed of every random choice.
    fps : float, default=25.0
        Frames per second (> 0).
    emotion : str or None, default=None
        One of ``EMOTIONS`` (None: drawn from the seed).
    strength : float or None, default=None
        Emotion strength in [0, 1] (None: drawn from the seed in [0.2, 1]).
    initiator : str or None, default=None
        ``"a"`` (left person) or ``"b"`` (right person) (None: drawn from the seed).
    interested : bool or None, default=None
        Whether the listener is interested (None: drawn from the seed).
    duration : float, default=30.0
        Length, seconds (> 1).

    Returns
    -------
    Scenario
        The scenario.

    Raises
    ------
    ValueError
        If ``duration`` is not over 1 s, or ``fps``, ``emotion``, ``strength`` or ``initiator`` is
        invalid.
    """
    c = _context("conversation", seed, fps, emotion, strength, initiator)
    rng = c.rng
    if interested is None:
        interested = bool(rng.random() < 0.5)
    c.meta["interested"] = bool(interested)
    if not duration > 1.0:
        raise ValueError(f"duration={duration!r}: a conversation needs more than 1 s")
    g = DOF_INDEX
    st = c.st
    fps = c.fps
    T = int(round(duration * fps))
    times = np.arange(T) / fps
    half = float(rng.uniform(0.55, 0.75))
    x = {"a": c.cx - half, "b": c.cx + half}
    off = {r["antecedent"]: int(round(r["offset_s"] * fps)) for r in PLANTED_RULES}
    prob = {r["antecedent"]: (r["p_interested"] if interested else r["p_uninterested"]) for r in PLANTED_RULES}
    # turns
    turns = []  # (speaker, start, end) frames
    spk, t = c.init, int(rng.integers(0, int(0.5 * fps) + 1))
    while t < T:
        d = int(rng.uniform(3.0, 6.0) / st.speed * fps)
        turns.append((spk, t, min(t + d, T)))
        t += d + int(rng.uniform(0.3, 0.8) * fps)
        spk = "b" if spk == "a" else "a"
    ev = {p: {n: np.zeros(T, np.int8) for n in ("nod", "shake", "talking")} for p in "ab"}
    look_away = {p: np.zeros(T) for p in "ab"}  # signed look-away angle target (rad)
    busy = {p: np.zeros(T + 1, bool) for p in "ab"}
    nod_dur = (int(0.6 * fps / st.speed), int(1.0 * fps / st.speed))
    for spk, t0, t1 in turns:
        lis = "b" if spk == "a" else "a"
        ev[spk]["talking"][t0:t1] = 1
        # the speaker looks away at the start of a turn (thinking) half of the time
        if rng.random() < 0.5:
            d = int(rng.uniform(0.8, 1.5) * fps)
            look_away[spk][t0 : min(t0 + d, t1)] = rng.choice([-1, 1]) * rng.uniform(0.5, 0.8)
        mx = max(off.values())
        for sig, rate in (("nod", 0.35), ("shake", 0.2)):
            # events end before the turn's end minus the offset, so responses stay in the turn
            for s0, d in _place_events(rng, t0, t1 - mx, rate / fps, nod_dur, int(0.4 * fps), busy[spk]):
                ev[spk][sig][s0 : s0 + d] = 1
                r0 = s0 + off[sig]
                busy[lis][r0 : r0 + d] = True  # reserve the listener's response slot either way
                if rng.random() < prob[sig]:
                    ev[lis][sig][r0 : r0 + d] = 1
    # spontaneous listener nods, away from reserved slots, and listener look-aways
    for spk, t0, t1 in turns:
        lis = "b" if spk == "a" else "a"
        for s0, d in _place_events(rng, t0, t1, 0.03 / fps, nod_dur, int(0.4 * fps), busy[lis]):
            ev[lis]["nod"][s0 : s0 + d] = 1
        rate = 0.04 if interested else 0.15
        t = t0 + int(rng.exponential(fps / rate))
        while t < t1:
            d = int(rng.uniform(0.6, 1.6) * fps)
            look_away[lis][t : min(t + d, t1)] = rng.choice([-1, 1]) * rng.uniform(0.5, 0.9)
            t += d + int(rng.exponential(fps / rate))
    P = {}
    k = np.ones(int(0.25 * fps) | 1) / (int(0.25 * fps) | 1)
    for p in "ab":
        Q = np.tile(_start_pose(c, p, x[p]), (T, 1))
        Q = _idle(c, Q, times, p)
        Q[:, g["head_turn"]] += np.convolve(look_away[p], k, mode="same")
        e = ev[p]
        for sig, dof, amp_rad, f in (("nod", "head_nod", 0.15, 2.0), ("shake", "head_turn", 0.3, 2.5)):
            on = np.flatnonzero(np.diff(np.r_[0, e[sig], 0]) == 1)
            offs = np.flatnonzero(np.diff(np.r_[0, e[sig], 0]) == -1)
            for a0, a1 in zip(on, offs):
                Q[:, g[dof]] += amp_rad * st.amp * oscillation(times, a0 / fps, (a1 - 1) / fps, f * st.speed)
        # gestures while talking: smooth random arm movements weighted by the talking state
        talk = np.convolve(e["talking"].astype(float), np.ones(int(0.5 * fps)) / int(0.5 * fps), mode="same")
        n = smooth_noise(rng, T, fps, 0.8 * st.speed, 6)
        for i, s in enumerate(("l", "r")):
            Q[:, g[f"{s}_shoulder_flex"]] += talk * st.amp * (0.35 + 0.2 * n[:, 3 * i])
            Q[:, g[f"{s}_elbow_flex"]] += talk * st.amp * (0.9 + 0.35 * n[:, 3 * i + 1])
            Q[:, g[f"{s}_shoulder_abd"]] += talk * st.amp * 0.1 * np.abs(n[:, 3 * i + 2])
        Q[:, g["torso_flex"]] += 0.03 * talk * n[:, 5]
        P[p] = ground(Q, c.dims[p])
    phase = np.ones(T, np.int32)
    events = {p: {n: ev[p][n] for n in ("nod", "shake", "talking")} for p in "ab"}
    c.meta.update({"turns": [[s, int(a), int(b)] for s, a, b in turns], "planted_offsets_frames": off})
    return _finish(c, P, phase, events)


# ------------------------------------------------------------------------------------- registry
SCENARIOS: dict[str, Callable[..., Scenario]] = {
    "handshake": handshake,
    "high_five": high_five,
    "push": push,
    "pull": pull,
    "wave": wave,
    "conversation": conversation,
}


def make_scenario(name: str, seed: int = 0, fps: float = 25.0, **kw: Any) -> Scenario:
    """Generate a scenario.

    Parameters
    ----------
    name : str
        One of ``SCENARIOS``, or ``"cmu"`` (a BVH pair: ``bvh_a``/``bvh_b`` in ``kw``, default the
        shared CMU pair).
    seed : int, default=0
        Seed of every random choice.
    fps : float, default=25.0
        Frames per second.
    **kw
        Further arguments of the generator.

    Returns
    -------
    Scenario
        The scenario.

    Raises
    ------
    ValueError
        If ``name`` is unknown.
    """
    if name == "cmu":
        a, b = kw.pop("bvh_a", None), kw.pop("bvh_b", None)
        if a is None or b is None:
            from counterpart.sim.capture import default_cmu_pair

            a, b = default_cmu_pair()
        return scenario_from_bvh(a, b, fps=fps, **kw)
    if name not in SCENARIOS:
        raise ValueError(f"unknown scenario {name!r}; choose one of {sorted(SCENARIOS)} or 'cmu'")
    return SCENARIOS[name](seed=seed, fps=fps, **kw)


def scenario_from_bvh(path_a: str, path_b: str, fps: float = 25.0, label: str = "handshake", seed: int = 0) -> Scenario:
    """A BVH pair as a scenario; see ``counterpart.sim.capture.scenario_from_bvh``.

    Parameters
    ----------
    path_a, path_b : str
        The two people's BVH files.
    fps : float, default=25.0
        Frames per second.
    label : str, default="handshake"
        Interaction name.
    seed : int, default=0
        Seed.

    Returns
    -------
    Scenario
        The scenario.
    """
    from counterpart.sim.capture import scenario_from_bvh as _from_bvh

    return _from_bvh(path_a, path_b, fps=fps, label=label, seed=seed)
