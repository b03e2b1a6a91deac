"""Compositing the video-texture avatar: the recording's masked frames drawn where the partner stands.

Place and scale come from the scene: the partner's joints (where the responder put the listener,
facing the speaker) are projected with the graph's camera; the avatar's foot point goes to the
projected point between the ankles on the floor, and its height in pixels to the projected height of
the body (floor to the top of the head). The frame is mirrored when the partner faces the other way
in the picture than the recorded person did. Blending (the paper is silent): the frames of a
cross-fade are mixed with premultiplied alpha, sum_k w_k a_k I_k / sum_k w_k a_k, so the two
silhouettes dissolve into each other without a dark fringe; the result goes over the frame with its
feathered alpha. The frames are decoded from the avatar file named in the Partner message (or the
renderer's ``avatar_file``), loaded once per file.
"""

from __future__ import annotations

import logging
from typing import Any

import cv2
import numpy as np

from counterpart.body.avatar_frames import AvatarFrames, load_avatar_frames
from counterpart.body.camera import Camera

log = logging.getLogger(__name__)

_HEAD, _LS, _RS, _LH, _RH, _LA, _RA = 0, 2, 5, 8, 11, 10, 13
#: metres from the head joint (the head's centre) to the top of the head
CROWN_M = 0.12


class AvatarPainter:
    """Draws avatar frames into images (module docstring).

    Parameters
    ----------
    avatar_file : str
        Use this file for every partner instead of the one each message names ('' : the message's).
    """

    def __init__(self, avatar_file: str = "") -> None:
        self.avatar_file = avatar_file
        self._stores: dict[str, AvatarFrames | None] = {}

    def frames(self, path: str) -> AvatarFrames | None:
        """The frames of an avatar file, loaded once.

        Parameters
        ----------
        path : str
            The avatar file.

        Returns
        -------
        AvatarFrames or None
            The frames; None (logged once) when the file cannot be read.
        """
        if path not in self._stores:
            try:
                self._stores[path] = load_avatar_frames(path)
            except (OSError, ValueError) as exc:
                log.warning("avatar frames unavailable, drawing the partner as cones instead: %s", exc)
                self._stores[path] = None
        return self._stores[path]

    def draw(self, img: np.ndarray, partner: Any, cam: Camera) -> bool | None:
        """Composite the partner's avatar frames into ``img`` in place.

        Parameters
        ----------
        img : ndarray of shape (H, W, 3), dtype uint8
            The picture, BGR; drawn into.
        partner : Any
            The Partner message: ``joints`` (14, 3) metres, world frame, ``avatar_frames`` (frame
            indices), ``avatar_weights`` (their cross-fade weights) and ``avatar_file``.
        cam : Camera
            The graph's camera.

        Returns
        -------
        bool or None
            Whether any of the avatar falls inside the picture, or None when there is nothing to draw it
            with (no frames, no file, no placement), so the caller can fall back to another style.
        """
        idx = np.asarray(partner.avatar_frames).astype(np.int64).reshape(-1)
        w = np.asarray(partner.avatar_weights, np.float32).reshape(-1)
        joints = np.asarray(partner.joints, np.float64)
        store = self.frames(self.avatar_file or partner.avatar_file) if len(idx) else None
        if store is None or joints.shape != (14, 3) or not np.isfinite(joints).all():
            return None
        if len(w) != len(idx) or not np.isfinite(w).all() or w.sum() <= 0:
            w = np.ones(len(idx), np.float32)
        if idx.min() < 0 or idx.max() >= len(store):
            log.warning(
                "avatar frame %d out of range of %d frames: not the same avatar file?", int(idx.max()), len(store)
            )
            return None
        g = store.geometry
        feet = 0.5 * (joints[_LA] + joints[_RA])
        feet[1] = 0.0
        top = feet + np.array([0.0, joints[_HEAD, 1] + CROWN_M, 0.0])
        left = (joints[_LH] - joints[_RH]) + (joints[_LS] - joints[_RS])
        facing = np.array([-left[2], 0.0, left[0]])
        facing /= max(float(np.linalg.norm(facing)), 1e-9)
        uv = cam.project(np.stack([feet, top, feet + 0.3 * facing]))
        if not np.isfinite(uv).all() or uv[0, 1] - uv[1, 1] <= 1:
            return None  # behind the camera, or seen from above: no upright placement
        scale = float(uv[0, 1] - uv[1, 1]) / max(g.height_px, 1.0)
        mirror = np.sign(uv[2, 0] - uv[0, 0]) * g.facing < 0
        # premultiplied blend of the frames of a cross-fade
        acc = np.zeros((g.h, g.w, 3), np.float32)
        alpha = np.zeros((g.h, g.w), np.float32)
        for t, wk in zip(idx, w / w.sum()):
            a = store.alpha(int(t)) * np.float32(wk)
            acc += store.image(int(t)).astype(np.float32) * a[..., None]
            alpha += a
        fx = g.foot[0]
        if mirror:
            acc, alpha, fx = acc[:, ::-1], alpha[:, ::-1], g.w - fx
        W, H = max(int(round(g.w * scale)), 1), max(int(round(g.h * scale)), 1)
        if W > 4 * img.shape[1] or H > 4 * img.shape[0]:
            return None  # a placement right in front of the lens: nothing sensible to draw
        acc = cv2.resize(np.ascontiguousarray(acc), (W, H), interpolation=cv2.INTER_LINEAR)
        alpha = cv2.resize(np.ascontiguousarray(alpha), (W, H), interpolation=cv2.INTER_LINEAR)
        x0 = int(round(uv[0, 0] - fx * scale))
        y0 = int(round(uv[0, 1] - g.foot[1] * scale))
        return _over(img, acc, alpha, x0, y0)


def _over(img: np.ndarray, premult: np.ndarray, alpha: np.ndarray, x0: int, y0: int) -> bool:
    """img[y0:, x0:] = premult + (1 - alpha) img, clipped to the image; whether anything overlapped."""
    H, W = img.shape[:2]
    h, w = alpha.shape
    ax0, ay0, ax1, ay1 = max(x0, 0), max(y0, 0), min(x0 + w, W), min(y0 + h, H)
    if ax1 <= ax0 or ay1 <= ay0:
        return False
    a = alpha[ay0 - y0 : ay1 - y0, ax0 - x0 : ax1 - x0, None]
    p = premult[ay0 - y0 : ay1 - y0, ax0 - x0 : ax1 - x0]
    roi = img[ay0:ay1, ax0:ax1]
    roi[:] = np.clip(p + (1.0 - a) * roi, 0, 255).astype(np.uint8)
    return bool((a > 0.5).any())


__all__ = ["AvatarPainter", "CROWN_M"]
