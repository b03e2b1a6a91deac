"""Benchmark of the social-signal labeller and the rule miner (issue 6, Okwechime et al.).

    python bench/labeller.py [--source sim] [--seeds 0-9] [--duration 120]
                             [--noise-mm 0] [--noise-deg 0] [--dense]

Input (``--source sim``, the default): the simulator's ``conversation`` scenario
(``counterpart.sim.scenarios.conversation``), fed to the labeller as the tracker would publish it: each
person's 14 ground-truth joints (float32 metres, as in ``tracker.Pose3D``) and the head yaw and
pitch of their ground-truth pose vector (``head_turn`` / ``head_nod`` of ``counterpart.body.pose``, which the
labeller node reads from ``TrackedBody.pose``). ``--noise-mm`` adds white Gaussian noise of that
standard deviation to every joint coordinate and ``--noise-deg`` to both head angles (default 0:
a perfect tracker). ``--source constructed`` uses ``counterpart.sim.planted_signals.conversation``
(geometry with planted nods, shakes, turns, sway; head yaw, no pitch). The JSON says which.

Seeds: the reported sequences are ``--seeds`` (default 20-39, 120 s each). The detector's
parameters (median widths, amplitude floors) were chosen on seeds 100-119, which this bench does
not report. Seeds 0-9 were a first held-out set: their result (nod F1 0.954, slow nods of sad
people missed) led to the longer median of the nod channels (one period of the band's lowest
frequency), so they are not the default; 20-39 were not looked at before that last change; the rule-mining conversations use seeds 1000-1059 (interested listener) and
2000-2059 (not interested), 120 s each: 180,000 frames per scenario.

Figures (last stdout line, one JSON object):
  nod_f1, shake_f1     event-level F1, offline labels (centred windows, ``label_pair_3d``), pooled
                       over seeds and both people. Events are the maximal runs of label 1 in the
                       truth (the scenario's per-frame signal labels) and in the prediction
                       (UNKNOWN counts as absent). A predicted and a true event match when their
                       frame intervals overlap by at least one frame; matching is one-to-one
                       (greedy by largest overlap), so one long detection spanning two true events
                       is one hit and one miss. precision = matched / predicted events, recall =
                       matched / true events, F1 = 2PR / (P + R). ``*_events`` gives the counts.
  nod_f1_stream, shake_f1_stream   the same for the streaming labeller (``SocialLabeller.update``
                       frame by frame, as the node runs it) after removing its fixed latency
                       ``stream_latency_s`` (half the FFT window: frame t is labelled from the
                       window ending at t)
  nod_f1_joints, shake_f1_joints   offline, joints only (no head angles): what a tracker without a
                       pose vector allows; shakes turn the head without moving the head joint
  gaze_acc             per-frame accuracy of gaze_at_other (known frames), offline, default 30 degree
                       threshold; gaze_acc_stream the streaming labeller's; gaze_acc_sim_threshold
                       offline with the simulator's own 0.3 rad threshold (the rest of the
                       difference is the threshold, not the head direction)
  planted_rules_recovered   fraction of the simulator's PLANTED_RULES x {interested, not} (4) that
                       the miner finds on the ground-truth label streams (speaker = the person
                       whose turn it is, listener response 10 frames later, bag 0); with
                       conf_abs_err_max, the largest |mined confidence - planted probability|, and
                       the interested / not-interested confidence ratios next to the planted ones
  planted_rules_recovered_labelled, conf_abs_err_max_labelled   the same from the labeller's output
                       (nod, shake, gaze, activity labelled offline; talking from the truth)
  labeller_fps         frames per second per person of SocialLabeller.update, streaming, 3D input
                       with head angles, two people per frame (median of 3 runs); labeller_fps_2d
                       the same with silhouette (2D) input
  face                 the face-video part (``--face-seeds``, default 20-29, ``--face-duration`` 30 s;
                       ``--no-face`` skips it): person A of the simulator's conversations rendered
                       face-on at 640x360 (``counterpart.sim.face.conversation_face_clip``: nods, shakes,
                       look-aways and talking turns with the scenario's own labels) at 25 and
                       29.97 fps, labelled frame by frame by ``SocialLabeller.update`` from the
                       image alone (face path: Haar cascade + tracking). ``nod_f1``/``shake_f1``:
                       event F1 as above after removing the streaming latency (the lower of the
                       two frame rates); ``nod_precision``/``nod_recall``/``shake_precision``/
                       ``shake_recall``: frame precision and recall against the scenario's labels
                       (the lower of the two rates; also as ``*_frame_precision`` per rate; a
                       rate whose clips hold no event of a kind has nan there, and the other
                       rate's figure stands);
                       ``still_false_rate``: the share of a still face's frames labelled nod or
                       shake (the ``still`` verdict clips below, every known frame; the higher of
                       the two rates); ``talk_acc``: per-frame accuracy of talking (UNKNOWN
                       counts as not talking; latency half the talk window removed; the lower of
                       the two frame rates); ``fps``: frames per second of ``SocialLabeller.update``
                       on the 640x360 frames with face detection and tracking, OpenCV on two
                       threads (rendering excluded), next to ``fps_reference_haar_every_frame``
                       (the plain cascade over each whole frame, the same frames),
                       ``fps_frontal_only`` (the labeller without the profile cascade,
                       ``profile_faces`` off: what looking for faces turned aside costs) and the
                       machine's load average. ``per_fps`` has every figure per frame rate,
                       with nod/shake frame recall and precision, ``still_nodshake_rate`` (the share
                       of frames more than 1 s from any true nod or shake that are labelled nod or
                       shake), ``face_known`` (the share of frames with a tracked face),
                       ``*_missed_no_face`` (the share of true nod/shake frames left UNKNOWN: no
                       face tracked, e.g. a head turned away before its face was first found) and
                       ``*_recall_pose_angles``/``*_precision_pose_angles``: the same detector
                       on the clip's ground-truth head angles (a perfect tracker's
                       ``head_nod``/``head_turn``; centred windows), the ceiling the simulator's
                       truth allows (a shake planted on the way back from a look-away is hardly
                       performed). ``per_seed``: recall, precision, true and predicted frames,
                       frames missed for want of a face and the pose-angle recall per clip (seed
                       and frame rate); ``nod_recall_min_seed``, ``nod_precision_min_seed``,
                       ``shake_recall_min_seed``, ``shake_precision_min_seed``: the worst clip's
                       figure over seeds and both rates (clips without a true, resp. predicted,
                       frame of the kind have none), ``worst_seed`` which clip it is.
                       ``laugh_recall``: the share of frames labelled laughing on clips of a
                       laughing face, ``laugh_false_rate_talk`` on clips of a talking face
                       (``gesture_face_clip`` laugh / talk, the verdict seeds, frames from 2 s on;
                       the lower / higher of the two rates: the conversations have no laughter).
                       The clips are ``realistic`` (blinks, slow lighting changes, JPEG quality 80).
                       ``verdicts``: short clips of one behaviour (``counterpart.sim.face.gesture_face_clip``
                       still / nod / shake, ``--face-verdict-seeds`` 0-2, both frame rates), each judged by which of
                       nod and shake is labelled on at least 30% of its frames after the first
                       2.6 s (neither: still); ``verdicts_right`` counts the right ones. The face
                       floors, event_on/event_off/local_s, max_flow_s, talk thresholds and
                       talk_gap_s were set on the gesture clips and conversation seeds 301
                       (25 fps) and 305 (29.97 fps), 45 s each, not on the reported seeds; the
                       localisation on the band's analytic envelope was chosen on seeds 301,
                       302, 305 (both rates) and 303 (25 fps), 45 s each; the nod's rotation
                       cue (the face's features relative to the top of the head, unit gain)
                       on seeds 303, 304 (sad: small nods of a head pitched down) and 311,
                       312 (happy: a knee bounce), 25 fps, 30 s each; taking the lateral motion
                       in step with that cue out of the shake channel (a nod of a head turned
                       aside), and its ridge, on seeds 301, 302, 303 and 305, both rates, 45 s
                       each. Face seeds 300-319 are tuning seeds (the bench warns).
  mine_s               seconds to mine 45,000 frames x 27 speaker + 27 listener labels (synthetic
                       planted streams, rates 0.02-0.3, min_support 0.005, max_len 4);
                       mine_synthetic_recovered its planted rules found; --dense adds mine_s_dense
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import cv2
import numpy as np
import pandas as pd

from counterpart.body.pose import DOF_INDEX
from counterpart.nodes.labeller.face import load_face_cascade
from counterpart.nodes.labeller.gaze import gaze_accuracy
from counterpart.nodes.labeller.head_motion import HeadMotionParams, head_channels_3d, scores_from_channels
from counterpart.nodes.labeller.labeller import FACE_ID_BASE, PersonObservation, SocialLabeller, label_pair_3d
from counterpart.nodes.labeller.mining import mine_rules, mine_transactions, turn_transactions
from counterpart.nodes.labeller.signals import SIGNALS
from counterpart.sim import planted_signals as synthetic
from counterpart.sim.face import FaceClip, conversation_face_clip, gesture_face_clip
from counterpart.sim.scenarios import PLANTED_RULES, SIGNAL_INDEX, SIGNAL_NAMES, conversation

FPS = 25.0
TUNING_SEEDS = range(100, 120)
#: rule-mining conversations: 60 x 120 s = 180,000 frames per scenario, so that the sampling error
#: of the simulator's own coin flips (about 500 planted shake events per scenario) stays well
#: under the 0.05 confidence tolerance
#: the simulator's gaze_at_other: head facing within 0.3 rad of the other's head
SIM_GAZE_THRESHOLD = 0.3
MINE_SEEDS = {"interested": range(1000, 1060), "not_interested": range(2000, 2060)}
MINE_DURATION_S = 120.0


@dataclass(frozen=True)
class Sequence:
    """Two people's tracker-like input with per-frame truth. joints_*: (T,14,3) m; head_yaw_*,
    head_pitch_*: (T,) rad relative to the torso, or None; truth_*: name -> (T,) bool for "nod",
    "shake", "gaze_at_other".
    """

    fps: float
    joints_a: np.ndarray
    joints_b: np.ndarray
    head_yaw_a: np.ndarray | None
    head_yaw_b: np.ndarray | None
    head_pitch_a: np.ndarray | None
    head_pitch_b: np.ndarray | None
    truth_a: dict[str, np.ndarray]
    truth_b: dict[str, np.ndarray]


def sim_sequence(
    seed: int, duration_s: float, noise_mm: float = 0.0, noise_deg: float = 0.0, **kw: object
) -> tuple[Sequence, object]:
    """One simulator conversation as the tracker would publish it (see the module docstring);
    returns (sequence, scenario).
    """
    sc = conversation(seed=seed, fps=FPS, duration=duration_s, **kw)  # type: ignore[arg-type]
    rng = np.random.default_rng([seed, 6])
    joints = sc.joints().astype(np.float32).astype(np.float64)
    if noise_mm > 0:
        joints = joints + rng.normal(0.0, noise_mm / 1000.0, joints.shape)
    ang = {}
    for p, poses in (("a", sc.poses_a), ("b", sc.poses_b)):
        for name, dof in (("yaw", "head_turn"), ("pitch", "head_nod")):
            a = poses[:, DOF_INDEX[dof]].copy()
            if noise_deg > 0:
                a += rng.normal(0.0, np.radians(noise_deg), a.shape)
            ang[name + p] = a
    truth = {
        p: {k: s[:, SIGNAL_INDEX[k]] == 1 for k in ("nod", "shake", "gaze_at_other")}
        for p, s in (("a", sc.signals_a), ("b", sc.signals_b))
    }
    seq = Sequence(
        FPS, joints[:, 0], joints[:, 1], ang["yawa"], ang["yawb"], ang["pitcha"], ang["pitchb"], truth["a"], truth["b"]
    )
    return seq, sc


def sim_source(seeds: list[int], duration_s: float, noise_mm: float, noise_deg: float) -> Iterator[Sequence]:
    for s in seeds:
        yield sim_sequence(s, duration_s, noise_mm, noise_deg)[0]


def constructed_source(seeds: list[int], duration_s: float, noise_mm: float, noise_deg: float) -> Iterator[Sequence]:
    for s in seeds:
        c = synthetic.conversation(duration_s, FPS, seed=s)
        yield Sequence(c.fps, c.joints_a, c.joints_b, c.head_yaw_a, c.head_yaw_b, None, None, c.truth_a, c.truth_b)


SOURCES: dict[str, Callable[[list[int], float, float, float], Iterator[Sequence]]] = {
    "sim": sim_source,
    "constructed": constructed_source,
}


# ------------------------------------------------------------------------------ event matching
def events(mask: np.ndarray) -> np.ndarray:
    """(K,2) [start, end) frame intervals of the maximal runs of True in a (T,) mask."""
    d = np.diff(np.r_[0, np.asarray(mask, dtype=np.int8), 0])
    return np.stack([np.flatnonzero(d == 1), np.flatnonzero(d == -1)], axis=1)


def match_events(pred: np.ndarray, truth: np.ndarray) -> tuple[int, int, int]:
    """(matched, predicted, true) event counts: one-to-one matching of overlapping intervals,
    greedy by largest overlap. pred, truth: (T,) bool masks.
    """
    p, t = events(pred), events(truth)
    if len(p) == 0 or len(t) == 0:
        return 0, len(p), len(t)
    ov = np.minimum(p[:, None, 1], t[None, :, 1]) - np.maximum(p[:, None, 0], t[None, :, 0])
    pairs = np.argwhere(ov > 0)
    pairs = pairs[np.argsort(-ov[pairs[:, 0], pairs[:, 1]], kind="stable")]
    used_p, used_t = set(), set()
    for i, j in pairs.tolist():
        if i not in used_p and j not in used_t:
            used_p.add(i)
            used_t.add(j)
    return len(used_p), len(p), len(t)


def event_f1(counts: list[tuple[int, int, int]]) -> tuple[float, dict[str, int]]:
    m, np_, nt = (int(sum(c[i] for c in counts)) for i in range(3))
    f1 = 2 * m / (np_ + nt) if np_ + nt else float("nan")
    return f1, {"matched": m, "predicted": np_, "true": nt}


# ------------------------------------------------------------------------------ labelling
def streaming_labels(c: Sequence, lab: SocialLabeller | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Run SocialLabeller frame by frame; returns (labels_a, labels_b), each (T,6) in SIGNALS order."""
    lab = lab or SocialLabeller(c.fps)
    t = c.joints_a.shape[0]
    out = {"a": np.zeros((t, len(SIGNALS)), np.int8), "b": np.zeros((t, len(SIGNALS)), np.int8)}
    obs = _observations(c)
    for i in range(t):
        res = lab.update(obs[i])
        for p in ("a", "b"):
            out[p][i] = [res[p][s][1] for s in SIGNALS]
    return out["a"], out["b"]


