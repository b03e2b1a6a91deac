"""Upright people inside regions that are not one whole person (counterpart.nodes.calibration.upright):
two drawn standing bodies joined by a thin band, one with an arm held out, as the silhouettes give
them at a wide bearing.
"""

from __future__ import annotations

from types import SimpleNamespace

import cv2
import numpy as np

from counterpart.nodes.calibration.observe import PeopleObservations
from counterpart.nodes.calibration.upright import upright_parts

W, H = 320, 240


def _body(img: np.ndarray, foot_x: int, foot_y: int, height: int, value: int) -> None:
    """A standing person of ``height`` pixels, feet at (foot_x, foot_y): head, torso, two legs."""
    head_r = int(0.07 * height)
    top = foot_y - height + 1
    cv2.circle(img, (foot_x, top + head_r), head_r, value, -1)
    cv2.rectangle(
        img,
        (foot_x - int(0.12 * height), top + 2 * head_r),
        (foot_x + int(0.12 * height), foot_y - int(0.45 * height)),
        value,
        -1,
    )
    for side in (-1, 1):
        x = foot_x + side * int(0.05 * height)
        cv2.rectangle(
            img, (x - int(0.03 * height), foot_y - int(0.46 * height)), (x + int(0.03 * height), foot_y), value, -1
        )


def _scene() -> tuple[np.ndarray, tuple[int, int, int, int]]:
    labels = np.zeros((H, W), np.uint8)
    _body(labels, 110, 200, 150, 1)  # near, taller in the image
    _body(labels, 190, 170, 110, 1)  # farther
    cv2.line(labels, (110, 120), (190, 110), 1, 3)  # a 3 px band: a line of the room, an arm between them
    cv2.rectangle(labels, (190, 100), (240, 105), 1, -1)  # the far one's arm held out
    ys, xs = np.nonzero(labels)
    return labels, (int(xs.min()), int(ys.min()), int(np.ptp(xs)) + 1, int(np.ptp(ys)) + 1)


def test_two_bodies_joined_by_a_band_are_found_with_their_heads_and_feet() -> None:
    labels, box = _scene()
    parts = upright_parts(labels, 1, box, (W, H))
    assert len(parts) == 2
    for (head, foot), (fx, fy, h) in zip(parts, [(110, 200, 150), (190, 170, 110)]):
        assert abs(foot[1] - (fy + 0.5)) <= 1 and abs(foot[0] - fx) <= 2, (head, foot)
        assert abs(head[1] - (fy - h + 0.5)) <= 1 and abs(head[0] - fx) <= 2, (head, foot)


def test_a_joined_region_counts_only_with_the_label_image() -> None:
    labels, box = _scene()
    region = SimpleNamespace(id=0, bbox=box, ctrl=None, ref_point=None, merged=False)
    obs = PeopleObservations(W, H)
    assert obs.add([region], 0.0) == 0  # wider than an upright person
    assert obs.add([region], 0.04, labels) == 2
    head, foot, track, _ = obs.arrays()
    assert len(set(track.tolist())) == 2 and (track < 0).all()  # ids of their own, apart from the tracks'
    shared = SimpleNamespace(id=0, bbox=box, ctrl=None, ref_point=None, merged=True)
    assert obs.add([shared], 0.08, labels) == 0  # split between two tracks by their old shapes: not used
    # what counts is whether each body is whole, not the region's box: a body cut by the image's
    # bottom edge is left out, the whole one beside it kept
    _body(labels, 40, H - 1, 120, 1)
    cv2.line(labels, (40, 160), (110, 150), 1, 3)
    whole = (0, 0, W, H)
    assert len(upright_parts(labels, 1, whole, (W, H))) == 2
