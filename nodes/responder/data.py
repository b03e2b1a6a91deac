"""Training data for the responder: two-person trajectories from files, BVH pairs or the simulator.

A data spec is one of::

    PATH.npz                 a two-person trajectory file (body.trajectory format)
    A.bvh:B.bvh              a BVH pair, one person per file (CMU style)
    sim                      every simulator scenario, ``seeds`` seeds each
    sim:handshake,push       the named simulator scenarios only
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence

import numpy as np

from counterpart.body.trajectory import TwoPersonTrajectory

#: the simulator's interaction types (counterpart.sim.scenarios.SCENARIOS), in a fixed order
SIM_SCENARIOS: tuple[str, ...] = ("handshake", "high_five", "push", "pull", "wave", "conversation")

Progress = Callable[[str], None]


def sim_trajectories(
    scenarios: Sequence[str] = SIM_SCENARIOS,
    seeds: Sequence[int] = range(6),
    fps: float = 25.0,
    max_frames: int | None = 400,
    **kw: object,
) -> list[TwoPersonTrajectory]:
    """Simulated interactions (joints only, no rendering), one per (scenario, seed).

    Parameters
    ----------
    scenarios : sequence of str, default=SIM_SCENARIOS
        Simulator scenario names, each one of ``SIM_SCENARIOS``.
    seeds : sequence of int, default=range(6)
        Seeds, one interaction per scenario and seed.
    fps : float, default=25.0
        Frame rate, frames per second.
    max_frames : int or None, default=400
        Crops long scenarios (conversations run 30 s) to keep training fast; None or 0: no crop.
    **kw : object
        Extra keyword arguments (``emotion``, ``strength``, ``initiator``) for the scenario generators.

    Returns
    -------
    list of TwoPersonTrajectory
        One trajectory per (scenario, seed), scenarios in the outer loop.

    Raises
    ------
    ValueError
        If a scenario name is unknown.
    """
    from counterpart.bus.plugins import simulator  # the simulator is only needed to build training data

    make_scenario = simulator().make_scenario

    out = []
    for name in scenarios:
        if name not in SIM_SCENARIOS:
            raise ValueError(f"unknown simulator scenario {name!r}; choose from {', '.join(SIM_SCENARIOS)}")
        for seed in seeds:
            sc = make_scenario(name, seed=int(seed), fps=fps, **kw)
            if max_frames and sc.n_frames > max_frames:
                sc = sc.crop(max_frames)
            out.append(sc.to_trajectory())
    return out


def load_data(
    specs: Sequence[str], seeds: Sequence[int] = range(6), fps: float = 25.0, progress: Progress | None = None
) -> list[TwoPersonTrajectory]:
    """Trajectories for every spec (see the module docstring), resampled to ``fps``.

    Parameters
    ----------
    specs : sequence of str
        Data specs: ``PATH.npz``, ``A.bvh:B.bvh``, ``sim`` or ``sim:NAME,NAME``.
    seeds : sequence of int, default=range(6)
        Simulator seeds, for the ``sim`` specs.
    fps : float, default=25.0
        Frame rate of the returned trajectories, frames per second.
    progress : callable or None, default=None
        Called with a line of text before each spec is read.

    Returns
    -------
    list of TwoPersonTrajectory
        The trajectories, in the order of ``specs``.

    Raises
    ------
    FileNotFoundError
        If a trajectory or BVH file does not exist.
    ValueError
        If no spec gives data, a BVH pair is malformed or a simulator scenario is unknown.
    """
    say = progress or (lambda s: None)
    out: list[TwoPersonTrajectory] = []
    for spec in specs:
        if spec == "sim" or spec.startswith("sim:"):
            names = SIM_SCENARIOS if spec == "sim" else tuple(n for n in spec[4:].split(",") if n)
            say(f"simulating {len(names)} scenario(s) x {len(list(seeds))} seed(s)")
            out += sim_trajectories(names, seeds, fps)
        elif spec.lower().endswith(".bvh") and ":" in spec:
            a, b = spec.rsplit(":", 1) if spec.count(":") == 1 else _split_bvh_pair(spec)
            for p in (a, b):
                if not os.path.exists(p):
                    raise FileNotFoundError(f"data {spec!r}: no such BVH file {p}")
            say(f"reading BVH pair {a} + {b}")
            out.append(TwoPersonTrajectory.from_bvh_pair(a, b).resample(fps))
        else:
            if not os.path.exists(spec):
                raise FileNotFoundError(
                    f"data {spec!r}: no such trajectory file (give PATH.npz, A.bvh:B.bvh, sim or sim:NAME,NAME)"
                )
            say(f"reading {spec}")
            tr = TwoPersonTrajectory.load(spec)
            out.append(tr if abs(tr.fps - fps) < 1e-6 else tr.resample(fps))
    if not out:
        raise ValueError("no training data: give at least one --data spec")
    return out


def _split_bvh_pair(spec: str) -> tuple[str, str]:
    i = spec.lower().find(".bvh:")
    if i < 0:
        raise ValueError(f"data {spec!r}: a BVH pair is A.bvh:B.bvh")
    return spec[: i + 4], spec[i + 5 :]


def summary(trajs: Sequence[TwoPersonTrajectory]) -> dict[str, object]:
    """A JSON-able summary of training data for model metadata.

    Parameters
    ----------
    trajs : sequence of TwoPersonTrajectory
        The training data.

    Returns
    -------
    dict
        ``sequences`` (count), ``frames`` (total), ``fps`` (median) and ``labels`` (count per label).
    """
    labels: dict[str, int] = {}
    for t in trajs:
        labels[t.label] = labels.get(t.label, 0) + 1
    return {
        "sequences": len(trajs),
        "frames": int(sum(t.n_frames for t in trajs)),
        "fps": float(np.median([t.fps for t in trajs])) if trajs else 0.0,
        "labels": labels,
    }
