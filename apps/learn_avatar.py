"""``counterpart learn avatar --video PERSON.avi [--labels L.npz] --out avatar.npz``: a video-texture
avatar from a recording of one person (:mod:`counterpart.nodes.responder.video_texture`).

The video must start with about a second of the empty room (the background the person's mask is
cut against), then show the person alone, facing the way the partner will face (``--facing``).
Without ``--labels`` the labeller labels every frame. Progress goes to stderr; the summary (frames,
graph, goals, seconds) to stdout as JSON; exit 0 on success, 2 on bad input (a video too short, a
signal that never occurs, a file that does not decode), 130 on Ctrl-C.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from counterpart.bus.cli_offline import run_offline

#: the one-line help of this command in `counterpart --help`
HELP = "a video-texture avatar from a recording of a person"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--video", required=True, metavar="PERSON.avi", help="the recording of the person")
    p.add_argument(
        "--labels",
        metavar="L.npz",
        default=None,
        help="per-frame social labels (.npz with signals_a/signals_b/signal_names, or .csv, as "
        "'counterpart mine' reads); default: the labeller labels the video",
    )
    p.add_argument("--person", default="a", help="which person of the label file is the recorded one (default a)")
    p.add_argument(
        "--signals",
        default="nod",
        metavar="A,B",
        help="signals the avatar must be able to show; learning stops, saying which, when one never "
        "occurs (default nod)",
    )
    p.add_argument(
        "--facing",
        choices=("left", "right"),
        default="left",
        help="the way the person faces in the video (default left: towards a person on the left "
        "of the picture, where the partner's counterpart stands in the demo)",
    )
    p.add_argument(
        "--train-frames",
        type=int,
        default=30,
        help="first frames, showing the empty room, that the background is learnt from (default 30)",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=2,
        help="processes cutting the masks out of the video, each a part of it (default 2)",
    )
    p.add_argument("--clusters", type=int, default=0, help="k of the k-medoids (default: one per second, 4-200)")
    p.add_argument("--out", required=True, help="avatar file to write (.npz)")


def main(args: argparse.Namespace) -> int:
    def say(msg: str) -> None:
        print(f"[learn avatar] {msg}", file=sys.stderr, flush=True)

    def work() -> dict[str, Any]:
        from counterpart.apps.avatar_video import video_recording
        from counterpart.nodes.responder.models import save_model
        from counterpart.nodes.responder.video_texture import VideoTextureConfig, fit_recording

        if args.train_frames < 2 or args.workers < 1:
            raise ValueError("--train-frames must be at least 2 and --workers at least 1")
        t0 = time.perf_counter()
        required = tuple(s.strip() for s in args.signals.split(",") if s.strip())
        say(f"reading {args.video}: the person's mask on every frame")
        rec = video_recording(
            args.video,
            args.labels,
            args.person,
            1.0 if args.facing == "right" else -1.0,
            args.train_frames,
            args.workers,
            required,
            say=say,
        )
        model = fit_recording(rec, VideoTextureConfig(n_clusters=args.clusters), required, say)
        info = {
            "video": args.video,
            "labels": args.labels or "labeller",
            "frames": int(len(rec.crops)),
            "frames_in_graph": int(model.alive_.sum()),
            "fps": rec.fps,
            "crop": list(rec.box),
            "clusters": len(model.members_),
            "edges": int(len(model.indices_)),
            "goals": model.goals_,
            "seconds": round(time.perf_counter() - t0, 2),
        }
        path = save_model(args.out, model, info)
        say(f"wrote {path} in {info['seconds']:.1f} s")
        return {"out": str(path), **info}

    return run_offline("learn avatar", args.out, work)
