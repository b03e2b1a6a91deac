"""Benchmark of the tracker on simulator video: accuracy of the annealed particle filter against
a plain particle filter with the same likelihood evaluations, and speed on one core.

    python bench/tracker.py [--frames 200] [--scenarios handshake push wave cmu] [--prior PATH]
                            [--seeds 0 1 2] [--scene-seeds 0] [--views 1]

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

``hmm_fit``: the default prior's HMM (30 states, full covariances, 25 iterations, its PCA
coefficients of the simulator's training sequences) fitted by the project's
``counterpart.body.gaussian_hmm`` and by hmmlearn's own ``GaussianHMM`` in the same run: seconds
of one core each (``ours_s``, ``hmmlearn_s``), their ratio (``speedup``) and the largest difference
of the fitted means and covariances relative to their scale (``max_rel_diff``: the same model);
``--no-hmm-fit`` leaves it out.

``--views 2`` or ``3`` adds the cameras of ``EXTRA_EYES`` (the scene rendered from the side and from
behind, aimed at person A): the tracker's likelihood sums over the views as in Deutscher et al.'s
three-camera set-up. The figures stay those of person A against the truth; reproj_px is in the
first (the default) camera. It shows what the one camera's ambiguities (depth, heading, limbs
towards the camera) cost each filter.
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
    from counterpart.nodes.tracker.tracker import Tracker
    from counterpart.sim.stream import SimStream

#: camera positions (metres) of the extra views of ``--views``: left of the scene and behind-left,
#: 2-2.2 m high, aimed at person A's place (-0.5, 0.9, 0); person B does not hide A from either
EXTRA_EYES = ((-3.8, 2.0, 1.2), (-2.5, 2.2, -3.2))


def _render_views(stream: SimStream, seed: int, views: int) -> tuple[list, list, np.ndarray, np.ndarray, list]:
    """Frames and person A's masks (per frame: arrays with one view, lists of ``views`` with more),
    person A's true joints (T, 14, 3) metres and their projections (T, 14, 2) in the first view.
    """
    from counterpart.body.camera import Camera
    from counterpart.sim.render import Renderer

    cams = [stream.camera] + [
        Camera.look_at(eye, (-0.5, 0.9, 0.0), 55.0, *stream.size) for eye in EXTRA_EYES[: views - 1]
    ]
    extra = [Renderer(stream.scenario, cam, seed=seed) for cam in cams[1:]]
    frames, masks, truth3, truth2 = [], [], [], []
    for i in range(stream.n_frames):
        img, tr = stream.render_with_truth(i)
        truth3.append(tr.joints3d[0])
        truth2.append(tr.joints2d[0])
        if not extra:
            frames.append(img)
            masks.append(tr.masks[0])
            continue
        rendered = [(img, tr)] + [r.render(i) for r in extra]
        frames.append([im for im, _ in rendered])
        masks.append([t.masks[0] for _, t in rendered])
    return frames, masks, np.array(truth3), np.array(truth2), cams


def _track_timed(trk: Tracker, frames: list, masks: list) -> tuple[np.ndarray, float, int]:
    """Track a sequence -> joints (T, 14, 3) (NaN where nobody was in view), seconds spent on the
    frames after the first (the first is the track's longer initial search) and their count.
    """
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


def hmm_fit_figures() -> dict:
    """The default prior's HMM fitted by ours and by hmmlearn's GaussianHMM (see the docstring)."""
    from hmmlearn.hmm import GaussianHMM

    from counterpart.body.gaussian_hmm import full_gaussian_hmm
    from counterpart.nodes.tracker.prior import DEFAULT_TRAINING, MotionPrior, load_sequences

    seqs, names = load_sequences(DEFAULT_TRAINING, 25.0)
    # the PCA only (an HMM of one state): the coefficients the default prior's HMM is fitted to
    pca = MotionPrior(n_states=1, seed=0).fit(seqs, names)
    Y, lengths = pca.to_latent(np.concatenate(seqs)), [len(q) for q in seqs]
    settings = {"n_components": 30, "n_iter": 25, "min_covar": 1e-4, "random_state": 0}
    fits = {}
    for name, make in (
        ("ours", lambda: full_gaussian_hmm(**settings)),
        ("hmmlearn", lambda: GaussianHMM(covariance_type="full", **settings)),
    ):
        t0 = time.process_time()
        fits[name] = (make().fit(Y, lengths), time.process_time() - t0)
    (a, ta), (b, tb) = fits["ours"], fits["hmmlearn"]
    diff = max(float(np.abs(x - y).max() / np.abs(y).max()) for x, y in ((a.means_, b.means_), (a.covars_, b.covars_)))
    return {
        "ours_s": round(ta, 2),
        "hmmlearn_s": round(tb, 2),
        "speedup": round(tb / ta, 2),
        "max_rel_diff": float(f"{diff:.2e}"),
        "frames": len(Y),
        "dims": Y.shape[1],
    }


def main() -> int:
    from counterpart.nodes.tracker.likelihood import ConeLikelihood, make_observation
    from counterpart.nodes.tracker.prior import MotionPrior, load_default_prior
    from counterpart.nodes.tracker.tracker import APFConfig, Tracker, TrackerConfig
    from counterpart.sim.stream import open_stream

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=200, help="frames per scenario at most")
    ap.add_argument("--scenarios", nargs="+", default=["handshake", "push", "wave", "cmu"])
    ap.add_argument("--prior", default="default", help="prior .npz, 'default' or 'none'")
    ap.add_argument("--layers", type=int, default=10)
    ap.add_argument("--particles", type=int, default=256)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="tracker seeds (runs per filter)")
    ap.add_argument("--scene-seeds", type=int, nargs="+", default=[0], help="simulator seeds of the sequences")
    ap.add_argument(
        "--views",
        type=int,
        default=1,
        choices=range(1, len(EXTRA_EYES) + 2),
        help="cameras: 1 (monocular, the issue's figures) or more (see EXTRA_EYES)",
    )
    ap.add_argument("--no-hmm-fit", action="store_true", help="leave out the HMM fit's timing against hmmlearn's")
    args = ap.parse_args()
    hmm_fit = None if args.no_hmm_fit else hmm_fit_figures()
    prior = (
        None
        if args.prior == "none"
        else load_default_prior(progress=True)
        if args.prior == "default"
        else MotionPrior.load(args.prior)
    )

    errs: dict[tuple[str, int], list[np.ndarray]] = {}
    reproj, last100, times = [], [], {}
    n_total = 0
    for name, scene_seed in ((n, s) for n in args.scenarios for s in args.scene_seeds):
        try:
            stream = open_stream(name, seed=scene_seed, frames=args.frames)
        except (ValueError, FileNotFoundError) as exc:
            print(f"skipping {name}:{scene_seed}: {exc}", file=sys.stderr)
            continue
        frames, masks, truth3, truth2, cams = _render_views(stream, scene_seed, args.views)
        cam = cams[0]
        for seed in args.seeds:
            for kind in ("apf", "pf"):
                apf = APFConfig(n_layers=args.layers, n_particles=args.particles, plain=kind == "pf")
                trk = Tracker(cams, "left", TrackerConfig(apf=apf), prior=prior, seed=seed)
                est, t_sum, n = _track_timed(trk, frames, masks)
                e = np.linalg.norm(est - truth3, axis=-1).mean(axis=1)
                errs.setdefault((kind, seed), []).append(e)
                if kind == "apf":
                    t, k = times.get(seed, (0.0, 0))
                    times[seed] = (t + t_sum, k + n)
                    reproj.append(np.linalg.norm(cam.project(est) - truth2, axis=-1).mean(axis=1))
                    last100.append(np.nanmax(e[-100:]))
                print(
                    f"{name}:{scene_seed} seed {seed} {kind}: {len(e)} frames, mpjpe {np.nanmean(e) * 1e3:.1f} mm",
                    file=sys.stderr,
                )
        n_total += len(frames)

    # likelihood cost per particle evaluation
    frame0, mask0 = (frames[0], masks[0]) if args.views == 1 else (frames[0][0], masks[0][0])
    obs = make_observation(frame0, mask0)  # one view's cost
    L = ConeLikelihood(cam)
    from counterpart.body.pose import neutral_pose

    P = neutral_pose()[None] + np.random.default_rng(0).normal(size=(args.particles, 28)) * 0.05
    L(P, obs)
    t0 = time.perf_counter()
    for _ in range(50):
        L(P, obs)
    us_per_eval = (time.perf_counter() - t0) / (50 * args.particles) * 1e6

    per_seed = {
        kind: [float(np.nanmean(np.concatenate(errs[kind, seed]))) * 1e3 for seed in args.seeds]
        for kind in ("apf", "pf")
    }
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
        "layers": args.layers,
        "particles": args.particles,
        "seeds": args.seeds,
        "scene_seeds": args.scene_seeds,
        "views": args.views,
        "scenarios": args.scenarios,
        "prior": args.prior,
        "load_average": round(os.getloadavg()[0], 2),
        "hmm_fit": hmm_fit,
    }
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
