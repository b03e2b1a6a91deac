"""Messages of the camera node."""
from __future__ import annotations

import numpy as np

from .core import EMPTY, message


@message("camera.Frame", 1)
class Frame:
    """One video frame. ``image`` is (H, W, 3) uint8 BGR (encoding ``bgr8``) or (H, W) uint8 (``mono8``).

    ``stamp`` is CLOCK_MONOTONIC ns at capture (for a file: at read); ``seq`` counts from 0;
    ``source_time`` is the position in the source in seconds (file time, or 0 for live devices).
    """

    image: np.ndarray = EMPTY
    encoding: str = "bgr8"
    source: str = ""
    source_time: float = 0.0
