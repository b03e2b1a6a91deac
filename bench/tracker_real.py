"""CPU time of the tracker node's per-frame work on a real clip, at a fixed search, offline.

    python bench/tracker_real.py [--clip 0_1_4] [--layers 2] [--particles 112] [--reps 3] [--poses OUT.npy]

The clip (``../shared/data/ut_interaction/set1``) is read as the real-time graph reads it (frames
scaled to 320 pixels wide, ``launch/demo.yaml``), its silhouettes extracted once (Horprasert, the
background fitted robustly on the first 20 frames, no sample-consensus model, the leg step on 2 x 2
blocks) and its camera estimated from the people (``apps.calibration``); none of that is timed.
Then, ``--reps`` times, both sides are tracked frame by frame as the tracker node does it
(``nodes/tracker/node.py``: the frame's edges once, each side's ``begin``, the joint search of
both, one kinematics for the estimates, ``end``) with ``--layers`` x ``--particles`` on every frame
(no budget; the demo's budget settles near 2 x 110 on these clips), and each frame's handling is
timed in the process's CPU time. The default motion prior, seeds 0 and 1 as the node's.

Last stdout line, one JSON object: ``cpu_ms_per_frame`` (median over the reps of the median over
the steady frames, those with both sides tracked past their first search), ``cpu_ms_per_frame_min``
(the least rep's), ``cpu_ms_per_rep`` and ``frames``, ``steady_frames``, and ``poses_sha1`` (of
the estimated poses, (T, 2, 28) float64, NaN where a side is absent): the same digest before and
after a change means the same output to the last bit. ``--poses`` saves them.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import hashlib  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

cv2.setNumThreads(1)

CLIPS = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "ut_interaction" / "set1"


def record(clip: Path) -> tuple[list[np.ndarray], list[tuple[np.ndarray, list[tuple[str, int, tuple]]]], Any]:
    """The clip's frames at 320 pixels wide, each frame's labels and people (side, id, bbox), and
    the camera estimated from the people in it.
    """
    from counterpart.apps.calibration import calibrate_video
    from counterpart.body.camera import camera_for_size
    from counterpart.nodes.camera.pacing import convert, output_size
    from counterpart.nodes.silhouette.body_shadow import BodyShadowConfig
    from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor

    cap = cv2.VideoCapture(str(clip))
    frames = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        frames.append(convert(f, output_size((f.shape[1], f.shape[0]), 320))[0])
    if not frames:
        raise SystemExit(f"{clip}: no frame decodes")
    est, _ = calibrate_video(clip, train_frames=20)
    camera = camera_for_size(est.camera(), frames[0].shape[1], frames[0].shape[0])
    ex = SilhouetteExtractor(
        backend="horprasert", backend_params={"dynamic": False, "body_shadow": BodyShadowConfig(leg_scale=2)}
    )
    ex.fit_background(frames[:20], robust=True)
    recs = []
    for f in frames:
        r = ex.process(f)
        recs.append((r.labels.copy(), [(p.side, p.id, tuple(p.bbox)) for p in r.people]))
    return frames, recs, camera


def track(frames: list, recs: list, camera: Any, prior: Any, layers: int, particles: int) -> tuple[np.ndarray, list]:
    """Both sides tracked as the node does it -> poses (T, 2, 28) and per frame (CPU s, steady)."""
    from counterpart.nodes.tracker.likelihood import frame_edges
    from counterpart.nodes.tracker.tracker import (
        SIDES,
        APFConfig,
        Tracker,
        TrackerConfig,
        joints_jointly,
        search_jointly,
    )

    trackers: dict[str, Tracker] = {}
    poses = np.full((len(frames), 2, 28), np.nan)
    cpu = []
    for t, (image, (labels, people)) in enumerate(zip(frames, recs)):
        c0 = time.process_time()
        in_view = [s for s in SIDES if any(p[0] == s for p in people)]
        edges = frame_edges(image) if len(in_view) > 1 else None
        begun = []
        for side in in_view:
            pid = next(p[1] for p in people if p[0] == side)
            if side not in trackers:
                config = TrackerConfig(apf=APFConfig(n_layers=layers, n_particles=particles))
                trackers[side] = Tracker(camera, side, config, prior=prior, seed=SIDES.index(side))
            tr = trackers[side]
            other = next((p[2] for p in people if p[0] != side and p[0] in SIDES), None)
            try:
                search = tr.begin(image, labels == pid + 1, other, edges, None)
            except ValueError:  # a region that cannot be placed: that side skips the frame
                continue
            if search is not None:
                begun.append((side, tr, search, tr.tracking))
        ests = search_jointly([b[1] for b in begun], [b[2] for b in begun])
        joints = joints_jointly([b[1] for b in begun], ests)
        for (side, tr, search, _), est, j in zip(begun, ests, joints):
            poses[t, SIDES.index(side)] = tr.end(search, est, j).pose
        cpu.append((time.process_time() - c0, len(begun) == 2 and all(b[3] for b in begun)))
    return poses, cpu


def main() -> None:
    from counterpart.nodes.tracker.prior import resolve_prior

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--clip", default="0_1_4", help="a clip of the set (its stem) or a video file")
    ap.add_argument("--layers", type=int, default=2)
    ap.add_argument("--particles", type=int, default=112)
    ap.add_argument("--reps", type=int, default=3, help="runs over the clip (the timing's median of them)")
    ap.add_argument("--poses", default="", help="save the estimated poses (.npy)")
    args = ap.parse_args()
    clip = Path(args.clip) if Path(args.clip).suffix else CLIPS / f"{args.clip}.avi"
    if not clip.exists():
        raise SystemExit(f"{clip}: not found (the real clips are in {CLIPS})")
    frames, recs, camera = record(clip)
    prior = resolve_prior("default")
    per_rep, digest, steady = [], "", 0
    for _ in range(args.reps):
        poses, cpu = track(frames, recs, camera, prior, args.layers, args.particles)
        st = [c for c, s in cpu if s]
        steady = len(st)
        per_rep.append(float(np.median(st)) * 1e3 if st else float("nan"))
        digest = hashlib.sha1(np.ascontiguousarray(poses).tobytes()).hexdigest()
        print(f"rep: median {per_rep[-1]:.2f} ms CPU per frame over {steady} steady frames", flush=True)
    if args.poses:
        np.save(args.poses, poses)
    print(
        json.dumps(
            {
                "clip": clip.stem,
                "layers": args.layers,
                "particles": args.particles,
                "frames": len(frames),
                "steady_frames": steady,
                "cpu_ms_per_frame": round(float(np.median(per_rep)), 2),
                "cpu_ms_per_frame_min": round(float(np.min(per_rep)), 2),
                "cpu_ms_per_rep": [round(x, 2) for x in per_rep],
                "poses_sha1": digest,
            }
        )
    )


if __name__ == "__main__":
    main()