def _observations(c: Sequence) -> list[dict[str, PersonObservation]]:
    def val(a: np.ndarray | None, i: int) -> float | None:
        return None if a is None else float(a[i])

    return [
        {
            "a": PersonObservation(
                joints=c.joints_a[i], head_yaw=val(c.head_yaw_a, i), head_pitch=val(c.head_pitch_a, i)
            ),
            "b": PersonObservation(
                joints=c.joints_b[i], head_yaw=val(c.head_yaw_b, i), head_pitch=val(c.head_pitch_b, i)
            ),
        }
        for i in range(c.joints_a.shape[0])
    ]


def offline_labels(
    c: Sequence,
    angles: bool = True,
    gaze_threshold: float = float(np.radians(30.0)),
) -> tuple[np.ndarray, np.ndarray]:
    """label_pair_3d (centred windows): (labels_a, labels_b), each (T,6)."""
    kw = (
        dict(head_yaw_a=c.head_yaw_a, head_yaw_b=c.head_yaw_b, head_pitch_a=c.head_pitch_a, head_pitch_b=c.head_pitch_b)
        if angles
        else {}
    )
    _, la, _, lb = label_pair_3d(
        c.joints_a,
        c.joints_b,
        c.fps,
        center=True,  # type: ignore[arg-type]
        gaze_threshold=gaze_threshold,
        **kw,
    )
    return la, lb


