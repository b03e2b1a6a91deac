"""Benchmark of the silhouette node's algorithms: speed and quality, ours (Horprasert) vs MOG2.

Usage: python bench/silhouette.py [--source synthetic|vtest|sim|all] [--frames N] [--out FILE]

For each data source, on the same frames:
  * ms per frame of background subtraction: ours (classify + model update) vs OpenCV MOG2 with
    shadow detection (vs KNN too, for reference);
  * ms per frame of the whole extractor (subtraction, clean-up, tracking, B-splines);
  * spline_px: mean distance (pixels) from each person's boundary to their fitted B-spline;
  * where the source has ground truth (synthetic; the simulator, once wired in): foreground
    precision / recall / F1 per subtractor and the fraction of cast-shadow pixels called
    foreground.
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

from nodes.silhouette.backends import make_subtractor
from nodes.silhouette.pipeline import SilhouetteExtractor
from nodes.silhouette.regions import clean_mask
from body.spline import oriented_boundary, spline_distance
from nodes.silhouette.synthetic import two_person_sequence

VTEST = os.environ.get("COUNTERPART_VTEST", "/work/shared/data/video/vtest.avi")
TRAIN_FRAMES = 30


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


def sim_source(n_frames: int) -> Source | None:
    """TODO: frames with ground-truth person and shadow masks from the project simulator (sim/).

    Wire this to the simulator's renderer once it exists: return
    Source("sim", frames (N, H, W, 3) uint8 BGR, people (N, H, W) bool, shadows (N, H, W) bool),
    with the first TRAIN_FRAMES frames either empty or with people walking (the robust fit
    copes with both). Until then the source is reported as unavailable.
    """
    return None


SOURCES = {"synthetic": synthetic_source, "vtest": vtest_source, "sim": sim_source}


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
    ex = SilhouetteExtractor(backend="horprasert", backend_params={"train_frames": TRAIN_FRAMES})
    times, dists, counts = [], [], []
    for f in frames:
        t0 = time.perf_counter()
        r = ex.process(f)
        times.append(time.perf_counter() - t0)
        counts.append(len(r.people))
        for p in r.people:
            if p.ctrl is None:
                continue
            contour, _ = oriented_boundary(r.labels == p.id + 1)
            dists.append(spline_distance(contour, p.ctrl))
    return {
        "extractor_ms_per_frame": 1e3 * float(np.median(times[TRAIN_FRAMES:])),
        "spline_px": float(np.mean(dists)) if dists else None,
        "spline_px_p95": float(np.percentile(dists, 95)) if dists else None,
        "people_per_frame": float(np.mean(counts[TRAIN_FRAMES:])),
        "max_people": int(max(counts)),
    }


def run(source_names: list[str], n_frames: int) -> dict[str, Any]:
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
    return report


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--source", choices=[*SOURCES, "all"], default="all")
    ap.add_argument("--frames", type=int, default=150, help="frames per source, including 30 for training")
    ap.add_argument("--out", help="also write the JSON report to this file")
    args = ap.parse_args(argv)
    if args.frames <= TRAIN_FRAMES + 1:
        ap.error(f"--frames must be > {TRAIN_FRAMES + 1} (the first {TRAIN_FRAMES} train the model)")
    names = list(SOURCES) if args.source == "all" else [args.source]
    report = run(names, args.frames)
    line = json.dumps(report)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(line + "\n")
    print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
