"""Training each responder model from two-person trajectories (and the simulator defaults)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.messages import EMOTIONS

from .data import SIM_SCENARIOS, sim_trajectories

Progress = Callable[[str], None] | None


def default_training_data(name: str, progress: Progress = None) -> list[TwoPersonTrajectory]:
    """The simulator data each default model is trained on (sized to train in well under 60 s).

    Parameters
    ----------
    name : str
        The model: ``"dual-hmm"``, ``"joint-shape"``, ``"listener"``, ``"emotion"`` or ``"gpdm"``.
    progress : callable or None
        Called with a line of progress text.

    Returns
    -------
    list of TwoPersonTrajectory
        The simulated training trajectories.

    Raises
    ------
    ValueError
        For an unknown model name.
    """
    say = progress or (lambda s: None)
    say(f"{name}: simulating training data")
    if name == "dual-hmm":
        return sim_trajectories(SIM_SCENARIOS, range(8), max_frames=300)
    if name == "joint-shape":
        return sim_trajectories(SIM_SCENARIOS, range(5), max_frames=250)
    if name == "listener":
        return sim_trajectories(("conversation",), range(8), max_frames=None)
    if name == "emotion":
        out = sim_trajectories(SIM_SCENARIOS, range(2), max_frames=200, emotion="neutral")
        for e in EMOTIONS[1:]:
            for s in (0.2, 0.5, 0.8, 1.0):
                out += sim_trajectories(SIM_SCENARIOS, range(2), max_frames=200, emotion=e, strength=s)
        return out
    if name == "gpdm":
        return gpdm_training_data()
    raise ValueError(f"unknown responder model {name!r}")


def gpdm_training_data(seeds: int = 8, max_frames: int = 250) -> list[TwoPersonTrajectory]:
    """The gpdm's default data: high fives and handshakes, neutral and each emotion at strengths 0.5
    and 1, the hands meeting 0.1 m lower, at, and 0.1 m higher than the simulator's own height in
    turn (2 x 7 x ``seeds`` trials, 112 by default).

    Parameters
    ----------
    seeds : int
        Simulator seeds per scenario and emotion setting.
    max_frames : int
        Frames per trial at most.

    Returns
    -------
    list of TwoPersonTrajectory
        The simulated trials.
    """
    out = []
    for e in EMOTIONS:
        for s in (0.0,) if e == "neutral" else (0.5, 1.0):
            for seed in range(seeds):
                out += sim_trajectories(
                    ("handshake", "high_five"),
                    [seed],
                    max_frames=max_frames,
                    emotion=e,
                    strength=s,
                    hand_dy=(-0.1, 0.0, 0.1)[seed % 3],
                )
    return out


def speaker_listener(t: TwoPersonTrajectory) -> tuple[np.ndarray, np.ndarray]:
    """The speaker's and the listener's signal labels of a conversation: the speaker talks more.

    Parameters
    ----------
    t : TwoPersonTrajectory
        The conversation, with ``signals_a`` and ``signals_b``.

    Returns
    -------
    speaker : ndarray of shape (T, K)
        The speaker's signal labels.
    listener : ndarray of shape (T, K)
        The listener's signal labels.

    Raises
    ------
    ValueError
        If the trajectory has no signals.
    """
    if t.signals_a is None:
        raise ValueError(f"trajectory {t.label!r} has no signals: the listener model needs signals_a/_b")
    k = t.signal_names.index("talking") if "talking" in t.signal_names else None
    a_talks = k is None or (t.signals_a[:, k] == 1).sum() >= (t.signals_b[:, k] == 1).sum()
    return (t.signals_a, t.signals_b) if a_talks else (t.signals_b, t.signals_a)


def train(name: str, data: Sequence[TwoPersonTrajectory], progress: Progress = None, **params: Any) -> Any:
    """Fit model ``name`` on trajectories.

    Parameters
    ----------
    name : str
        The model: ``"dual-hmm"``, ``"joint-shape"``, ``"listener"``, ``"emotion"`` or ``"gpdm"``.
    data : sequence of TwoPersonTrajectory
        The training trajectories.
    progress : callable or None
        Called with a line of progress text.
    **params : Any
        Keyword parameters of the model's constructor.

    Returns
    -------
    Any
        The fitted model.

    Raises
    ------
    ValueError
        For an unknown model name.
    """
    say = progress or (lambda s: None)
    if name == "dual-hmm":
        from .dual_hmm import DualHMM

        model = DualHMM(**params)
        folds = model.config.correction.folds
        extra = f", then the placement correction on {folds} held-out folds" if folds else ""
        say(f"dual-hmm: fitting PCA + HMM on {len(data)} sequences{extra}")
        return model.fit(data)
    if name == "joint-shape":
        from .joint_shape import JointShapeModel
        from .shapes import trajectory_shapes

        say(f"joint-shape: silhouettes and splines of {len(data)} sequences")
        shapes = [trajectory_shapes(t) for t in data]
        say("joint-shape: prototypes, behaviours and Markov chain")
        return JointShapeModel(**params).fit(shapes)
    if name == "listener":
        from .listener import ListenerModel, count_rules

        fps = float(data[0].fps)
        model = ListenerModel(fps=fps, **params)
        offset = int(round(model.offset_s * fps))
        groups: dict[str, list[TwoPersonTrajectory]] = {}
        for t in data:
            key = {True: "interested", False: "not_interested"}.get(t.meta.get("interested"), "interested")
            groups.setdefault(key, []).append(t)
        rules = {}
        for key, ts in groups.items():
            pairs = [speaker_listener(t) for t in ts]
            rules[key] = count_rules([p[0] for p in pairs], [p[1] for p in pairs], data[0].signal_names, offset)
            say(f"listener: {len(rules[key])} rules for {key} ({len(ts)} conversations)")
        return model.fit(rules, {"offset": offset, "fps": fps})
    if name == "emotion":
        from .emotion import EmotionModel

        say(f"emotion: ranking functions from {len(data)} labelled sequences")
        return EmotionModel(**params).fit_trajectories(data)
    if name == "gpdm":
        from .gpdm import GPDM

        return GPDM(**params).fit(data, say)
    raise ValueError(f"unknown responder model {name!r}")
