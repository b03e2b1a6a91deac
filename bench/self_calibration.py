"""The camera estimated from the people in view (``counterpart.nodes.calibration``), on the simulator with random
cameras against its truth, and on real clips for plausibility.

Simulator (``sim_figures``): per seed, the scenario ``SCENARIOS[seed % 6]`` seen from a random camera
(``sim:NAME?seed=S&camera=random``: height 1-3 m, tilt 0-35 degrees, horizontal view 40-75 degrees,
bearing -60 to 60 degrees about the pair, so the two people stand at different depths),
its first ``--seconds`` (3 s) through the silhouette node's extractor as the lockstep graph runs it
(background fitted on the first 20 frames with the people in view, then every frame from the first),
the head and foot points of the upright people (of the standing bodies in a region that is not one
person too, from the frame's label image; of the people detector's boxes on a frame with neither
and on every third frame)
and the lines of the scene, one estimate at the end:

- ``calib_height_err`` (relative), ``calib_tilt_err_deg``, ``calib_focal_err`` (relative): medians
  over the seeds of the absolute errors; a seed without an estimate counts as an infinite error;
- ``calib_within``: share of seeds with height within 10%, tilt within 3 degrees and focal length
  within 10%, all three; ``calib_within_height_tilt``: height and tilt within their limits (the
  focal length left out: at low tilt no view of people fixes it);
- ``calib_estimated``: share of seeds with an estimate at all (enough views of whole upright people);
- ``calib_credible``: share of seeds whose estimate the calibration node would publish (the horizon
  seen: ``counterpart.apps.calibration.graph_would_use``, the node's default bounds);
  ``calib_within_published``: share within the limits of the camera the graph ends up with (the
  estimate where credible, the default camera elsewhere); ``calib_credible_wrong``: the seeds whose
  estimate is credible but outside the limits (the graph publishes a wrong camera);
- ``calib_truth_points``: the same figures from the true head and foot points (the crown and the
  mid-ankle on the ground, from the simulator's joints) and no lines: the limit of the geometry of
  people alone, whatever the silhouettes; ``calib_truth_points_lines``: the true points with the
  scene's lines as the estimate has them (the limit of the estimator's cues, whatever the
  silhouettes); ``calib_true_heads``: the estimate's observations, each one's head point replaced
  by the true crown of the person it lies on (:func:`true_heads`), with the estimate's lines: how
  much of the gap between the estimate and the true points the head points make (a hand held
  up, a ghost of the room stuck on a head: the height, and with it the scale, goes wrong) and how
  much the feet and the people seen; ``calib_room_lines`` and ``calib_truth_points_room_lines``: the estimate's
  observations, and the true points, with the room's *true* line families (``bench/room_lines.py``:
  every board edge, wall line and poster edge in view, from the simulator's geometry): how much of
  the shortfall is the line detector and its grouping, and how much the geometry (few families in
  view, far vanishing points);
- ``calib_tilt_bands``: per band of the true tilt (0-10, 10-20, 20-35 degrees), the seeds in it and,
  for the estimate, the true points, the true points with lines (``truth_``, ``truth_lines_``), and
  the estimate and the true points with the room's true lines (``room_``, ``truth_room_``),
  the share within all three limits, within the height and tilt limits, within the focal limit, and
  the median focal error; the estimate's credible share;
- ``calib_within_known_fov`` (and ``calib_known_fov``: the medians too): the estimate given the camera's
  horizontal field of view to the whole degree, as a user reads it off a spec sheet (``--fov``,
  ``calibration.fov_deg``): the focal length no longer left to the lines where they cannot fix it;
- the reference in the same run: the default camera's errors (``calib_default_*``), what the graph
  uses without calibration.

Seeds: the estimator's noise model was chosen on seeds 0-11 and on synthetic projections
(tests/test_calibration_estimate.py); with the camera's bearing (second session) every change was
tried on seeds 0-49 only (``calib_tuning_seeds``); the figures are quoted on seeds from
``--first-seed`` (1000-1049, ``calib_report_seeds``). Later sessions looked at why some of those
fail, and the people grown from their gestures (``nodes/calibration/still.py``) were made while
looking at some of them and at seeds 2000-2049, and so were the rules that leave out people whose
statures disagree or who lie within another (``CalibrationConfig.max_stature_ratio``,
``nested_share``); seeds 3000-3049 were run to check those changes (never to choose one), and
seeds 4000-4049 were first run on the final one. A later rule that found the head under a hand
held up (an opening with a horizontal line) was tried on 0-49, 1000-1049 and 2000-2049 and run on
3000-5049; it was taken out (on one UT clip, the three views it moved let a fragment count as a
person, and the estimate went to the tilt's bound). A fit on that bound now gives way to one
inside it (``estimate._refine_best``; chosen on that clip, unchanged on 0-2049); with it, the rule
no longer hurt that clip, but a view-by-view look at 2000-2049 against the true crowns showed it
moving correct heads down by 10-20% of the person's height on many views (24 of one seed's), so
it stays out. Seeds 5000-5049 chose nothing: they are kept as fresh seeds, to check a change chosen
on the others, never to choose one. A later session split the failures of every set, 5000-5049
among them, by cause (``calib_true_heads``, and views looked at against the true crowns); the
changes it tried were measured on all the sets and none was kept.

Real clips (``real_figures``): UT-Interaction set 1 (``../shared/data/ut_interaction/set1``), one
static elevated camera; each clip is a crop of its frames around the people, so its principal point
is not at the crop's centre, which the estimate assumes. Per clip, ``counterpart calibrate``'s
estimate; across the clips, the median and interquartile range of height, tilt and focal length
(the spread across clips of one scene), and how many the node would publish.

A real camera with a published calibration (``pets_figures``, ``--pets``, on by default where the
file is): ``../shared/data/video/vtest.avi``, OpenCV's sample pedestrian video, is view 1 of PETS
2009's sequence S2.L1 (a camera on a building over a campus path, people walking at many depths for
80 s). ``counterpart calibrate``'s estimate against that view's calibration (:data:`PETS_CAMERA`):
``calib_pets_height_err`` and ``calib_pets_focal_err`` (relative), ``calib_pets_tilt_err_deg``,
``calib_pets_credible`` (whether the node would publish it). Two of the estimator's rules came
from looking at this video (each walker's own lean; the test that drops a line family counting the
family's own scatter); they were kept because they left the simulator's figures and the UT clips'
estimates as they were; no setting was chosen on its numbers.

Usage: ``python bench/self_calibration.py [--seeds 50] [--seconds 3] [--jobs 1] [--clips 12|all|0]
[--inputs-cache DIR] [--no-pets]``; last stdout line: one JSON object. ``--inputs-cache`` keeps each
seed's costly inputs (:func:`sim_inputs`: the silhouettes' and the detector's observations, the
median view of the scene and the people's boxes on it, the truth) so that a change to the estimator
or to the scene lines' detection and grouping is measured in seconds; it is stale once anything
upstream of the estimate changes. ``bench/real_video.py`` reports the simulator figures under the same names.
"""

