"""The real UT-Interaction clips of ``../shared/data`` as the silhouette tests use them: a clip, its
reference keypoints, and the share of those keypoints the silhouettes cover.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, read_frames
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


def people_share(frames: np.ndarray, first: int, **backend_params: Any) -> float:
    """Mean share of the frame's pixels in people's regions, from frame ``first`` on."""
    return float(np.mean([(labels > 0).mean() for labels in labels_of(frames, **backend_params)[first:]]))


def keypoints_inside(frames: np.ndarray, kp: np.ndarray, vis: np.ndarray, **backend_params: Any) -> float:
    """Share of the visible reference keypoints (visibility >= 0.5, frames 10 on) inside some
    person's region, the background fitted on the first 30 frames with ``backend_params``.
    """
    inside = []
    for i, (f, labels) in enumerate(zip(frames, labels_of(frames, **backend_params))):
        if i < 10 or i >= len(kp):
            continue
        xy = np.rint(kp[i][vis[i] >= 0.5]).astype(int)
        ok = (xy[:, 0] >= 0) & (xy[:, 0] < f.shape[1]) & (xy[:, 1] >= 0) & (xy[:, 1] < f.shape[0])
        inside.extend(labels[xy[ok, 1], xy[ok, 0]] > 0)
    return float(np.mean(inside))
