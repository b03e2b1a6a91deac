"""``counterpart track VIDEO --out poses.npz``: offline 3D tracking of a video file.

The silhouette node's background model and the tracker's annealed particle filter, frame by frame,
without the bus (``counterpart.apps.tracking.track_video``); the layout of the output file is in its
docstring. Without a calibration file the camera is first estimated from the people in the video's
first ``--calibration-frames`` frames, as ``counterpart calibrate`` does, and used where the graph's
calibration node would publish it (``counterpart.apps.calibration.graph_would_use``); otherwise, as
in the graph, the default camera. Progress goes to stderr; Ctrl-C writes the frames done so far
(``complete`` False). Exit code 0 on success, 2 on bad input, 130 when interrupted.
"""

from __future__ import annotations

import argparse
import sys

from counterpart.apps.offline import (
    FrameProgress,
    add_fov_argument,
    add_video_arguments,
    npz_name,
    positive,
    run_offline,
)
from counterpart.apps.shared_pass import SharedPass
from counterpart.body.camera import Camera, load_camera_file
from counterpart.nodes.silhouette import BACKEND_NAMES
from counterpart.nodes.tracker.prior import LOADING_DEFAULT_PRIOR, resolve_prior
from counterpart.nodes.tracker.tracker import SIDES

#: the one-line help of this command in `counterpart --help`
HELP = "offline: the 3D body of the people of a video file"
#: ``--camera`` values that name no file
ESTIMATE, DEFAULT = "estimate", "default"
#: frames the camera is estimated from (10 s at 30 fps: people seen standing and moving)
CALIBRATION_FRAMES = 300


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the options of ``counterpart track`` to a parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The parser (of the subcommand).
    """
    add_video_arguments(p, "output .npz (joints, poses, ess, ... per frame and side)", "track at most this many frames")
    p.add_argument(
        "--people",
        nargs="+",
        default=list(SIDES),
        choices=SIDES,
        help="sides of the frame to track: left, right or both (default: both)",
    )
    p.add_argument(
        "--camera",
        default=ESTIMATE,
        metavar="FILE|estimate|default",
        help="calibration, JSON or YAML: {fx, fy, cx, cy, width, height, R, t} or {eye, target, "
        "fov_deg, width, height}; 'estimate' (the default): estimated from the people in the video, as the "
        "graph's calibration node does, and used where the node would use it, else the default camera; "
        "'default': the simulator's camera at the video's size",
    )
    p.add_argument(
        "--calibration-frames",
        type=int,
        default=CALIBRATION_FRAMES,
        help=f"with --camera estimate: the first frames the camera is estimated from (default {CALIBRATION_FRAMES})",
    )
    add_fov_argument(p)
    p.add_argument(
        "--prior",
        default="default",
        help="motion prior: 'default' (built from the simulator when missing), 'none', or a .npz",
    )
    p.add_argument("--layers", type=int, default=10, help="annealing layers per frame")
    p.add_argument("--particles", type=int, default=256, help="particles per layer")
    p.add_argument(
        "--backend", default="horprasert", choices=BACKEND_NAMES, help="background subtractor of the silhouette node"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the particle filters")


def load_camera(path: str) -> Camera:
    """A Camera from the ``--camera`` file.

    Parameters
    ----------
    path : str
        The calibration file, JSON or YAML.

    Returns
    -------
    Camera
        The calibrated camera.

    Raises
    ------
    ValueError
        The file is unreadable or invalid; the message names the option, the file and the bad key.
    """
    try:
        return load_camera_file(path)
    except ValueError as exc:
        raise ValueError(f"--camera {str(exc).removeprefix('calibration file ')}") from None


def main(args: argparse.Namespace) -> int:
    """Track the video of ``args`` and write the output file, printing its summary as JSON.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of :func:`add_arguments`.

    Returns
    -------
    int
        Exit code: 0 on success, 2 on bad input, 130 when interrupted.
    """
    from counterpart.nodes.tracker.tracker import people_problem

    from .calibration import estimate_config
    from .tracking import track_video

    if not positive(args, ("layers", "particles", "train_frames", "max_frames", "calibration_frames"), "track"):
        return 2
    problem = people_problem(list(args.people))
    if problem:  # said before the camera is estimated from the video
        print(f"counterpart track: --people {problem}", file=sys.stderr)
        return 2
    args.out = npz_name(args.out)
    if args.fov and args.camera != ESTIMATE:
        print(
            f"counterpart track: --fov is for --camera estimate; the camera {args.camera!r} has its own focal length",
            file=sys.stderr,
        )
        return 2
    try:
        estimate_config(args.fov)
    except ValueError as exc:
        print(f"counterpart track: {exc}", file=sys.stderr)
        return 2

    def work() -> dict:
        from counterpart.body.image_sequence import video_info

        named = args.camera not in (ESTIMATE, DEFAULT)
        camera = load_camera(args.camera) if named else None
        video_info(args.video)  # a missing or undecodable video is said before a minute of building a prior
        from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, iter_video

        source = "file" if named else DEFAULT
        frames = None
        if args.camera == ESTIMATE:
            # the camera's frames are tracked too: one pass of the silhouettes for both
            extractor = SilhouetteExtractor(backend=args.backend)
            shared = SharedPass(iter_video(args.video, extractor, args.max_frames, args.train_frames))
            camera, source = estimated_camera(args, shared)
            frames = shared.again()
        if args.prior == "default":
            print(
                f"[track] {LOADING_DEFAULT_PRIOR}",
                file=sys.stderr,
                flush=True,
            )
        return track_video(
            args.video,
            args.out,
            people=args.people,
            camera=camera,
            prior=resolve_prior(args.prior),
            layers=args.layers,
            particles=args.particles,
            max_frames=args.max_frames,
            train_frames=args.train_frames,
            seed=args.seed,
            progress=FrameProgress("track", limit=args.max_frames),
            camera_source=source,
            frames=frames,
            backend=args.backend,
        )

    return run_offline("track", args.out, work)


def estimated_camera(args: argparse.Namespace, shared: SharedPass | None = None) -> tuple[Camera | None, str]:
    """The camera of ``args.video`` from the people in its first ``args.calibration_frames``
    frames, where the graph's calibration node would use it; the reason is printed either way.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of :func:`add_arguments`.
    shared : SharedPass or None, default=None
        The silhouettes' pass over the video, its first frames kept for the tracking; None: a pass
        of its own.

    Returns
    -------
    camera : Camera or None
        The estimated camera, or None (the default camera).
    source : str
        "estimated" or "default".
    """
    from .calibration import calibrate_video, estimate_config, graph_would_use

    n = min(args.calibration_frames, args.max_frames or args.calibration_frames)
    try:
        est, _ = calibrate_video(
            args.video,
            n,
            args.train_frames,
            estimate_config(args.fov),
            progress=FrameProgress("track: camera", limit=n),
            frames=shared.first(n) if shared is not None else None,
            backend=args.backend,
        )
    except ValueError as exc:
        print(f"[track] the default camera: no estimate of this video's camera ({exc})", file=sys.stderr, flush=True)
        return None, DEFAULT
    if not graph_would_use(est):
        print(
            f"[track] the default camera: the estimate from the people is not sure enough to use ({est.describe()}); "
            "give a calibration file with --camera for a better one",
            file=sys.stderr,
            flush=True,
        )
        return None, DEFAULT
    print(f"[track] camera estimated from the people: {est.describe()}", file=sys.stderr, flush=True)
    return est.camera(), "estimated"


if __name__ == "__main__":
    ap = argparse.ArgumentParser(prog="counterpart track", description=__doc__.split("\n")[0])
    add_arguments(ap)
    sys.exit(main(ap.parse_args()))
