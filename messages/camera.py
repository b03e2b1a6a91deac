"""Messages of the camera node."""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message


@message("camera.Frame", 1)
class Frame:
    """One video frame.

    ``stamp`` is CLOCK_MONOTONIC ns at capture (for a file: at read); ``seq`` counts from 0.

    Attributes
    ----------
    image : ndarray of shape (H, W, 3) or (H, W), dtype uint8
        BGR (encoding ``bgr8``) or grey (``mono8``) pixels.
    encoding : str
        ``bgr8`` or ``mono8``.
    source : str
        Where the frame comes from.
    source_time : float
        Position in the source in seconds (file time, or 0 for live devices).
    fps : float
        The source's frame rate in frames per second (0: unknown), so that consumers (the video
        the renderer writes, the labeller's analysis windows) follow the input rather than a default.
    """

    image: np.ndarray = EMPTY
    encoding: str = "bgr8"
    source: str = ""
    source_time: float = 0.0
    fps: float = 0.0


@message("camera.CameraInfo", 1)
class CameraInfo:
    """The calibration of the camera for frames of ``width`` x ``height`` pixels (as ROS's
    CameraInfo), published (latched) by the calibration node so that every node projects with the
    same camera. Pinhole, OpenCV convention, no distortion: ``X_c = R X_w + t``; world Y up, the
    ground plane y = 0. ``seq`` is the first frame it holds for.

    Attributes
    ----------
    width, height : int
        Frame size in pixels.
    fx, fy : float
        Focal lengths in pixels.
    cx, cy : float
        Principal point in pixels.
    R : ndarray of shape (3, 3), dtype float64
        World-to-camera rotation.
    t : ndarray of shape (3,), dtype float64
        World-to-camera translation in metres.
    source : str
        Where it comes from (``default``, ``file:PATH``, ``estimated``).
    undecided_from : int
        The first frame seq whose camera is not decided yet: a later message for frames of this size
        holds only from there on. A lockstep graph's calibration node says it on every frame, and
        the nodes that use the camera hold such frames until a message decides them, so that a
        replay is the same in every run. -1: every frame's camera is decided (a fixed camera, or
        the estimate's last).
    """

    width: int = 0
    height: int = 0
    fx: float = 0.0
    fy: float = 0.0
    cx: float = 0.0
    cy: float = 0.0
    R: np.ndarray = EMPTY
    t: np.ndarray = EMPTY
    source: str = ""
    undecided_from: int = -1