def bench_fps(c: Sequence, repeats: int = 3) -> tuple[float, float]:
    """Per-person frames per second of the streaming labeller, 3D (with head angles) and 2D input
    (medians of ``repeats`` runs).
    """
    t = c.joints_a.shape[0]
    obs = _observations(c)
    k = 300 / 1.7  # silhouette-like input: x/y of the joints in pixels, 300 px per 1.7 m
    cp = np.stack(
        [
            40 * np.sin(np.linspace(0, 2 * np.pi, 32, endpoint=False)),
            -150 * np.cos(np.linspace(0, 2 * np.pi, 32, endpoint=False)),
        ],
        -1,
    )
    obs2 = []
    for i in range(t):
        d = {}
        for p, j in (("a", c.joints_a[i]), ("b", c.joints_b[i])):
            ref = np.array([320 + k * j[1, 0], 480 - k * 0.9])
            d[p] = PersonObservation(
                head_px=np.array([320 + k * j[0, 0], 480 - k * j[0, 1]]),
                ref_px=ref,
                height_px=300.0,
                control_points=cp + ref,
            )
        obs2.append(d)
    out = []
    for o_all in (obs, obs2):
        runs = []
        for _ in range(repeats):
            lab = SocialLabeller(c.fps)
            t0 = time.perf_counter()
            for o in o_all:
                lab.update(o)
            runs.append(2 * t / (time.perf_counter() - t0))
        out.append(float(np.median(runs)))
    return out[0], out[1]


