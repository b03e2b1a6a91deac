"""Where the partner stands and what it does on real clips: the responder's algorithms over a tracked clip.

Used by ``bench/real_video.py`` (its tracking part writes one ``track_video`` file per clip). For each
clip the observed side's tracked joints go through the default dual-HMM and the responder node's
stage (``counterpart.nodes.responder.staging.Stage``, the node's defaults) frame by frame as the responder node
runs them, and its hand contact (``counterpart.nodes.responder.reach``) (a lost or missing person: the partner holds for ``HOLD_FRAMES``, then none), and the
partner is projected with the camera the tracking recorded. Figures:

- ``partner_distance_ok``: share of frames with a partner whose ground distance from the observed
  person (mid-hips on the floor, metres) lies in [0.5, 1.2] m;
- ``partner_overlap``: share of frames with a partner whose projected box overlaps the observed
  person's reference box (MediaPipe keypoints of vis >= 0.5) by more than ``OVERLAP_IOU``;
- ``partner_in_picture``: share of frames with a partner of which some joint is inside the picture;
- handshake clips (class 0, observed: the left person): at the moment the real hands meet (the
  frame where the two people's reference wrists are nearest), the pixel distance from the partner's
  nearer projected wrist to the observed person's reference wrist nearest the other person, over
  that person's reference height h: ``handshake_hand_h`` (median over clips) and
  ``handshake_hand_ok`` (share of clips within ``HAND_H`` h);
- push clips (class 5, observed: the pusher, the person whose reference wrist comes nearest the
  other's shoulders and hips): the partner's ground distance from the observed person, its largest
  value in the second after that moment minus its value then (metres): ``push_back_m`` (median) and
  ``push_moves_back`` (share of clips where it grows by at least ``BACK_M``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from counterpart.body.camera import Camera
from counterpart.body.skeleton import JOINT_INDEX
from counterpart.nodes.responder.frames import actor_frame
from counterpart.nodes.responder.models import load_default
from counterpart.nodes.responder.reach import reach
from counterpart.nodes.responder.staging import Stage

VIS = 0.5
HOLD_FRAMES = 15  # the responder node's default hold_frames
OVERLAP_IOU = 0.25
HAND_H = 0.15
BACK_M = 0.1
MIN_M, MAX_M = 0.5, 1.2
WRISTS = [JOINT_INDEX["l_wrist"], JOINT_INDEX["r_wrist"]]
TORSO = [JOINT_INDEX[j] for j in ("l_shoulder", "r_shoulder", "l_hip", "r_hip")]
HANDSHAKE, PUSH = 0, 5


def interaction_class(clip: Path) -> int:
    """UT-Interaction class of a clip from its name ``{clip}_{sequence}_{class}``."""
    return int(clip.stem.split("_")[2])


def _nearest(a: np.ndarray, va: np.ndarray, b: np.ndarray, vb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per frame the smallest distance between points a (T, A, 2) and b (T, B, 2) that are both
    visible (va (T, A), vb (T, B)), inf where none; and the index of a's point of that pair.
    """
    d = np.linalg.norm(a[:, :, None] - b[:, None], axis=-1)
    d = np.where(va[:, :, None] & vb[:, None] & np.isfinite(d), d, np.inf)
    flat = d.reshape(len(d), -1)
    return flat.min(axis=1), flat.argmin(axis=1) // b.shape[1]


def contact(kp: np.ndarray, vis: np.ndarray, h: np.ndarray, label: int) -> tuple[int, int, int] | None:
    """The moment of the interaction by the reference: (frame, observed person, its wrist joint).

    kp (T, 2, 14, 2) pixels, vis (T, 2, 14), h (T, 2) heights (pixels). Handshake: the frame where
    the two people's wrists are nearest (over their mean height); the observed person is 0 (the
    left one). Push: the frame where one person's wrist is nearest the other's torso; that person
    (the pusher) is observed. None when the reference never shows the joints needed.
    """
    seen = (vis >= VIS) & np.isfinite(kp).all(axis=-1)
    # frames without a reference height (a joint missing) cannot say how near the people are
    scale = np.where(np.isfinite(h).all(axis=1), np.maximum(h.mean(axis=1), 1.0), np.nan)
    if label == HANDSHAKE:
        d, k = _nearest(kp[:, 0, WRISTS], seen[:, 0, WRISTS], kp[:, 1, WRISTS], seen[:, 1, WRISTS])
        d = np.nan_to_num(d / scale, nan=np.inf)
        t = int(np.argmin(d))
        return None if not np.isfinite(d[t]) else (t, 0, WRISTS[int(k[t])])
    best = None
    for p in (0, 1):
        d, k = _nearest(kp[:, p, WRISTS], seen[:, p, WRISTS], kp[:, 1 - p, TORSO], seen[:, 1 - p, TORSO])
        d = np.nan_to_num(d / scale, nan=np.inf)
        t = int(np.argmin(d))
        if np.isfinite(d[t]) and (best is None or d[t] < best[0]):
            best = (d[t], t, p, WRISTS[int(k[t])])
    return None if best is None else best[1:]


