"""Messages of the camera node."""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message


@message("camera.Frame", 1)
class Frame:
    """One video frame. ``image`` is (H, W, 3) uint8 BGR (encoding ``bgr8``) or (H, W) uint8 (``mono8``).

    ``stamp`` is CLOCK_MONOTONIC ns at capture (for a file: at read); ``seq`` counts from 0;
    ``source_time`` is the position in the source in seconds (file time, or 0 for live devices);
    ``fps`` the source's frame rate in frames per second (0: unknown), so that consumers (the video
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
    CameraInfo), published once (latched) by the calibration node so that every node projects
    with the same camera. Pinhole, OpenCV convention, no distortion: ``fx, fy, cx, cy`` pixels;
    ``R`` (3, 3) float64 world-to-camera rotation and ``t`` (3,) float64 translation in metres
    (``X_c = R X_w + t``; world Y up, the ground plane y = 0). ``source``: where it comes from
    (``default``, ``file:PATH``, ``estimated``); ``seq`` the frame it was made for.
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