# ------------------------------------------------------------------------------ face video
FACE_FPS = (25.0, 29.97)
#: face-part conversation seeds the face path's settings were chosen on (never reported)
FACE_TUNING_SEEDS = range(300, 320)


def face_labels(clip: FaceClip, lab: SocialLabeller | None = None) -> tuple[np.ndarray, list[str], float]:
    """Label a face clip from its images alone: (T, 6) labels of the face's person (UNKNOWN where
    no face is tracked), the per-frame source, and the labeller's frames per second.
    """
    lab = lab or SocialLabeller(clip.fps)
    out = np.full((clip.n_frames, len(SIGNALS)), -1, np.int8)
    src = []
    busy = 0.0
    for i in range(clip.n_frames):
        img = clip.render(i)
        t0 = time.perf_counter()
        res = lab.update({}, image=img)
        busy += time.perf_counter() - t0
        pid = min((p for p in res if p >= FACE_ID_BASE), default=None)
        if pid is not None:
            out[i] = [res[pid][s][1] for s in SIGNALS]
        src.append(lab.sources.get(pid, "") if pid is not None else "")
    return out, src, clip.n_frames / busy


def _frame_pr(pred: np.ndarray, truth: np.ndarray) -> tuple[int, int, int]:
    return int((pred & truth).sum()), int(pred.sum()), int(truth.sum())


def pose_angle_labels(clip: FaceClip) -> dict[str, np.ndarray]:
    """The reference of the face path: nod/shake labels (centred windows, so aligned with the
    truth) from the clip's own ground-truth head angles (what a perfect tracker's ``head_nod`` /
    ``head_turn`` gives), with the same detector and defaults. A true nod or shake this misses was
    hardly performed by the simulated head (e.g. a shake planted on the way back from a look-away).
    """
    p = HeadMotionParams(clip.fps)
    zero = np.zeros((clip.n_frames, 3))
    ch = head_channels_3d(zero, zero, None, clip.yaw, p.head_radius_m, clip.pitch, p.pitch_radius_m)
    r = scores_from_channels(ch, p, center=True, angles=(True, True))
    return {"nod": r.nod == 1, "shake": r.shake == 1}


