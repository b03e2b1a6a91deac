"""Smoothing the frames of a noisy camera before they are compared with the background.

The background model tells a person from the room pixel by pixel, against each pixel's own spread
(``background``): the spread it learns from a noisy camera (low light, a small sensor, footage
that is barely compressed) is wide, and a person whose clothes differ from the room by little
more than that falls apart into pieces that no clean-up joins. Averaging neighbouring pixels
narrows the noise where the picture is flat and keeps the difference a person makes, which spans
many pixels: a Gaussian of standard deviation ``s`` pixels divides independent pixel noise by
about ``2 sqrt(pi) s``. The camera's noise is measured once, on the training frames
(:func:`frame_noise`), and only footage noisier than ``DenoiseConfig.floor`` is smoothed, by a
Gaussian that grows with its noise (:func:`smoothing_sigma`): the compressed footage of most
recordings, whose still parts repeat from frame to frame, and the simulator's sensor noise are
left as they are.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

#: about how many pixels of each frame :func:`frame_noise` looks at
SAMPLE_PIXELS = 65536


@dataclass(frozen=True)
class DenoiseConfig:
    """When and how much a noisy camera's frames are smoothed.

    Parameters
    ----------
    floor : float, default=3.0
        Noise (grey levels, :func:`frame_noise`) up to which frames are left as they are: over the
        simulator's sensor noise and that of the synthetic scenes, which are tuned without
        smoothing, and over that of compressed recordings.
    noise_per_sigma : float, default=3.0
        Grey levels of noise per pixel of the Gaussian's standard deviation (chosen on the tuning
        clips with noise of 3 to 10 grey levels added, and on the simulator with noise added,
        whose thin limbs a wider Gaussian washes out).
    max_sigma : float, default=2.0
        The widest Gaussian, pixels (reached at 6 grey levels of noise).
    """

    floor: float = 3.0
    noise_per_sigma: float = 3.0
    max_sigma: float = 2.0

    def __post_init__(self) -> None:
        if not (self.floor >= 0 and self.noise_per_sigma > 0 and self.max_sigma >= 0):
            raise ValueError(
                f"DenoiseConfig: floor {self.floor!r} must be >= 0, noise_per_sigma {self.noise_per_sigma!r} > 0 "
                f"and max_sigma {self.max_sigma!r} >= 0"
            )


def frame_noise(frames: np.ndarray) -> float:
    """The camera's noise, grey levels: from the median change of a pixel's value from one frame to
    the next, over every pixel, channel and pair of frames, once each frame is scaled to the same
    mean brightness. People who move change the pixels along their edges from one frame to the
    next, a minority that the median leaves out.

    Parameters
    ----------
    frames : ndarray of shape (N, H, W, C) or (N, H, W), dtype uint8
        Frames of a still camera, N >= 2.

    Returns
    -------
    float
        The noise, grey levels (0 for frames that repeat exactly where the scene is still).
    """
    stack = np.asarray(frames)
    if stack.ndim < 3 or len(stack) < 2:
        raise ValueError(f"frame_noise needs 2 or more frames (N, H, W[, C]), got shape {stack.shape}")
    # a grid of pixels is enough, and keeps a stack of large frames from filling the memory
    step = max(1, round(np.sqrt(stack.shape[1] * stack.shape[2] / SAMPLE_PIXELS)))
    s = stack[:, ::step, ::step].astype(np.float32)
    # each frame brought to the stack's mean brightness (per channel): a camera's exposure settling,
    # or a light dimming, over the frames would otherwise pass for noise in every pixel
    mean = s.mean(axis=(1, 2), keepdims=True)
    s *= mean.mean(axis=0, keepdims=True) / np.maximum(mean, 1.0)
    d = np.abs(np.diff(s, axis=0))
    # a fixed dither undoes the whole grey levels of still pixels, whose median would move by steps of one
    d += np.random.default_rng(0).uniform(-0.5, 0.5, d.shape).astype(np.float32)
    # the median of |x - y| of two independent normal values of std s is 0.6745 sqrt(2) s
    return float(np.median(np.abs(d)) / (0.6745 * np.sqrt(2.0)))


def smoothing_sigma(noise: float, config: DenoiseConfig = DenoiseConfig()) -> float:
    """The Gaussian's standard deviation (pixels) for a camera of that noise; 0: none.

    Parameters
    ----------
    noise : float
        The camera's noise, grey levels (:func:`frame_noise`).
    config : DenoiseConfig, default=DenoiseConfig()
        The floor and the rate.

    Returns
    -------
    float
        ``noise / noise_per_sigma`` up to ``max_sigma`` where the noise is over the floor, else 0.
    """
    if not noise > config.floor:
        return 0.0
    return float(min(noise / config.noise_per_sigma, config.max_sigma))


def smooth(frame: np.ndarray, sigma: float) -> np.ndarray:
    """A frame smoothed by a Gaussian of ``sigma`` pixels (the frame itself for 0).

    Parameters
    ----------
    frame : ndarray of shape (H, W) or (H, W, C), dtype uint8
        The frame.
    sigma : float
        Standard deviation, pixels; 0: none.

    Returns
    -------
    ndarray
        The same shape and dtype (a new array when smoothed).
    """
    return cv2.GaussianBlur(frame, (0, 0), sigma) if sigma > 0 else frame
