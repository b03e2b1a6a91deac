"""The built-in world: two people interacting in front of a camera, rendered with ground truth.

Modules: ``counterpart.sim.scenarios`` (seeded motion and labels), ``counterpart.sim.motion`` (keyframes, reaching),
``counterpart.sim.capture`` (BVH pairs as scenarios), ``counterpart.sim.appearance`` and ``counterpart.sim.render`` (video frames and
ground truth), ``counterpart.sim.stream`` (``open_stream``, what the camera node opens for ``sim:NAME``),
``counterpart.sim.dataset`` (trajectories for training, no rendering), ``counterpart.sim.listener`` (one person
rendered alone), ``counterpart.sim.cli`` (``counterpart sim``).

Nodes reach the simulator through its entry point (``counterpart.bus.plugins.simulator``), never by
importing it; the functions below are that interface.
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
    """See ``counterpart.sim.stream.open_stream`` (imported lazily: ``import sim`` stays cheap).

    Parameters
    ----------
    scenario : str, default="handshake"
        Name of the simulated scenario.
    seed : int, default=0
        Random seed of the scenario.
    width, height : int or None, default=320, 240
        Frame size in pixels; None means 320 x 240.
    fps : float or None, default=25.0
        Frame rate in frames per second; None means 25.
    **kw : Any
        Further scenario or stream options.

    Returns
    -------
    SimStream
        The open simulated stream.

    Raises
    ------
    ValueError
        For an unknown scenario or option (the message lists the known ones).
    """
    from counterpart.sim.stream import open_stream as _open

    return _open(scenario, seed=seed, width=width, height=height, fps=fps, **kw)


def make_scenario(name: str, seed: int = 0, fps: float = 25.0, **kw: Any):  # noqa: ANN201
    """See ``counterpart.sim.scenarios.make_scenario`` (imported lazily).

    Parameters
    ----------
    name : str
        One of ``counterpart.sim.scenarios.SCENARIOS``, or ``"cmu"`` (which takes ``bvh_a``/``bvh_b``).
    seed : int, default=0
        Random seed.
    fps : float, default=25.0
        Frame rate in frames per second.
    **kw : Any
        Options of the scenario.

    Returns
    -------
    Scenario
        The generated scenario (motion and labels).

    Raises
    ------
    ValueError
        For an unknown scenario name.
    """
    from counterpart.sim.scenarios import make_scenario as _make

    return _make(name, seed=seed, fps=fps, **kw)


def listener_recording(seconds: float = 60.0, seed: int = 0, interested: bool = True, empty_s: float = 1.6):  # noqa: ANN201
    """See ``counterpart.sim.listener.listener_recording`` (imported lazily).

    Parameters
    ----------
    seconds : float, default=60.0
        Length of the ``conversation`` in seconds.
    seed : int, default=0
        Random seed.
    interested : bool, default=True
        Whether the listener is interested in the (out of view) speaker.
    empty_s : float, default=1.6
        Seconds of the empty room before the listener appears.

    Returns
    -------
    ListenerRecording
        The recording of the listener alone.
    """
    from counterpart.sim.listener import listener_recording as _listener

    return _listener(seconds, seed=seed, interested=interested, empty_s=empty_s)