def staged_partner(track_npz: Path, side: int) -> tuple[np.ndarray, np.ndarray, Camera, float]:
    """The partner the responder node would draw for the tracked ``side`` of a ``track_video`` file.

    Returns partner (T, 14, 3) world metres (NaN: none), observed (T, 14, 3) (NaN: lost or
    missing), the camera of the tracking, and the clip's fps.
    """
    d = np.load(track_npz)
    camera = Camera.from_dict(json.loads(str(d["camera"])))
    fps = float(d["fps"])
    joints, lost = d["joints"][:, side].astype(np.float64), d["lost"][:, side]
    model, stage = load_default("dual-hmm"), Stage()
    model.reset()
    partner = np.full_like(joints, np.nan)
    observed = np.where(lost[:, None, None], np.nan, joints)
    last = -(10**9)
    for t in range(len(joints)):
        if lost[t] or not np.isfinite(joints[t]).all():
            if t - last <= HOLD_FRAMES:
                partner[t] = partner[last]
            continue
        staged = stage(joints[t], model.step(joints[t]), (t - last) / fps if last >= 0 else 1.0 / fps)
        partner[t] = reach(joints[t], staged)[0]
        last = t
    return partner, observed, camera, fps


def _box(points: np.ndarray) -> np.ndarray | None:
    pts = points[np.isfinite(points).all(axis=-1)]
    return None if len(pts) < 2 else np.r_[pts.min(0), pts.max(0)]


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    w = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    h = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = w * h
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def partner_clip(clip: Path, track_npz: Path, kp: np.ndarray, vis: np.ndarray, h: np.ndarray) -> dict[str, Any]:
    """The partner's figures on one clip (counts, to pool; and the clip's interaction figure).

    kp (T, 2, 14, 2), vis (T, 2, 14), h (T, 2): the reference over the frames scored.
    """
    label = interaction_class(clip)
    moment = contact(kp, vis, h, label) if label in (HANDSHAKE, PUSH) else None
    side = moment[1] if moment is not None and label == PUSH else 0
    partner, observed, camera, fps = staged_partner(track_npz, side)
    n = min(len(partner), len(kp))
    partner, observed = partner[:n], observed[:n]
    has = np.isfinite(partner).all(axis=(1, 2))
    both = has & np.isfinite(observed).all(axis=(1, 2))
    gap = np.full(n, np.nan)
    if both.any():
        gap[both] = np.linalg.norm((actor_frame(partner[both])[0] - actor_frame(observed[both])[0])[:, [0, 2]], axis=1)
    uv = camera.project(np.where(has[:, None, None], partner, 0.0))
    overlap = in_picture = 0
    for t in np.flatnonzero(has):
        in_picture += bool(camera.in_image(uv[t]).any())
        ref = _box(np.where((vis[t, side] >= VIS)[:, None], kp[t, side], np.nan))
        mine = _box(uv[t])
        overlap += ref is not None and mine is not None and _iou(ref, mine) > OVERLAP_IOU
    out: dict[str, Any] = {
        "frames": int(has.sum()),
        "gap_n": int(both.sum()),
        "gap_ok": int(((gap >= MIN_M - 1e-6) & (gap <= MAX_M + 1e-6)).sum()),
        "overlap": int(overlap),
        "in_picture": int(in_picture),
        "label": label,
    }
    if moment is not None and moment[0] < n:
        t, p, wrist = moment
        if label == HANDSHAKE and has[t]:
            out["hand_h"] = float(np.linalg.norm(uv[t, WRISTS] - kp[t, p, wrist], axis=-1).min() / max(h[t, p], 1.0))
        elif label == HANDSHAKE:
            out["hand_h"] = float("inf")  # no partner at the moment of the handshake: a miss
        if label == PUSH:
            after = gap[t : t + round(fps) + 1]
            out["back_m"] = (
                float(np.nanmax(after) - gap[t]) if np.isfinite(gap[t]) and np.isfinite(after).any() else float("nan")
            )
    return out


def partner_figures(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Pool ``partner_clip`` rows into the bench's figures."""
    frames = sum(r["frames"] for r in rows)
    hands = [r["hand_h"] for r in rows if "hand_h" in r]
    backs = [r["back_m"] for r in rows if "back_m" in r]
    return {
        "partner_distance_ok": round(sum(r["gap_ok"] for r in rows) / max(sum(r["gap_n"] for r in rows), 1), 4),
        "partner_overlap": round(sum(r["overlap"] for r in rows) / max(frames, 1), 4),
        "partner_in_picture": round(sum(r["in_picture"] for r in rows) / max(frames, 1), 4),
        "handshake_clips": len(hands),
        "handshake_hand_h": round(float(np.median(hands)), 3) if hands else None,
        "handshake_hand_ok": round(float(np.mean([x <= HAND_H for x in hands])), 3) if hands else None,
        "push_clips": len(backs),
        "push_back_m": round(float(np.nanmedian(backs)), 3) if backs and np.isfinite(backs).any() else None,
        "push_moves_back": round(float(np.mean([x >= BACK_M for x in backs])), 3) if backs else None,
    }
