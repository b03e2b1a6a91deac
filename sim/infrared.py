"""A day/night camera's picture once it has turned to infrared, made from colour frames, for
measuring how the silhouettes cope with the switch (``bench/real_silhouettes.py``, the tests of
``counterpart.nodes.silhouette.colour_switch``).

Such a camera drops its colour (three equal channels, however the codec carries them) and lights
the room with its own infrared lamps: the picture comes out brighter and flatter than the colour
one of the same room.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["INFRARED_GAIN", "INFRARED_OFFSET", "infrared_frames"]

#: the infrared picture's contrast and brightness against the colour frames' grey levels
INFRARED_GAIN = 0.8
INFRARED_OFFSET = 30.0


def infrared_frames(frames: np.ndarray) -> np.ndarray:
    """Colour frames as the infrared picture of the same room: ``INFRARED_GAIN`` x grey +
    ``INFRARED_OFFSET``, in three equal channels.

    Parameters
    ----------
    frames : ndarray of shape (N, H, W, 3), dtype uint8
        BGR frames.

    Returns
    -------
    ndarray of shape (N, H, W, 3), dtype uint8
        The infrared frames.
    """
    grey = np.stack([cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]).astype(np.float32)
    ir = np.clip(np.rint(INFRARED_GAIN * grey + INFRARED_OFFSET), 0, 255).astype(np.uint8)
    return np.repeat(ir[..., None], 3, axis=-1)
