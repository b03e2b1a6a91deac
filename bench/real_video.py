"""The demo on real two-person video: ``counterpart demo --input CLIP`` over UT-Interaction clips.

Each clip goes through the real command (six node processes, the lockstep graph
``launch/lockstep.yaml``) with a time limit; the figures come from the run's own summary
(``OUT/demo_stats.json``) and from the video it wrote:

- ``partner_present``: share of output frames with a partner drawn in the picture, per clip and
  pooled; ``partner_present_after_1s`` the same without each clip's first second (the background
  is learnt and the tracks start there); ``clips_partner_95``: clips whose after-1s share is at
  least 0.95; ``clips_two_people`` / ``clips_two_people_partner_95`` the same over the clips in
  which both people are in view (the target: every one of them): by the reference keypoints, each
  person with at least ``TWO_PEOPLE_JOINTS`` joints of visibility >= 0.5 per frame on average (a few
  clips of set 1 are cropped to one person);
- ``hangs``: runs (clips and the short-input cases) that did not end within the limit;
- ``fps_match``: clips whose output video plays at the input's frame rate (the file's own header
  read back with OpenCV, beside the demo's ``fps_in``/``fps_out``);
- the short inputs: the first clip cut to 1 and 5 frames (``--frames``), and started past its end
  (a source that fails before its first frame), each must end by itself;
- reference in the same run: the real-time graph (``--realtime``) on the first ``--reference``
  clips, where the nodes that cannot keep up on this machine drop frames (``partner_present_realtime``).

Tracking accuracy (``--pck-clips``, default the same clips; ``--no-pck`` skips it): each clip is
tracked offline without the bus, configured as the lockstep graph configures its nodes
(``counterpart.apps.tracking.track_video``: both sides, the default motion prior, 10 layers x 256
particles, the background fitted on the first 20 frames, the camera the calibration node publishes
when given no file), and its joints projected with the camera the run recorded. They are compared
with the reference keypoints ``../shared/data/ut_interaction/keypoints/<stem>.npz`` (MediaPipe,
person 0 the left one at frame 0) on every frame the video decodes:

- ``pck10``, ``pck20``: PCK@0.1h and PCK@0.2h, the share of the reference joints of visibility
  >= 0.5 whose tracked joint lies within 0.1 h (0.2 h) pixels, h the reference person's height on
  that frame (head to the midpoint of the two ankles); the tracked side "left" is person 0 and
  "right" person 1; a frame on which a side is missing or lost counts all its joints as misses;
  the reference's head is the nose, so the tracked head is compared as the nose of the body
  model (``nose_points``: the front of its head along the body's facing);
- ``pck10_box``, ``pck20_box``: the same for the box-template baseline, no tracking: one fixed 2D
  template for both people, the mean of the reference joints (vis >= 0.5) normalised to their
  person's silhouette box on the "tune" clips of the run (all clips when it has none; on the tune
  split it is therefore measured on the clips it was learnt from), scaled into the box of the
  silhouette the tracker is fed on that frame (the first person the silhouette node reports on
  that side), from a second pass of the same silhouette extractor (``iter_video``; it is
  deterministic, and ``pck_details.silhouette_ids_agree`` checks that the ids match the tracker's);
- ``pck_excluded``: share of frames left out because the reference itself is broken there (both
  reference skeletons on one person, ``real_silhouettes.reference_collapsed``);
- split: clips whose first number is even are "tune", odd "report" (as ``bench/real_silhouettes.py``);
  the top-level figures are the report split's, ``tune`` holds the same for the tune split;
  ``pck_details`` per split also gives the figures with the two sides matched to the reference
  people per frame by the smaller mean pixel distance (people and the reference's crops can swap
  when they touch), per clip figures (with ``partner_overlap_frames``, the frames counted in
  ``partner_overlap``), the template, and the seconds per clip of the tracking and of the silhouette
  pass (``track_s``, ``box_s``), and ``by_joint``: per joint, [pck10, pck20, pck10_box, pck20_box,
  joints scored].

People cut off by the frame (``--no-cut`` skips it): each clip again, cut off above the people's
knees (``real_silhouettes.cut_row``; a lossless copy, ``cut_copy``) as a camera nearer them would
see them, tracked the same way: ``pck10_cut``, ``pck20_cut`` on the reference joints still in the
picture; ``scale_cut``, the median over frames of the tracked body's projected height (nose to
mid-ankle) over the reference's h; the same as it was before (``CUT_BEFORE``: the tracker's window
ending at the frame, its first search from the box in view, the silhouettes' people detector without
the frame continued below): ``*_cut_before``; and the whole clips' tracks scored on the same joints,
``pck10_uncut_same_joints``, ``pck20_uncut_same_joints``; and the partner staged beside the
person cut off (``real_partner``, the moment of the interaction found on the joints in the
picture): ``partner_distance_ok_cut``, ``partner_overlap_cut``, ``partner_in_picture_cut``,
``partner_scale_cut``, ``handshake_hand_h_cut``, ``push_back_m_cut``. Report and tune splits as above.

A slower camera (``--slow-step K``, default 3; 0 skips it): each clip again with every K-th frame
only, a lossless copy at 1/K of its frame rate (10 fps for K = 3: a webcam in low light, many
surveillance recordings), tracked with that rate told to the trackers (their motion prior's steps
taken over the longer interval, ``tracker.prior.PriorPredictor``): ``pck10_slow``, ``pck20_slow``;
told nothing, as if the frames came at the prior's rate: ``*_slow_unscaled``; the whole clips'
tracks on the same frames, ``pck10_full_rate_same_frames``, ``pck20_full_rate_same_frames``; and the
partner staged beside the first track: ``partner_distance_ok_slow``, ``partner_overlap_slow``,
``partner_in_picture_slow``, ``partner_scale_slow``, ``handshake_hand_h_slow``, ``push_back_m_slow``.

Silhouettes (``--no-silhouettes`` skips them): ``people_found`` and ``keypoint_coverage`` as
``bench/real_silhouettes.py`` defines them (the silhouette node's extractor with its defaults, the
background trained on each clip's first frames with the people in view, scored from frame 10), over
every clip of the report split (odd first number), the tune split's under ``silhouette_details``.

Speed (``--speed-frames``, default 600; 0 skips it): the real-time demo graph (``launch/demo.yaml``,
as ``bench/e2e.py`` runs it) on each of the ``--reference`` clips at its own 30 fps, looped to that many
frames with both people tracked, and on the simulator in the same run: ``fps`` (median over the
clips of the sustained frame rate through the graph), ``latency_p95_ms`` (median of the steady-state
p95 capture-to-render latency, after the first 3 s), ``fps_sim`` and ``latency_p95_ms_sim``; per clip,
with the share of frames the tracker and the partner kept up with and the cores the graph needed,
under ``speed_details``.

Camera calibration from the people (``--calib-seeds``, default 50; 0 skips it): ``calib_height_err``,
``calib_tilt_err_deg``, ``calib_focal_err`` (medians of the absolute errors) and ``calib_within``
(share of seeds within 10% / 3 degrees / 10%) on the simulator with random cameras, from each
scene's first 3 s, as ``bench/self_calibration.py`` defines them (with its reference figures: the
default camera's, the true head/foot points', the share the calibration node would publish);
``calib_details`` holds the per-seed rows and the estimates on these clips with their spread.

The clips: ``../shared/data/ut_interaction/set1`` (read its README). Nothing is tuned here; the
default picks every fifth clip of the 60 (12 clips, all six interaction classes), ``--clips all``
runs every one. Usage: ``python bench/real_video.py [--clips all|N] [--timeout S] [--reference K]
[--pck-clips all|N] [--pck-classes 0,5] [--jobs J] [--no-pck] [--no-cut] [--slow-step K] [--no-demo] [--tracks DIR]
[--no-silhouettes] [--speed-frames N] [--calib-seeds N]``
(``--tracks``: keep the tracks, and reuse those already there). Last stdout line: one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from contextlib import nullcontext
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from real_partner import (  # bench/ is on sys.path as a script
    interaction_class,
    partner_clip,
    partner_figures,
    silhouette_people,
)
from real_silhouettes import VIS, cut_row, reference_collapsed

from counterpart.body.camera import Camera
from counterpart.body.image_sequence import read_frames, video_info
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.people_detector import PeopleDetector
from counterpart.body.pose import neutral_pose
from counterpart.body.skeleton import DEFAULT_DIMS, JOINT_INDEX, JOINTS, N_JOINTS
from counterpart.nodes.responder.frames import actor_frame
from counterpart.nodes.tracker.likelihood import LikelihoodConfig
from counterpart.nodes.tracker.tracker import InitConfig, TrackerConfig

REPO = Path(__file__).resolve().parents[1]
CLIPS = REPO.parent / "shared" / "data" / "ut_interaction" / "set1"
KEYPOINTS = CLIPS.parent / "keypoints"
#: tracked side k is reference person k (person 0 is the one on the left at frame 0)
SIDES = ("left", "right")
#: as the lockstep graph (launch/lockstep.yaml) configures the silhouette and tracker nodes
TRAIN_FRAMES, LAYERS, PARTICLES = 20, 10, 256
#: the slow pass keeps every this many-th frame (``--slow-step``): the clips' 30 fps become 10
SLOW_STEP = 3
HEAD, ANKLES = JOINT_INDEX["head"], [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]
ALPHAS = (0.1, 0.2)
#: the default body's head centre above its mid-ankle, metres
_NEUTRAL = forward_kinematics(neutral_pose(DEFAULT_DIMS)).reshape(14, 3)
MODEL_HEAD_ANKLE = float(_NEUTRAL[HEAD, 1] - _NEUTRAL[ANKLES, 1].mean())


#: visible reference joints per frame, on average, of a person who is in view in a clip
TWO_PEOPLE_JOINTS = 5.0


def two_people(clip: Path) -> bool:
    """Whether both people of ``clip`` are in view, by its reference keypoints (vis (T, 2, 14))."""
    vis = np.load(KEYPOINTS / f"{clip.stem}.npz")["vis"]
    return bool(((vis >= 0.5).sum(axis=2).mean(axis=0) >= TWO_PEOPLE_JOINTS).all())


def clip_list(which: str) -> list[Path]:
    clips = sorted(CLIPS.glob("*.avi"), key=lambda p: int(p.stem.split("_")[0]))
    if which == "all":
        return clips
    return clips[:: max(1, len(clips) // int(which))][: int(which)]


def run_demo(clip: Path, out: Path, timeout: float, *extra: str) -> dict:
    """One ``counterpart demo --input clip``; its summary, exit code, wall time and whether it hung."""
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    proc = subprocess.Popen(
        [sys.executable, "-m", "counterpart.bus.cli", "demo", "--input", str(clip), "--out", str(out), *extra],
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        _, err = proc.communicate(timeout=timeout)
        hung = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, 9)
        _, err = proc.communicate()
        hung = True
    stats_file = out / "demo_stats.json"
    stats = json.loads(stats_file.read_text()) if stats_file.exists() and not hung else {}
    stats.pop("nodes", None)
    return {
        "code": proc.returncode,
        "hung": hung,
        "wall_s": round(time.monotonic() - t0, 1),
        "reason": err.strip().splitlines()[-1] if err.strip() else "",
        **stats,
    }


def video_fps(out: Path) -> float:
    videos = [p for p in out.glob("demo.*") if p.suffix in (".mp4", ".avi")]
    if not videos:
        return 0.0
    cap = cv2.VideoCapture(str(videos[0]))
    fps = float(cap.get(cv2.CAP_PROP_FPS))
    cap.release()
    return fps


def split_of(clip: Path) -> str:
    """Return "tune" for the clips whose first number is even, "report" for the odd ones (as real_silhouettes)."""
    return "tune" if int(clip.stem.split("_")[0]) % 2 == 0 else "report"


def nose_points(joints: np.ndarray) -> np.ndarray:
    """Where the nose of the body model is: (..., 14, 3) joints (metres) -> (..., 3).

    The reference's "head" is the nose, the body model's the head centre at eye level: the nose
    is taken on the front of the model's head, the head cone's radius at its centre (the mean of
    ``r_chin`` and ``r_crown``, scaled with the body) along the body's facing (``actor_frame``).
    """
    _, theta = actor_frame(np.nan_to_num(joints))
    facing = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    stature = joints[..., HEAD, 1] - joints[..., ANKLES, 1].mean(axis=-1)
    radius = 0.5 * (DEFAULT_DIMS.r_chin + DEFAULT_DIMS.r_crown) * stature / MODEL_HEAD_ANKLE
    return joints[..., HEAD, :] + facing * radius[..., None]


def tracked_pixels(track_npz: Path) -> tuple[np.ndarray, np.ndarray]:
    """The tracked joints of a ``track_video`` file projected with the camera it recorded, the head
    as the nose (``nose_points``: the reference's head is the nose).

    Returns est (T, 2, 14, 2) pixels, NaN where the side was not tracked, lost, or the joint is
    behind the camera, and ids (T, 2) the silhouette node's person id per side (-1: none).
    """
    d = np.load(track_npz)
    camera = Camera.from_dict(json.loads(str(d["camera"])))
    joints = d["joints"].astype(np.float64)
    joints[..., HEAD, :] = nose_points(joints)
    est = camera.project(joints)
    est[d["lost"]] = np.nan  # a lost track is a miss, whatever joints it left behind
    return est, d["ids"]


def silhouette_boxes(clip: Path) -> tuple[np.ndarray, np.ndarray]:
    """The silhouette box of each side per frame, as the offline tracker's extractor finds them.

    The same extractor and training as ``track_video`` (``iter_video``, default parameters,
    ``TRAIN_FRAMES``), and the same choice of person per side (the first one reported with that
    side). Returns boxes (T, 2, 4) float (x, y, w, h) pixels, NaN where the side has nobody, and
    ids (T, 2) person ids (-1: none).
    """
    from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, iter_video

    boxes, ids = [], []
    for _, result in iter_video(clip, SilhouetteExtractor(), None, TRAIN_FRAMES):
        row, row_ids = np.full((2, 4), np.nan), np.full(2, -1)
        for k, side in enumerate(SIDES):
            person = next((p for p in result.people if p.side == side), None)
            if person is not None:
                row[k], row_ids[k] = person.bbox, person.id
        boxes.append(row)
        ids.append(row_ids)
    return np.array(boxes), np.array(ids)


def reference_height(kp: np.ndarray) -> np.ndarray:
    """Kp (T, 2, 14, 2) pixels -> (T, 2) each person's height in pixels: head to mid-ankle."""
    return np.linalg.norm(kp[:, :, HEAD] - kp[:, :, ANKLES].mean(axis=2), axis=-1)


def pck_counts(est: np.ndarray, kp: np.ndarray, scored: np.ndarray, h: np.ndarray) -> dict[str, int]:
    """Joints within each ``ALPHAS`` x h of the reference.

    est, kp (T, 2, 14, 2) pixels (est NaN: missing, a miss); scored (T, 2, 14) bool, the joints
    that count; h (T, 2) reference heights, pixels. Returns {"n": joints scored, "hit10": ...,
    "hit20": ...} (pooled over clips by summing, so PCK weighs every joint alike).
    """
    d = np.linalg.norm(est - kp, axis=-1)  # NaN where est is missing: NaN < x is False, a miss
    out = {"n": int(scored.sum())}
    for a in ALPHAS:
        out[f"hit{round(a * 100)}"] = int((scored & (d < a * h[..., None])).sum())
    return out


def match_per_frame(est: np.ndarray, kp: np.ndarray, scored: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Est (T, 2, 14, 2) with its two sides swapped on the frames where the swap brings them closer
    to the reference people kp (T, 2, 14, 2) (mean pixel distance over the scored joints, NaN
    ignored; both assignments must have one). Returns (est matched, swapped (T,) bool).
    """

    def cost(e: np.ndarray) -> np.ndarray:
        d = np.where(scored, np.linalg.norm(e - kp, axis=-1), np.nan)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN frames: no cost, no swap
            return np.nanmean(d.reshape(len(d), -1), axis=1)

    keep, swap = cost(est), cost(est[:, ::-1])
    swapped = swap < keep  # False where either is NaN
    return np.where(swapped[:, None, None, None], est[:, ::-1], est), swapped


def box_template(boxes: np.ndarray, kp: np.ndarray, scored: np.ndarray) -> np.ndarray:
    """The mean reference skeleton in box coordinates: (14, 2), x and y as fractions of the box's
    width and height from its top-left corner. boxes (T, 2, 4) (x, y, w, h) pixels, NaN: none;
    kp (T, 2, 14, 2) pixels; scored (T, 2, 14) the joints to learn from (frames of several clips
    may be stacked on the first axis).
    """
    rel = (kp - boxes[:, :, None, :2]) / np.maximum(boxes[:, :, None, 2:], 1.0)
    use = scored & np.isfinite(rel).all(axis=-1)
    return np.where(use[..., None], rel, 0.0).sum(axis=(0, 1)) / np.maximum(use.sum(axis=(0, 1)), 1)[:, None]


def template_pixels(template: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Template (14, 2) box fractions scaled into boxes (T, 2, 4) -> (T, 2, 14, 2) pixels (NaN: no box)."""
    return boxes[:, :, None, :2] + template * boxes[:, :, None, 2:]


def pck_clip(clip: Path, work: Path, cut: bool = False, slow_step: int = 0) -> dict[str, Any]:
    """Track one clip offline and gather what the PCK needs: the projected estimates, the boxes,
    the reference and which of its joints count; plus timings and the excluded frames; ``cut``:
    the cut pass too (``cut_clip``); ``slow_step`` > 1: the slow pass too (``slow_clip``).
    """
    from counterpart.apps.tracking import track_video
    from counterpart.nodes.tracker.prior import resolve_prior

    t0 = time.monotonic()
    if not (work / f"{clip.stem}-track.npz").exists():  # ``--tracks``: a track kept from an earlier run is reused
        track_video(
            clip,
            work / f"{clip.stem}-track.npz",
            people=SIDES,
            camera=None,
            prior=resolve_prior("default"),
            layers=LAYERS,
            particles=PARTICLES,
            train_frames=TRAIN_FRAMES,
        )
    t1 = time.monotonic()
    boxes, box_ids = silhouette_boxes(clip)
    t2 = time.monotonic()
    est, ids = tracked_pixels(work / f"{clip.stem}-track.npz")
    ref = np.load(KEYPOINTS / f"{clip.stem}.npz")
    # OpenCV decodes a frame or two fewer than the reference has: score the frames both have
    n = min(len(est), len(boxes), len(ref["kp"]))
    kp, vis = ref["kp"][:n].astype(np.float64), ref["vis"][:n]
    collapsed = np.array([reference_collapsed(kp[t], vis[t]) for t in range(n)], dtype=bool)
    scored = (vis >= VIS) & ~collapsed[:, None, None]
    h = reference_height(kp)
    return {
        **({"cut": cut_clip(clip, work, kp, scored, h)} if cut else {}),
        **({"slow": slow_clip(clip, work, slow_step, kp, scored, h)} if slow_step > 1 else {}),
        "est": est[:n],
        "boxes": boxes[:n],
        "kp": kp,
        "scored": scored,
        "h": h,
        "collapsed": int(collapsed.sum()),
        "frames": n,
        "track_s": t1 - t0,
        "box_s": t2 - t1,
        "ids_agree": int((ids[:n] == box_ids[:n]).all(axis=1).sum()),
        "partner": partner_clip(clip, work / f"{clip.stem}-track.npz", kp, vis, h),
    }


#: the cut pass as it was before people cut off by the frame were looked after: the tracker's
#: window ending at the frame and its first search from the box in view, the silhouettes'
#: detector without the frame continued below (the reference in the same run)
CUT_BEFORE = {
    "tracker": TrackerConfig(init=InitConfig(cut_off=False), likelihood=LikelihoodConfig(past_border=0.0)),
    "backend_params": {"detector": PeopleDetector()},
}


#: the partner's figures (``real_partner.partner_figures``) also given for the cut and slow passes
PASS_PARTNER = (
    "partner_distance_ok",
    "partner_overlap",
    "partner_in_picture",
    "partner_scale",
    "handshake_hand_h",
    "push_back_m",
)


def cut_copy(clip: Path, work: Path, kp: np.ndarray, vis: np.ndarray) -> tuple[Path, int]:
    """The clip cut off above the people's knees (``real_silhouettes.cut_row``) as a lossless copy
    in ``work`` (FFV1, the clip's frame rate), and the row it ends at.
    """
    r = cut_row(kp, vis)
    path = work / f"{clip.stem}-cut.avi"
    if not path.exists():
        lossless_copy(read_frames(clip)[:, :r], path, video_info(clip)[0] or 30.0)
    return path, r


def lossless_copy(frames: np.ndarray, path: Path, fps: float) -> None:
    """Write frames (T, H, W, 3) uint8 BGR to ``path`` as FFV1 at ``fps``."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FFV1"), fps, (frames.shape[2], frames.shape[1]))
    for f in frames:
        writer.write(np.ascontiguousarray(f))
    writer.release()


def pass_estimates(path: Path, npz: Path, n: int, **extra: Any) -> np.ndarray:
    """A pass's copy of a clip tracked as the tracking part tracks (kept in ``npz``, and read from
    it when there), its joints projected (``tracked_pixels``) over ``n`` frames, NaN past those
    tracked; ``extra``: ``track_video``'s keyword arguments over the part's.
    """
    from counterpart.apps.tracking import track_video
    from counterpart.nodes.tracker.prior import resolve_prior

    if not npz.exists():
        track_video(
            path,
            npz,
            people=SIDES,
            prior=resolve_prior("default"),
            layers=LAYERS,
            particles=PARTICLES,
            train_frames=TRAIN_FRAMES,
            **extra,
        )
    est = tracked_pixels(npz)[0][:n]
    return np.concatenate([est, np.full((n - len(est), *est.shape[1:]), np.nan)])


def cut_clip(clip: Path, work: Path, kp: np.ndarray, scored: np.ndarray, h: np.ndarray) -> dict[str, Any]:
    """The cut pass of one clip: tracked as it is and as before (``CUT_BEFORE``), its PCK counts on
    the reference joints still in the picture (of those ``scored`` on the whole clip), their
    ``scored`` mask, and the tracked body's scale: its projected height (nose to mid-ankle) over
    the reference's, per frame where both are known.
    """
    ref = np.load(KEYPOINTS / f"{clip.stem}.npz")
    path, r = cut_copy(clip, work, ref["kp"], ref["vis"])
    out: dict[str, Any] = {"scored": scored & (kp[..., 1] < r)}
    ankles = scored[:, :, HEAD] & scored[:, :, ANKLES].all(axis=-1)
    for name, extra in (("", {}), ("_before", CUT_BEFORE)):
        est = pass_estimates(path, work / f"{clip.stem}-cut{name}-track.npz", len(kp), **extra)
        out["counts" + name] = pck_counts(est, kp, out["scored"], h)
        tall = np.linalg.norm(est[:, :, HEAD] - est[:, :, ANKLES].mean(axis=2), axis=-1) / h
        out["scale" + name] = tall[ankles & np.isfinite(tall)].tolist()
    # the partner the responder stages beside the person cut off (the moment of the interaction is
    # looked for on the joints in the picture)
    visible = np.where(kp[..., 1] < r, ref["vis"][: len(kp)], 0.0)
    people = silhouette_people(path)
    out["partner"] = partner_clip(clip, work / f"{clip.stem}-cut-track.npz", kp, visible, h, people)
    return out


def slow_clip(clip: Path, work: Path, step: int, kp: np.ndarray, scored: np.ndarray, h: np.ndarray) -> dict[str, Any]:
    """The slow pass of one clip: every ``step``-th frame as a lossless copy at 1/``step`` of its
    frame rate (a camera that delivers fewer frames, e.g. a webcam in low light), tracked with the
    rate told to the trackers and not (``_unscaled``: as if at the motion prior's rate); their PCK
    counts on the reference of the frames kept, the frames kept, and the partner staged beside
    the first track (``partner_clip``).
    """
    path = work / f"{clip.stem}-slow{step}.avi"
    if not path.exists():
        lossless_copy(read_frames(clip)[::step], path, (video_info(clip)[0] or 30.0) / step)
    kept = np.arange(0, len(kp), step)
    out: dict[str, Any] = {"kept": kept}
    for name, told in (("", None), ("_unscaled", 0.0)):
        est = pass_estimates(path, work / f"{clip.stem}-slow{step}{name}-track.npz", len(kept), fps=told)
        out["counts" + name] = pck_counts(est, kp[kept], scored[kept], h[kept])
    vis = np.load(KEYPOINTS / f"{clip.stem}.npz")["vis"][: len(kp)][kept]
    npz = work / f"{clip.stem}-slow{step}-track.npz"
    out["partner"] = partner_clip(clip, npz, kp[kept], vis, h[kept], silhouette_people(path))
    return out


def slow_figures(rows: list[dict[str, Any]], step: int) -> dict[str, Any]:
    """The slow pass's figures pooled over the clips' rows (``pck_clip`` with ``slow_step``):
    ``pck10_slow``, ``pck20_slow``, ``_unscaled``, the whole clips' tracks on the same frames
    (``pck10_full_rate_same_frames``, ...), and the partner's (``partner_distance_ok_slow``, ...).
    """
    full = []
    for r in rows:
        kept = r["slow"]["kept"]
        full.append(pck_counts(r["est"][kept], r["kp"][kept], r["scored"][kept], r["h"][kept]))
    return {
        "slow_step": step,
        **pass_figures(
            rows,
            "slow",
            {
                "_slow": [r["slow"]["counts"] for r in rows],
                "_slow_unscaled": [r["slow"]["counts_unscaled"] for r in rows],
                "_full_rate_same_frames": full,
            },
        ),
    }


def pass_figures(rows: list[dict[str, Any]], name: str, counts: dict[str, list[dict[str, int]]]) -> dict[str, Any]:
    """A pass's PCK of each set of per-clip ``counts`` pooled (``pck10`` + its suffix, ...) and its
    partner's figures (``PASS_PARTNER``, suffixed ``_`` + ``name``) from the clips' ``rows[name]``.
    """
    out: dict[str, Any] = {}
    for suffix, clip_counts in counts.items():
        n = max(sum(c["n"] for c in clip_counts), 1)
        for a in ALPHAS:
            out[f"pck{round(a * 100)}{suffix}"] = round(sum(c[f"hit{round(a * 100)}"] for c in clip_counts) / n, 4)
    partner = partner_figures([r[name]["partner"] for r in rows])
    return {**out, **{f"{k}_{name}": partner[k] for k in PASS_PARTNER}}


def cut_figures(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The cut pass's figures pooled over the clips' rows (``pck_clip`` with ``cut``): ``pck10_cut``,
    ``pck20_cut`` and ``_before``, the same joints of the whole clips' tracks
    (``pck10_uncut_same_joints``, ...), and the median ``scale_cut`` and ``scale_cut_before``.
    """
    uncut = [pck_counts(r["est"], r["kp"], r["cut"]["scored"], r["h"]) for r in rows]
    out = pass_figures(
        rows,
        "cut",
        {
            "_cut": [r["cut"]["counts"] for r in rows],
            "_cut_before": [r["cut"]["counts_before"] for r in rows],
            "_uncut_same_joints": uncut,
        },
    )
    for name in ("", "_before"):
        scale = [v for r in rows for v in r["cut"]["scale" + name]]
        out["scale_cut" + name] = round(float(np.median(scale)), 3) if scale else None
    out["cut_joints"] = sum(int(r["cut"]["scored"].sum()) for r in rows)
    return out


def pck_figures(rows: list[dict[str, Any]], template: np.ndarray, per_frame: bool) -> dict[str, Any]:
    """PCK of the tracker and of the box template pooled over the clips' rows (``pck_clip``);
    ``per_frame``: match the sides to the reference people per frame (``match_per_frame``).
    """
    tot: dict[str, int] = {}
    swapped = 0
    for r in rows:
        est, box = r["est"], template_pixels(template, r["boxes"])
        if per_frame:
            est, sw = match_per_frame(est, r["kp"], r["scored"])
            box, _ = match_per_frame(box, r["kp"], r["scored"])
            swapped += int(sw.sum())
        for name, e in (("", est), ("_box", box)):
            for k, v in pck_counts(e, r["kp"], r["scored"], r["h"]).items():
                tot[k + name] = tot.get(k + name, 0) + v
    frames = sum(r["frames"] for r in rows)
    out: dict[str, Any] = {}
    for name in ("", "_box"):
        for a in ALPHAS:
            out[f"pck{round(a * 100)}{name}"] = round(tot[f"hit{round(a * 100)}{name}"] / max(tot["n" + name], 1), 4)
    if per_frame:
        out["swapped_frames"] = round(swapped / max(frames, 1), 4)
    else:
        out["pck_excluded"] = round(sum(r["collapsed"] for r in rows) / max(frames, 1), 4)
        out["pck_joints"] = tot["n"]
    return out


def pck_by_joint(rows: list[dict[str, Any]], template: np.ndarray) -> dict[str, list[float]]:
    """Per joint of the reference, pooled over the clips' rows (``pck_clip``): [pck10, pck20,
    pck10_box, pck20_box, joints scored], as ``pck_figures`` defines them (sides as tracked).
    """
    n = np.zeros(N_JOINTS)
    hits = np.zeros((4, N_JOINTS))
    for r in rows:
        for i, e in enumerate((r["est"], template_pixels(template, r["boxes"]))):
            d = np.linalg.norm(e - r["kp"], axis=-1)
            for k, a in enumerate(ALPHAS):
                hits[2 * i + k] += (r["scored"] & (d < a * r["h"][..., None])).sum(axis=(0, 1))
        n += r["scored"].sum(axis=(0, 1))
    return {name: [*np.round(hits[:, j] / max(n[j], 1), 3).tolist(), int(n[j])] for j, name in enumerate(JOINTS)}


def run_pck(clips: list[Path], work: Path, jobs: int = 1, cut: bool = True, slow_step: int = 0) -> dict[str, Any]:
    """The tracking-accuracy part: the top-level figures (report split), ``tune`` and ``pck_details``;
    ``jobs`` clips tracked at once in worker processes (each clip's run is seeded: the figures
    do not depend on it); ``cut``: with the cut pass (``cut_figures``); ``slow_step`` > 1: with the
    slow pass (``slow_figures``).
    """
    rows: dict[str, dict[str, Any]] = {}
    with ProcessPoolExecutor(jobs) if jobs > 1 else nullcontext() as pool:
        n = len(clips)
        done = (
            pool.map(pck_clip, clips, [work] * n, [cut] * n, [slow_step] * n)
            if pool
            else (pck_clip(c, work, cut, slow_step) for c in clips)
        )
        for clip, r in zip(clips, done):
            rows[clip.stem] = r
            print(
                f"pck {clip.stem}: track {r['track_s']:.1f} s, boxes {r['box_s']:.1f} s, "
                f"{r['collapsed']}/{r['frames']} frames excluded",
                file=sys.stderr,
                flush=True,
            )
    splits = {s: [rows[c.stem] for c in clips if split_of(c) == s] for s in ("tune", "report")}
    # learnt on the tune clips only, so that the report split's baseline has not seen its clips
    learn = splits["tune"] or list(rows.values())
    template = box_template(
        np.concatenate([r["boxes"] for r in learn]),
        np.concatenate([r["kp"] for r in learn]),
        np.concatenate([r["scored"] for r in learn]),
    )
    result: dict[str, Any] = {"pck10": None, "pck20": None, "pck10_box": None, "pck20_box": None, "pck_excluded": None}
    details: dict[str, Any] = {
        "split": "tune: clips whose first number is even; report: odd (top-level figures)",
        "template": "mean reference joints (vis >= 0.5) in silhouette-box fractions (x, y), learnt on "
        + ("the tune clips of this run" if splits["tune"] else "all its clips (no tune clip in the run)"),
        "template_xy": np.round(template, 3).tolist(),
        "silhouette_ids_agree": round(
            sum(r["ids_agree"] for r in rows.values()) / max(sum(r["frames"] for r in rows.values()), 1), 4
        ),
        "track_s_per_clip": round(float(np.mean([r["track_s"] for r in rows.values()])), 1) if rows else None,
        "box_s_per_clip": round(float(np.mean([r["box_s"] for r in rows.values()])), 1) if rows else None,
        "per_clip": {
            stem: {
                "split": split_of(CLIPS / f"{stem}.avi"),
                **pck_figures([r], template, False),
                **{k: r["partner"][k] for k in ("hand_h", "back_m") if k in r["partner"]},
                "partner_overlap_frames": r["partner"]["overlap"],
                **({k: v for k, v in cut_figures([r]).items() if k.endswith(("_cut", "_cut_before"))} if cut else {}),
            }
            for stem, r in rows.items()
        },
    }
    for split, split_rows in splits.items():
        if not split_rows:
            continue
        figs = {
            **pck_figures(split_rows, template, False),
            "pck_clips": len(split_rows),
            **partner_figures([r["partner"] for r in split_rows]),
            **(cut_figures(split_rows) if cut else {}),
            **(slow_figures(split_rows, slow_step) if slow_step > 1 else {}),
        }
        details[split] = {
            "per_frame_matching": pck_figures(split_rows, template, True),
            "by_joint": pck_by_joint(split_rows, template),
        }
        if split == "report":
            result.update(figs)
        else:
            result["tune"] = figs
    result["pck_details"] = details
    return result


def run_demos(clips: list[Path], work: Path, timeout: float, reference: int) -> dict[str, Any]:
    """The demo part: every clip through ``counterpart demo --input``, the short inputs, the
    real-time reference on the first ``reference`` clips.
    """
    per_clip, hangs = {}, 0
    for i, clip in enumerate(clips):
        r = run_demo(clip, work / clip.stem, timeout)
        r["fps_video"] = video_fps(work / clip.stem)
        if i < reference:
            rt = run_demo(clip, work / f"{clip.stem}-rt", timeout, "--realtime")
            r["partner_present_realtime"] = rt.get("partner_present", 0.0)
            hangs += rt["hung"]
        hangs += r["hung"]
        per_clip[clip.stem] = r
        print(f"{clip.stem}: {json.dumps(r)}", file=sys.stderr, flush=True)
    short = {}
    for name, extra in (
        ("1_frame", ["--frames", "1"]),
        ("5_frames", ["--frames", "5"]),
        ("past_end", ["--set", "camera.start_frame=100000"]),
    ):
        r = run_demo(clips[0], work / f"short-{name}", min(timeout, 120.0), *extra)
        short[name] = {k: r.get(k) for k in ("code", "hung", "wall_s", "frames_in", "reason")}
        hangs += r["hung"]
        print(f"short {name}: {json.dumps(short[name])}", file=sys.stderr, flush=True)
    done = [r for r in per_clip.values() if not r["hung"] and r.get("frames_out")]
    pooled = sum(r["partner_drawn"] for r in done) / max(1, sum(r["frames_out"] for r in done))
    after = [r.get("partner_present_after_1s", 0.0) for r in per_clip.values()]
    ref = [r["partner_present_realtime"] for r in per_clip.values() if "partner_present_realtime" in r]
    result = {
        "clips": len(clips),
        "partner_present": round(pooled, 4),
        "partner_present_after_1s_median": round(float(np.median(after)), 4) if after else 0.0,
        "partner_present_after_1s_min": round(float(min(after)), 4) if after else 0.0,
        "clips_partner_95": sum(a >= 0.95 for a in after),
        "clips_two_people": sum(two_people(c) for c in clips),
        "clips_two_people_partner_95": sum(
            two_people(c) and per_clip[c.stem].get("partner_present_after_1s", 0.0) >= 0.95 for c in clips
        ),
        "partner_present_realtime": round(float(np.mean(ref)), 4) if ref else None,
        "partner_present_lockstep_same_clips": round(
            float(np.mean([r.get("partner_present", 0.0) for r in list(per_clip.values())[: len(ref)]])), 4
        )
        if ref
        else None,
        "hangs": hangs,
        "fps_match": sum(
            abs(r.get("fps_in", -1) - r["fps_video"]) < 0.01 and r.get("fps_in") == r.get("fps_out")
            for r in per_clip.values()
        ),
        "frames_with_people_share": round(
            sum(r.get("frames_with_people", 0) for r in done) / max(1, sum(r["frames_in"] for r in done)), 4
        ),
        "wall_s_median": float(np.median([r["wall_s"] for r in per_clip.values()])),
        "short_inputs": short,
        "per_clip": {
            k: {
                f: r.get(f)
                for f in (
                    "code",
                    "frames_in",
                    "partner_present",
                    "partner_present_after_1s",
                    "frames_with_people",
                    "fps_in",
                    "fps_video",
                )
            }
            for k, r in per_clip.items()
        },
    }
    return result


def run_silhouettes() -> dict[str, Any]:
    """The silhouette part: ``bench/real_silhouettes.py``'s figures of the silhouette node's
    extractor (its defaults) over every clip of the set, ``people_found`` and ``keypoint_coverage``
    on the report split (top level) and the tune split (``silhouette_details``).
    """
    from real_silhouettes import TRAIN_FRAMES as train_frames
    from real_silhouettes import clip_paths, run_clip, summarise

    out: dict[str, Any] = {"people_found": None, "keypoint_coverage": None}
    details: dict[str, Any] = {"train_frames": train_frames, "split": "tune: even first number; report: odd"}
    for split in ("tune", "report"):
        paths = clip_paths(split)
        rows = []
        for p in paths:
            rows.append(run_clip(p, True, train_frames))
            print(f"silhouettes {split} {p.stem}: {json.dumps(summarise(rows[-1:])['people_found'])}", file=sys.stderr)
        if not rows:
            continue
        s = summarise(rows)
        details[split] = {
            k: s[k] for k in ("people_found", "keypoint_coverage", "extra_people", "misses", "fps", "clips")
        }
        if split == "report":
            out.update(people_found=s["people_found"], keypoint_coverage=s["keypoint_coverage"])
    out["silhouette_details"] = details
    return out


def run_speed(clips: list[Path], frames: int, work: Path, warmup_s: float = 3.0) -> dict[str, Any]:
    """The speed part: the real-time demo graph (``launch/demo.yaml``, as ``bench/e2e.py`` runs it)
    on each of ``clips`` at its own frame rate, looped to ``frames`` frames with both people tracked,
    and on the simulator beside them in the same run. ``fps``: the median over the clips of the
    sustained frame rate through the graph; ``latency_p95_ms``: the median of the steady-state p95
    capture-to-render latency (after ``warmup_s``); the simulator's as ``fps_sim`` and
    ``latency_p95_ms_sim``; per clip and the steady shares under ``speed_details``. The graphs' bags
    go under ``work``.
    """
    from e2e import realtime

    from counterpart.apps.demo import ensure_models

    ensure_models()
    work.mkdir(parents=True, exist_ok=True)
    keys = (
        "fps_sustained",
        "source_fps",
        "latency_p95_steady_ms",
        "tracker_frac_steady",
        "partner_frac_steady",
        "cores_needed",
        "drop_frac",
    )
    runs: dict[str, dict[str, Any]] = {}
    for clip in clips:
        sets = {"camera.source": str(clip.resolve()), "camera.loop": True, "tracker.people": ["left", "right"]}
        r = realtime(work, f"rt-{clip.stem}", "demo.yaml", frames, warmup_s, sets)
        runs[clip.stem] = {k: r.get(k) for k in keys}
    sim = realtime(work, "rt-sim", "demo.yaml", frames, warmup_s)
    real = list(runs.values())
    return {
        "fps": round(float(np.median([r["fps_sustained"] for r in real])), 2) if real else None,
        "latency_p95_ms": round(float(np.median([r["latency_p95_steady_ms"] for r in real])), 1) if real else None,
        "fps_sim": sim["fps_sustained"],
        "latency_p95_ms_sim": sim["latency_p95_steady_ms"],
        "speed_details": {
            "graph": "launch/demo.yaml in real time, two people tracked, each clip looped",
            "frames": frames,
            "load_avg_1min": round(os.getloadavg()[0], 2),
            "clips": runs,
            "sim": {k: sim.get(k) for k in keys},
        },
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--clips", default="12", help="'all' or how many clips, spread over the set (default 12)")
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds a run may take before it counts as hung")
    ap.add_argument("--reference", type=int, default=3, help="clips also run through the real-time graph")
    ap.add_argument(
        "--pck-clips",
        default=None,
        help="'all' or how many clips to track offline for the PCK figures (default: as --clips)",
    )
    ap.add_argument(
        "--pck-classes",
        default=None,
        help="only clips of these interaction classes in the tracking part, e.g. '0,5' (handshake, push)",
    )
    ap.add_argument("--no-pck", action="store_true", help="skip the tracking-accuracy part")
    ap.add_argument("--no-cut", action="store_true", help="skip the tracking part's cut pass")
    ap.add_argument(
        "--slow-step",
        type=int,
        default=SLOW_STEP,
        help="the tracking part's slow pass keeps every K-th frame of each clip, at 1/K of its frame rate "
        f"(default {SLOW_STEP}: 10 fps; 0 or 1: no slow pass)",
    )
    ap.add_argument("--jobs", type=int, default=1, help="clips of the tracking part tracked at once (processes)")
    ap.add_argument("--no-demo", action="store_true", help="skip the demo runs (only the tracking part)")
    ap.add_argument(
        "--tracks",
        type=Path,
        help="folder to keep each clip's track_video file in (CLIP-track.npz; default: a new temporary "
        "folder); a clip whose file is there already is not tracked again: its figures are then those of "
        "the tracker that wrote it (for a change to the partner's staging or the figures, not the tracker)",
    )
    ap.add_argument(
        "--calib-seeds",
        type=int,
        default=50,
        help="simulated random cameras for the calibration figures (bench/self_calibration.py); 0 skips",
    )
    ap.add_argument(
        "--no-silhouettes", action="store_true", help="skip the silhouette part (people_found, keypoint_coverage)"
    )
    ap.add_argument(
        "--speed-frames",
        type=int,
        default=600,
        help="frames of each reference clip played in real time for the speed figures (fps, latency_p95_ms); 0 skips",
    )
    args = ap.parse_args()
    if not CLIPS.is_dir():
        sys.exit(f"bench/real_video.py: {CLIPS} not found (the shared data, see ../shared/data/README.md)")
    clips = clip_list(args.clips)
    work = args.tracks or Path(tempfile.mkdtemp(prefix="cp-real-"))
    work.mkdir(parents=True, exist_ok=True)
    result: dict[str, Any] = {} if args.no_demo else run_demos(clips, work, args.timeout, args.reference)
    if not args.no_pck:
        pck = clip_list(args.pck_clips or args.clips)
        if args.pck_classes:
            pck = [c for c in pck if interaction_class(c) in {int(k) for k in args.pck_classes.split(",")}]
        if not pck:
            ap.error(
                f"--pck-classes {args.pck_classes}: none of the {args.pck_clips or args.clips} clips chosen is of "
                "these classes; give more clips (--pck-clips all)"
            )
        result.update(run_pck(pck, work, args.jobs, not args.no_cut, args.slow_step))
    if not args.no_silhouettes:
        result.update(run_silhouettes())
    if args.speed_frames and args.reference:
        result.update(run_speed(clips[: args.reference], args.speed_frames, work / "speed"))
    if args.calib_seeds:  # the camera from the people: simulator truth, and the spread on these clips
        from self_calibration import real_figures, sim_figures

        calib = sim_figures(args.calib_seeds)
        result.update({k: v for k, v in calib.items() if k != "calib_rows"})
        result["calib_details"] = {"rows": calib["calib_rows"], **real_figures(clips)}
    print(json.dumps(result))


if __name__ == "__main__":
    main()