from __future__ import annotations

import argparse
import json
import pickle
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from contextlib import nullcontext
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from room_lines import room_lines  # noqa: E402

from counterpart.apps.calibration import graph_would_use  # noqa: E402
from counterpart.body.camera import Camera, default_camera  # noqa: E402
from counterpart.body.people_detector import PeopleDetector  # noqa: E402
from counterpart.body.skeleton import JOINT_INDEX  # noqa: E402
from counterpart.nodes.calibration.estimate import CalibrationConfig, CameraEstimate, estimate_camera  # noqa: E402
from counterpart.nodes.calibration.lines import scene_lines  # noqa: E402
from counterpart.nodes.calibration.observe import PeopleObservations, SceneFrames  # noqa: E402
from counterpart.sim.camera import RandomCameraConfig  # noqa: E402

CLIPS = REPO.parent / "shared" / "data" / "ut_interaction" / "set1"
TRAIN_FRAMES = 20  # as launch/lockstep.yaml's silhouette node
#: OpenCV's sample pedestrian video: PETS 2009, sequence S2.L1, view 1 (the same 795 frames)
PETS_VIDEO = REPO.parent / "shared" / "data" / "video" / "vtest.avi"
#: that view's published calibration (PETS 2009's View_001.xml, Tsai's model, rounded): camera height
#: above the ground plane (m), downward pitch of the optical axis (deg) and focal length (px, the
#: mean of its horizontal 1185 and vertical 1195); its principal point (324, 283) is 60 px left of
#: the frame's centre, which the estimate assumes, and its lens bends straight lines by up to 2-3% of
#: their distance from it near the corners (kappa1 5.1e-3 per mm^2), which the estimate does not model
PETS_CAMERA = {"height": 7.07, "tilt_deg": 16.5, "focal": 1190.0}
LIMITS = {"height": 0.10, "tilt": 3.0, "focal": 0.10}
#: bands of the true tilt, degrees (from, to): at 0 people on a ground plane do not fix the focal length
TILT_BANDS = ((0.0, 10.0), (10.0, 20.0), (20.0, 35.1))


