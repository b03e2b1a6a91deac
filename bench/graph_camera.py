"""The tracked bodies against the people in the picture while the graph's camera is refined.

The lockstep graph (``launch/lockstep.yaml``, as ``counterpart demo --input`` runs it) starts on the
default camera and the calibration node then steps the published camera towards its estimate, a
bounded step a frame; the tracker carries its tracks through every step
(``nodes/tracker/camera_change.py``). On a camera far from the default (a camera high over a path, as
in ``../shared/data/video/vtest.avi``, PETS 2009 S2.L1 view 1, people at many depths) every body
tracked before the camera settles has to be moved and resized with it, or it is drawn at another
person's size.

Per tracked body and frame, the *fit*: the height in the picture of its joints (head joint to the
lower ankle, projected with the camera the graph used on that frame) over the height of the
silhouette it was fitted to (the silhouette node's region of that id). A body standing upright over
a person of its stature has the fit ``fit_standing`` (the head joint lies below the crown, the ankle
joint above the sole).

- ``fit_graph``: the median fit in the graph; ``fit_offline``: the same for the reference in the same
  run, the same frames tracked offline (``counterpart.apps.tracking.track_video``, the tracker's
  settings of the lockstep graph and its default motion prior) with the camera the graph ended on,
  fixed from the first frame;
- ``misfit_graph`` / ``misfit_offline``: the share of bodies whose fit lies more than 25% off
  ``fit_standing`` (drawn a quarter taller or shorter than the person, or worse);
  ``misfit_graph_settled``: the same from ``camera_settled_frame`` on, the first frame from which
  the graph's camera stays within 3% of its last focal length and height and 0.5 degrees of its tilt
  (null where it settles after the last frame: the offline reference then has the camera of a graph
  still on its way, and says little);
- ``bodies_graph``, ``bodies_offline``: the body-frames counted; ``ids_agree``: the share of the
  offline tracks' silhouette ids that the graph's silhouettes hold on that frame (the two passes of
  the extractor are the same computation); ``camera_updates``: the cameras the graph used (each
  different from the one before);
- the real-time graph (``launch/demo.yaml``, as ``counterpart demo --input VIDEO --realtime`` and
  a live camera run it: frames at 320 pixels wide, each node drops what it cannot keep up with, the
  calibration's estimates paced), over the whole video (``--realtime-frames``) once:
  ``first_estimate_s_realtime``, the video's second from which its first estimated camera holds
  (null where none came), ``misfit_realtime`` and ``fit_realtime`` over all its bodies,
  ``people_per_frame_realtime`` (the silhouette node's people per frame: there is no truth, but
  walkers missed show here), and
  ``realtime_estimates``, ``realtime_estimates_not_credible``, ``realtime_estimates_deferred``: the
  calibration node's tallies;
- ``runs_identical``: whether ``--runs`` (default 2) runs of the graph published the same poses on
  every frame (a lockstep replay is deterministic however far behind the calibration node runs),
  ``runs_frames_differing`` the frames on which some run's poses differ from the first's; the
  figures above are the first run's.

Usage: ``python bench/graph_camera.py [--video PATH] [--frames 300] [--runs 2] [--realtime-frames 0|-1]``; skips, saying why,
when the video is absent; last stdout line: one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from contextlib import nullcontext
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.append(str(REPO / "bench"))

from e2e import run_graph  # noqa: E402

from counterpart.apps.tracking import track_video  # noqa: E402
from counterpart.body.camera import Camera, camera_for_size, camera_from_info, same_camera  # noqa: E402
from counterpart.body.kinematics import forward_kinematics  # noqa: E402
from counterpart.body.pose import neutral_pose  # noqa: E402
from counterpart.body.skeleton import DEFAULT_DIMS  # noqa: E402
from counterpart.bus.bag import BagReader  # noqa: E402
from counterpart.nodes.calibration.smooth import camera_parameters  # noqa: E402
from counterpart.nodes.camera.pacing import convert, output_size  # noqa: E402
from counterpart.nodes.tracker.prior import resolve_prior  # noqa: E402

SHARED = Path(os.environ.get("COUNTERPART_SHARED_DATA") or REPO.parent / "shared" / "data")
VIDEO = SHARED / "video" / "vtest.avi"
TRAIN_FRAMES = 20  # as launch/lockstep.yaml's silhouette node
MAX_SIDE = 640  # as launch/lockstep.yaml's camera node
MISFIT = 0.25
_JOINTS = forward_kinematics(neutral_pose(DEFAULT_DIMS), DEFAULT_DIMS)[0]
#: the fit of a body standing upright over a person of its stature: head joint to ankle over crown to sole
FIT_STANDING = float((_JOINTS[0, 1] - _JOINTS[[10, 13], 1].min()) / DEFAULT_DIMS.height)


def fit(joints: np.ndarray, camera: Camera, silhouette_height: float) -> float:
    """Projected height of the joints (head to the lower ankle) over the silhouette's, pixels/pixels."""
    uv = camera.project(np.asarray(joints, np.float64))
    return float((np.max(uv[[10, 13], 1]) - uv[0, 1]) / max(silhouette_height, 1.0))


