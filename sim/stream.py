"""The simulator as a frame stream: what the camera node opens for ``sim:SCENARIO?seed=S&...``.

    stream = open_stream("handshake", seed=3, width=320, height=240, fps=25)
    frame, t = stream.render(i)        # (H, W, 3) uint8 BGR, scene time in seconds
    truth = stream.truth(i)            # counterpart.sim.render.FrameTruth: joints, masks, shadow, labels
    stream.n_frames, stream.fps, stream.size   # size = (width, height)

Options (keywords, strings accepted as they come from a URI query): ``emotion`` (neutral, happy,
sad, angry), ``strength`` (0-1), ``initiator`` (a/b), ``interested`` (conversation: 1/0),
``duration`` (conversation, seconds), ``frames`` (cap the frame count), ``noise`` (sensor noise
sigma, grey levels), ``bvh_a``/``bvh_b`` (scenario "cmu"), ``camera`` (``default``: the camera of
``counterpart.body.camera.default_camera``; ``random``: a camera of random height 1-3 m, tilt 0-35 degrees and
horizontal field of view 40-75 degrees and bearing -60 to 60 degrees about the pair (0: square-on to
the line between them) drawn from the seed that keeps both people in view,
``counterpart.sim.camera.random_camera``; its drawn parameters are in ``stream.scenario.meta["camera"]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from counterpart.body.camera import Camera, default_camera
from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.sim.render import FrameTruth, Renderer
from counterpart.sim.scenarios import Scenario, make_scenario

_FLOAT = ("strength", "duration", "noise")
_INT = ("frames",)
_BOOL = ("interested",)
_STR = ("emotion", "initiator", "bvh_a", "bvh_b", "camera")
CAMERAS = ("default", "random")


def _parse_options(kw: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in kw.items():
        if v is None:
            continue
        if k in _FLOAT:
            out[k] = float(v)
        elif k in _INT:
            out[k] = int(v)
        elif k in _BOOL:
            if isinstance(v, str):
                if v.lower() not in ("1", "0", "true", "false", "yes", "no"):
                    raise ValueError(f"option {k}={v!r}: use 1/0 or true/false")
                v = v.lower() in ("1", "true", "yes")
            out[k] = bool(v)
        elif k in _STR:
            out[k] = str(v)
        else:
            raise ValueError(f"unknown simulator option {k!r}; known: {sorted(_FLOAT + _INT + _BOOL + _STR)}")
    return out


class SimStream:
    """A rendered scenario, frame by frame (see the module docstring).

    Parameters
    ----------
    scenario : Scenario
        The motion and labels.
    camera : Camera
        The camera.
    seed : int, default=0
        Seeds the renderer (room, lighting, clothing and sensor noise).
    noise_sigma : float, default=2.0
        Sensor noise sigma, grey levels.
    n_frames : int or None, default=None
        Cap on the frame count; ``None`` for the whole scenario.

    Attributes
    ----------
    scenario : Scenario
        The motion and labels (cropped to ``n_frames``).
    renderer : Renderer
        The ``counterpart.sim.render.Renderer``.
    camera : Camera
        The camera.
    seed : int
        Seed of the renderer.

    Raises
    ------
    ValueError
        ``n_frames`` is below 1.
    """

    def __init__(
        self, scenario: Scenario, camera: Camera, seed: int = 0, noise_sigma: float = 2.0, n_frames: int | None = None
    ) -> None:
        if n_frames is not None:
            if n_frames < 1:
                raise ValueError(f"frames={n_frames}: need at least 1")
            scenario = scenario.crop(min(n_frames, scenario.n_frames))
        self.scenario = scenario
        self.camera = camera
        self.renderer = Renderer(scenario, camera, seed=seed, noise_sigma=noise_sigma)
        self.seed = seed

    @property
    def n_frames(self) -> int:
        """Number of frames."""
        return self.scenario.n_frames

    @property
    def fps(self) -> float:
        """Frames per second."""
        return float(self.scenario.fps)

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of the frames, pixels."""
        return (self.camera.width, self.camera.height)

    def render(self, i: int) -> tuple[np.ndarray, float]:
        """Frame ``i`` with sensor noise.

        Parameters
        ----------
        i : int
            Frame index.

        Returns
        -------
        frame : ndarray of shape (H, W, 3), dtype uint8
            The image, BGR.
        time_s : float
            Scene time, seconds.

        Raises
        ------
        IndexError
            ``i`` is outside the scenario's frames.
        """
        frame, truth = self.renderer.render(i)
        return frame, truth.time_s

    def render_with_truth(self, i: int, noise: bool = True) -> tuple[np.ndarray, FrameTruth]:
        """Frame ``i`` and its ground truth.

        Parameters
        ----------
        i : int
            Frame index.
        noise : bool, default=True
            Whether to add sensor noise.

        Returns
        -------
        frame : ndarray of shape (H, W, 3), dtype uint8
            The image, BGR.
        truth : FrameTruth
            Its ground truth.

        Raises
        ------
        IndexError
            ``i`` is outside the scenario's frames.
        """
        return self.renderer.render(i, noise=noise)

    def truth(self, i: int) -> FrameTruth:
        """Ground truth of frame ``i`` (renders it: the masks come from the drawing).

        Parameters
        ----------
        i : int
            Frame index.

        Returns
        -------
        FrameTruth
            Joints, masks, shadow and labels of the frame.

        Raises
        ------
        IndexError
            ``i`` is outside the scenario's frames.
        """
        return self.renderer.render(i, noise=False)[1]

    def background(self, i: int) -> np.ndarray:
        """The room at frame ``i``'s lighting, no people, no shadows, no noise.

        Parameters
        ----------
        i : int
            Frame index.

        Returns
        -------
        ndarray of shape (H, W, 3), dtype uint8
            The background, BGR.

        Raises
        ------
        IndexError
            ``i`` is outside the scenario's frames.
        """
        return self.renderer.background(i)

    @property
    def trajectory(self) -> TwoPersonTrajectory:
        """The two people's motion of the scenario."""
        return self.scenario.to_trajectory()

    def close(self) -> None:
        self.renderer._cache.clear()


