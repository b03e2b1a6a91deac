"""Messages of the silhouette node (Johnson, Galata & Hogg 1998; Baumberg & Hogg)."""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message, struct


@struct
class PersonShape:
    """One person's silhouette in image pixels.

    ``ctrl`` (n, 2) float32: control points of the closed uniform cubic B-spline of the boundary,
    starting at the reference point at the top of the head; ``ref_point`` (2,) float32; ``centroid``
    (2,) float32; ``bbox`` (x, y, w, h); ``height`` in pixels; ``merged`` when the region was shared
    with another person in this frame (split by the previous shapes).
    """

    id: int = 0
    side: str = "left"
    ctrl: np.ndarray = EMPTY
    ref_point: np.ndarray = EMPTY
    centroid: np.ndarray = EMPTY
    bbox: tuple[int, int, int, int] = (0, 0, 0, 0)
    height: float = 0.0
    area: int = 0
    merged: bool = False


@message("silhouette.Silhouettes", 1)
class Silhouettes:
    """The people of one frame. ``labels`` (H, W) uint8: 0 background, id + 1 per person (empty
    when the node thins the mask out); ``width``/``height`` are the frame's size.
    """

    people: list[PersonShape] = ()
    labels: np.ndarray = EMPTY
    width: int = 0
    height: int = 0