def worst_seed_figures(per_seed: list[dict[str, object]]) -> dict[str, object]:
    """The lowest per-clip nod/shake frame recall and precision over seeds and frame rates
    (``*_min_seed``), with the clip it comes from (``worst_seed``); clips without a true (for
    recall) or a predicted (for precision) frame of a kind have no figure and are skipped.
    """
    out: dict[str, object] = {}
    where: dict[str, object] = {}
    for k in ("nod", "shake"):
        for fig in ("recall", "precision"):
            rows = [r for r in per_seed if r[f"{k}_{fig}"] == r[f"{k}_{fig}"]]  # type: ignore[comparison-overlap]
            key = f"{k}_{fig}_min_seed"
            if not rows:
                out[key] = float("nan")
                continue
            r = min(rows, key=lambda r: float(r[f"{k}_{fig}"]))  # type: ignore[arg-type]
            out[key] = r[f"{k}_{fig}"]
            where[key] = {"seed": r["seed"], "fps": r["fps"]}
    out["worst_seed"] = where
    return out


def face_part(seeds: list[int], duration_s: float, verdict_seeds: list[int] | None = None) -> dict[str, object]:
    """The face-video figures (see the module docstring)."""
    cv2.setNumThreads(2)
    per: dict[str, dict[str, object]] = {}
    per_seed: list[dict[str, object]] = []
    for fps in FACE_FPS:
        n_win = HeadMotionParams(fps).n
        lat = n_win - 1 - n_win // 2  # a frame's label comes when its window's centre is that frame
        talk_lat = int(round(0.5 * fps))  # the talk window is 1 s, labelled at its end
        cnt: dict[str, list[tuple[int, int, int]]] = {
            f"{k}{x}": [] for k in ("nod", "shake") for x in ("", "_fr", "_ref", "_unknown")
        }
        talk_ok = talk_n = still_fp = still_n = known = frames = 0
        for seed in seeds:
            clip = conversation_face_clip(seed=seed, fps=fps, duration=duration_s)
            lab, _, _ = face_labels(clip)
            ref = pose_angle_labels(clip)
            row: dict[str, object] = {"seed": seed, "fps": fps}
            for k in ("nod", "shake"):
                pred = lab[lat:, SIGNALS.index(k)] == 1
                tr = clip.truth[k][: len(pred)]
                cnt[k].append(match_events(pred, tr))
                cnt[k + "_fr"].append(_frame_pr(pred, tr))
                cnt[k + "_ref"].append(_frame_pr(ref[k], clip.truth[k]))
                unknown = lab[lat:, SIGNALS.index(k)] == -1
                cnt[k + "_unknown"].append(_frame_pr(unknown, tr))
                m, p_, t_ = cnt[k + "_fr"][-1]
                row[f"{k}_true_frames"] = t_
                row[f"{k}_predicted_frames"] = p_
                row[f"{k}_recall"] = round(m / t_, 4) if t_ else float("nan")
                row[f"{k}_precision"] = round(m / p_, 4) if p_ else float("nan")
                row[f"{k}_missed_no_face"] = cnt[k + "_unknown"][-1][0]
                mr, _, tr_ = cnt[k + "_ref"][-1]
                row[f"{k}_recall_pose_angles"] = round(mr / tr_, 4) if tr_ else float("nan")
            per_seed.append(row)
            ev = (clip.truth["nod"] | clip.truth["shake"]).astype(float)
            near = np.convolve(ev, np.ones(2 * int(fps) + 1), mode="same") > 0
            shifted = lab[lat:]
            calm = ~near[: len(shifted)]
            fp = (shifted[:, SIGNALS.index("nod")] == 1) | (shifted[:, SIGNALS.index("shake")] == 1)
            still_fp += int((fp & calm).sum())
            still_n += int(calm.sum())
            talk = lab[talk_lat:, SIGNALS.index("talking")] == 1
            talk_ok += int((talk == clip.truth["talking"][: len(talk)]).sum())
            talk_n += len(talk)
            known += int((lab[:, 0] != -1).sum())
            frames += clip.n_frames
            print(f"face clip seed {seed} at {fps} fps: {clip.n_frames} frames", file=sys.stderr)
        r: dict[str, object] = {}
        for k in ("nod", "shake"):
            f1, c = event_f1(cnt[k])
            m, p_, t_ = (sum(x[i] for x in cnt[k + "_fr"]) for i in range(3))
            r[f"{k}_f1"] = round(f1, 4)
            r[f"{k}_events"] = c
            r[f"{k}_frame_recall"] = r[f"{k}_recall"] = round(m / t_, 4) if t_ else float("nan")
            r[f"{k}_frame_precision"] = r[f"{k}_precision"] = round(m / p_, 4) if p_ else float("nan")
            m, p_, t_ = (sum(x[i] for x in cnt[k + "_ref"]) for i in range(3))
            r[f"{k}_recall_pose_angles"] = round(m / t_, 4) if t_ else float("nan")
            r[f"{k}_precision_pose_angles"] = round(m / p_, 4) if p_ else float("nan")
            m, _, t_ = (sum(x[i] for x in cnt[k + "_unknown"]) for i in range(3))
            r[f"{k}_missed_no_face"] = round(m / t_, 4) if t_ else float("nan")
        r["talk_acc"] = round(talk_ok / talk_n, 4)
        r["still_nodshake_rate"] = round(still_fp / max(still_n, 1), 4)
        r["face_known"] = round(known / frames, 4)
        per[f"{fps:g}"] = r
    # speed: the labeller alone on pre-rendered 640x360 frames
    clip = conversation_face_clip(seed=seeds[0], fps=FACE_FPS[0], duration=20.0)
    imgs = [clip.render(i) for i in range(min(clip.n_frames, 400))]
    fps_of = {}
    for name, profile in (("profile", True), ("frontal", False)):
        lab = SocialLabeller(clip.fps, track_params={"profile_faces": profile})
        t0 = time.perf_counter()
        for img in imgs:
            lab.update({}, image=img)
        fps_of[name] = len(imgs) / (time.perf_counter() - t0)
    fps_lab = fps_of["profile"]
    # reference, same frames and threads: the plain cascade over the whole frame, every frame
    cascade = load_face_cascade()
    t0 = time.perf_counter()
    for img in imgs[:100]:
        cascade.detectMultiScale(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), 1.1, 5, minSize=(40, 40))
    fps_haar = min(len(imgs), 100) / (time.perf_counter() - t0)
    verdicts = []
    still_cnt = {f"{fps:g}": [0, 0] for fps in FACE_FPS}
    for fps in FACE_FPS:
        for kind in ("still", "nod", "shake"):
            for seed in verdict_seeds if verdict_seeds is not None else range(3):
                g = gesture_face_clip(kind, fps=fps, duration=6.0, seed=seed)
                lab_g, _, _ = face_labels(g)
                tail = lab_g[int(2.6 * fps) :]
                share = {k: float((tail[:, SIGNALS.index(k)] == 1).mean()) for k in ("nod", "shake")}
                if kind == "still":
                    known_g = lab_g[:, SIGNALS.index("nod")] != -1
                    moving = (lab_g[:, SIGNALS.index("nod")] == 1) | (lab_g[:, SIGNALS.index("shake")] == 1)
                    still_cnt[f"{fps:g}"][0] += int((moving & known_g).sum())
                    still_cnt[f"{fps:g}"][1] += int(known_g.sum())
                got = max(share, key=share.get) if max(share.values()) >= 0.3 else "still"
                verdicts.append(
                    {
                        "kind": kind,
                        "fps": fps,
                        "seed": seed,
                        "verdict": got,
                        "nod_share": round(share["nod"], 3),
                        "shake_share": round(share["shake"], 3),
                    }
                )
    for key, (fp, n_known) in still_cnt.items():
        per[key]["still_false_rate"] = round(fp / n_known, 4) if n_known else float("nan")
    # laughing: the conversations have none, so one-behaviour clips (wide-open mouth with a
    # smile, or speech), frames from 2 s on (the 1 s talk window inside the behaviour)
    for fps in FACE_FPS:
        shares: dict[str, list[float]] = {"laugh": [], "talk": []}
        for kind in shares:
            for seed in verdict_seeds if verdict_seeds is not None else range(3):
                lab_g, _, _ = face_labels(gesture_face_clip(kind, fps=fps, duration=4.0, seed=seed))
                shares[kind].append(float((lab_g[int(2.0 * fps) :, SIGNALS.index("laughing")] == 1).mean()))
        per[f"{fps:g}"]["laugh_recall"] = round(float(np.mean(shares["laugh"])), 4)
        per[f"{fps:g}"]["laugh_false_rate_talk"] = round(float(np.mean(shares["talk"])), 4)
    names = ("nod_f1", "shake_f1", "talk_acc", "nod_precision", "nod_recall", "shake_precision", "shake_recall")

    def over_rates(key: str, pick: Callable[[list[float]], float]) -> float:
        # a rate without any event of a kind has nan figures for it: the other rate's stand
        vals = [float(per[f"{f:g}"][key]) for f in FACE_FPS]  # type: ignore[arg-type]
        known = [v for v in vals if v == v]
        return pick(known) if known else float("nan")

    worst: dict[str, object] = {k: over_rates(k, min) for k in (*names, "laugh_recall")}
    worst.update(worst_seed_figures(per_seed))
    worst["still_false_rate"] = over_rates("still_false_rate", max)
    worst["laugh_false_rate_talk"] = over_rates("laugh_false_rate_talk", max)
    return {
        **worst,
        "fps": round(fps_lab, 1),
        "fps_reference_haar_every_frame": round(fps_haar, 1),
        "fps_frontal_only": round(fps_of["frontal"], 1),
        "load_avg_1min": round(os.getloadavg()[0], 2),
        "frame_size": [640, 360],
        "opencv_threads": 2,
        "seeds": seeds,
        "duration_s": duration_s,
        "per_fps": per,
        "per_seed": per_seed,
        "verdicts_right": sum(v["kind"] == v["verdict"] for v in verdicts),
        "verdicts_total": len(verdicts),
        "verdicts": verdicts,
    }


