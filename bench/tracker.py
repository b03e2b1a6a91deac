"""Benchmark of the tracker on simulator video: accuracy of the annealed particle filter against
a plain particle filter with the same likelihood evaluations, and speed on one core.

    python bench/tracker.py [--frames 200] [--scenarios handshake push wave cmu] [--prior PATH]
                            [--seeds 0 1 2] [--scene-seeds 0]

Person A (the left one) of each scenario (simulator seed 0, or each of ``--scene-seeds``: tune on
other seeds than the bench's; the default prior is trained on seeds 100-102) is tracked from the
rendered frames (edge term) and the simulator's visible-pixel masks (silhouette term), once per
tracker seed (``--seeds``): a particle filter's run is chaotic, and one seed's pooled error differs
from another's by several millimetres, so the figures are means over seeds.
The last stdout line is one JSON object: mpjpe_mm (mean per-joint position error of the APF,
10 x 256, mean over seeds), reproj_px (mean 2D error of its projected joints), mpjpe_pf_mm (plain
PF of 2,560 particles), ratio (mpjpe_mm / mpjpe_pf_mm), the per-seed values (mpjpe_mm_per_seed,
mpjpe_pf_mm_per_seed), ms_per_frame (APF, per person and frame, one thread; median over seeds),
us_per_eval (likelihood time per particle), max_err_mm_last100 (worst frame error over each
sequence's last 100 frames, any seed), frames (per seed).
"""
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from typing import TYPE_CHECKING  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

cv2.setNumThreads(1)

if TYPE_CHECKING:
    from nodes.tracker.tracker import Tracker


def _track_timed(trk: Tracker, frames: list[np.ndarray], masks: list[np.ndarray]) -> tuple[np.ndarray, float, int]:
    """Track a sequence -> joints (T, 14, 3) (NaN where nobody was in view), seconds spent on the
    frames after the first (the first is the track's longer initial search) and their count."""
    est = np.full((len(frames), 14, 3), np.nan)
    t_sum, n = 0.0, 0
    for i, (img, m) in enumerate(zip(frames, masks)):
        t0 = time.perf_counter()
        r = trk.update(img, m)
        dt = time.perf_counter() - t0
        if r is not None:
            est[i] = r.joints
            if i > 0:
                t_sum += dt
                n += 1
    return est, t_sum, n


def main() -> int:
    from nodes.tracker.likelihood import ConeLikelihood, make_observation
    from nodes.tracker.prior import MotionPrior, load_default_prior
    from nodes.tracker.tracker import Tracker
    from sim.stream import open_stream

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=200, help="frames per scenario at most")
    ap.add_argument("--scenarios", nargs="+", default=["handshake", "push", "wave", "cmu"])
    ap.add_argument("--prior", default="default", help="prior .npz, 'default' or 'none'")
    ap.add_argument("--layers", type=int, default=10)
    ap.add_argument("--particles", type=int, default=256)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="tracker seeds (runs per filter)")
    ap.add_argument("--scene-seeds", type=int, nargs="+", default=[0],
                    help="simulator seeds of the sequences")
    args = ap.parse_args()
    prior = None if args.prior == "none" else load_default_prior(progress=True) if args.prior == "default" \
        else MotionPrior.load(args.prior)

    errs: dict[tuple[str, int], list[np.ndarray]] = {}
    reproj, last100, times = [], [], {}
    n_total = 0
    for name, scene_seed in ((n, s) for n in args.scenarios for s in args.scene_seeds):
        try:
            stream = open_stream(name, seed=scene_seed, frames=args.frames)
        except (ValueError, FileNotFoundError) as exc:
            print(f"skipping {name}:{scene_seed}: {exc}", file=sys.stderr)
            continue
        frames, masks, truth3, truth2 = [], [], [], []
        for i in range(stream.n_frames):
            img, tr = stream.render_with_truth(i)
            frames.append(img)
            masks.append(tr.masks[0])
            truth3.append(tr.joints3d[0])
            truth2.append(tr.joints2d[0])
        truth3, truth2 = np.array(truth3), np.array(truth2)
        cam = stream.camera
        for seed in args.seeds:
            for kind in ("apf", "pf"):
                trk = Tracker(cam, "left", args.layers, args.particles, prior=prior, plain=kind == "pf",
                              seed=seed)
                est, t_sum, n = _track_timed(trk, frames, masks)
                e = np.linalg.norm(est - truth3, axis=-1).mean(axis=1)
                errs.setdefault((kind, seed), []).append(e)
                if kind == "apf":
                    t, k = times.get(seed, (0.0, 0))
                    times[seed] = (t + t_sum, k + n)
                    reproj.append(np.linalg.norm(cam.project(est) - truth2, axis=-1).mean(axis=1))
                    last100.append(np.nanmax(e[-100:]))
                print(f"{name}:{scene_seed} seed {seed} {kind}: {len(e)} frames, "
                      f"mpjpe {np.nanmean(e) * 1e3:.1f} mm", file=sys.stderr)
        n_total += len(frames)

    # likelihood cost per particle evaluation
    obs = make_observation(frames[0], masks[0])
    L = ConeLikelihood(cam)
    from body.pose import neutral_pose
    P = neutral_pose()[None] + np.random.default_rng(0).normal(size=(args.particles, 28)) * 0.05
    L(P, obs)
    t0 = time.perf_counter()
    for _ in range(50):
        L(P, obs)
    us_per_eval = (time.perf_counter() - t0) / (50 * args.particles) * 1e6

    per_seed = {kind: [float(np.nanmean(np.concatenate(errs[kind, seed]))) * 1e3 for seed in args.seeds]
                for kind in ("apf", "pf")}
    apf, pf = float(np.mean(per_seed["apf"])), float(np.mean(per_seed["pf"]))
    res = {
        "mpjpe_mm": round(apf, 1),
        "reproj_px": round(float(np.nanmean(np.concatenate(reproj))), 2),
        "mpjpe_pf_mm": round(pf, 1),
        "ratio": round(apf / pf, 3),
        "mpjpe_mm_per_seed": [round(x, 1) for x in per_seed["apf"]],
        "mpjpe_pf_mm_per_seed": [round(x, 1) for x in per_seed["pf"]],
        "ms_per_frame": round(float(np.median([t / max(1, n) for t, n in times.values()])) * 1e3, 1),
        "us_per_eval": round(us_per_eval, 2),
        "max_err_mm_last100": round(float(np.max(last100)) * 1e3, 1),
        "frames": n_total,
        "layers": args.layers, "particles": args.particles, "seeds": args.seeds,
        "scene_seeds": args.scene_seeds,
        "scenarios": args.scenarios, "prior": args.prior,
        "load_average": round(os.getloadavg()[0], 2),
    }
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
