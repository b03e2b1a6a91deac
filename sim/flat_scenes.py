"""Small synthetic scenes with ground truth for tests and benchmarks of the silhouette node.

Not the rendered scenarios of ``counterpart.sim.scenarios``: a textured static background with sensor noise, two
flat-coloured figures that walk towards each other, shake hands (their regions merge) and step
back, each casting a shadow on the ground that darkens the background by a constant factor
(same chromaticity, as Horprasert et al. assume). Frames are uint8 BGR.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True, eq=False)
class SyntheticSequence:
    """A synthetic image sequence with its ground truth.

    Parameters
    ----------
    frames : ndarray of shape (N, H, W, 3), dtype uint8
        BGR frames.
    person_masks : ndarray of shape (N, 2, H, W), dtype bool
        Each person's pixels (person 0 starts on the left).
    shadow_masks : ndarray of shape (N, H, W), dtype bool
        Shadow pixels not covered by a person.
    background : ndarray of shape (H, W, 3), dtype float32
        Noise-free background.
    heights : ndarray of shape (2,)
        The people's heights, pixels.
    """

    frames: np.ndarray
    person_masks: np.ndarray
    shadow_masks: np.ndarray
    background: np.ndarray
    heights: np.ndarray


def textured_background(h: int, w: int) -> np.ndarray:
    """A textured BGR background, 40..180 grey levels, chromaticity varying over the image.

    Parameters
    ----------
    h, w : int
        Image size, pixels.

    Returns
    -------
    ndarray of shape (h, w, 3), dtype float32
        The background.
    """
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    return np.stack(
        [
            90 + 40 * np.sin(xx / 9.0) + 10 * np.cos(yy / 5.0),
            130 + 40 * np.cos(yy / 11.0 + xx / 23.0),
            110 + 35 * np.sin((xx + yy) / 13.0),
        ],
        axis=-1,
    ).astype(np.float32)


def draw_figure(mask: np.ndarray, cx: float, feet_y: int, height: float, arm: int = 0) -> None:
    """Draw a standing figure (head, body, one horizontal arm) into a mask.

    Parameters
    ----------
    mask : ndarray of shape (H, W), dtype uint8
        Drawn into in place (1 on the figure).
    cx : float
        Horizontal centre of the figure, pixels.
    feet_y : int
        Row of the feet, pixels.
    height : float
        Figure height, pixels.
    arm : int, default=0
        Arm length, pixels (negative: pointing left; 0: no arm).
    """
    cx_i = int(round(cx))
    top = int(feet_y - height)
    head_r = max(3, int(height * 0.09))
    cv2.circle(mask, (cx_i, top + head_r), head_r, 1, -1)
    body_h = int(height - 2 * head_r)
    cv2.ellipse(
        mask, (cx_i, top + 2 * head_r + body_h // 2), (max(2, int(height * 0.14)), body_h // 2), 0, 0, 360, 1, -1
    )
    if arm:
        y = top + 2 * head_r + int(body_h * 0.3)
        cv2.line(mask, (cx_i, y), (cx_i + arm, y + 3), 1, thickness=max(2, int(height * 0.05)))


def two_person_sequence(
    n_frames: int = 60,
    size: tuple[int, int] = (240, 320),
    noise: float = 2.5,
    shadow_factor: float = 0.6,
    empty_frames: int = 0,
    seed: int = 0,
) -> SyntheticSequence:
    """Two people meet, shake hands and part.

    Parameters
    ----------
    n_frames : int, default=60
        Frames with the people.
    size : tuple of int, default=(240, 320)
        (H, W) pixels.
    noise : float, default=2.5
        Std of the Gaussian pixel noise, grey levels.
    shadow_factor : float, default=0.6
        Brightness factor of shadow pixels.
    empty_frames : int, default=0
        Frames of the empty scene first.
    seed : int, default=0
        Noise seed.

    Returns
    -------
    SyntheticSequence
        ``empty_frames + n_frames`` frames with their ground truth.
    """
    h, w = size
    rng = np.random.default_rng(seed)
    bg = textured_background(h, w)
    heights = np.array([0.62 * h, 0.52 * h])
    feet = int(0.92 * h)
    colours = (np.array([200.0, 60.0, 40.0]), np.array([40.0, 50.0, 210.0]))
    walk = n_frames // 3
    hold = n_frames - 2 * walk
    meet_a, meet_b = 0.44 * w, 0.56 * w
    xa = np.concatenate(
        [np.linspace(0.12 * w, meet_a, walk), np.full(hold, meet_a), np.linspace(meet_a, 0.2 * w, walk)]
    )
    xb = np.concatenate(
        [np.linspace(0.88 * w, meet_b, walk), np.full(hold, meet_b), np.linspace(meet_b, 0.8 * w, walk)]
    )
    total = empty_frames + n_frames
    frames = np.empty((total, h, w, 3), np.uint8)
    persons = np.zeros((total, 2, h, w), bool)
    shadows = np.zeros((total, h, w), bool)
    arm_len = int(0.13 * w)
    for k in range(total):
        f = bg + rng.normal(0.0, noise, bg.shape).astype(np.float32)
        j = k - empty_frames
        if j >= 0:
            arm = arm_len if walk - walk // 3 <= j < walk + hold + walk // 3 else 0
            sh = np.zeros((h, w), np.uint8)
            for p, (x, sign) in enumerate(((xa[j], 1), (xb[j], -1))):
                m = np.zeros((h, w), np.uint8)
                draw_figure(m, x, feet, heights[p], sign * arm)
                persons[k, p] = m.astype(bool)
                # Shadow: a flattened ellipse on the ground, cast towards the bottom right.
                cv2.ellipse(
                    sh,
                    (int(x + 0.1 * heights[p]), feet + 2),
                    (int(0.3 * heights[p]), max(3, int(0.06 * h))),
                    0,
                    0,
                    360,
                    1,
                    -1,
                )
            anyone = persons[k].any(axis=0)
            shadows[k] = sh.astype(bool) & ~anyone
            f[shadows[k]] *= shadow_factor
            for p in range(2):
                f[persons[k, p]] = colours[p] + rng.normal(0.0, noise, (int(persons[k, p].sum()), 3))
        frames[k] = np.clip(np.rint(f), 0, 255).astype(np.uint8)
    return SyntheticSequence(frames, persons, shadows, bg, heights)