# ------------------------------------------------------------------------------ rule mining
def planted_rule_recovery() -> dict[str, dict[str, object]]:
    """Mine the simulator's conversations (MINE_SEEDS, MINE_DURATION_S each) per scenario, from the
    ground-truth labels ("truth") and from the labeller's ("labelled"), and compare the planted
    rules' confidences with their planted probabilities.
    """
    offset = int(round(PLANTED_RULES[0]["offset_s"] * FPS))
    names = list(SIGNAL_NAMES)
    tx: dict[str, dict[str, list[pd.DataFrame]]] = {"truth": {}, "labelled": {}}
    frames: dict[str, int] = {}
    for scen, seeds in MINE_SEEDS.items():
        frames[scen] = 0
        for s in seeds:
            seq, sc = sim_sequence(s, MINE_DURATION_S, interested=(scen == "interested"))
            la, lb = sc.signals_a, sc.signals_b  # type: ignore[attr-defined]
            tx["truth"].setdefault(scen, []).append(turn_transactions(la, lb, names, offset=offset))
            pa, pb = offline_labels(seq)
            la, lb = la.copy(), lb.copy()
            for lab, pred in ((la, pa), (lb, pb)):
                for k in ("nod", "shake", "gaze_at_other", "activity"):
                    lab[:, SIGNAL_INDEX[k]] = pred[:, SIGNALS.index(k)]
            tx["labelled"].setdefault(scen, []).append(turn_transactions(la, lb, names, offset=offset))
            frames[scen] += la.shape[0]
    out: dict[str, dict[str, object]] = {}
    for source, per_scen in tx.items():
        found, errs = 0, []
        conf: dict[str, dict[str, float]] = {}
        t_mine = 0.0
        for scen, parts in per_scen.items():
            t0 = time.perf_counter()
            rules = mine_transactions(
                pd.concat(parts, ignore_index=True), min_support=0.005, min_confidence=0.1, max_len=4
            )
            t_mine += time.perf_counter() - t0
            by_key = {r.key: r for r in rules}
            conf[scen] = {}
            for r in PLANTED_RULES:
                key = ((f"S:{r['antecedent']}",), (f"L:{r['consequent']}",))
                p = r["p_interested"] if scen == "interested" else r["p_uninterested"]
                hit = by_key.get(key)
                if hit is not None:
                    found += 1
                    errs.append(abs(hit.confidence - p))
                    conf[scen][f"{r['antecedent']}->{r['consequent']}"] = round(hit.confidence, 4)
        ratios = {
            k: round(conf["interested"][k] / conf["not_interested"][k], 3)
            for k in conf["interested"]
            if conf["not_interested"].get(k)
        }
        total = len(PLANTED_RULES) * len(MINE_SEEDS)
        out[source] = {
            "recovered": found / total,
            "planted": total,
            "conf_abs_err_max": max(errs) if errs else float("nan"),
            "confidences": conf,
            "ratio": ratios,
            "frames": frames,
            "mine_s": t_mine,
        }
    return out


