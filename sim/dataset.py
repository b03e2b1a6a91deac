"""Training data without rendering: scenario trajectories over seeds (the fast path)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.sim.scenarios import SCENARIOS, make_scenario


def generate_dataset(
    scenarios: Iterable[str] | None = None, seeds: Iterable[int] = range(10), fps: float = 25.0, **kw: Any
) -> list[TwoPersonTrajectory]:
    """One ``counterpart.body.trajectory.TwoPersonTrajectory`` per (scenario, seed), poses only (no images).

    Args:
        scenarios: names from ``counterpart.sim.scenarios.SCENARIOS`` (default: all of them).
        seeds: integer seeds.
        fps: frames per second.
        **kw: passed to every generator (e.g. ``emotion="angry"``, ``strength=0.8``;
            ``interested``/``duration`` reach only ``conversation``).

    Returns
    -------
        trajectories in scenario-major order; each one's ``meta`` holds the seed, emotion,
        strength, initiator, interest and body sizes.
    """
    names = list(SCENARIOS) if scenarios is None else list(scenarios)
    for n in names:
        if n not in SCENARIOS:
            raise ValueError(f"generate_dataset: unknown scenario {n!r}; choose from {sorted(SCENARIOS)}")
    conv_only = {"interested", "duration"}
    out = []
    for n in names:
        args = kw if n == "conversation" else {k: v for k, v in kw.items() if k not in conv_only}
        for s in seeds:
            out.append(make_scenario(n, seed=int(s), fps=fps, **args).to_trajectory())
    return out