def tilt_deg(camera: Camera) -> float:
    """Downward pitch of the optical axis, degrees."""
    return float(np.degrees(np.arcsin(-camera.R[2, 1])))


def errors(height: float, tilt: float, focal: float, truth: Camera) -> dict[str, float]:
    """Absolute errors of (height m, tilt deg, focal px) against a true camera."""
    return {
        "height": abs(height / truth.centre[1] - 1),
        "tilt": abs(tilt - tilt_deg(truth)),
        "focal": abs(focal / truth.fx - 1),
    }


def estimate_errors(est: CameraEstimate | None, truth: Camera) -> dict[str, float]:
    """Errors of an estimate; infinite without one (JSON: null in the rows)."""
    if est is None:
        return {"height": np.inf, "tilt": np.inf, "focal": np.inf}
    return errors(est.height, est.tilt_deg, est.focal, truth)


def within(e: dict[str, float]) -> bool:
    return all(e[k] <= v for k, v in LIMITS.items())


def summary(errs: list[dict[str, float]], prefix: str) -> dict[str, Any]:
    """Medians of the absolute errors (null when over half the seeds gave no estimate) and the share
    within the limits.
    """
    return _finite(
        {
            f"{prefix}height_err": round(float(np.median([e["height"] for e in errs])), 4),
            f"{prefix}tilt_err_deg": round(float(np.median([e["tilt"] for e in errs])), 3),
            f"{prefix}focal_err": round(float(np.median([e["focal"] for e in errs])), 4),
            f"{prefix}within": round(float(np.mean([within(e) for e in errs])), 4),
        }
    )