def bench_mining(
    n_frames: int = 45000,
    n_signals: int = 27,
    seed: int = 0,
    base_rate: tuple[float, float] = (0.02, 0.3),
    min_support: float = 0.005,
) -> dict[str, float]:
    """Mining speed on planted synthetic streams: n_signals speaker + n_signals listener labels,
    each on at a rate drawn from base_rate (mean ~0.16), default max_len 4.
    """
    planted = [(0, 0, 0.9), (1, 2, 0.6), (3, 5, 0.3), (8, 8, 0.75), (13, 20, 0.5), (26, 26, 0.4)]
    sp, li, names = synthetic.planted_label_streams(
        n_frames, n_signals, planted, offset=10, seed=seed, base_rate=base_rate
    )
    t0 = time.perf_counter()
    rules = mine_rules(sp, li, names, offset=10, min_support=min_support, min_confidence=0.2)
    mine_s = time.perf_counter() - t0
    by_key = {r.key: r for r in rules}
    found = sum(((f"S:{names[x]}",), (f"L:{names[y]}",)) in by_key for x, y, _ in planted)
    return {
        "mine_s": mine_s,
        "mine_rules": len(rules),
        "mine_label_rate": float(sp.mean()),
        "mine_synthetic_recovered": found / len(planted),
    }


