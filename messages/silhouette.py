"""Messages of the silhouette node (Johnson, Galata & Hogg 1998; Baumberg & Hogg)."""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message, struct


@struct
class PersonShape:
    """One person's silhouette in image pixels.

    Attributes
    ----------
    id : int
        The person's id.
    side : str
        The person's side of the frame (``"left"`` by default).
    ctrl : ndarray of shape (n, 2), dtype float32
        Control points of the closed uniform cubic B-spline of the boundary, starting at the
        reference point at the top of the head, pixels.
    ref_point : ndarray of shape (2,), dtype float32
        The reference point, pixels.
    centroid : ndarray of shape (2,), dtype float32
        The region's centroid, pixels.
    bbox : tuple of int
        Bounding box ``(x, y, w, h)``, pixels.
    height : float
        Height in pixels.
    area : int
        Area, pixels.
    merged : bool
        True when the region was shared with another person in this frame (split by the previous
        shapes).
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
    """The people of one frame.

    Attributes
    ----------
    people : list of PersonShape
        The people seen in the frame.
    labels : ndarray of shape (H, W), dtype uint8
        0 background, id + 1 per person; empty when the node thins the mask out.
    width : int
        The frame's width, pixels.
    height : int
        The frame's height, pixels.
    """

    people: list[PersonShape] = ()
    labels: np.ndarray = EMPTY
    width: int = 0
    height: int = 0