def sim_inputs(seed: int, seconds: float) -> dict[str, Any]:
    """What one simulated scene gives the estimator (the costly part of a seed): its silhouettes'
    and detector's head/foot observations, the scene's line families, the true camera and the true
    head/foot points.
    """
    from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor
    from counterpart.sim.scenarios import SCENARIOS
    from counterpart.sim.stream import open_stream

    name = list(SCENARIOS)[seed % len(SCENARIOS)]
    stream = open_stream(name, seed=seed, camera="random", frames=int(round(seconds * 25.0)))
    truth = stream.camera
    frames = [stream.render(i)[0] for i in range(stream.n_frames)]
    extractor = SilhouetteExtractor()
    extractor.fit_background(frames[:TRAIN_FRAMES], robust=True)
    obs, scene, detector = PeopleObservations(*stream.size), SceneFrames(), PeopleDetector()
    for i, frame in enumerate(frames):
        result = extractor.process(frame)
        obs.add_frame(frame, i / stream.fps, obs.add(result.people, i / stream.fps, result.labels), detector)
        if scene.wants(i):
            scene.add(frame, result.people)
    # the true points: the crown (11 cm over the head joint) over the mid-ankle put on the ground
    J = stream.scenario.joints()
    head = J[:, :, JOINT_INDEX["head"]] + [0.0, 0.11, 0.0]
    foot = 0.5 * (J[:, :, JOINT_INDEX["l_ankle"]] + J[:, :, JOINT_INDEX["r_ankle"]]) * [1.0, 0.0, 1.0]
    T = len(J)
    return {
        "seed": seed,
        "scenario": name,
        "camera_meta": stream.scenario.meta["camera"],
        "truth": truth,
        "size": stream.size,
        "observations": obs.arrays(),
        "scene": (scene.image(), list(scene.boxes)),
        "truth_points": (
            truth.project(head).reshape(-1, 2),
            truth.project(foot).reshape(-1, 2),
            np.tile([0, 1], T),
            np.repeat(np.arange(T) / stream.fps, 2),
        ),
    }


def true_heads(observations: tuple, truth_points: tuple) -> np.ndarray:
    """The observations' head points replaced by the true crowns of the people they lie on.

    Parameters
    ----------
    observations : tuple of (head, foot, track, time_s)
        The estimate's observations (:meth:`PeopleObservations.arrays`): (N, 2), (N, 2) pixels,
        (N,) ids, (N,) seconds.
    truth_points : tuple of (head, foot, track, time_s)
        The true crowns and mid-ankles on the ground of every person on every frame, the same way.

    Returns
    -------
    ndarray of shape (N, 2)
        Each observation's head point: the crown of the true person of its frame whose crown and
        foot lie nearest it in x (the sum of the two distances, pixels); its own head where no
        true person is on its frame.
    """
    head, foot, _, t = (np.asarray(a, np.float64) for a in observations)
    th, tf, _, tt = (np.asarray(a, np.float64) for a in truth_points)
    head = head.reshape(-1, 2).copy()
    if not len(head) or not len(th):
        return head
    cost = np.abs(foot[:, None, 0] - tf[None, :, 0]) + np.abs(head[:, None, 0] - th[None, :, 0])
    cost[np.abs(t[:, None] - tt[None, :]) > 1e-6] = np.inf
    j = np.argmin(cost, axis=1)
    found = np.isfinite(cost[np.arange(len(j)), j])
    head[found] = th[j[found]]
    return head


def sim_row(inputs: dict[str, Any]) -> dict[str, Any]:
    """One scene's estimate from its silhouettes, from its true head/foot points, and the errors of
    each (``inputs``: :func:`sim_inputs`).
    """
    truth, size = inputs["truth"], inputs["size"]
    head, foot, track, t = inputs["observations"]
    lines = scene_lines(*inputs["scene"])
    est = estimate_camera(head, foot, track, size, t, lines=lines)
    th, tf, tk, tt = inputs["truth_points"]
    oracle = estimate_camera(th, tf, tk, size, tt)
    oracle_lines = estimate_camera(th, tf, tk, size, tt, lines=lines)
    crowns = estimate_camera(
        true_heads(inputs["observations"], inputs["truth_points"]), foot, track, size, t, lines=lines
    )
    room = room_lines(truth, inputs["seed"])
    room_est = estimate_camera(head, foot, track, size, t, lines=room)
    oracle_room = estimate_camera(th, tf, tk, size, tt, lines=room)
    # a user's spec sheet: the horizontal view to the whole degree
    fov = round(float(np.degrees(2.0 * np.arctan(size[0] / 2.0 / truth.fx))))
    known_fov = estimate_camera(head, foot, track, size, t, CalibrationConfig().with_known_fov(fov), lines)
    ok = est is not None and graph_would_use(est)
    default = default_camera(*size)
    published = estimate_errors(est, truth) if ok else errors(default.centre[1], tilt_deg(default), default.fx, truth)
    return {
        "seed": inputs["seed"],
        "scenario": inputs["scenario"],
        "camera": inputs["camera_meta"],
        "observations": len(head),
        "estimate": est.summary() if est is not None else None,
        "errors": estimate_errors(est, truth),
        "credible": bool(ok),
        "published": published,
        "truth_points": estimate_errors(oracle, truth),
        "truth_points_lines": estimate_errors(oracle_lines, truth),
        "true_heads": estimate_errors(crowns, truth),
        "room_lines": estimate_errors(room_est, truth),
        "truth_points_room_lines": estimate_errors(oracle_room, truth),
        "known_fov": estimate_errors(known_fov, truth),
        "default": errors(default.centre[1], tilt_deg(default), default.fx, truth),
    }