def _seeds(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b) + 1)) if b else [int(a)]
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--source", choices=sorted(SOURCES), default="sim")
    ap.add_argument("--seeds", default="20-39", help="reported seeds, e.g. 20-39 or 0,3,5 (not 100-119: tuning)")
    ap.add_argument("--duration", type=float, default=120.0, help="seconds per sequence")
    ap.add_argument("--noise-mm", type=float, default=0.0, help="joint noise (sim source), mm")
    ap.add_argument("--noise-deg", type=float, default=0.0, help="head angle noise (sim source), degrees")
    ap.add_argument("--no-mining", action="store_true", help="skip the rule figures")
    ap.add_argument("--no-face", action="store_true", help="skip the face-video part")
    ap.add_argument("--face-seeds", default="20-29", help="conversation seeds of the face part (not 300-319: tuning)")
    ap.add_argument("--face-duration", type=float, default=30.0, help="seconds per face clip")
    ap.add_argument("--face-verdict-seeds", default="0-2", help="seeds of the one-behaviour verdict clips")
    ap.add_argument(
        "--dense", action="store_true", help="also time mining on dense labels (mean rate ~0.27, min_support 0.01)"
    )
    a = ap.parse_args()
    seeds = _seeds(a.seeds)
    tuned = sorted(set(seeds) & set(TUNING_SEEDS))
    if a.source == "sim" and tuned:
        print(f"warning: seeds {tuned} were used to choose the detector's parameters", file=sys.stderr)

    seqs = list(SOURCES[a.source](seeds, a.duration, a.noise_mm, a.noise_deg))
    lat = HeadMotionParams(FPS).n // 2
    cnt: dict[str, list[tuple[int, int, int]]] = {}
    gz: dict[str, list[np.ndarray]] = {"off": [], "stream": [], "sim_th": [], "truth": []}
    for c in seqs:
        off = offline_labels(c)
        joints_only = offline_labels(c, angles=False)
        stream = streaming_labels(c)
        sim_th = offline_labels(c, gaze_threshold=SIM_GAZE_THRESHOLD)
        for p, tr in ((0, c.truth_a), (1, c.truth_b)):
            for k in ("nod", "shake"):
                col = SIGNALS.index(k)
                cnt.setdefault(k, []).append(match_events(off[p][:, col] == 1, tr[k]))
                cnt.setdefault(k + "_joints", []).append(match_events(joints_only[p][:, col] == 1, tr[k]))
                s = stream[p][lat:, col] == 1  # frame t + lat is labelled from the window centred at t
                cnt.setdefault(k + "_stream", []).append(match_events(s, tr[k][: len(s)]))
            g = SIGNALS.index("gaze_at_other")
            gz["off"].append(off[p][:, g])
            gz["stream"].append(stream[p][:, g])
            gz["sim_th"].append(sim_th[p][:, g])
            gz["truth"].append(tr["gaze_at_other"].astype(np.int8))
        print(f"labelled {c.joints_a.shape[0]} frames x 2 people", file=sys.stderr)
    truth_g = np.concatenate(gz["truth"])
    res: dict[str, object] = {
        "source": a.source,
        "input": (
            "simulator conversation, ground-truth joints (float32) + pose head_turn/head_nod"
            f", noise {a.noise_mm:g} mm / {a.noise_deg:g} deg"
            if a.source == "sim"
            else "constructed geometry (counterpart.sim.planted_signals), joints + head yaw"
        ),
        "seeds": a.seeds,
        "duration_s": a.duration,
        "people_sequences": 2 * len(seqs),
    }
    for k in ("nod", "shake", "nod_stream", "shake_stream", "nod_joints", "shake_joints"):
        f1, c = event_f1(cnt[k])
        res[f"{k.split('_')[0]}_f1" + ("_" + k.split("_")[1] if "_" in k else "")] = round(f1, 4)
        if "_" not in k:
            res[f"{k}_events"] = c
    res["stream_latency_s"] = lat / FPS
    res["gaze_acc"] = round(gaze_accuracy(np.concatenate(gz["off"]), truth_g), 4)
    res["gaze_acc_stream"] = round(gaze_accuracy(np.concatenate(gz["stream"]), truth_g), 4)
    res["gaze_acc_sim_threshold"] = round(gaze_accuracy(np.concatenate(gz["sim_th"]), truth_g), 4)
    if not a.no_mining:
        rec = planted_rule_recovery()
        for tag, source in (("", "truth"), ("_labelled", "labelled")):
            r = rec[source]
            res[f"planted_rules_recovered{tag}"] = r["recovered"]
            res[f"conf_abs_err_max{tag}"] = round(float(r["conf_abs_err_max"]), 4)  # type: ignore[arg-type]
            res[f"rule_confidences{tag}"] = r["confidences"]
            res[f"rule_ratio{tag}"] = r["ratio"]
            if not tag:
                res["planted_rules"] = r["planted"]
                res["rule_ratio_planted"] = {
                    f"{p['antecedent']}->{p['consequent']}": round(p["p_interested"] / p["p_uninterested"], 3)
                    for p in PLANTED_RULES
                }
                res["rule_frames"] = r["frames"]
                res["rule_mine_s"] = round(float(r["mine_s"]), 3)  # type: ignore[arg-type]
    fps3, fps2 = bench_fps(seqs[0])
    res["labeller_fps"] = round(fps3, 1)
    res["labeller_fps_2d"] = round(fps2, 1)
    m = bench_mining()
    res.update({k: (round(v, 4) if isinstance(v, float) else v) for k, v in m.items()})
    if a.dense:
        # dense labels (mean rate ~0.27) make far more frequent itemsets: the cost grows fast
        d = bench_mining(base_rate=(0.05, 0.5), min_support=0.01)
        res["mine_s_dense"] = round(d["mine_s"], 3)
        res["mine_label_rate_dense"] = round(d["mine_label_rate"], 3)
    if not a.no_face:
        face_tuned = sorted(set(_seeds(a.face_seeds)) & set(FACE_TUNING_SEEDS))
        if face_tuned:
            print(f"warning: face seeds {face_tuned} were used to choose the face path's settings", file=sys.stderr)
        res["face"] = face_part(_seeds(a.face_seeds), a.face_duration, _seeds(a.face_verdict_seeds))
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
