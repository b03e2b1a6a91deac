"""``counterpart calibrate VIDEO --out camera.yaml``: the camera of a video, estimated offline from
the people in it.

Focal length, tilt, roll and height above the ground from the heads and feet of the upright people
(``counterpart.apps.calibration.calibrate_video``), printed with their uncertainty (one standard
deviation); the file is a calibration every node and command that takes a camera reads
(``calibration.file``, ``counterpart demo --camera``, ``counterpart track --camera``). Whether the
graph's calibration node would use the estimate itself (``graph_would_use``) is printed and in the
summary. Progress goes
to stderr; the last stdout line is a JSON summary. Exit code 0 on success, 2 on bad input (or too
few people seen), 130 when interrupted.
"""

from __future__ import annotations

import argparse
import sys

from counterpart.apps.offline import FrameProgress, add_fov_argument, add_video_arguments, positive, run_offline

#: the one-line help of this command in `counterpart --help`
HELP = "offline: the camera of a video file, estimated from the people in it"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_video_arguments(p, "output calibration file (.yaml or .json)", "use at most this many frames (default: all)")
    p.add_argument(
        "--person-height",
        type=float,
        default=1.75,
        help="mean height of the people's outlines, hair and shoes included, metres (the prior that sets the scale)",
    )
    p.add_argument("--person-height-std", type=float, default=0.09, help="its standard deviation, metres")
    add_fov_argument(p)


def main(args: argparse.Namespace) -> int:
    from .calibration import calibrate_video, camera_file_text, estimate_config, graph_would_use

    if not positive(args, ("train_frames", "max_frames"), "calibrate"):
        return 2
    if not (0.5 < args.person_height < 2.5 and 0 < args.person_height_std < 0.5):
        print(
            "counterpart calibrate: --person-height must be in (0.5, 2.5) m and --person-height-std in (0, 0.5) m",
            file=sys.stderr,
        )
        return 2
    try:
        config = estimate_config(args.fov, person_height=args.person_height, person_height_std=args.person_height_std)
    except ValueError as exc:
        print(f"counterpart calibrate: {exc}", file=sys.stderr)
        return 2

    def work() -> dict:
        est, summary = calibrate_video(
            args.video,
            args.max_frames,
            args.train_frames,
            config,
            progress=FrameProgress("calibrate", limit=args.max_frames),
        )
        camera = est.camera()
        text = camera_file_text(camera, est, args.video, args.fov)
        with open(args.out, "w", encoding="utf-8") as f:
            f.write(text)
        print(f"[calibrate] {est.describe()}", file=sys.stderr, flush=True)
        used = graph_would_use(est, config)
        if not used:
            print(
                "[calibrate] not sure enough for the graph's calibration node, which would keep its default camera "
                "(more frames, people walking in depth, or the room's straight lines in view narrow it); the file "
                "holds the estimate all the same",
                file=sys.stderr,
                flush=True,
            )
        return {
            **summary,
            "estimate": est.summary(),
            "fov_given_deg": args.fov or None,
            "graph_would_use": used,
            "out": args.out,
        }

    return run_offline("calibrate", args.out, work)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(prog="counterpart calibrate", description=__doc__.split("\n")[0])
    add_arguments(ap)
    sys.exit(main(ap.parse_args()))
