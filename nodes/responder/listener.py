"""Listener behaviour from mined association rules (Okwechime et al., "Social interactive human
video synthesis").

Rules are ``{S:x, ...} -> {L:y, ...}`` with a confidence P(listener does y at t + s | speaker shows
x at t), mined per scenario: ``interested`` and ``not_interested`` listeners (the labeller's rules
file, format ``counterpart.labeller.rules``). The user sets the listener's interest level
I in {1, 2, 3}; a rule's confidence at that level is::

    c(r, I) = c_not(r) + (I - 1) / 2 (c_int(r) - c_not(r))      (both scenarios in the file)
    c(r, I) = g_I c(r),  g = (0.4, 0.7, 1.0)                      (one scenario: a gain)

so I = 1 reproduces the not-interested listener, I = 3 the interested one and I = 2 lies half way.
When the speaker's signals make a rule's antecedent true (at its onset frame t), each consequent y
is chosen with probability p(y) = 1 - prod_r (1 - c(r, I)) over the matching rules (noisy-or) and
then performed from frame t + s for ``response_s`` seconds (s = the rules' offset). Behaviour
names are the labeller's signals: ``nod``, ``shake``, ``gaze_at_other``, ``activity``.

The partner's body: a neutral standing person (``counterpart.body.pose.neutral_pose``) facing the speaker
``distance`` metres in front of them; a nod is an oscillation of ``head_nod`` (2.5 Hz, 0.25 rad), a
shake one of ``head_turn`` with a little ``head_tilt`` so the head centre moves sideways (3 Hz),
``gaze_at_other`` turns the head to the speaker (otherwise it looks 0.5 rad aside), ``activity``
sways the torso (0.6 Hz).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import DOF_INDEX, neutral_pose
from counterpart.body.skeleton import DEFAULT_DIMS, BodyDims

from .frames import actor_frame

RULES_FORMAT = "counterpart.labeller.rules"
BEHAVIOURS: tuple[str, ...] = ("nod", "shake", "gaze_at_other", "activity")
INTEREST_GAIN: tuple[float, float, float] = (0.4, 0.7, 1.0)

#: (antecedent items, consequent items, confidence)
RuleTuple = tuple[tuple[str, ...], tuple[str, ...], float]


def read_rules_file(path: str | os.PathLike[str]) -> tuple[dict[str, list[RuleTuple]], dict[str, Any]]:
    """Scenario -> rules and the mining parameters, from a labeller rules file (JSON).

    Parameters
    ----------
    path : str or PathLike
        The rules file (format ``counterpart.labeller.rules``, version 1).

    Returns
    -------
    rules : dict of str to list of RuleTuple
        Scenario -> its rules (antecedent items, consequent items, confidence).
    params : dict of str to object
        The mining parameters (e.g. ``offset`` in frames and ``fps``).

    Raises
    ------
    ValueError
        The file is unreadable, not a rules file, or of another version.
    """
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        raise ValueError(f"{os.fspath(path)}: cannot read a rules file ({e})") from None
    if not isinstance(doc, dict) or doc.get("format") != RULES_FORMAT:
        raise ValueError(f'{os.fspath(path)}: not a rules file (expected "format": "{RULES_FORMAT}")')
    if int(doc.get("version", 0)) != 1:
        raise ValueError(f"{os.fspath(path)}: rules file version {doc.get('version')!r}; this reader knows 1")
    scen = {
        k: [(tuple(r["antecedent"]), tuple(r["consequent"]), float(r["confidence"])) for r in v]
        for k, v in doc.get("scenarios", {}).items()
    }
    return scen, dict(doc.get("params", {}))


def count_rules(
    speaker: Sequence[np.ndarray], listener: Sequence[np.ndarray], names: Sequence[str], offset: int
) -> list[RuleTuple]:
    """Single-item rules S:x -> L:y from recordings: confidence = P(L:y at t + s | S:x at t) over
    frames t.

    Parameters
    ----------
    speaker : sequence of ndarray of shape (T, K)
        The speaker's labels per recording: 1 present; -1 unknown counts as absent.
    listener : sequence of ndarray of shape (T, K)
        The listener's labels of the same recordings.
    names : sequence of str, length K
        The signals' names.
    offset : int
        The response offset s, frames.

    Returns
    -------
    list of RuleTuple
        One rule per pair (x, y) seen together at least once.
    """
    K = len(names)
    joint, ante = np.zeros((K, K)), np.zeros(K)
    for sp, li in zip(speaker, listener):
        s, l_ = np.asarray(sp) == 1, np.asarray(li) == 1
        if len(s) <= offset:
            continue
        s, l_ = s[: len(s) - offset].astype(float), l_[offset:].astype(float)
        joint += s.T @ l_
        ante += s.sum(0)
    return [
        ((f"S:{names[i]}",), (f"L:{names[j]}",), float(joint[i, j] / ante[i]))
        for i in range(K)
        for j in range(K)
        if ante[i] > 0 and joint[i, j] > 0
    ]


class ListenerModel:
    """Chooses listener behaviour from rule confidences at an interest level (module docstring).

    Parameters
    ----------
    offset_s : float, default=0.4
        Response delay s, seconds (a rules file's ``offset``/``fps`` override it).
    response_s : float, default=1.0
        How long a chosen behaviour lasts, seconds.
    distance : float, default=1.2
        Distance from the speaker, metres.
    fps : float, default=25.0
        Frames per second of the steps.
    random_state : int, default=0
        Seed of the behaviour choices.

    Attributes
    ----------
    rules_ : dict of str to list of RuleTuple
        The rules per scenario, set by :meth:`fit`.
    behaviour_ : str
        What the listener does at the last step, behaviours joined by ``+`` (empty: none).

    Raises
    ------
    ValueError
        A negative ``offset_s``, or a ``response_s``, ``distance`` or ``fps`` not above 0.
    """

    name = "listener"

    def __init__(
        self,
        offset_s: float = 0.4,
        response_s: float = 1.0,
        distance: float = 1.2,
        fps: float = 25.0,
        random_state: int = 0,
    ) -> None:
        if offset_s < 0 or response_s <= 0 or distance <= 0 or fps <= 0:
            raise ValueError("offset_s >= 0, response_s > 0, distance > 0 and fps > 0 are required")
        self.offset_s, self.response_s, self.distance = float(offset_s), float(response_s), float(distance)
        self.fps, self.random_state = float(fps), int(random_state)
        self.interest = 3
        self.dims: BodyDims = DEFAULT_DIMS

    # ------------------------------------------------------------------ rules
    def fit(self, rules: Mapping[str, Sequence[RuleTuple]], params: Mapping[str, Any] | None = None) -> ListenerModel:
        """Take the mined rules per scenario (``interested``/``not_interested``, or any one scenario).

        Parameters
        ----------
        rules : mapping of str to sequence of RuleTuple
            Scenario -> its rules.
        params : mapping of str to object or None, default=None
            The mining parameters; ``offset`` (frames, at ``fps``) sets ``offset_s``.

        Returns
        -------
        ListenerModel
            This model, fitted and reset.

        Raises
        ------
        ValueError
            No rules.
        """
        if not rules or not any(rules.values()):
            raise ValueError("ListenerModel.fit: no rules; mine some with 'counterpart mine' first")
        self.rules_ = {k: [(tuple(a), tuple(c), float(p)) for a, c, p in v] for k, v in rules.items()}
        p = dict(params or {})
        if "offset" in p:
            self.offset_s = float(p["offset"]) / float(p.get("fps", self.fps))
        self.reset()
        return self

    @classmethod
    def from_rules_file(cls, path: str | os.PathLike[str], **kw: Any) -> ListenerModel:
        """A model fitted on a labeller rules file.

        Parameters
        ----------
        path : str or PathLike
            The rules file.
        **kw : object
            The constructor's parameters.

        Returns
        -------
        ListenerModel
            The fitted model.

        Raises
        ------
        ValueError
            The file is unreadable, not a rules file, or holds no rules.
        """
        scen, params = read_rules_file(path)
        return cls(**kw).fit(scen, params)

    def confidences(self, interest: int) -> dict[tuple[tuple[str, ...], tuple[str, ...]], float]:
        """Rule -> confidence at an interest level (the interpolation / gain of the module docstring).

        Parameters
        ----------
        interest : int
            Interest level, 1, 2 or 3.

        Returns
        -------
        dict of (tuple of str, tuple of str) to float
            (antecedent items, consequent items) -> confidence.

        Raises
        ------
        ValueError
            An interest level other than 1, 2 or 3.
        """
        if interest not in (1, 2, 3):
            raise ValueError(f"interest={interest!r}: the interest level is 1, 2 or 3")
        r = self.rules_
        if "interested" in r and "not_interested" in r:
            hi = {(a, c): p for a, c, p in r["interested"]}
            lo = {(a, c): p for a, c, p in r["not_interested"]}
            k = (interest - 1) / 2
            return {key: lo.get(key, 0.0) + k * (hi.get(key, 0.0) - lo.get(key, 0.0)) for key in hi.keys() | lo.keys()}
        only = r.get("interested") or next(iter(r.values()))
        return {(a, c): INTEREST_GAIN[interest - 1] * p for a, c, p in only}

    def response_probabilities(
        self, speaker_items: set[str] | Sequence[str], interest: int | None = None
    ) -> dict[str, float]:
        """Behaviour -> probability that the listener performs it, given the speaker's present signals
        by noisy-or over the matching rules.

        Parameters
        ----------
        speaker_items : set or sequence of str
            The speaker's present signals, ``"nod"`` or ``"S:nod"``.
        interest : int or None, default=None
            Interest level 1-3; None for the model's ``interest``.

        Returns
        -------
        dict of str to float
            Behaviour -> probability, for the behaviours of the matching rules.
        """
        items = {s if s.startswith("S:") else f"S:{s}" for s in speaker_items}
        miss: dict[str, float] = {}
        for (ante, cons), p in self.confidences(self.interest if interest is None else interest).items():
            if set(ante) <= items:
                for c in cons:
                    y = c[2:] if c.startswith("L:") else c
                    miss[y] = miss.get(y, 1.0) * (1.0 - min(max(p, 0.0), 1.0))
        return {y: 1.0 - m for y, m in miss.items()}

    # ------------------------------------------------------------------ online
    def reset(self) -> None:
        self._rng = np.random.default_rng(self.random_state)
        self._t = 0
        self._prev: set[str] = set()
        self._active: dict[str, tuple[int, int]] = {}  # behaviour -> (start frame, end frame)
        self.behaviour_ = ""

    def step(self, speaker_signals: Mapping[str, bool], observed: np.ndarray | None = None) -> np.ndarray:
        """One frame: the listener's response to the speaker. ``behaviour_`` names what it does.

        Parameters
        ----------
        speaker_signals : mapping of str to bool
            The speaker's signals, name -> present.
        observed : ndarray of shape (14, 3) or None, default=None
            The speaker's joints, metres, world frame; None places the listener at a fixed spot.

        Returns
        -------
        ndarray of shape (14, 3), dtype float32
            The listener's joints, metres, world frame.
        """
        now = {k for k, v in speaker_signals.items() if v}
        onsets = now - self._prev
        self._prev = now
        if onsets:
            probs = self.response_probabilities(now)
            # only rules that this frame's onsets switch on
            fresh = self.response_probabilities(now - onsets) if now - onsets else {}
            s = int(round(self.offset_s * self.fps))
            for y, p in probs.items():
                if p > fresh.get(y, 0.0) and self._rng.random() < p:
                    start = self._t + s
                    self._active[y] = (start, start + int(round(self.response_s * self.fps)))
        t = self._t
        on = {y for y, (a, b) in self._active.items() if a <= t < b}
        self._active = {y: ab for y, ab in self._active.items() if ab[1] > t}
        self.behaviour_ = "+".join(sorted(on))
        self._t += 1
        return self.body(on, t, observed)

    def body(self, behaviours: set[str], t: int, observed: np.ndarray | None = None) -> np.ndarray:
        """Listener joints for a set of behaviours at frame t, facing the speaker.

        Parameters
        ----------
        behaviours : set of str
            The behaviours performed (of ``BEHAVIOURS``).
        t : int
            Frame index (the oscillations' time is ``t / fps``).
        observed : ndarray of shape (14, 3) or None, default=None
            The speaker's joints, metres, world frame; the listener stands ``distance`` in front of
            them. None: at x = 0.6 m, z = 0, yaw -pi/2.

        Returns
        -------
        ndarray of shape (14, 3), dtype float32
            The listener's joints, metres, world frame.
        """
        if observed is not None:
            o, th = actor_frame(np.asarray(observed, np.float64))
            fwd = np.array([np.sin(th), np.cos(th)])
            x, z, yaw = o[0] + self.distance * fwd[0], o[2] + self.distance * fwd[1], th + np.pi
        else:
            x, z, yaw = 0.6, 0.0, -np.pi / 2
        P = neutral_pose(self.dims, x=x, z=z, yaw=yaw)
        time = t / self.fps
        if "nod" in behaviours:
            P[DOF_INDEX["head_nod"]] += 0.25 * np.sin(2 * np.pi * 2.5 * time)
        if "shake" in behaviours:
            P[DOF_INDEX["head_turn"]] += 0.5 * np.sin(2 * np.pi * 3.0 * time)
            P[DOF_INDEX["head_tilt"]] += 0.15 * np.sin(2 * np.pi * 3.0 * time)
        if "gaze_at_other" not in behaviours and observed is not None and "nod" not in behaviours:
            P[DOF_INDEX["head_turn"]] += 0.5
        if "activity" in behaviours:
            P[DOF_INDEX["torso_lateral"]] += 0.12 * np.sin(2 * np.pi * 0.6 * time)
        return forward_kinematics(P, self.dims)[0].astype(np.float32)

    # ------------------------------------------------------------------ persistence
    def get_state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """The fitted model as arrays and configuration, for saving.

        Returns
        -------
        arrays : dict of str to ndarray
            Empty: the model has no arrays.
        config : dict of str to object
            The constructor's parameters and ``rules``.
        """
        config = {
            "offset_s": self.offset_s,
            "response_s": self.response_s,
            "distance": self.distance,
            "fps": self.fps,
            "random_state": self.random_state,
            "rules": {k: [[list(a), list(c), p] for a, c, p in v] for k, v in self.rules_.items()},
        }
        return {}, config

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray], config: dict[str, Any]) -> ListenerModel:
        """A fitted model from what :meth:`get_state` gave.

        Parameters
        ----------
        arrays : dict of str to ndarray
            Unused.
        config : dict of str to object
            The constructor's parameters and ``rules``.

        Returns
        -------
        ListenerModel
            The model.
        """
        c = dict(config)
        rules = c.pop("rules")
        return cls(**c).fit({k: [(tuple(a), tuple(cc), float(p)) for a, cc, p in v] for k, v in rules.items()})
