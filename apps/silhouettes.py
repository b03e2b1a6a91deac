"""``counterpart silhouettes VIDEO --out people.npz``: the silhouette node's algorithm over a video file.

Background model (fitted on the first ``--train-frames`` frames; people may be in view), clean-up,
people with sides, ids and B-spline outlines, one row per person and frame
(``counterpart.nodes.silhouette.pipeline.extract_video`` gives the file's layout). For batch labelling of a
corpus. Progress goes to stderr; Ctrl-C writes the frames done so far (``complete`` False).
Exit code 0 on success, 2 on bad input, 130 when interrupted.
"""

from __future__ import annotations

import argparse
import sys

from counterpart.apps.offline import FrameProgress, add_video_arguments, npz_name, positive, run_offline
from counterpart.nodes.silhouette import BACKEND_NAMES

#: the one-line help of this command in `counterpart --help`
HELP = "offline: the people's silhouettes of a video file"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_video_arguments(p, "output .npz (one row per person and frame)", "process at most this many frames")
    p.add_argument("--backend", default="horprasert", choices=BACKEND_NAMES, help="background subtractor")
    p.add_argument(
        "--min-area",
        type=int,
        default=300,
        help="smallest person region, pixels (0: from the frame size, a person 1.7 m tall 30 m away)",
    )
    p.add_argument("--n-ctrl", type=int, default=32, help="B-spline control points per outline")


def main(args: argparse.Namespace) -> int:
    if not positive(args, ("train_frames", "max_frames"), "silhouettes"):
        return 2
    args.out = npz_name(args.out)

    def work() -> dict:
        from counterpart.body.image_sequence import video_info

        video_info(args.video)  # a missing or undecodable video is said before the algorithms are loaded
        from counterpart.nodes.silhouette.pipeline import extract_video

        return extract_video(
            args.video,
            args.out,
            max_frames=args.max_frames,
            train_frames=args.train_frames,
            progress=FrameProgress("silhouettes", limit=args.max_frames),
            backend=args.backend,
            min_area=args.min_area or None,
            n_ctrl=args.n_ctrl,
        )

    return run_offline("silhouettes", args.out, work)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(prog="counterpart silhouettes", description=__doc__.split("\n")[0])
    add_arguments(ap)
    sys.exit(main(ap.parse_args()))
