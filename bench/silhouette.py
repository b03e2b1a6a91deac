"""Benchmark of the silhouette node's algorithms: quality and speed, ours (Horprasert) vs OpenCV.

Usage: python bench/silhouette.py [--source synthetic|vtest|sim|all] [--frames N]
           [--scenarios handshake,push,wave,conversation] [--seeds 0,1,2] [--sim-frames 250]
           [--threads 1] [--no-real | --real-only | --speed-only] [--out FILE]

Real footage (``../shared/data/cdnet``, skipped when absent; ``--real-only`` runs only this):
each CDnet sequence (pedestrians, busStation) is fed from its first frame to ours, MOG2, KNN and
GSOC, each through ``SilhouetteExtractor`` with the node's defaults (the same clean-up: open 3,
close 7, holes filled, minimum area from the frame size, tracking), and the published label mask
is scored with the CDnet protocol: F1 pooled over the evaluated frames (``temporalROI.txt``),
label 255 positive, 0 and 50 negative, 85 and 170 ignored. The first half of the evaluated frames
was used to tune our model (``*_tune``); the figures (``f1_ours``, ``f1_mog2``, ``f1_knn``,
``f1_gsoc``) are those of the second half; ``f1_ours_auto_area``: ours with the minimum area
from the frame size and camera (``min_area=None``, node ``min_area: 0``) instead of the node's
300 px; ``f1_ours_no_body_shadow``: ours without taking the shadow labels inside a body (dark
clothes, hair) back as foreground (node ``body_shadow_px: 0``; the default is 15);
``f1_ours_no_legs``: ours without the leg step of that rule (node ``body_shadow_leg_ncc: -1``; the
default is 0.5: a shadow hanging from foreground that does not keep the floor's texture is a leg). Ours with the node defaults has the sample-consensus model and the shadow texture test
on (``dynamic: true, shadow_ncc: 0.4``). ``shadow_f1`` (ours; ``shadow_f1_mog2`` / ``_knn``
theirs): the SHADOW class of the raw pixels against label 50, where the ground truth marks shadows.
A grey or infrared camera: each sequence again made grey (three equal channels), ours as it is
(``f1_ours_grey``: the background found monochrome, shadows and highlights bounded tightly) and
with colour footage's shadow bounds (``f1_ours_grey_colour_bounds``: as it was before), and MOG2
without shadow detection (``f1_mog2_grey``).
Top-level key ``real``: one object per sequence.

People in view from the first frame (``real_people_start``): each CDnet sequence started at every
150th evaluated frame whose first frame shows people (at least 0.5% of its pixels foreground in
the ground truth), 150 frames from there; ours fits on the first 30 of them with the people
detector (the node's default) and without it (``plain``: the per-pixel median alone), MOG2 and KNN
learn them; F1 from frame 30 of each start on, pooled over the starts and sequences:
``f1_people_start`` (ours), ``f1_people_start_plain``, ``f1_people_start_mog2``,
``f1_people_start_knn``. The rule that tells a walker from a still person in the training frames
(``people._walked_off``) was chosen on vtest.avi and on starts at frame 400 of both sequences, none
of which is among these starts.

Speed beside MOG2: ``fps_320x240_2cores`` (ours) and ``fps_320x240_2cores_mog2`` (the same
extractor with MOG2 as its backend), whole extractor with splines, two OpenCV threads and our
models' learning steps in a worker thread (their default, ``threaded``), sim frames; the two
extractors take turns every ``SPEED_CHUNK`` frames, so a swing of the machine's load falls on
both; ``fps_ratio_mog2`` is ours over MOG2's. ``cpu_ms_main_2cores`` / ``cpu_ms_process_2cores``
(``*_mog2``: MOG2's): ms of CPU per frame of the calling thread and of the whole process in that
run, from the threads' CPU clocks (load-robust, unlike the fps; the calling thread's CPU is the
two-core rate's floor when the learning thread has a core of its own).
``*_2cores_cv1`` (``fps_320x240_2cores_cv1``, ``fps_320x240_2cores_mog2_cv1``,
``cpu_ms_main_2cores_cv1``, ``cpu_ms_process_2cores_cv1``): the same run with one OpenCV thread, our
worker thread the only other one: after each call that OpenCV parallelises (the connected
components of the body-shadow step and of the tracker) its pool thread busy-waits for more work on
the core the worker needs; the labels are the same. MOG2's own calls are not parallelised at this size.
``--speed-only`` runs only the speed figures (run it alone on the machine: they are wall-clock
medians); ``load_1min`` is the machine's load average when they were taken.

Simulator evaluation (``--source sim`` or ``all``): every scenario x seed, 320x240, with the
renderer's cast shadows, lighting drift and sensor noise, in two starts: 30 frames of the empty
room first (ours fits on them, robust=False), and people in view from frame 0 (ours fits robustly
on the first 30 frames). Every backend (ours, MOG2, KNN, CNT) runs through ``SilhouetteExtractor``
as the node does, and its published label mask (after clean-up, minimum area, tracking) is scored
on the same frames (from frame 30 on) against the truth masks; cast-shadow pixels are background.
Top-level keys: f1_ours / f1_mog2 / f1_knn / f1_cnt (pooled pixel counts over all sequences, and
per start: *_empty_start, *_people_start), shadow_as_fg (fraction of truth shadow pixels in our
published mask), spline_px (mean distance of the mask contour points to our fitted 32-point
spline), id_swaps (handshake and push sequences, both starts: a published id mapped by overlap to
person A in one frame and B in a later one), fps_320x240 (whole extractor: background, clean-up,
tracking, splines, on the sim source, ``--threads`` OpenCV threads; with one, the learning steps
run in line: a one-core figure), cpu_ms_320x240 (that run's ms of CPU per frame of the calling
thread: with one OpenCV thread, the whole extractor's work, load-robust unlike the fps) and
fps_768x576 (the same on vtest.avi, when present).

Per source (synthetic, vtest, sim), on the same frames:
  * ms per frame of background subtraction: ours (classify + model update) vs OpenCV MOG2 with
    shadow detection (vs KNN too, for reference);
  * ms per frame of the whole extractor (subtraction, clean-up, tracking, B-splines);
  * spline_px: mean distance (pixels) from each person's boundary to their fitted B-spline;
  * where the source has ground truth: foreground precision / recall / F1 per subtractor and the
    fraction of cast-shadow pixels called foreground.
The last stdout line is one JSON object with all figures.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from dataclasses import dataclass
from typing import Any

if __package__ in (None, ""):  # run as a script: make the repository importable
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import cv2
import numpy as np

from counterpart.body.spline import oriented_boundary, spline_distance
from counterpart.nodes.silhouette.backends import make_subtractor
from counterpart.nodes.silhouette.background import SHADOW
from counterpart.nodes.silhouette.body_shadow import BodyShadowConfig
from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor
from counterpart.nodes.silhouette.regions import clean_mask
from counterpart.sim.flat_scenes import two_person_sequence

VTEST = os.environ.get("COUNTERPART_VTEST", "/work/shared/data/video/vtest.avi")
SHARED = os.environ.get("COUNTERPART_SHARED_DATA") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "shared", "data"
)
CDNET = os.path.join(SHARED, "cdnet")
TRAIN_FRAMES = 30
#: the people-in-view starts on CDnet (``people_start_evaluation``): every this many evaluated
#: frames, this many frames long, where at least this share of the first frame is foreground
PEOPLE_START_EVERY = 150
PEOPLE_START_FRAMES = 150
PEOPLE_START_MIN_FG = 0.005
#: frames each extractor runs before the other takes its turn, in the two-core speed figures
SPEED_CHUNK = 30
REAL_BACKENDS = ("horprasert", "mog2", "knn", "gsoc")
#: ours for distant people: the minimum area from the frame size and camera
#: (``SilhouetteExtractor(min_area=None)``); reported as ``*_ours_auto_area``
AUTO_AREA = "horprasert-auto-area"
#: ours without the shadow labels inside a body taken back as foreground (node ``body_shadow_px: 0``,
#: ``body_shadow.BodyShadowConfig(span_px=0)``); reported as ``*_ours_no_body_shadow``
NO_BODY_SHADOW = "horprasert-no-body-shadow"
#: ours without the body-shadow rule's leg step (node ``body_shadow_leg_ncc: -1``,
#: ``BodyShadowConfig(leg_ncc=-1)``); reported as ``*_ours_no_legs``
NO_LEGS = "horprasert-no-legs"
#: ours on the sequence made grey (three equal channels, a grey or infrared camera): as it is (the
#: background found monochrome) and with colour footage's shadow bounds (``mono_chroma_deg: 0``, as
#: before); MOG2 on the grey frames (no shadow detection, as the node runs it on grey frames);
#: reported as ``*_ours_grey``, ``*_ours_grey_colour_bounds``, ``*_mog2_grey``
GREY, GREY_COLOUR_BOUNDS, MOG2_GREY = "horprasert-grey", "horprasert-grey-colour-bounds", "mog2-grey"
#: CDnet ground-truth labels (changedetection.net): positives, negatives (static, hard shadow)
GT_FG, GT_SHADOW, GT_STATIC = 255, 50, 0


@dataclass
class Source:
    """Frames (N, H, W, 3) uint8; optional ground truth: people (N, H, W) bool, shadows (N, H, W) bool."""

    name: str
    frames: np.ndarray
    people: np.ndarray | None = None
    shadows: np.ndarray | None = None


def synthetic_source(n_frames: int) -> Source:
    seq = two_person_sequence(n_frames=max(n_frames - TRAIN_FRAMES, 30), size=(480, 640), empty_frames=TRAIN_FRAMES)
    return Source("synthetic", seq.frames, seq.person_masks.any(axis=1), seq.shadow_masks)


def vtest_source(n_frames: int) -> Source | None:
    if not os.path.isfile(VTEST):
        return None
    cap = cv2.VideoCapture(VTEST)
    frames = []
    while len(frames) < n_frames:
        ok, f = cap.read()
        if not ok:
            break
        frames.append(f)
    cap.release()
    return Source("vtest", np.stack(frames)) if frames else None


@dataclass
class SimSequence:
    """A rendered simulator sequence: frames (N, H, W, 3) uint8 BGR, people (N, 2, H, W) bool
    (A, B visible pixels), shadows (N, H, W) bool (cast shadow on the floor), and the number of
    leading frames that are empty (room only, lit and noised like the rest).
    """

    name: str
    frames: np.ndarray
    people: np.ndarray
    shadows: np.ndarray
    empty_frames: int


def render_sim(
    scenario: str, seed: int, empty_frames: int = 0, max_frames: int | None = None, size: tuple[int, int] = (320, 240)
) -> SimSequence:
    """Render a simulator scenario with ground truth.

    ``empty_frames`` > 0 puts that many frames of the empty room before the scene, at the scene
    times -empty_frames/fps .. -1/fps (so the lighting drift runs on continuously into frame 0),
    with the renderer's sensor noise. ``max_frames`` caps the scene's frames (not counting the
    empty ones).
    """
    from counterpart.sim.stream import open_stream

    st = open_stream(scenario, seed=seed, width=size[0], height=size[1], frames=max_frames)
    r = st.renderer
    n = st.n_frames
    h, w = size[1], size[0]
    frames = np.empty((empty_frames + n, h, w, 3), np.uint8)
    people = np.zeros((empty_frames + n, 2, h, w), bool)
    shadows = np.zeros((empty_frames + n, h, w), bool)
    for k in range(empty_frames):
        t = (k - empty_frames) / st.fps
        img = r.bg * np.float32(r.lighting.gain(t))
        rng = np.random.default_rng([seed, 98, k])
        img += rng.standard_normal(img.shape, dtype=np.float32) * np.float32(r.noise_sigma)
        frames[k] = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    for i in range(n):
        f, truth = r.render(i)
        frames[empty_frames + i] = f
        people[empty_frames + i] = truth.masks
        shadows[empty_frames + i] = truth.shadow
    st.close()
    tag = f"{scenario}:{seed}" + (f"+{empty_frames}empty" if empty_frames else "")
    return SimSequence(tag, frames, people, shadows, empty_frames)


def _assign_truth(labels: np.ndarray, people: list, truth: np.ndarray, min_frac: float = 0.3) -> dict[int, int]:
    """Published person id -> 0 (A) / 1 (B): the truth mask holding most of the person's pixels,
    when it holds at least ``min_frac`` of them (else the person is not mapped this frame).
    """
    out: dict[int, int] = {}
    for p in people:
        mine = labels == p.id + 1
        n = int(mine.sum())
        if n == 0:
            continue
        ov = [int((mine & truth[k]).sum()) for k in range(2)]
        k = int(np.argmax(ov))
        if ov[k] >= min_frac * n:
            out[p.id] = k
    return out


def _f1(tp: float, n_pred: float, n_gt: float) -> tuple[float, float, float]:
    prec = tp / max(n_pred, 1.0)
    rec = tp / max(n_gt, 1.0)
    return prec, rec, 2 * prec * rec / max(prec + rec, 1e-12)


def evaluate_sequence(
    seq: SimSequence, backend: str, train_frames: int = TRAIN_FRAMES, splines: bool = False
) -> dict[str, Any]:
    """Run one backend through ``SilhouetteExtractor`` as the node does and score what it publishes.

    Scored frames: from ``max(empty_frames, train_frames)`` on (every backend has had
    ``train_frames`` frames to learn and the scene has started). Foreground = the published label
    mask (after clean-up, minimum area, tracking); truth = the union of both people's masks, cast
    shadows count as background. Returns tp / predicted / truth pixel counts, shadow pixels
    labelled foreground / shadow pixels, id swaps, and (``splines``) the spline distances.
    """
    params: dict[str, Any] = {}
    if backend == "horprasert":
        # Empty frames to learn from: the plain fit (Horprasert eqs. 1-4); people in view: robust.
        params = {"train_frames": train_frames, "robust": seq.empty_frames < train_frames}
    ex = SilhouetteExtractor(backend=backend, backend_params=params)
    start = max(seq.empty_frames, train_frames)
    tp = n_pred = n_gt = sh_fg = sh_n = 0
    swaps = 0
    last: dict[int, int] = {}
    dists: list[float] = []
    for k, frame in enumerate(seq.frames):
        if backend != "horprasert" and ex.n_frames < train_frames - 1:
            ex.learn(frame)
            continue
        r = ex.process(frame)
        if k < start:
            continue
        fg = r.labels > 0
        gt = seq.people[k].any(axis=0)
        tp += int((fg & gt).sum())
        n_pred += int(fg.sum())
        n_gt += int(gt.sum())
        sh = seq.shadows[k]
        sh_fg += int((fg & sh).sum())
        sh_n += int(sh.sum())
        for pid, who in _assign_truth(r.labels, r.people, seq.people[k]).items():
            if pid in last and last[pid] != who:
                swaps += 1
            last[pid] = who
        if splines:
            for p in r.people:
                if p.ctrl is not None:
                    contour, _ = oriented_boundary(r.labels == p.id + 1)
                    dists.append(spline_distance(contour, p.ctrl))
    return {
        "tp": tp,
        "pred": n_pred,
        "gt": n_gt,
        "shadow_fg": sh_fg,
        "shadow": sh_n,
        "id_swaps": swaps,
        "frames": len(seq.frames) - start,
        "spline_px": dists,
    }


SIM_BACKENDS = ("horprasert", "mog2", "knn", "cnt")


def sim_evaluation(
    scenarios: list[str], seeds: list[int], max_frames: int, backends: tuple[str, ...] = SIM_BACKENDS
) -> dict[str, Any]:
    """Every scenario x seed x start (empty room first / people from frame 0) x backend."""
    per_seq: dict[str, Any] = {}
    keys = ("tp", "pred", "gt", "shadow_fg", "shadow")
    total = {b: dict.fromkeys(keys, 0) for b in backends}
    by_start = {s: {b: dict.fromkeys(keys, 0) for b in backends} for s in ("empty_start", "people_start")}
    swaps = 0
    dists: list[float] = []
    for sc in scenarios:
        for seed in seeds:
            for empty in (TRAIN_FRAMES, 0):
                seq = render_sim(sc, seed, empty_frames=empty, max_frames=max_frames)
                row: dict[str, Any] = {}
                for b in backends:
                    ev = evaluate_sequence(seq, b, splines=b == "horprasert")
                    start = "empty_start" if empty else "people_start"
                    for key in keys:
                        total[b][key] += ev[key]
                        by_start[start][b][key] += ev[key]
                    row[f"f1_{b}"] = round(_f1(ev["tp"], ev["pred"], ev["gt"])[2], 4)
                    if b == "horprasert":
                        row["shadow_as_fg"] = round(ev["shadow_fg"] / max(ev["shadow"], 1), 4)
                        row["id_swaps"] = ev["id_swaps"]
                        if sc in ("handshake", "push"):
                            swaps += ev["id_swaps"]
                        dists.extend(ev["spline_px"])
                per_seq[seq.name] = row
                print(f"sim {seq.name}: {row}", flush=True)

    def summary(t: dict[str, float]) -> dict[str, float]:
        prec, rec, f1 = _f1(t["tp"], t["pred"], t["gt"])
        return {"precision": prec, "recall": rec, "f1": f1, "shadow_as_fg": t["shadow_fg"] / max(t["shadow"], 1)}

    out: dict[str, Any] = {"sequences": per_seq}
    for b in backends:
        out[b] = summary(total[b])
    for start, tot in by_start.items():
        out[start] = {b: summary(tot[b]) for b in backends}
    out["id_swaps_handshake_push"] = swaps
    out["spline_px"] = float(np.mean(dists)) if dists else None
    out["spline_px_p95"] = float(np.percentile(dists, 95)) if dists else None
    return out


def sim_source(n_frames: int) -> Source | None:
    """One simulator sequence (handshake, seed 0, 320x240) as a plain Source, people from frame 0.

    The full simulator evaluation (several scenarios and seeds, with and without empty training
    frames, every backend through the extractor) is ``sim_evaluation``.
    """
    seq = render_sim("handshake", 0, empty_frames=0, max_frames=n_frames)
    return Source("sim", seq.frames, seq.people.any(axis=1), seq.shadows)


SOURCES = {"synthetic": synthetic_source, "vtest": vtest_source, "sim": sim_source}


def load_cdnet(seq_dir: str) -> tuple[np.ndarray, np.ndarray, int, int]:
    """A CDnet sequence: frames (N, H, W, 3) uint8 BGR and ground truth (N, H, W) uint8 of frames
    1..N, N the last evaluated frame, and the first and last evaluated frame numbers (1-based,
    ``temporalROI.txt``; the frames before the first are for learning).
    """
    with open(os.path.join(seq_dir, "temporalROI.txt")) as fh:
        first, last = (int(v) for v in fh.read().split()[:2])
    frames = np.stack([cv2.imread(os.path.join(seq_dir, "input", f"in{i:06d}.jpg")) for i in range(1, last + 1)])
    gt = np.stack(
        [
            cv2.imread(os.path.join(seq_dir, "groundtruth", f"gt{i:06d}.png"), cv2.IMREAD_GRAYSCALE)
            for i in range(1, last + 1)
        ]
    )
    return frames, gt, first, last


def evaluate_real(frames: np.ndarray, gt: np.ndarray, first: int, backend: str) -> dict[str, Any]:
    """See ``_evaluate_real``; ``backend`` AUTO_AREA is ours with ``min_area=None``, GREY,
    GREY_COLOUR_BOUNDS and MOG2_GREY run on the frames made grey.
    """
    if backend in (GREY, GREY_COLOUR_BOUNDS, MOG2_GREY):
        frames = np.stack([cv2.cvtColor(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR) for f in frames])
    if backend == MOG2_GREY:
        ex = SilhouetteExtractor(backend="mog2", backend_params={"detectShadows": False})
    elif backend in (GREY, GREY_COLOUR_BOUNDS):
        params = {"train_frames": TRAIN_FRAMES, **({"mono_chroma_deg": 0.0} if backend == GREY_COLOUR_BOUNDS else {})}
        ex = SilhouetteExtractor(backend_params=params)
    elif backend == AUTO_AREA:
        ex = SilhouetteExtractor(min_area=None, backend_params={"train_frames": TRAIN_FRAMES})
    elif backend in (NO_BODY_SHADOW, NO_LEGS):
        config = BodyShadowConfig(span_px=0) if backend == NO_BODY_SHADOW else BodyShadowConfig(leg_ncc=-1.0)
        ex = SilhouetteExtractor(backend_params={"train_frames": TRAIN_FRAMES, "body_shadow": config})
    else:
        ex = SilhouetteExtractor(
            backend=backend, backend_params={"train_frames": TRAIN_FRAMES} if backend == "horprasert" else {}
        )
    return _evaluate_real(ex, frames, gt, first, backend.startswith("horprasert"))


def _evaluate_real(
    ex: SilhouetteExtractor, frames: np.ndarray, gt: np.ndarray, first: int, ours: bool
) -> dict[str, Any]:
    """Run one backend through ``SilhouetteExtractor`` with the node's defaults (the same clean-up,
    minimum area and tracking for every backend) over all frames from frame 1, and count CDnet's
    way on the evaluated frames (``first`` on, 1-based): the published label mask against label 255
    positive, 0 and 50 negative, 85 (outside the region of interest) and 170 (unknown) ignored.
    Counts are kept apart for the first half of the evaluated frames ("tune") and the second
    ("report"). Shadow counts: the model's SHADOW class against label 50, on the same pixels.
    """
    mid = first + (len(frames) - first + 1) // 2
    keys = ("tp", "fp", "fn", "sh_tp", "sh_fp", "sh_fn")
    out = {half: dict.fromkeys(keys, 0) for half in ("tune", "report")}
    for k, frame in enumerate(frames):
        n = k + 1
        if not ours and ex.n_frames < TRAIN_FRAMES - 1:
            ex.learn(frame)
            continue
        r = ex.process(frame)
        if n < first:
            continue
        c = out["tune" if n < mid else "report"]
        g = gt[k]
        pos = g == GT_FG
        neg = (g == GT_STATIC) | (g == GT_SHADOW)
        fg = r.labels > 0
        c["tp"] += int(np.count_nonzero(fg & pos))
        c["fp"] += int(np.count_nonzero(fg & neg))
        c["fn"] += int(np.count_nonzero(pos & ~fg))
        if r.classes is not None:
            sh = r.classes == SHADOW
            gsh = g == GT_SHADOW
            scored = pos | neg
            c["sh_tp"] += int(np.count_nonzero(sh & gsh))
            c["sh_fp"] += int(np.count_nonzero(sh & scored & ~gsh))
            c["sh_fn"] += int(np.count_nonzero(gsh & ~sh))
    return out


def _f1_counts(tp: int, fp: int, fn: int) -> float:
    return round(_f1(tp, tp + fp, tp + fn)[2], 4)


def real_evaluation(seq_names: list[str] | None = None) -> dict[str, Any] | None:
    """CDnet-protocol F1 of ours, MOG2, KNN and GSOC on the sequences of ``CDNET`` (None when the
    data is absent). Per sequence: ``f1_<backend>`` on the report half (the second half of the
    evaluated frames, never used to tune), ``f1_<backend>_tune`` on the first half, and
    ``shadow_f1`` (ours; ``shadow_f1_mog2`` / ``_knn`` theirs) where the ground truth marks shadows.
    """
    if not os.path.isdir(CDNET):
        return None
    names = seq_names or sorted(
        d for d in os.listdir(CDNET) if os.path.isfile(os.path.join(CDNET, d, "temporalROI.txt"))
    )
    out: dict[str, Any] = {}
    for name in names:
        frames, gt, first, last = load_cdnet(os.path.join(CDNET, name))
        row: dict[str, Any] = {
            "frames": int(last),
            "evaluated": [first, last],
            "split": "tune: first half of the evaluated frames; figures: second half",
        }
        has_shadow = bool(np.any(gt[first - 1 :] == GT_SHADOW))
        for b in (*REAL_BACKENDS, AUTO_AREA, NO_BODY_SHADOW, NO_LEGS, GREY, GREY_COLOUR_BOUNDS, MOG2_GREY):
            t0 = time.perf_counter()
            ev = evaluate_real(frames, gt, first, b)
            tag = {
                "horprasert": "ours",
                AUTO_AREA: "ours_auto_area",
                NO_BODY_SHADOW: "ours_no_body_shadow",
                NO_LEGS: "ours_no_legs",
                GREY: "ours_grey",
                GREY_COLOUR_BOUNDS: "ours_grey_colour_bounds",
                MOG2_GREY: "mog2_grey",
            }.get(b, b)
            for half, suffix in (("report", ""), ("tune", "_tune")):
                c = ev[half]
                row[f"f1_{tag}{suffix}"] = _f1_counts(c["tp"], c["fp"], c["fn"])
                if has_shadow and b in ("horprasert", AUTO_AREA, NO_BODY_SHADOW, NO_LEGS, "mog2", "knn"):
                    key = {
                        "horprasert": "shadow_f1",
                        AUTO_AREA: "shadow_f1_auto_area",
                        NO_BODY_SHADOW: "shadow_f1_no_body_shadow",
                        NO_LEGS: "shadow_f1_no_legs",
                    }.get(b, f"shadow_f1_{b}")
                    row[key + suffix] = _f1_counts(c["sh_tp"], c["sh_fp"], c["sh_fn"])
            row[f"fps_{tag}"] = round(len(frames) / (time.perf_counter() - t0), 1)
        out[name] = row
        print(f"real {name}: {row}", flush=True)
    return out


def people_start_evaluation(seq_names: list[str] | None = None) -> dict[str, Any] | None:
    """CDnet with people in view from the first frame: each sequence started at every
    ``PEOPLE_START_EVERY``-th evaluated frame whose ground truth holds at least
    ``PEOPLE_START_MIN_FG`` of foreground (people standing, or walking past, when the model starts
    to learn), ``PEOPLE_START_FRAMES`` frames from there. Ours fits robustly on the first
    ``TRAIN_FRAMES`` of them, with the people detector (the node's default,
    ``people.fit_around_people``) and without it (``plain``: the per-pixel median alone), and labels
    every frame; MOG2 and KNN learn those frames; all are scored CDnet's way from frame
    ``TRAIN_FRAMES`` of each start on, pooled over the starts. None when the data is absent.
    """
    if not os.path.isdir(CDNET):
        return None
    names = seq_names or sorted(
        d for d in os.listdir(CDNET) if os.path.isfile(os.path.join(CDNET, d, "temporalROI.txt"))
    )
    backends = {
        "ours": lambda: SilhouetteExtractor(backend_params={"train_frames": TRAIN_FRAMES}),
        "plain": lambda: SilhouetteExtractor(backend_params={"train_frames": TRAIN_FRAMES, "people_aware": False}),
        "mog2": lambda: SilhouetteExtractor(backend="mog2"),
        "knn": lambda: SilhouetteExtractor(backend="knn"),
    }
    pooled = {b: [0, 0, 0] for b in backends}
    out: dict[str, Any] = {}
    for name in names:
        frames, gt, first, last = load_cdnet(os.path.join(CDNET, name))
        starts = [
            a
            for a in range(first, last - PEOPLE_START_FRAMES + 2, PEOPLE_START_EVERY)
            if np.mean(gt[a - 1] == GT_FG) >= PEOPLE_START_MIN_FG
        ]
        row: dict[str, Any] = {"starts": starts}
        for b, make in backends.items():
            tp = fp = fn = 0
            for a in starts:
                ex = make()
                seg = frames[a - 1 : a - 1 + PEOPLE_START_FRAMES]
                c = _evaluate_real(
                    ex, seg, gt[a - 1 : a - 1 + PEOPLE_START_FRAMES], TRAIN_FRAMES + 1, b in ("ours", "plain")
                )
                tp += c["tune"]["tp"] + c["report"]["tp"]
                fp += c["tune"]["fp"] + c["report"]["fp"]
                fn += c["tune"]["fn"] + c["report"]["fn"]
            row[f"f1_people_start_{b}"] = _f1_counts(tp, fp, fn)
            for i, v in enumerate((tp, fp, fn)):
                pooled[b][i] += v
        out[name] = row
        print(f"real people start {name}: {row}", flush=True)
    for b, (tp, fp, fn) in pooled.items():
        out[f"f1_people_start_{b}"] = _f1_counts(tp, fp, fn)
    return out


def speed_two_cores(frames: np.ndarray, opencv_threads: int = 2) -> dict[str, float]:
    """Frames per second of the whole extractor (background, clean-up, tracking, B-splines) with
    ``opencv_threads`` OpenCV threads (two: two cores; one: our worker thread is the second),
    ours and with MOG2 as its backend, on the same frames in the same run.

    After the training frames the two take turns every ``SPEED_CHUNK`` frames, each on its own
    frames in order, so a change of the machine's load in the middle of the run slows both; fps
    is one over the median time per frame. ``ratio``: ours over MOG2's. ``cpu_main_<name>`` and
    ``cpu_process_<name>``: ms of CPU per frame of the calling thread (the critical path when the
    worker thread has a core of its own) and of the whole process (all threads; a learning step
    still running when a chunk ends counts in the next chunk, of either extractor), from the
    threads' CPU clocks, which a loaded machine changes far less than the wall clock.
    """
    threads = cv2.getNumThreads()
    cv2.setNumThreads(opencv_threads)
    try:
        exs = {
            "ours": SilhouetteExtractor(backend="horprasert", backend_params={"train_frames": TRAIN_FRAMES}),
            "mog2": SilhouetteExtractor(backend="mog2"),
        }
        times: dict[str, list[float]] = {name: [] for name in exs}
        cpu = {name: np.zeros(2) for name in exs}  # seconds: calling thread, process
        for ex in exs.values():
            for f in frames[:TRAIN_FRAMES]:
                ex.process(f)
        for k0 in range(TRAIN_FRAMES, len(frames), SPEED_CHUNK):
            for name, ex in exs.items():
                c0 = np.array([time.thread_time(), time.process_time()])
                for f in frames[k0 : k0 + SPEED_CHUNK]:
                    t0 = time.perf_counter()
                    ex.process(f)
                    times[name].append(time.perf_counter() - t0)
                cpu[name] += np.array([time.thread_time(), time.process_time()]) - c0
        out = {name: round(1.0 / float(np.median(t)), 1) for name, t in times.items()}
        out["ratio"] = round(out["ours"] / out["mog2"], 3)
        for name, (main, proc) in cpu.items():
            out[f"cpu_main_{name}"] = round(1e3 * main / len(times[name]), 3)
            out[f"cpu_process_{name}"] = round(1e3 * proc / len(times[name]), 3)
        return out
    finally:
        cv2.setNumThreads(threads)


def _cpu_figures(two: dict[str, float], tag: str = "") -> dict[str, float]:
    """``speed_two_cores``'s CPU figures under the JSON's names: ``cpu_ms_main_2cores`` and
    ``cpu_ms_process_2cores`` (ours), ``*_mog2`` (MOG2's), each name ending in ``tag``.
    """
    return {
        f"cpu_ms_{kind}_2cores{suffix}{tag}": two[f"cpu_{kind}_{name}"]
        for name, suffix in (("ours", ""), ("mog2", "_mog2"))
        for kind in ("main", "process")
    }


def _two_core_figures(frames: np.ndarray) -> dict[str, float]:
    """``speed_two_cores`` with two OpenCV threads, then with one (names ending ``_cv1``), under
    the JSON's names.
    """
    out: dict[str, float] = {}
    for threads, tag in ((2, ""), (1, "_cv1")):
        two = speed_two_cores(frames, threads)
        out[f"fps_320x240_2cores{tag}"] = two["ours"]
        out[f"fps_320x240_2cores_mog2{tag}"] = two["mog2"]
        out[f"fps_ratio_mog2{tag}"] = two["ratio"]
        out.update(_cpu_figures(two, tag))
    return out


def _time_subtractor(name: str, frames: np.ndarray, truth: Source) -> dict[str, Any]:
    params = {"train_frames": TRAIN_FRAMES} if name == "horprasert" else {}
    sub = make_subtractor(name, **params)
    times, masks, labels = [], [], []
    for f in frames:
        t0 = time.perf_counter()
        m = sub.apply(f)
        times.append(time.perf_counter() - t0)
        masks.append(m)
        labels.append(sub.labels)
    # Timed frames: after the warm-up (ours trains on the first TRAIN_FRAMES frames).
    out: dict[str, Any] = {"ms_per_frame": 1e3 * float(np.median(times[TRAIN_FRAMES:]))}
    if truth.people is not None:
        pred = np.stack(masks[TRAIN_FRAMES:])
        clean = np.stack([clean_mask(m, 3, 7, True, 300) for m in masks[TRAIN_FRAMES:]])
        gt = truth.people[TRAIN_FRAMES:]
        for key, p in (("raw", pred), ("clean", clean)):
            tp = float((p & gt).sum())
            prec = tp / max(float(p.sum()), 1.0)
            rec = tp / max(float(gt.sum()), 1.0)
            out[f"{key}_precision"] = prec
            out[f"{key}_recall"] = rec
            out[f"{key}_f1"] = 2 * prec * rec / max(prec + rec, 1e-12)
        if truth.shadows is not None:
            sh = truth.shadows[TRAIN_FRAMES:]
            out["shadow_as_foreground"] = float(pred[sh].mean()) if sh.any() else None
    return out


def _time_extractor(frames: np.ndarray) -> dict[str, Any]:
    """Time the extractor in a loop of its own, then check its splines on a second run over the same
    frames (the algorithm is deterministic): measuring the splines between timed frames evicted the
    extractor's arrays from the caches and added about a fifth to its time, for work a node never does.
    """
    # one OpenCV thread: a one-core figure, so the models' learning steps run in line too
    threaded = cv2.getNumThreads() > 1
    params = {"train_frames": TRAIN_FRAMES, "threaded": threaded, "sample_params": {"threaded": threaded}}
    ex = SilhouetteExtractor(backend="horprasert", backend_params=params)
    times, cpu = [], 0.0
    for k, f in enumerate(frames):
        c0, t0 = time.thread_time(), time.perf_counter()
        ex.process(f)
        times.append(time.perf_counter() - t0)
        if k >= TRAIN_FRAMES:
            cpu += time.thread_time() - c0
    ex = SilhouetteExtractor(backend="horprasert", backend_params={"train_frames": TRAIN_FRAMES})
    dists, counts = [], []
    for f in frames:
        r = ex.process(f)
        counts.append(len(r.people))
        for p in r.people:
            if p.ctrl is None:
                continue
            contour, _ = oriented_boundary(r.labels == p.id + 1)
            dists.append(spline_distance(contour, p.ctrl))
    return {
        "extractor_ms_per_frame": 1e3 * float(np.median(times[TRAIN_FRAMES:])),
        "extractor_cpu_ms_per_frame": 1e3 * cpu / max(len(frames) - TRAIN_FRAMES, 1),
        "spline_px": float(np.mean(dists)) if dists else None,
        "spline_px_p95": float(np.percentile(dists, 95)) if dists else None,
        "people_per_frame": float(np.mean(counts[TRAIN_FRAMES:])),
        "max_people": int(max(counts)),
    }


def run(
    source_names: list[str], n_frames: int, scenarios: list[str], seeds: list[int], sim_frames: int, real: bool = True
) -> dict[str, Any]:
    report: dict[str, Any] = {
        "bench": "silhouette",
        "cpu_threads": cv2.getNumThreads(),
        "machine": platform.machine(),
        "frames_requested": n_frames,
        "sources": {},
    }
    for name in source_names:
        src = SOURCES[name](n_frames)
        if src is None:
            report["sources"][name] = {"available": False}
            print(f"{name}: not available, skipped", flush=True)
            continue
        h, w = src.frames.shape[1:3]
        res: dict[str, Any] = {"available": True, "frames": int(len(src.frames)), "size": [int(h), int(w)]}
        for sub in ("horprasert", "mog2", "knn"):
            res[sub] = _time_subtractor(sub, src.frames, src)
        res.update(_time_extractor(src.frames))
        res["speedup_vs_mog2"] = res["mog2"]["ms_per_frame"] / res["horprasert"]["ms_per_frame"]
        report["sources"][name] = res
        print(
            f"{name} {w}x{h}, {len(src.frames)} frames: horprasert {res['horprasert']['ms_per_frame']:.1f} ms, "
            f"mog2 {res['mog2']['ms_per_frame']:.1f} ms, knn {res['knn']['ms_per_frame']:.1f} ms, "
            f"extractor {res['extractor_ms_per_frame']:.1f} ms, spline_px {res['spline_px']}",
            flush=True,
        )
    srcs = report["sources"]
    if "sim" in source_names and scenarios and seeds:
        ev = sim_evaluation(scenarios, seeds, sim_frames)
        report["sim_evaluation"] = ev
        for b, key in (("horprasert", "f1_ours"), ("mog2", "f1_mog2"), ("knn", "f1_knn"), ("cnt", "f1_cnt")):
            report[key] = round(ev[b]["f1"], 4)
            for start in ("empty_start", "people_start"):
                report[f"{key}_{start}"] = round(ev[start][b]["f1"], 4)
        report["shadow_as_fg"] = round(ev["horprasert"]["shadow_as_fg"], 4)
        for start in ("empty_start", "people_start"):
            report[f"shadow_as_fg_{start}"] = round(ev[start]["horprasert"]["shadow_as_fg"], 4)
        report["spline_px"] = round(ev["spline_px"], 4) if ev["spline_px"] is not None else None
        report["id_swaps"] = ev["id_swaps_handshake_push"]
        report["sim_sequences"] = len(ev["sequences"])
    if srcs.get("sim", {}).get("available"):
        report["fps_320x240"] = round(1e3 / srcs["sim"]["extractor_ms_per_frame"], 1)
        report["cpu_ms_320x240"] = round(srcs["sim"]["extractor_cpu_ms_per_frame"], 3)
        report.update(_two_core_figures(sim_source(n_frames).frames))
    if real:
        ev_real = real_evaluation()
        if ev_real is not None:
            report["real"] = ev_real
        starts = people_start_evaluation()
        if starts is not None:
            report["real_people_start"] = starts
            for b in ("ours", "plain", "mog2", "knn"):
                key = "f1_people_start" if b == "ours" else f"f1_people_start_{b}"
                report[key] = starts[f"f1_people_start_{b}"]
    if srcs.get("vtest", {}).get("available"):
        report["fps_768x576"] = round(1e3 / srcs["vtest"]["extractor_ms_per_frame"], 1)
    return report


def speed_report(n_frames: int) -> dict[str, Any]:
    """The speed figures alone, on the sim source: ``fps_320x240`` (whole extractor with splines,
    the OpenCV threads set by ``--threads``) and ``cpu_ms_320x240`` (its calling thread's CPU ms per
    frame), ``fps_320x240_2cores`` and ``fps_320x240_2cores_mog2``
    (two threads, ours and MOG2 as the backend, same frames, same run), and the 1-minute load
    average before and after, since wall-clock medians are only comparable on an idle machine.
    """
    frames = sim_source(n_frames).frames
    load0 = os.getloadavg()[0]
    one = _time_extractor(frames)
    two = _two_core_figures(frames)
    return {
        "bench": "silhouette",
        "cpu_threads": cv2.getNumThreads(),
        "machine": platform.machine(),
        "frames_requested": n_frames,
        "fps_320x240": round(1e3 / one["extractor_ms_per_frame"], 1),
        "cpu_ms_320x240": round(one["extractor_cpu_ms_per_frame"], 3),
        **two,
        "load_1min": [round(load0, 2), round(os.getloadavg()[0], 2)],
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--source", choices=[*SOURCES, "all"], default="all")
    ap.add_argument("--frames", type=int, default=150, help="frames per source, including 30 for training")
    ap.add_argument(
        "--scenarios",
        default="handshake,push,wave,conversation",
        help="simulator scenarios of the quality evaluation (comma-separated)",
    )
    ap.add_argument("--seeds", default="0,1,2", help="simulator seeds (comma-separated)")
    ap.add_argument("--sim-frames", type=int, default=250, help="cap on each simulator sequence's frames")
    ap.add_argument("--threads", type=int, default=1, help="OpenCV threads (1: the one-core figures)")
    ap.add_argument("--no-real", action="store_true", help="skip the real-footage (CDnet) evaluation")
    ap.add_argument("--real-only", action="store_true", help="only the real-footage (CDnet) evaluation")
    ap.add_argument(
        "--speed-only", action="store_true", help="only the speed figures (fps_320x240, *_2cores, beside MOG2)"
    )
    ap.add_argument("--out", help="also write the JSON report to this file")
    args = ap.parse_args(argv)
    if args.frames <= TRAIN_FRAMES + 1:
        ap.error(f"--frames must be > {TRAIN_FRAMES + 1} (the first {TRAIN_FRAMES} train the model)")
    cv2.setNumThreads(args.threads)
    names = list(SOURCES) if args.source == "all" else [args.source]
    scenarios = [s for s in args.scenarios.split(",") if s]
    seeds = [int(s) for s in args.seeds.split(",") if s]
    if args.speed_only:
        report = speed_report(args.frames)
        print(json.dumps(report))
        return 0
    if args.real_only:
        names, scenarios = [], []
    report = run(names, args.frames, scenarios, seeds, args.sim_frames, real=not args.no_real)
    line = json.dumps(report)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(line + "\n")
    print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
