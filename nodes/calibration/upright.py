"""Upright people inside a region that is not one whole person: the head and foot points of each
standing body in a region's pixels.

The silhouettes join people into one region when something thin links them (an outstretched arm,
a cast shadow on the floor, a faint line of the room the background model gets wrong), and a
region with an arm held out is too wide to pass for an upright person. A person standing is a tall
vertical run of pixels in every column from the head to the feet; an arm, a shadow on the floor or
a line of the room is a thin horizontal band. A morphological opening with a vertical line (as
tall as a share of the region) keeps the first and removes the second (Soille, "Morphological
Image Analysis", 2003, ch. 4: openings by line segments keep the structures the segment fits in);
the connected parts left that are tall and narrow are the standing bodies.

Image coordinates are pixels, x = column, y = row; boxes are (x, y, w, h).
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from .estimate import usable

#: the vertical line of the opening, as a share of the region's height: taller than an arm or a
#: shadow band is thick (about 5% of a person's height), shorter than the neck and head (about 15%)
OPEN_SHARE = 0.08
#: a part shorter than this share of the tallest part of the region is a piece, not a body
MIN_PART_SHARE = 0.6
#: share of a part's height, at its top and bottom, whose pixels give the head's and feet's x
END_SHARE = 0.05


def upright_parts(
    labels: np.ndarray, label: int, bbox: Any, size: tuple[int, int]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The standing bodies in one region of a label image.

    Parameters
    ----------
    labels : ndarray of shape (H, W), integer
        The label image (0 background).
    label : int
        The region's label in ``labels``.
    bbox : sequence of 4 numbers
        The region's box (x, y, w, h), pixels.
    size : tuple of (int, int)
        (width, height) of the frame, pixels.

    Returns
    -------
    list of (head, foot)
        Each body's head point (the top of its pixels, the mean x of its top rows) and foot point
        (the bottom of its pixels, the mean x of its bottom rows), ndarrays of shape (2,), pixels;
        left to right. Only bodies that pass ``estimate.usable`` (whole, tall, narrow).
    """
    x, y, w, h = (int(v) for v in bbox)
    crop = (labels[y : y + h, x : x + w] == label).astype(np.uint8)
    if h < 3 or w < 1 or not crop.any():
        return []
    k = max(3, int(round(OPEN_SHARE * h)))
    opened = cv2.morphologyEx(crop, cv2.MORPH_OPEN, np.ones((k, 1), np.uint8))
    n, cc, stats, _ = cv2.connectedComponentsWithStats(opened, connectivity=8)
    if n <= 1:
        return []
    tallest = stats[1:, cv2.CC_STAT_HEIGHT].max()
    out = []
    for j in range(1, n):
        px, py, pw, ph = stats[j, :4]
        if ph < MIN_PART_SHARE * tallest or not usable((x + px, y + py, pw, ph), *size):
            continue
        ys, xs = np.nonzero(cc == j)
        band = max(1, int(round(END_SHARE * ph)))
        top, bottom = ys.min(), ys.max()
        head = np.array([xs[ys < top + band].mean() + x, top + y - 0.5])
        foot = np.array([xs[ys > bottom - band].mean() + x, bottom + y + 0.5])
        out.append((head, foot))
    return sorted(out, key=lambda hf: hf[1][0])


__all__ = ["upright_parts"]
