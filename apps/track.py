"""``counterpart track VIDEO --out poses.npz``: offline 3D tracking of a video file.

The silhouette node's background model and the tracker's annealed particle filter, frame by frame,
without the bus (``counterpart.apps.tracking.track_video``); the layout of the output file is in its
docstring. Progress goes to stderr; Ctrl-C writes the frames done so far (``complete`` False).
Exit code 0 on success, 2 on bad input, 130 when interrupted.
"""

from __future__ import annotations

import argparse
import sys

from counterpart.apps.offline import FrameProgress, add_video_arguments, positive, run_offline
from counterpart.body.camera import Camera, load_camera_file
from counterpart.nodes.silhouette.backends import BACKEND_NAMES
from counterpart.nodes.tracker.prior import resolve_prior
from counterpart.nodes.tracker.tracker import SIDES

#: the one-line help of this command in `counterpart --help`
HELP = "offline: the 3D body of the people of a video file"


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
        default=["left"],
        choices=SIDES,
        help="sides of the frame to track: left, right or both (default: left)",
    )
    p.add_argument(
        "--camera",
        default=None,
        metavar="FILE",
        help="calibration, JSON or YAML: {fx, fy, cx, cy, width, height, R, t} or {eye, target, "
        "fov_deg, width, height} (default: the simulator's camera at the video's size)",
    )
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
    from .tracking import track_video

    if not positive(args, ("layers", "particles", "train_frames", "max_frames"), "track"):
        return 2

    def work() -> dict:
        from counterpart.nodes.silhouette.pipeline import video_info

        camera = load_camera(args.camera) if args.camera else None
        video_info(args.video)  # a missing or undecodable video is said before a minute of building a prior
        if args.prior == "default":
            print(
                "[track] loading the default motion prior (built from the simulator on first use, about a minute)",
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
            progress=FrameProgress("track"),
            backend=args.backend,
        )

    return run_offline("track", args.out, work)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(prog="counterpart track", description=__doc__.split("\n")[0])
    add_arguments(ap)
    sys.exit(main(ap.parse_args()))
