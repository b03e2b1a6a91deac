"""Shadow labels inside a body: dark clothes and hair that the shadow test takes for shadows.

Horprasert's shadow class (a pixel darker than its background with the same chromaticity) also
takes in dark trousers, hair and shirts on a grey room. A cast shadow lies on the ground or a wall
BESIDE a person: at or below their feet, or off to one side. A shadow-labelled pixel that has
foreground both above and below it within ``span_px`` rows (Serra's closing by a vertical line),
and that lies above the lowest ``foot_fraction`` of the foreground's vertical extent in its
connected region of foreground and shadow, is inside the body: it is relabelled foreground.
The feet band keeps the floor shadow between and around the feet (the simulator's and CDnet's
cast shadows lie there), and the closing keeps shadows beside the body.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .background import FOREGROUND, SHADOW


@dataclass(frozen=True)
class BodyShadowConfig:
    """Which shadow labels are taken back as foreground.

    Parameters
    ----------
    span_px : int, default=15
        Length in pixels of the vertical closing: a shadow pixel needs foreground above and below
        it within this many rows (at 320x240; scale with the frame height). 0: off.
    foot_fraction : float, default=0.2
        The lowest part of a region's foreground extent, as a fraction of its height, where
        shadows stay shadows (the feet touch their own cast shadow there); in [0, 1).
    edge_px : int, default=0
        Also take back the shadow pixels within this many pixels of foreground (a person's
        blurred, darker rim), above the feet band too; 0: none.
    """

    span_px: int = 15
    foot_fraction: float = 0.2
    edge_px: int = 0

    def __post_init__(self) -> None:
        if self.span_px < 0:
            raise ValueError(f"body shadow span_px must be >= 0 (0: off), got {self.span_px}")
        if not 0.0 <= self.foot_fraction < 1.0:
            raise ValueError(f"body shadow foot_fraction must be in [0, 1), got {self.foot_fraction}")
        if self.edge_px < 0:
            raise ValueError(f"body shadow edge_px must be >= 0 (0: none), got {self.edge_px}")


def reclaim_body_shadow(labels: np.ndarray, config: BodyShadowConfig) -> np.ndarray:
    """Relabel the shadow pixels inside a body as foreground.

    Parameters
    ----------
    labels : ndarray of shape (H, W), uint8
        Class labels (``background`` codes). Not modified.
    config : BodyShadowConfig
        The closing length and the feet band.

    Returns
    -------
    ndarray of shape (H, W), uint8
        ``labels`` itself when nothing changes, else a copy with the reclaimed pixels FOREGROUND.
    """
    if config.span_px == 0:
        return labels
    fg = cv2.compare(labels, FOREGROUND, cv2.CMP_EQ)
    closed = cv2.morphologyEx(fg, cv2.MORPH_CLOSE, np.ones((config.span_px, 1), np.uint8))
    if config.edge_px:
        side = 2 * config.edge_px + 1
        cv2.max(closed, cv2.dilate(fg, np.ones((side, side), np.uint8)), dst=closed)
    cand = np.flatnonzero((labels.ravel() == SHADOW) & (closed.ravel() != 0))
    if cand.size == 0:
        return labels
    h, w = labels.shape
    body = cv2.bitwise_or(fg, cv2.compare(labels, SHADOW, cv2.CMP_EQ))
    n, comp = cv2.connectedComponents(body, connectivity=8)
    comp_flat = comp.ravel()
    fg_idx = np.flatnonzero(labels.ravel() == FOREGROUND)  # on bool: several times faster than on fg's 0 / 255
    fg_comp = comp_flat[fg_idx]
    fg_row = fg_idx // w
    top = np.full(n, h, np.int64)
    bottom = np.full(n, -1, np.int64)
    np.minimum.at(top, fg_comp, fg_row)
    np.maximum.at(bottom, fg_comp, fg_row)
    c = comp_flat[cand]
    # a candidate touches or is enclosed by foreground, so its region has some: bottom >= top
    above_feet = (bottom[c] - cand // w) > config.foot_fraction * (bottom[c] - top[c] + 1)
    if not above_feet.any():
        return labels
    out = labels.copy()
    out.ravel()[cand[above_feet]] = FOREGROUND
    return out
