"""The real UT-Interaction clips of ``../shared/data`` as the silhouette tests use them: a clip, its
reference keypoints, and the share of those keypoints the silhouettes cover.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np

from counterpart.body.image_sequence import read_frames
from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor
from tests.shared_data import DATA

#: one clip of set 1: a person walks up to another and points (both in view from the first frame)
UT_CLIP = DATA / "ut_interaction" / "set1" / "3_1_3.avi"


def clip_with_keypoints(path: Any = UT_CLIP) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The clip's frames (N, H, W, 3) uint8, its reference keypoints (T, 2, 14, 2) pixels and their
    visibility (T, 2, 14).
    """
    ref = np.load(DATA / "ut_interaction" / "keypoints" / f"{path.stem}.npz")
    return read_frames(path), ref["kp"], ref["vis"]


def labels_of(frames: np.ndarray, **backend_params: Any) -> list[np.ndarray]:
    """Each frame's people labels (H, W) int32, the background fitted on the first 30 frames with
    ``backend_params``.
    """
    ex = SilhouetteExtractor(backend_params=backend_params)
    ex.fit_background(list(frames[:30]))
    return [ex.process(f).labels for f in frames]


@cache
def clip_labels() -> list[np.ndarray]:
    """``labels_of`` the frames of ``UT_CLIP`` with the default parameters (made once: several tests
    compare against them).
    """
    return labels_of(clip_with_keypoints()[0])


def people_share(labels: list[np.ndarray], first: int) -> float:
    """Mean share of the frame's pixels in people's regions (``labels_of``), from frame ``first`` on."""
    return float(np.mean([(frame > 0).mean() for frame in labels[first:]]))


def keypoints_inside(frames: np.ndarray, kp: np.ndarray, vis: np.ndarray, **backend_params: Any) -> float:
    """Share of the visible reference keypoints (visibility >= 0.5, frames 10 on) inside some
    person's region, the background fitted on the first 30 frames with ``backend_params``.
    """
    return labels_cover(labels_of(frames, **backend_params), kp, vis)


def labels_cover(labels: list[np.ndarray], kp: np.ndarray, vis: np.ndarray) -> float:
    """Share of the visible reference keypoints (visibility >= 0.5, frames 10 on) inside some
    person's region of ``labels`` (``labels_of``).
    """
    inside = []
    for i, frame in enumerate(labels):
        if i < 10 or i >= len(kp):
            continue
        xy = np.rint(kp[i][vis[i] >= 0.5]).astype(int)
        ok = (xy[:, 0] >= 0) & (xy[:, 0] < frame.shape[1]) & (xy[:, 1] >= 0) & (xy[:, 1] < frame.shape[0])
        inside.extend(frame[xy[ok, 1], xy[ok, 0]] > 0)
    return float(np.mean(inside))
