"""The built-in world: two people interacting in front of a camera, rendered with ground truth.

Modules: ``sim.scenarios`` (seeded motion and labels), ``sim.motion`` (keyframes, reaching),
``sim.capture`` (BVH pairs as scenarios), ``sim.appearance`` and ``sim.render`` (video frames and
ground truth), ``sim.stream`` (``open_stream``, what the camera node opens for ``sim:NAME``),
``sim.dataset`` (trajectories for training, no rendering), ``sim.cli`` (``counterpart sim``).
"""
from __future__ import annotations

from typing import Any


def open_stream(scenario: str = "handshake", seed: int = 0, width: int | None = 320,
                height: int | None = 240, fps: float | None = 25.0, **kw: Any):  # noqa: ANN201
    """See ``sim.stream.open_stream`` (imported lazily: ``import sim`` stays cheap)."""
    from sim.stream import open_stream as _open
    return _open(scenario, seed=seed, width=width, height=height, fps=fps, **kw)
