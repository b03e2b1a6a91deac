"""The built-in world: two people interacting in front of a camera, rendered with ground truth.

Modules: ``counterpart.sim.scenarios`` (seeded motion and labels), ``counterpart.sim.motion`` (keyframes, reaching),
``counterpart.sim.capture`` (BVH pairs as scenarios), ``counterpart.sim.appearance`` and ``counterpart.sim.render`` (video frames and
ground truth), ``counterpart.sim.stream`` (``open_stream``, what the camera node opens for ``sim:NAME``),
``counterpart.sim.dataset`` (trajectories for training, no rendering), ``counterpart.sim.cli`` (``counterpart sim``).
"""

from __future__ import annotations

from typing import Any


def open_stream(
    scenario: str = "handshake",
    seed: int = 0,
    width: int | None = 320,
    height: int | None = 240,
    fps: float | None = 25.0,
    **kw: Any,
):  # noqa: ANN201
    """See ``counterpart.sim.stream.open_stream`` (imported lazily: ``import sim`` stays cheap)."""
    from counterpart.sim.stream import open_stream as _open

    return _open(scenario, seed=seed, width=width, height=height, fps=fps, **kw)