def open_stream(
    scenario: str = "handshake",
    seed: int = 0,
    width: int | None = 320,
    height: int | None = 240,
    fps: float | None = 25.0,
    **kw: Any,
) -> SimStream:
    """Open a simulated scene.

    Parameters
    ----------
    scenario : str, default="handshake"
        The scenario's name.
    seed : int, default=0
        Seed of the scenario, the renderer and a random camera.
    width, height : int or None, default=320, 240
        Frame size, pixels; ``None`` means 320 / 240.
    fps : float or None, default=25.0
        Frames per second; ``None`` means 25.
    **kw : object
        The options of the module docstring (strings accepted as they come from a URI query).

    Returns
    -------
    SimStream
        The stream.

    Raises
    ------
    ValueError
        An unknown scenario or option, or a bad option value (the message lists the known ones).
    """
    opts = _parse_options(kw)
    width = int(width or 320)
    height = int(height or 240)
    fps = float(fps or 25.0)
    frames = opts.pop("frames", None)
    noise = opts.pop("noise", 2.0)
    camera = opts.pop("camera", "default")
    if camera not in CAMERAS:
        raise ValueError(f"option camera={camera!r}: use one of {', '.join(CAMERAS)}")
    sc = make_scenario(scenario, seed=int(seed), fps=fps, **opts)
    cam = default_camera(width, height)
    if camera == "random":
        from counterpart.sim.camera import random_camera

        cam, drawn = random_camera(sc.joints(), np.random.default_rng([int(seed), 7331]), width, height)
        sc.meta["camera"] = drawn
    return SimStream(sc, cam, seed=int(seed), noise_sigma=noise, n_frames=frames)


def default_sequence() -> SimStream:
    """The demo: handshake, seed 0, 320x240 at 25 fps.

    Returns
    -------
    SimStream
        The stream.
    """
    return open_stream("handshake", seed=0)