def sim_seed(seed: int, seconds: float, cache: str | None = None) -> dict[str, Any]:
    """One simulated scene, end to end: :func:`sim_row` of :func:`sim_inputs` (kept in, or read from,
    ``cache``/SEED_SECONDS.pkl when a folder is given).
    """
    if cache is None:
        return sim_row(sim_inputs(seed, seconds))
    path = Path(cache) / f"{seed}_{seconds:g}.pkl"
    if path.is_file():
        with path.open("rb") as fh:
            inputs = pickle.load(fh)
    else:
        inputs = sim_inputs(seed, seconds)
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("wb") as fh:
            pickle.dump(inputs, fh)
    return sim_row(inputs)


def tilt_bands(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per band of the true tilt (:data:`TILT_BANDS`): the seeds in it, and for the estimate and
    for the true points (``truth_``) the share within all three limits, within the height and tilt
    limits, and the median focal error: where the geometry of people gives out, and where the
    estimator falls short of it.
    """
    out: dict[str, Any] = {}
    for lo, hi in TILT_BANDS:
        band = [r for r in rows if lo <= r["camera"]["tilt_deg"] < hi]
        key = f"{lo:g}-{hi:g}"
        if not band:
            out[key] = {"seeds": 0}
            continue
        v: dict[str, Any] = {"seeds": len(band)}
        for name, prefix in (
            ("errors", ""),
            ("truth_points", "truth_"),
            ("truth_points_lines", "truth_lines_"),
            ("room_lines", "room_"),
            ("truth_points_room_lines", "truth_room_"),
        ):
            errs = [r[name] for r in band]
            v[f"{prefix}within"] = round(float(np.mean([within(e) for e in errs])), 4)
            v[f"{prefix}within_height_tilt"] = round(
                float(np.mean([e["height"] <= LIMITS["height"] and e["tilt"] <= LIMITS["tilt"] for e in errs])), 4
            )
            v[f"{prefix}within_focal"] = round(float(np.mean([e["focal"] <= LIMITS["focal"] for e in errs])), 4)
            v[f"{prefix}focal_err"] = _finite(round(float(np.median([e["focal"] for e in errs])), 4))
        v["credible"] = round(float(np.mean([r["credible"] for r in band])), 4)
        out[key] = v
    return out


def _finite(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    return None if isinstance(v, float) and not np.isfinite(v) else v


def sim_figures(
    seeds: int = 50, seconds: float = 3.0, first_seed: int = 1000, jobs: int = 1, cache: str | None = None
) -> dict[str, Any]:
    """The simulator part (see the module docstring): the figures and the per-seed rows (seeds in
    ``jobs`` processes; each seed's inputs kept in ``cache`` when a folder is given).
    """
    rows = []
    t0 = time.monotonic()
    with ProcessPoolExecutor(jobs) if jobs > 1 else nullcontext() as pool:
        done = (pool.map if pool is not None else map)(
            sim_seed, range(first_seed, first_seed + seeds), [seconds] * seeds, [cache] * seeds
        )
        for r in done:
            rows.append(r)
            e = r["errors"]
            print(
                f"[calib] seed {r['seed']} {r['scenario']}: height {e['height']:.3f} tilt {e['tilt']:.2f} deg focal "
                f"{e['focal']:.3f} (credible {r['credible']}, {r['observations']} obs, "
                f"{time.monotonic() - t0:.1f} s in all)",
                file=sys.stderr,
                flush=True,
            )
    out = {
        **summary([r["errors"] for r in rows], "calib_"),
        "calib_within_height_tilt": round(
            float(
                np.mean(
                    [r["errors"]["height"] <= LIMITS["height"] and r["errors"]["tilt"] <= LIMITS["tilt"] for r in rows]
                )
            ),
            4,
        ),
        "calib_estimated": round(float(np.mean([r["estimate"] is not None for r in rows])), 4),
        "calib_credible": round(float(np.mean([r["credible"] for r in rows])), 4),
        "calib_within_published": summary([r["published"] for r in rows], "")["within"],
        "calib_credible_wrong": [r["seed"] for r in rows if r["credible"] and not within(r["errors"])],
        "calib_truth_points": summary([r["truth_points"] for r in rows], ""),
        "calib_truth_points_lines": summary([r["truth_points_lines"] for r in rows], ""),
        "calib_true_heads": summary([r["true_heads"] for r in rows], ""),
        "calib_room_lines": summary([r["room_lines"] for r in rows], ""),
        "calib_truth_points_room_lines": summary([r["truth_points_room_lines"] for r in rows], ""),
        "calib_known_fov": summary([r["known_fov"] for r in rows], ""),
        "calib_within_known_fov": summary([r["known_fov"] for r in rows], "")["within"],
        **summary([r["default"] for r in rows], "calib_default_"),
        "calib_seeds": seeds,
        "calib_first_seed": first_seed,
        "calib_tuning_seeds": "0-49 (the estimator and the credibility bounds were tuned there; later rules were chosen looking at the failures of 1000-1049 and 2000-2049 too, and 5000-5049 are kept fresh: see the docstring)",
        "calib_report_seeds": f"{first_seed}-{first_seed + seeds - 1}",
        "calib_camera_ranges": {
            "height_m": list(RandomCameraConfig().height),
            "tilt_deg": list(RandomCameraConfig().tilt_deg),
            "fov_deg": list(RandomCameraConfig().fov_deg),
            "azimuth_deg": list(RandomCameraConfig().azimuth_deg),
        },
        "calib_seconds": seconds,
    }
    low = [r for r in rows if r["camera"]["tilt_deg"] < 10.0]
    out["calib_within_tilt_under_10"] = summary([r["errors"] for r in low], "")["within"] if low else None
    out["calib_tilt_bands"] = tilt_bands(rows)
    out["calib_rows"] = [
        {
            k: _finite(r[k])
            for k in (
                "seed",
                "scenario",
                "camera",
                "estimate",
                "errors",
                "credible",
                "truth_points",
                "truth_points_lines",
                "true_heads",
                "room_lines",
                "truth_points_room_lines",
                "known_fov",
            )
        }
        for r in rows
    ]
    return out


def real_figures(clips: list[Path]) -> dict[str, Any]:
    """Per clip the estimate of ``counterpart calibrate``; the spread across the clips."""
    from counterpart.apps.calibration import calibrate_video

    per: dict[str, Any] = {}
    for clip in clips:
        t0 = time.monotonic()
        try:
            est, _ = calibrate_video(clip, train_frames=TRAIN_FRAMES)
        except ValueError as exc:
            per[clip.stem] = {"error": str(exc)}
            continue
        per[clip.stem] = {
            "height": round(est.height, 3),
            "tilt_deg": round(est.tilt_deg, 2),
            "focal": round(est.focal, 1),
            "roll_deg": round(est.roll_deg, 2),
            "height_std": round(est.height_std, 3),
            "tilt_std_deg": round(est.tilt_std_deg, 2),
            "focal_std": round(est.focal_std, 3),
            "depth_spread": round(est.depth_spread, 3),
            "horizon_segments": est.horizon_segments,
            "credible": bool(graph_would_use(est)),
            "size": [est.width, est.height_px],
        }
        print(f"[calib] {clip.stem}: {est.describe()} ({time.monotonic() - t0:.1f} s)", file=sys.stderr, flush=True)
    ok = [v for v in per.values() if "error" not in v]

    def spread(key: str) -> dict[str, float] | None:
        v = np.array([r[key] for r in ok], float)
        if not len(v):
            return None
        q25, q50, q75 = np.percentile(v, [25, 50, 75])
        return {
            "median": round(float(q50), 3),
            "iqr": round(float(q75 - q25), 3),
            "min": round(float(v.min()), 3),
            "max": round(float(v.max()), 3),
        }

    return {
        "real_clips": len(clips),
        "real_estimated": len(ok),
        "real_credible": sum(r["credible"] for r in ok),
        "real_height": spread("height"),
        "real_tilt_deg": spread("tilt_deg"),
        "real_focal": spread("focal"),
        "real_per_clip": per,
    }


def pets_figures(video: Path = PETS_VIDEO) -> dict[str, Any]:
    """``counterpart calibrate``'s estimate of a real camera whose calibration is published: errors
    against :data:`PETS_CAMERA` (relative height and focal length, tilt in degrees), whether the
    node would publish it, the estimate itself.
    """
    from counterpart.apps.calibration import calibrate_video

    t0 = time.monotonic()
    est, _ = calibrate_video(video)
    print(f"[calib] {video.name}: {est.describe()} ({time.monotonic() - t0:.1f} s)", file=sys.stderr, flush=True)
    ref = PETS_CAMERA
    return {
        "calib_pets_height_err": round(abs(est.height / ref["height"] - 1), 4),
        "calib_pets_tilt_err_deg": round(abs(est.tilt_deg - ref["tilt_deg"]), 2),
        "calib_pets_focal_err": round(abs(est.focal / ref["focal"] - 1), 4),
        "calib_pets_credible": bool(graph_would_use(est)),
        "calib_pets_estimate": {
            k: round(v, 3) if isinstance(v, float) else v for k, v in est.summary().items() if k != "people_heights"
        },
        "calib_pets_reference": ref,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=50, help="simulated scenes (default 50)")
    ap.add_argument("--first-seed", type=int, default=1000, help="first seed (0-49 were used for tuning)")
    ap.add_argument("--seconds", type=float, default=3.0, help="seconds of each scene used (default 3)")
    ap.add_argument("--jobs", type=int, default=1, help="processes for the simulated scenes (default 1)")
    ap.add_argument("--clips", default="12", help="real clips: 'all', how many spread over set 1, or 0 (none)")
    ap.add_argument(
        "--inputs-cache",
        default=None,
        help="folder keeping each seed's inputs (observations, median view, truth) for changes to the estimator "
        "or the lines; stale once the silhouettes, the observations or the simulator change",
    )
    ap.add_argument(
        "--pets",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="the PETS 2009 view of ../shared/data/video/vtest.avi against its published calibration (default on, "
        "where the file is)",
    )
    args = ap.parse_args()
    out = sim_figures(args.seeds, args.seconds, args.first_seed, args.jobs, args.inputs_cache) if args.seeds else {}
    from real_video import clip_list  # the same choice of clips as the demo bench

    clips = clip_list(args.clips) if args.clips != "0" and CLIPS.is_dir() else []
    if clips:
        out.update(real_figures(clips))
    if args.pets and PETS_VIDEO.is_file():
        out.update(pets_figures())
    print(json.dumps(out))


if __name__ == "__main__":
    main()