def read_graph(bag: Path, size: tuple[int, int]) -> tuple[dict, dict, list[tuple[int, Camera]]]:
    """(seq -> {id: silhouette height}, seq -> [(id, joints)], [(seq, camera)] in seq order)."""
    heights: dict[int, dict[int, float]] = {}
    bodies: dict[int, list[tuple[int, np.ndarray]]] = {}
    cams: list[tuple[int, Camera]] = []
    for topic, _, m in BagReader(bag).messages(decode_messages=True):
        if topic == "silhouettes":
            heights[m.seq] = {p.id: float(p.height) for p in m.people}
        elif topic == "pose":
            bodies[m.seq] = [(b.id, np.asarray(b.joints)) for b in m.people if not b.lost]
        elif topic == "camera_info":
            cams.append((m.seq, camera_from_info(m)))
    cams.sort(key=lambda c: c[0])
    # a lockstep calibration node says the same camera again on every frame it decides
    cams = [c for k, c in enumerate(cams) if k == 0 or not same_camera(c[1], cams[k - 1][1])]
    return heights, bodies, cams or [(0, camera_for_size(None, *size))]


def camera_at(cams: list[tuple[int, Camera]], seq: int) -> Camera:
    held = [c for s, c in cams if s <= seq]
    return held[-1] if held else cams[0][1]


def settled_frame(cams: list[tuple[int, Camera]]) -> int:
    """The first seq from which every camera is within 3% (focal, height) and 0.5 degrees (tilt) of the last."""
    last = camera_parameters(cams[-1][1])
    seq = cams[-1][0]
    for s, c in reversed(cams):
        d = np.abs(camera_parameters(c) - last)
        if d[0] > 0.03 or d[3] > 0.03 or d[1] > np.radians(0.5):
            break
        seq = s
    return int(seq)


def graph_fits(
    heights: dict[int, dict[int, float]],
    bodies: dict[int, list[tuple[int, np.ndarray]]],
    cams: list[tuple[int, Camera]],
) -> list[tuple[int, float]]:
    """(seq, fit) of every tracked body whose silhouette the graph holds, with the camera of its frame."""
    return [
        (seq, fit(j, camera_at(cams, seq), heights[seq][i]))
        for seq, found in bodies.items()
        for i, j in found
        if i in heights.get(seq, {})
    ]


def misfit(fits: list[float]) -> float | None:
    """The share of fits more than ``MISFIT`` off ``FIT_STANDING`` (None for none)."""
    return round(float(np.mean(np.abs(np.asarray(fits) / FIT_STANDING - 1) > MISFIT)), 4) if fits else None


def realtime_figures(video: Path, frames: int, workdir: Path, sets: dict[str, Any] | None = None) -> dict[str, Any]:
    """The real-time graph's fits and first estimate over ``frames`` frames (0: all) of ``video``,
    with the launch file's parameters ``sets`` (NODE.PARAM: value) changed.
    """
    import cv2

    cap = cv2.VideoCapture(str(video))
    fps = cap.get(cv2.CAP_PROP_FPS) or 25.0
    width, height = cap.get(cv2.CAP_PROP_FRAME_WIDTH), cap.get(cv2.CAP_PROP_FRAME_HEIGHT)
    cap.release()
    bag, wall, _, _ = run_graph(
        workdir,
        "realtime",
        "demo.yaml",
        {"camera.source": str(video), "camera.max_frames": frames, **(sets or {})},
        ["pose", "camera_info", "silhouettes"],
    )
    size = (320, round(320 * height / width))  # demo.yaml's camera node: width 320
    heights, bodies, cams = read_graph(bag, size)
    estimated = [
        m.seq
        for topic, _, m in BagReader(bag).messages(decode_messages=True)
        if topic == "camera_info" and m.source == "estimated"
    ]
    stats = json.loads((workdir / "realtime.home" / "latest" / "stats" / "calibration.json").read_text())
    tally = stats.get("figures", {})
    fits = [f for _, f in graph_fits(heights, bodies, cams)]
    return {
        "first_estimate_s_realtime": round(min(estimated) / fps, 2) if estimated else None,
        "fit_realtime": round(float(np.median(fits)), 4) if fits else None,
        "misfit_realtime": misfit(fits),
        "bodies_realtime": len(fits),
        "people_per_frame_realtime": round(float(np.mean([len(h) for h in heights.values()])), 3) if heights else None,
        "realtime_frames": len(heights),
        "realtime_estimates": int(tally.get("estimates", 0)),
        "realtime_estimates_not_credible": int(tally.get("estimates_not_credible", 0)),
        "realtime_estimates_deferred": int(tally.get("estimates_deferred", 0)),
        "realtime_wall_s": round(wall, 1),
    }


