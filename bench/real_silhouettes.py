"""Silhouettes on real two-person video: are both people found whole, on the right side.

Usage: python bench/real_silhouettes.py [--clips report|tune|all] [--every K] [--train-frames 30]
           [--max-clips N] [--only STEM,...] [--no-baseline] [--shake-px 2] [--no-grey] [--light 1.7] [--no-cut]
           [--white-balance 1.06,1,0.95] [--no-infrared] [--noise 6] [--shrink 0.35] [--jpeg 25]
           [--threads 1] [--out FILE]

Data: ``../shared/data/ut_interaction`` (set 1 of UT-Interaction: 60 clips, two people in view and
mostly still from the first frame, static elevated camera), with reference 2D keypoints of both
people on every frame (MediaPipe Pose; person 0 is the one on the left at frame 0). The clips whose
first number is even were used to tune the method ("tune"); the figures to quote are those of the
odd ones ("report"), which the method never saw while it was tuned.

Each clip is run as the silhouette node runs it: the background is fitted on the first
``--train-frames`` frames (``SilhouetteExtractor.fit_background(frames, robust=True)``), then
every frame from frame 0 is processed. Two fits side by side in the same run:

* ``ours``: the defaults: people detected in the training frames and kept out of the model
  (``people.fit_around_people``), highlights bounded (``max_highlight_brightness``), new people
  only from upright regions (``PersonTracker(min_upright=1.0)``);
* ``baseline``: the algorithm as it was before (``BASELINE``): the plain robust median fit, no
  bound on highlights, any region a new person.

Scored from frame 10 on, except on frames where the two reference skeletons lie on one person
(``reference_collapsed``: about a quarter of the frames of set 1, most of them after the people
have come close; their share is reported as ``reference_collapsed``), for each person with at
least ``MIN_VISIBLE`` reference keypoints of visibility >= 0.5 on that frame:

* ``people_found``: share of frames on which every such person is found: the region holding most of
  their visible keypoints holds at least half of them, is reported with their side (person 0
  "left", person 1 "right"), and is not the other person's region;
* ``keypoint_coverage``: share of the people's visible keypoints that fall inside their own region
  (the region with their side that holds most of their keypoints), pooled over people and frames;
* ``extra_people``: mean number of reported people per frame that hold the keypoints of neither
  scored person (ghosts, fragments, passers-by: the clips have other people walking at their edges
  now and then, so it is not 0 even for a perfect method);
* ``keypoint_coverage_person``: the same for each reference person on their own (person 0, 1;
  None where never scored); ``person_clips_covered``: the share of (clip, person) pairs scored
  whose coverage is at least ``PERSON_COVERAGE`` (the issue asks it of each person);
* ``fit_s``: seconds per ``fit_background`` call; ``fps``: frames per second of ``process``.

Where the misses are: ``misses`` counts the missed person-frames by cause (``miss_cause``):
``missing`` (no region on their keypoints: not found yet, or lost), ``shared`` (their keypoints
on the other person's region: merged), ``split`` (no region holds half of them), ``side`` (found
with the other side: identities exchanged); ``missed_frames`` the frames with a miss.

The reference can also swap the two people when they touch (hugs, pushes) without collapsing;
such frames count as misses (seen by eye on the hug clips 14_3_1 and 32_6_1). The people of set 1
never pass each other, so a frame on which reference person 0's body (head, neck, shoulders,
hips) stands right of person 1's is one the reference got wrong (``reference_reversed``: their
share of the scored frames); ``people_found_reference_ordered`` is ``people_found`` without them,
reported beside it, not instead of it.

A shaken camera (a pole in the wind, a tripod on a wooden floor, a hand): each clip again, its
decoded frames moved by ``counterpart.sim.camera_shake`` (a sway of ``--shake-px`` pixels and a tremor of half that,
seeded by the clip's name; no second compression) and its reference keypoints with them, through
ours as it is (``*_shaken``: the shake followed, ``nodes/silhouette/shake.py``) and with the shake
left unfollowed (``*_shaken_unfollowed``, the algorithm for a still camera): ``people_found_shaken``,
``keypoint_coverage_shaken`` and the same ``_unfollowed``; ``shake_err_px_median`` and ``_p95``, the
error of the followed shift against the true one per frame (pixels); ``fps_shaken``.

A noisy camera (a webcam in a dim room, a small sensor): each clip again with Gaussian noise of
``--noise`` grey levels added to every pixel of every frame, through ours as it is (``*_noisy``: the
camera's noise measured on the training frames and its frames smoothed, ``nodes/silhouette/denoise.py``)
and without the smoothing (``*_noisy_unsmoothed``): ``people_found_noisy``, ``keypoint_coverage_noisy``,
``extra_people_noisy``, ``person_clips_covered_noisy`` and the same ``_unsmoothed``.

Small people (a small video, people far from the camera): each clip again scaled by ``--shrink``
(0.35: the people 35-100 pixels tall, some shorter than the HOG detector's window), through ours as
it is (``*_small``: a training frame in which the detector finds no one searched again enlarged,
``PeopleDetector``'s ``enlarge``) and without that search (``*_small_unenlarged``):
``people_found_small``, ``keypoint_coverage_small``, ``extra_people_small``,
``person_clips_covered_small`` and the same ``_unenlarged``.

Heavy compression (a cheap webcam's MJPEG, a stream at a low bit rate): each clip again with every
frame saved as a JPEG of quality ``--jpeg`` (25) and read back, on top of its own compression:
``people_found_jpeg``, ``keypoint_coverage_jpeg``, ``extra_people_jpeg``, ``person_clips_covered_jpeg``.

A grey or infrared camera (three equal channels, however they come): each clip again made grey,
through ours as it is (``*_grey``: the background found monochrome, its shadows and highlights
bounded tightly, ``background.ShadowConfig.mono_min_shadow_brightness``) and with the bounds of
colour footage (``*_grey_colour_bounds``, the algorithm as it was before: a person a shade darker
or lighter than the room a shadow or a highlight): ``people_found_grey``, ``keypoint_coverage_grey``,
``extra_people_grey``, ``person_clips_covered_grey`` and the same ``_colour_bounds``.

A camera near the people (a webcam in a room, a camera at a door): each clip again, its frames
cut off above the people's knees (``cut_row``: the 10th percentile over frames and people of their
mid-thigh rows), the joints below the cut not scored, through ours as it is (``*_cut``: people cut
off by the frame's bottom edge looked for in the frame continued below, ``people.CUT_OFF_BELOW``)
and without that (``*_cut_uncontinued``, the detector as it was before): ``people_found_cut``,
``keypoint_coverage_cut``, ``extra_people_cut``, ``person_clips_covered_cut`` and the same
``_uncontinued``.

A light switched on (or off) mid-clip: each clip again, its frames from frame 50 on times ``--light``
(1.7: beyond the brightest highlight a colour model takes; clipped at 255), through ours as it is
(``*_lit``: the model re-exposed at once, ``background.AdaptationConfig.exposure_step``) and with the
exposure not followed (``*_lit_unfollowed``, as it was before: the room foreground from then on):
``people_found_lit``, ``keypoint_coverage_lit``, ``extra_people_lit`` and the same ``_unfollowed``;
``people_share_lit`` (and ``_unfollowed``): the mean share of the frame in people's regions from frame
50 on, against ``people_share``, ours on the clips as they are.

A camera's white balance turning mid-clip (its automatic white balance as someone in a coloured coat
comes in): each clip again, its frames from frame 50 on times ``--white-balance``'s gains of B, G
and R (1.06, 1, 0.95: a cast of about 5%, which changes the brightness by well under the exposure
step), through ours as it is (``*_wb``: each channel re-exposed by its own gain,
``background.AdaptationConfig.white_balance_step``) and with the channels only followed together
(``*_wb_unfollowed``, as it was before): ``people_found_wb``, ``keypoint_coverage_wb``,
``extra_people_wb``, ``people_share_wb`` and the same ``_unfollowed``.

A day/night camera turning to infrared mid-clip (a room getting dark): each clip again, its frames
from frame 50 on grey and lit as the camera's own infrared lamps light a room (``sim.infrared``:
brighter and flatter), through ours as it is (``*_ir``: the switch from colour to monochrome seen,
``colour_switch``, and the background learnt again from the frames after it, which are held back
meanwhile as a recording's first frames are) and without (``*_ir_unfollowed``, as it was before:
the colour model kept): ``people_found_ir``, ``keypoint_coverage_ir``, ``extra_people_ir``,
``people_share_ir`` and the same ``_unfollowed``; ``people_found_late_ir`` (and ``_unfollowed``):
people found on the frames from frame 50 on alone; ``relearns_ir``: the switches seen (one per
clip long enough to show one is right).

The last stdout line is one JSON object with the figures: top level the report split's
``people_found``, ``keypoint_coverage`` (ours) and ``*_baseline``; per split and per clip below.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

if __package__ in (None, ""):  # run as a script: make the repository importable
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import cv2
import numpy as np

from counterpart.body.image_sequence import read_frames
from counterpart.body.people_detector import PeopleDetector
from counterpart.body.skeleton import JOINT_INDEX
from counterpart.nodes.silhouette.colour_switch import ColourSwitchConfig
from counterpart.nodes.silhouette.people import CUT_OFF_BELOW
from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, process_frames
from counterpart.sim.camera_shake import shake_path, shaken
from counterpart.sim.infrared import infrared_frames

DATA = (
    Path(os.environ.get("COUNTERPART_SHARED_DATA") or Path(__file__).resolve().parents[2] / "shared" / "data")
    / "ut_interaction"
)
#: first scored frame: the node reports people from the first frame, but the people found on the
#: very first frames matter less than a stable answer afterwards (the issue's measure)
FIRST_SCORED = 10
#: frames the background is trained on (``--train-frames``)
TRAIN_FRAMES = 30
#: a person is scored on a frame when at least this many of their keypoints are visible
MIN_VISIBLE = 4
VIS = 0.5
#: reference skeletons closer than this fraction of a person's height are one person (see
#: ``reference_collapsed``): such frames are not scored
COLLAPSE_FRAC = 0.1
SIDES = ("left", "right")
#: extractor parameters that give back the algorithm as it was before people-aware fitting
BASELINE = {
    "backend_params": {"people_aware": False, "max_highlight_brightness": 1e9},
    "tracker_params": {"min_upright": 0.0},
}


def clip_paths(split: str) -> list[Path]:
    """The clips of a split: "tune" (first number even), "report" (odd) or "all", sorted by name."""
    paths = sorted((DATA / "set1").glob("*.avi"), key=lambda p: [int(v) for v in p.stem.split("_")])
    if split == "all":
        return paths
    parity = 0 if split == "tune" else 1
    return [p for p in paths if int(p.stem.split("_")[0]) % 2 == parity]


def reference_collapsed(kp: np.ndarray, vis: np.ndarray) -> bool:
    """Whether the two reference skeletons of a frame, kp (2, 14, 2) pixels and vis (2, 14), lie
    on the same person: the median distance of their joints visible in both is under
    ``COLLAPSE_FRAC`` of the person's height (nose to mid-ankle). The reference detector follows
    each person with a crop; when the people come close both crops can end on one of them, and
    the reference then says nothing about the other.
    """
    both = (vis[0] >= VIS) & (vis[1] >= VIS)
    if both.sum() < MIN_VISIBLE:
        return False
    d = np.median(np.linalg.norm(kp[0][both] - kp[1][both], axis=1))
    h = max(abs(kp[0, 0, 1] - kp[0, [10, 13], 1].mean()), abs(kp[1, 0, 1] - kp[1, [10, 13], 1].mean()), 20.0)
    return bool(d < COLLAPSE_FRAC * h)


#: the causes of a miss (``miss_cause``), in the order they are tested
MISS_CAUSES = ("missing", "shared", "split", "side")


def miss_cause(best: int, held: int, n: int, side: str | None, want: str, chosen: list[int]) -> str:
    """Why a scored person is not found: "missing" (none of their keypoints on any region: not
    found yet, or lost), "shared" (their region is the other person's: merged), "split" (no
    region holds half of their keypoints), "side" (the region holding them is reported with the
    other side: an identity exchanged). ``best`` the region holding most (``held``) of their
    ``n`` keypoints, ``side`` its side, ``want`` theirs, ``chosen`` the other person's region.
    """
    if best == 0:
        return "missing"
    if best in chosen:
        return "shared"
    if held < 0.5 * n:
        return "split"
    return "side" if side != want else "ok"


#: the joints whose median column places a reference person left or right: head, neck,
#: shoulders, hips (the body, not the arms and legs that reach across in a hug or a kick)
_BODY = (0, 1, 2, 5, 8, 11)


def reference_reversed(kp: np.ndarray, vis: np.ndarray) -> bool:
    """Whether reference person 0 (the left one at frame 0) stands right of person 1 on this
    frame, kp (2, 14, 2) pixels, vis (2, 14): the body joints' median columns, each person with
    at least two visible. In set 1 the two people never pass each other, so such a frame is one
    on which the reference's crops have exchanged the people (they touch); reported, not excluded.
    """
    x = []
    for k in range(2):
        sel = vis[k, list(_BODY)] >= VIS
        if sel.sum() < 2:
            return False
        x.append(float(np.median(kp[k, list(_BODY), 0][sel])))
    return x[0] > x[1]


def score_frame(labels: np.ndarray, people: list, kp: np.ndarray, vis: np.ndarray) -> dict[str, int]:
    """One frame's counts.

    labels (H, W) int32 person id + 1 per pixel; people: the reported ``Person`` list; kp (2, 14, 2)
    pixels x, y and vis (2, 14) of the two reference people. Returns counts: scored (1 if any
    person is scored), found (1 if all scored people are found), kp_total, kp_inside, reported,
    matched (regions holding most of a scored person's keypoints).
    """
    h, w = labels.shape
    side_of = {p.id + 1: p.side for p in people}
    out = {"scored": 0, "found": 0, "kp_total": 0, "kp_inside": 0, "reported": len(people), "matched": 0}
    chosen: list[int] = []
    ok_all = True
    for k in range(2):
        sel = vis[k] >= VIS
        if sel.sum() < MIN_VISIBLE:
            continue
        out["scored"] = 1
        xy = np.rint(kp[k][sel]).astype(int)
        inside_img = (xy[:, 0] >= 0) & (xy[:, 0] < w) & (xy[:, 1] >= 0) & (xy[:, 1] < h)
        lab = np.zeros(len(xy), np.int64)
        lab[inside_img] = labels[xy[inside_img, 1], xy[inside_img, 0]]
        n = len(xy)
        out["kp_total"] += n
        out[f"kp_total_{k}"] = n
        counts = np.bincount(lab, minlength=1)
        counts[0] = 0
        # their region for coverage: the one with their side that holds most of their keypoints
        own = [r for r in range(1, len(counts)) if side_of.get(r) == SIDES[k]]
        if own:
            r_own = max(own, key=lambda r: counts[r])
            out["kp_inside"] += int(counts[r_own])
            out[f"kp_inside_{k}"] = int(counts[r_own])
        best = int(np.argmax(counts))
        found = best > 0 and counts[best] >= 0.5 * n and side_of.get(best) == SIDES[k] and best not in chosen
        if not found:
            out[f"miss_{miss_cause(best, counts[best], n, side_of.get(best), SIDES[k], chosen)}"] = 1
        chosen.append(best)
        ok_all &= found
    out["found"] = int(out["scored"] and ok_all)
    out["reversed"] = int(out["scored"] and reference_reversed(kp, vis))
    out["found_reversed"] = out["found"] * out["reversed"]
    # regions that hold most of some scored person's keypoints; the rest are extra
    out["matched"] = len({r for r in chosen if r > 0})
    return out


#: the cut pass keeps each frame of a clip above this percentile, over its frames and people, of
#: the rows of their mid-thighs (``cut_row``)
CUT_PERCENTILE = 10
_THIGHS = [JOINT_INDEX[j] for j in ("l_hip", "r_hip", "l_knee", "r_knee")]


def cut_row(kp: np.ndarray, vis: np.ndarray) -> int:
    """The row at which the cut pass ends a clip's frames, as a camera nearer the people would:
    the ``CUT_PERCENTILE``-th percentile over frames and people of the mean row of their visible
    hips and knees (both people cut off above the knees on most frames), even (lossless codecs
    of the cut copies want it).

    kp (T, 2, 14, 2) pixels, vis (T, 2, 14).
    """
    rows = np.where(vis[:, :, _THIGHS] >= VIS, kp[:, :, _THIGHS, 1], np.nan).reshape(-1, len(_THIGHS))
    rows = rows[np.isfinite(rows).any(axis=1)]
    r = int(np.percentile(np.nanmean(rows, axis=1), CUT_PERCENTILE))
    return r - r % 2


def cut_frames(frames: np.ndarray, kp: np.ndarray, vis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cut pass's clip: its frames above :func:`cut_row`, and the visibilities with the
    joints below it (out of the picture) made 0, so that they are not scored.
    """
    r = cut_row(kp, vis)
    return np.ascontiguousarray(frames[:, :r]), np.where(kp[..., 1] < r, vis, 0.0)


def run_clip(
    path: Path,
    ours: bool,
    train_frames: int,
    shake_px: float = 0.0,
    grey: bool = False,
    light: float = 1.0,
    cut: bool = False,
    backend: dict[str, Any] | None = None,
    white_balance: tuple[float, float, float] | None = None,
    infrared: bool = False,
    colour_switch: ColourSwitchConfig | None = None,
    noise: float = 0.0,
    shrink: float = 1.0,
    jpeg: int = 0,
) -> dict[str, Any]:
    """Fit and process one clip as the node does; returns its summed counts and timings.

    ``shake_px`` > 0: the clip shaken by ``sim.camera_shake`` (seeded by its name; the reference keypoints moved with
    it); unless ``backend`` turns the following off (``shake`` False), the counts then also hold
    the error of the followed shift against the true one (``shake_err``, pixels, per frame).
    ``grey``: the clip's frames made grey (three equal channels, as a grey or infrared camera's
    come). ``light``: the light's gain from frame ``LIGHT_FRAME`` on (a light switched on or off).
    ``cut``: the clip cut off above the people's knees (:func:`cut_frames`). ``white_balance``: the
    gains of B, G and R from frame ``LIGHT_FRAME`` on (the camera's white balance turning).
    ``noise``: Gaussian noise of that std (grey levels) added to every pixel of every frame, as a
    camera in low light gives (seeded by the clip's name and the frame). ``shrink`` < 1: the clip's
    frames and its reference keypoints scaled by it (people far from the camera, a small video).
    ``jpeg`` > 0: every frame compressed again as a JPEG of that quality (a cheap webcam's MJPEG, a
    stream at a low bit rate: blocks and ringing on top of the clip's own compression).
    ``infrared``: the frames from ``LIGHT_FRAME`` on as a day/night camera's infrared picture
    (``sim.infrared.infrared_frames``). ``backend``: subtractor parameters over ours (or the baseline's);
    ``colour_switch``: the extractor's (None: its default).
    """
    frames = read_frames(path)
    ref = np.load(DATA / "keypoints" / f"{path.stem}.npz")
    kp, vis = ref["kp"], ref["vis"]
    if shrink != 1.0:
        frames = np.stack([cv2.resize(f, None, fx=shrink, fy=shrink, interpolation=cv2.INTER_AREA) for f in frames])
        kp = kp * shrink
    n = min(len(frames), len(kp))
    true_shift = None
    if shake_px > 0:
        true_shift = shake_path(len(frames), shake_px, [int(v) for v in path.stem.split("_")])
        frames = shaken(frames, true_shift)
        kp = kp + true_shift[: len(kp), None, None, :]
    if cut:
        frames, vis = cut_frames(frames, kp, vis)
    if grey:
        frames = np.stack([cv2.cvtColor(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR) for f in frames])
    if light != 1.0 or white_balance is not None:
        gains = np.float32(light) * np.asarray(white_balance or (1.0, 1.0, 1.0), np.float32)
        lit = frames[LIGHT_FRAME:].astype(np.float32) * gains
        frames = np.concatenate([frames[:LIGHT_FRAME], np.clip(np.rint(lit), 0, 255).astype(np.uint8)])
    if infrared:
        frames = np.concatenate([frames[:LIGHT_FRAME], infrared_frames(frames[LIGHT_FRAME:])])
    if noise > 0:
        seed = [int(v) for v in path.stem.split("_")]
        frames = np.stack(
            [
                np.clip(f + np.random.default_rng([*seed, t]).normal(0.0, noise, f.shape), 0, 255).astype(np.uint8)
                for t, f in enumerate(frames)
            ]
        )
    if jpeg > 0:
        frames = np.stack(
            [
                cv2.imdecode(cv2.imencode(".jpg", f, [cv2.IMWRITE_JPEG_QUALITY, jpeg])[1], cv2.IMREAD_COLOR)
                for f in frames
            ]
        )
    base = {} if ours else BASELINE
    params = {"train_frames": train_frames, **base.get("backend_params", {}), **(backend or {})}
    follow = params.get("shake", True) is not False
    ex = SilhouetteExtractor(
        backend_params=params, tracker_params=base.get("tracker_params"), colour_switch=colour_switch
    )
    t0 = time.perf_counter()
    ex.fit_background(list(frames[:train_frames]), robust=True)
    fit_s = time.perf_counter() - t0
    tot: dict[str, Any] = {"shake_err": []}
    proc_s = 0.0
    # the frames as a recording's go through the graph: a switch to infrared is learnt again, from
    # the frames after it held back meanwhile (time of the whole loop, refits included)
    results = process_frames(ex, frames[:n], train_frames)
    for t in range(n):
        t0 = time.perf_counter()
        r = next(results)[1]
        proc_s += time.perf_counter() - t0
        tot["relearns"] = tot.get("relearns", 0) + int(r.relearn)
        if t >= LIGHT_FRAME:
            tot["share_sum"] = tot.get("share_sum", 0.0) + float(np.count_nonzero(r.labels)) / r.labels.size
            tot["share_n"] = tot.get("share_n", 0) + 1
        if true_shift is not None and follow:
            # the model is on the first training frame's pixels: the shift to find is relative to it
            est = ex.subtractor.shake.last
            want = true_shift[t] - true_shift[0]
            tot["shake_err"].append(float(np.hypot(*(want - (est if est is not None else 0.0)))))
        if t < FIRST_SCORED:
            continue
        if reference_collapsed(kp[t], vis[t]):
            tot["collapsed"] = tot.get("collapsed", 0) + 1
            continue
        for key, v in score_frame(r.labels, r.people, kp[t], vis[t]).items():
            tot[key] = tot.get(key, 0) + v
            if t >= LIGHT_FRAME and key in ("found", "scored"):
                tot[f"{key}_late"] = tot.get(f"{key}_late", 0) + v
    tot.setdefault("collapsed", 0)
    tot["fit_s"] = fit_s
    tot["process_s"] = proc_s
    tot["frames"] = n
    return tot


#: amplitude of the shaken pass's camera shake, pixels (``--shake-px``)
SHAKE_PX = 2.0
#: std of the noisy pass's noise, grey levels (``--noise``): a webcam in a dim room
NOISE = 6.0
#: the scale of the small pass's clips (``--shrink``): their people 35-100 pixels tall
SHRINK = 0.35
#: the JPEG quality of the compressed pass (``--jpeg``): a cheap webcam's MJPEG
JPEG = 25


def extra_passes(
    shake_px: float,
    grey: bool,
    light: float,
    cut: bool = True,
    white_balance: tuple[float, float, float] | None = None,
    infrared: bool = True,
    noise: float = 0.0,
    shrink: float = 1.0,
    jpeg: int = 0,
) -> dict[str, dict[str, Any]]:
    """The passes of ours on altered clips, by name: :func:`run_clip`'s keyword arguments. The
    shaken clips with the shake followed and not (``shake_px`` > 0); the grey clips as they are
    and with colour footage's shadow bounds (``grey``); the clips lit by ``light`` from frame
    ``LIGHT_FRAME`` on, the new exposure followed and not (``light`` other than 1); the clips cut
    off above the knees, with people cut off by the frame looked for and not (``cut``); the clips
    whose white balance turns by ``white_balance`` from ``LIGHT_FRAME`` on, each channel followed
    and the channels only together (not None); the clips turned infrared from ``LIGHT_FRAME`` on,
    the background learnt again and not (``infrared``); the clips with a noisy camera's noise of
    ``noise`` grey levels, its frames smoothed and not (``noise`` > 0); the clips scaled by
    ``shrink``, frames in which the detector finds no one searched again enlarged and not
    (``shrink`` < 1); the clips compressed again as JPEGs of quality ``jpeg`` (> 0).
    """
    out: dict[str, dict[str, Any]] = {}
    if cut:
        out["cut"] = {"cut": True}
        out["cut_uncontinued"] = {"cut": True, "backend": {"detector": PeopleDetector()}}
    if light != 1.0:
        out["lit"] = {"light": light}
        out["lit_unfollowed"] = {"light": light, "backend": {"exposure_step": 0.0}}
    if white_balance is not None:
        out["wb"] = {"white_balance": white_balance}
        out["wb_unfollowed"] = {"white_balance": white_balance, "backend": {"white_balance_step": 0.0}}
    if infrared:
        out["ir"] = {"infrared": True}
        out["ir_unfollowed"] = {"infrared": True, "colour_switch": ColourSwitchConfig(frames=0)}
    if noise > 0:
        out["noisy"] = {"noise": noise}
        out["noisy_unsmoothed"] = {"noise": noise, "backend": {"denoise": False}}
    if shrink < 1.0:
        out["small"] = {"shrink": shrink}
        out["small_unenlarged"] = {"shrink": shrink, "backend": {"detector": PeopleDetector(below_frac=CUT_OFF_BELOW)}}
    if jpeg > 0:
        out["jpeg"] = {"jpeg": jpeg}
    if shake_px > 0:
        out["shaken"] = {"shake_px": shake_px}
        # the frames as they come: the shake left in the training frames would read as noise and be smoothed
        out["shaken_unfollowed"] = {"shake_px": shake_px, "backend": {"shake": False, "denoise": False}}
    if grey:
        out["grey"] = {"grey": True}
        out["grey_colour_bounds"] = {"grey": True, "backend": {"mono_chroma_deg": 0.0}}
    return out


#: the light's gain of the lit pass (``--light``), and the frame it changes on
LIGHT = 1.7
LIGHT_FRAME = 50
#: the gains of B, G and R of the white-balance pass (``--white-balance``), from ``LIGHT_FRAME`` on
WHITE_BALANCE = (1.06, 1.0, 0.95)

#: the issue's bar for each person's keypoint coverage (``person_clips_covered``)
PERSON_COVERAGE = 0.9


def _person_coverage(counts: dict[str, Any], k: int) -> float | None:
    """Share of reference person k's visible keypoints inside their own region, from summed
    counts; None where they were never scored.
    """
    n = counts.get(f"kp_total_{k}", 0)
    return round(counts.get(f"kp_inside_{k}", 0) / n, 4) if n else None


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    err = np.concatenate([np.asarray(r.get("shake_err", []), float) for r in rows])
    s = {k: sum(r.get(k, 0) for r in rows) for k in set().union(*rows) if k != "shake_err"}
    # each person of each clip on their own (the "each person's keypoints")
    per_person = [_person_coverage(r, k) for r in rows for k in range(2)]
    covered = [c >= PERSON_COVERAGE for c in per_person if c is not None]
    ordered = s["scored"] - s["reversed"]
    return {
        "people_found": round(s["found"] / max(s["scored"], 1), 4),
        "keypoint_coverage": round(s["kp_inside"] / max(s["kp_total"], 1), 4),
        "keypoint_coverage_person": [_person_coverage(s, k) for k in range(2)],
        "person_clips_covered": round(float(np.mean(covered)), 4) if covered else None,
        "extra_people": round((s["reported"] - s["matched"]) / max(s["scored"], 1), 3),
        "people_share": round(s.get("share_sum", 0.0) / max(s.get("share_n", 0), 1), 4),
        "reference_collapsed": round(s["collapsed"] / max(s["collapsed"] + s["scored"], 1), 3),
        "reference_reversed": round(s["reversed"] / max(s["scored"], 1), 4),
        "people_found_reference_ordered": round((s["found"] - s["found_reversed"]) / max(ordered, 1), 4),
        "missed_frames": s["scored"] - s["found"],
        # from the frame the lit, white-balance and infrared passes change on
        "people_found_late": round(s.get("found_late", 0) / max(s.get("scored_late", 0), 1), 4),
        "relearns": s.get("relearns", 0),
        "misses": {c: s.get(f"miss_{c}", 0) for c in MISS_CAUSES},
        "fit_s": round(s["fit_s"] / len(rows), 3),
        "fps": round(s["frames"] / max(s["process_s"], 1e-9), 1),
        "clips": len(rows),
        **(
            {
                "shake_err_px_median": round(float(np.median(err)), 3),
                "shake_err_px_p95": round(float(np.percentile(err, 95)), 3),
            }
            if len(err)
            else {}
        ),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clips", choices=("report", "tune", "all"), default="all")
    ap.add_argument("--every", type=int, default=1, help="use every K-th clip of the split (quick looks)")
    ap.add_argument("--max-clips", type=int, default=None)
    ap.add_argument("--only", default="", help="comma-separated clip stems (e.g. 0_1_4) to run alone")
    ap.add_argument("--train-frames", type=int, default=TRAIN_FRAMES)
    ap.add_argument("--threads", type=int, default=1, help="OpenCV threads")
    ap.add_argument("--no-baseline", action="store_true", help="skip the baseline (tuning runs)")
    ap.add_argument(
        "--shake-px",
        type=float,
        default=SHAKE_PX,
        help="amplitude of the camera shake of the shaken pass, pixels (0: no shaken pass)",
    )
    ap.add_argument("--no-grey", action="store_true", help="no grey pass")
    ap.add_argument(
        "--light",
        type=float,
        default=LIGHT,
        help=f"gain of the light from frame {LIGHT_FRAME} on in the lit pass (1: no lit pass)",
    )
    ap.add_argument("--no-cut", action="store_true", help="no cut pass")
    ap.add_argument("--no-infrared", action="store_true", help="no infrared pass")
    ap.add_argument(
        "--white-balance",
        default=",".join(str(v) for v in WHITE_BALANCE),
        help=f"gains of B,G,R from frame {LIGHT_FRAME} on in the white-balance pass ('1,1,1': no such pass)",
    )
    ap.add_argument(
        "--noise",
        type=float,
        default=NOISE,
        help="std of the noise added to every frame of the noisy pass, grey levels (0: no noisy pass)",
    )
    ap.add_argument(
        "--shrink",
        type=float,
        default=SHRINK,
        help="scale of the clips of the small pass, in (0, 1] (1: no small pass)",
    )
    ap.add_argument(
        "--jpeg",
        type=int,
        default=JPEG,
        help="JPEG quality every frame of the compressed pass is saved at again, 1-100 (0: no compressed pass)",
    )
    ap.add_argument("--out", help="also write the JSON report to this file")
    args = ap.parse_args(argv)
    if not (DATA / "set1").is_dir():
        print(json.dumps({"bench": "real_silhouettes", "available": False, "reason": f"{DATA} not found"}))
        return 0
    cv2.setNumThreads(args.threads)
    splits = ("tune", "report") if args.clips == "all" else (args.clips,)
    methods = {"ours": True} if args.no_baseline else {"ours": True, "baseline": False}
    wb = tuple(float(v) for v in args.white_balance.split(","))
    if len(wb) != 3 or min(wb) <= 0:
        ap.error(f"--white-balance {args.white_balance!r}: give three positive gains B,G,R, e.g. 1.06,1,0.95")
    if not 0.0 < args.shrink <= 1.0:
        ap.error(f"--shrink {args.shrink}: give a scale in (0, 1], e.g. 0.35 (1: no small pass)")
    if not 0 <= args.jpeg <= 100:
        ap.error(f"--jpeg {args.jpeg}: give a JPEG quality in 1-100, e.g. 25 (0: no compressed pass)")
    passes = extra_passes(
        args.shake_px,
        not args.no_grey,
        args.light,
        not args.no_cut,
        None if wb == (1, 1, 1) else wb,
        not args.no_infrared,
        args.noise,
        args.shrink,
        args.jpeg,
    )
    report: dict[str, Any] = {
        "bench": "real_silhouettes",
        "train_frames": args.train_frames,
        "first_scored_frame": FIRST_SCORED,
        "split": "tune: clips whose first number is even; report: odd",
        "clips": {},
    }
    for split in splits:
        paths = clip_paths(split)[:: args.every][: args.max_clips]
        if args.only:
            paths = [p for p in paths if p.stem in args.only.split(",")]
        if not paths:  # --only named no clip of this split
            continue
        rows: dict[str, list[dict[str, Any]]] = {m: [] for m in (*methods, *passes)}
        for p in paths:
            line = {}
            for m, is_ours in methods.items():
                r = run_clip(p, is_ours, args.train_frames)
                rows[m].append(r)
                line[m] = summarise([r])
            for m, kw in passes.items():
                r = run_clip(p, True, args.train_frames, **kw)
                rows[m].append(r)
                line[m] = summarise([r])
            report["clips"][p.stem] = {
                m: {
                    k: line[m][k]
                    for k in ("people_found", "keypoint_coverage", "keypoint_coverage_person", "extra_people", "misses")
                }
                for m in line
            }
            print(p.stem, json.dumps(report["clips"][p.stem]), flush=True)
        report[split] = {m: summarise(rows[m]) for m in rows}
    done = [split for split in splits if split in report]
    if not done:
        ap.error(f"--only {args.only!r}: no clip of the split(s) {', '.join(splits)} has that name")
    main_split = "report" if "report" in done else done[0]
    for m in passes:
        for k in ("people_found", "keypoint_coverage", "extra_people", "person_clips_covered", "people_share"):
            report[f"{k}_{m}"] = report[main_split][m][k]
    if "noisy" in passes:
        report["noise"] = args.noise
    if "small" in passes:
        report["shrink"] = args.shrink
    if "jpeg" in passes:
        report["jpeg_quality"] = args.jpeg
    if "lit" in passes:
        report["light"] = args.light
    if "wb" in passes:
        report["white_balance"] = list(wb)
    if "ir" in passes:
        for m in ("ir", "ir_unfollowed"):
            report[f"people_found_late_{m}"] = report[main_split][m]["people_found_late"]
        report["relearns_ir"] = report[main_split]["ir"]["relearns"]
    if "shaken" in passes:
        report["shake_px"] = args.shake_px
        report["shake_err_px_median"] = report[main_split]["shaken"]["shake_err_px_median"]
        report["shake_err_px_p95"] = report[main_split]["shaken"]["shake_err_px_p95"]
        report["fps_shaken"] = report[main_split]["shaken"]["fps"]
    for m in methods:
        suffix = "" if m == "ours" else "_baseline"
        for k in (
            "people_found",
            "keypoint_coverage",
            "extra_people",
            "people_found_reference_ordered",
            "reference_reversed",
            "person_clips_covered",
            "people_share",
            "misses",
            "fps",
            "fit_s",
        ):
            report[k + suffix] = report[main_split][m][k]
    report["quoted_split"] = main_split
    line = json.dumps(report)
    if args.out:
        Path(args.out).write_text(line + "\n")
    print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
