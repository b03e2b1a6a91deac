"""Camera shake added to recorded frames: a sway and a tremor of the picture, as a camera on a pole
in the wind, a tripod on a wooden floor or a hand gives it, for measuring how the silhouettes cope
(``bench/real_silhouettes.py``, the tests of ``counterpart.nodes.silhouette.shake``).

Shifts are (x, y) pixels of the picture: the content of frame i moves by ``shift[i]``.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["shake_path", "shaken"]


def shake_path(n: int, amplitude: float, seed: int | list[int]) -> np.ndarray:
    """A shake over ``n`` frames: per axis a sway of ``amplitude`` pixels (a sine with a period of
    10 to 60 frames) plus a tremor (white noise of std ``amplitude / 2``).

    Parameters
    ----------
    n : int
        Frames.
    amplitude : float
        Sway amplitude, pixels (>= 0).
    seed : int or list of int
        Seed of the random periods, phases and tremor.

    Returns
    -------
    ndarray of shape (n, 2)
        float64 shift (x, y) of each frame, pixels.

    Raises
    ------
    ValueError
        For a negative ``amplitude`` or ``n``.
    """
    if amplitude < 0 or n < 0:
        raise ValueError(f"amplitude and n must be >= 0, got {amplitude} and {n}")
    rng = np.random.default_rng(seed)
    t = np.arange(n)[:, None]
    period, phase = rng.uniform(10.0, 60.0, 2), rng.uniform(0.0, 2 * np.pi, 2)
    return amplitude * np.sin(2 * np.pi * t / period + phase) + rng.normal(0.0, amplitude / 2, (n, 2))


def shaken(frames: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """Frames as a shaken camera sees them: each moved by its shift (Lanczos resampling, the
    closest of OpenCV's to a camera's own subpixel sampling; the edges mirrored).

    Parameters
    ----------
    frames : ndarray of shape (N, H, W, 3) or (N, H, W), dtype uint8
        The frames of a still camera.
    shift : ndarray of shape (N, 2)
        Shift (x, y) of each frame, pixels.

    Returns
    -------
    ndarray
        The shaken frames, the shape and dtype of ``frames``.

    Raises
    ------
    ValueError
        When there are fewer shifts than frames.
    """
    if len(shift) < len(frames):
        raise ValueError(f"{len(frames)} frames need as many shifts, got {len(shift)}")
    h, w = frames.shape[1:3]
    out = np.empty_like(frames)
    for i, (f, (dx, dy)) in enumerate(zip(frames, shift)):
        m = np.float32([[1, 0, dx], [0, 1, dy]])
        out[i] = cv2.warpAffine(f, m, (w, h), flags=cv2.INTER_LANCZOS4, borderMode=cv2.BORDER_REFLECT)
    return out