def figures(video: Path, frames: int, workdir: Path, runs: int = 2) -> dict[str, Any]:
    import cv2

    # the frames as the camera node hands them on (max_side 640), for the offline reference too
    cap = cv2.VideoCapture(str(video))
    fps = cap.get(cv2.CAP_PROP_FPS)
    folder = workdir / "frames"
    folder.mkdir()
    size = None
    for n in range(frames):
        ok, image = cap.read()
        if not ok:
            break
        size = size or output_size((image.shape[1], image.shape[0]), max_side=MAX_SIDE)
        cv2.imwrite(str(folder / f"{n:06d}.png"), convert(image, size)[0])
    cap.release()
    if size is None:
        raise ValueError(f"{video}: no frame could be read")
    bag, wall, _, _ = run_graph(
        workdir,
        "graph",
        "lockstep.yaml",
        {"camera.source": str(video), "camera.max_frames": frames},
        ["pose", "camera_info", "silhouettes"],
    )
    heights, bodies, cams = read_graph(bag, size)
    differing: set[int] = set()
    for k in range(1, runs):
        again, _, _, _ = run_graph(
            workdir,
            f"graph-{k}",
            "lockstep.yaml",
            {"camera.source": str(video), "camera.max_frames": frames},
            ["pose"],
        )
        other = read_graph(again, size)[1]
        differing |= {
            seq
            for seq in set(bodies) | set(other)
            if [(i, j.tobytes()) for i, j in bodies.get(seq, [])] != [(i, j.tobytes()) for i, j in other.get(seq, [])]
        }
    settled = settled_frame(cams)
    graph = graph_fits(heights, bodies, cams)
    npz = workdir / "offline.npz"
    track_video(
        folder,
        npz,
        camera=cams[-1][1],
        prior=resolve_prior("default"),
        train_frames=TRAIN_FRAMES,
        camera_source="given",
        fps=fps,
    )
    d = np.load(npz)
    offline, agree = [], []
    for seq in range(int(d["n_frames"])):
        for s in range(len(d["sides"])):
            i = int(d["ids"][seq, s])
            if i < 0 or d["lost"][seq, s] or not np.isfinite(d["joints"][seq, s]).all():
                continue
            agree.append(i in heights.get(seq, {}))
            if agree[-1]:
                offline.append(fit(d["joints"][seq, s], cams[-1][1], heights[seq][i]))

    return {
        "fit_graph": round(float(np.median([f for _, f in graph])), 4),
        "fit_offline": round(float(np.median(offline)), 4),
        "fit_standing": round(FIT_STANDING, 4),
        "misfit_graph": misfit([f for _, f in graph]),
        "misfit_offline": misfit(offline),
        "misfit_graph_settled": misfit([f for s, f in graph if s >= settled]),
        "camera_settled_frame": settled,
        "camera_updates": len(cams),
        "bodies_graph": len(graph),
        "bodies_offline": len(offline),
        "ids_agree": round(float(np.mean(agree)), 4) if agree else None,
        "runs": runs,
        "runs_identical": not differing if runs > 1 else None,
        "runs_frames_differing": len(differing) if runs > 1 else None,
        "frames": frames,
        "graph_wall_s": round(wall, 1),
        "video": str(video),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--video", type=Path, default=VIDEO)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--runs", type=int, default=2, help="runs of the graph compared (1: no comparison)")
    ap.add_argument(
        "--realtime-frames",
        type=int,
        default=0,
        help="frames of the real-time graph's run (0: the whole video; -1: no run)",
    )
    ap.add_argument(
        "--realtime-set",
        action="append",
        default=[],
        metavar="NODE.PARAM=VALUE",
        help="change a parameter of the real-time graph (e.g. calibration.refit_growth=0 for the last release's pacing)",
    )
    ap.add_argument("--keep", type=Path, default=None, help="keep the run's files (bag, frames, offline tracks) here")
    args = ap.parse_args()
    if any("=" not in s for s in args.realtime_set):
        ap.error(f"--realtime-set {args.realtime_set}: NODE.PARAM=VALUE expected")
    sets = dict(s.split("=", 1) for s in args.realtime_set)  # the launcher reads each value as YAML
    if not args.video.exists():
        print(json.dumps({"skipped": f"{args.video} is absent (../shared/data, or COUNTERPART_SHARED_DATA)"}))
        return
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=False)
    with tempfile.TemporaryDirectory() if args.keep is None else nullcontext(str(args.keep)) as tmp:
        out = figures(args.video, args.frames, Path(tmp), args.runs) if args.frames > 0 else {}
        if args.realtime_frames >= 0:
            out.update(realtime_figures(args.video, args.realtime_frames, Path(tmp), sets))
            out["realtime_set"] = args.realtime_set
        print(json.dumps(out))


if __name__ == "__main__":
    main()
