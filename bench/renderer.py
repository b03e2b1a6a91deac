"""The renderer's CPU per frame, offline, on the inputs it got in the real-time graph.

    python bench/renderer.py --record CLIP [--frames 300] [--bag OUT.mcap]   # record, then time
    python bench/renderer.py --bag BAG [--repeats 3] [--profile] [--save FRAMES.npy]

``--record`` runs ``launch/demo.yaml`` on ``CLIP`` in real time (both people tracked, as
``bench/e2e.py --input`` does) with a recorder of everything the renderer subscribes to (frame,
partner, silhouettes, pose, signals, camera_info, the stats topics). The bag is then replayed into
the renderer's :class:`~counterpart.nodes.renderer.compositor.Compositor`, configured as demo.yaml's
renderer, in the bag's order and at its receive times (so the pairing is the same on every replay),
and each frame's work is timed on this thread's CPU clock (``time.thread_time``, which a loaded
machine stretches far less than wall time): ``render`` (compositing: the frame's copy, the
silhouettes' splines, the partner's cones, the skeletons, the badges, the controls bar) and
``video`` (writing it into a Motion-JPEG .avi, as the demo does), and the pairing of the
messages (``pair``: taking each message and finding the frames ready, per frame). Every replay renders the same
frames; ``digest`` (SHA-256 of all of them) says whether a change of the renderer kept every pixel.

Last stdout line: one JSON object: ``frames``, ``render_ms``, ``video_ms`` and ``pair_ms`` (median over the
repeats of the mean CPU ms per frame), ``render_ms_p95``, ``render_ms_new_partner`` (the median
frame that draws a partner message for the first time: its cones fitted and facets shaded, where a
held partner's are kept; ``new_partners`` such frames), ``partner_drawn`` (frames with a partner in
the picture), ``digest``. ``--profile`` prints cProfile's top functions of one more replay to
stderr; ``--save`` writes the rendered frames (N, H, W, 3) uint8 for a pixel comparison.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import cProfile  # noqa: E402
import hashlib  # noqa: E402
import io  # noqa: E402
import json  # noqa: E402
import pstats  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
STATS = ["camera/stats", "silhouette/stats", "tracker/stats", "labeller/stats", "responder/stats"]
TOPICS = ["frame", "partner", "silhouettes", "pose", "signals", "camera_info", *STATS]


def record(clip: Path, frames: int, bag: Path) -> None:
    """Run demo.yaml on ``clip`` in real time with a recorder of the renderer's inputs into ``bag``."""
    from counterpart.apps.demo import ensure_models

    ensure_models()  # the graph's model files, built once (as bench/e2e.py does)
    work = Path(tempfile.mkdtemp(prefix="bench-renderer-"))
    doc = {
        "include": [
            {
                "file": str(REPO / "launch" / "demo.yaml"),
                "set": {
                    "camera.source": str(clip.resolve()),
                    "camera.loop": True,
                    "camera.max_frames": frames,
                    "camera.pacing": "realtime",
                    "tracker.people": ["left", "right"],
                    "renderer.video": str(work / "demo.avi"),
                },
            }
        ],
        "nodes": {
            "recorder": {
                "run": "counterpart.bus.bag_nodes:Recorder",
                "policy": "reliable",
                "params": {"path": str(bag), "topics": TOPICS, "overwrite": True},
            }
        },
    }
    launch = work / "record.yaml"
    launch.write_text(yaml.safe_dump(doc))
    home = work / "home"
    home.mkdir(mode=0o700)
    env = {**os.environ, "COUNTERPART_HOME": str(home)}
    subprocess.run(
        [sys.executable, "-m", "counterpart.bus.cli", "launch", str(launch)],
        cwd=REPO,
        env=env,
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def load(bag: Path) -> list[tuple[str, float, Any]]:
    """The bag's messages of :data:`TOPICS`: (topic, receive time in seconds, message), in order."""
    import counterpart.nodes.responder.node  # noqa: F401 (registers the message types to decode)
    from counterpart.bus.bag import BagReader

    return [(t, ns * 1e-9, m) for t, ns, m in BagReader(bag).messages(TOPICS, decode_messages=True)]


def replay(msgs: list[tuple[str, float, Any]], video: Path | None, keep: list[np.ndarray] | None) -> dict[str, Any]:
    """Feed the messages to a compositor set up as demo.yaml's renderer and time each frame's
    rendering and video writing on this thread's CPU clock.
    """
    from counterpart.body.camera import camera_from_info
    from counterpart.nodes.renderer.compositor import Compositor
    from counterpart.nodes.renderer.video import VideoWriter

    comp = Compositor(
        want_partner=True,
        overlays={"skeleton": True, "splines": True, "signals": True, "stats": False, "controls": True},
        timeout=0.1,
        max_pending=128,
        adaptive=True,
        wait_camera=True,
    )
    writer = VideoWriter(video, 0.0) if video is not None else None
    render_s, video_s = [], []
    #: per frame: whether a partner was drawn for the first time (its cones fitted, facets shaded)
    new_partner: list[bool] = []
    drawn_before: set[int] = set()
    digest = hashlib.sha256()

    def out(bundles: list[Any]) -> None:
        for b in bundles:
            t0 = time.thread_time()
            img = comp.render(b)
            t1 = time.thread_time()
            if writer is not None:
                writer.write(img, b.frame.fps)
            t2 = time.thread_time()
            render_s.append(t1 - t0)
            fresh = comp.partner_drawn and id(b.partner) not in drawn_before
            new_partner.append(fresh)
            if fresh:
                drawn_before.add(id(b.partner))  # the messages stay alive in msgs: ids are not reused
            video_s.append(t2 - t1)
            digest.update(img.tobytes())
            if keep is not None:
                keep.append(img)

    pair_s = 0.0
    for topic, now, msg in msgs:
        t0 = time.thread_time()
        ready = comp.ready(now)  # the node's timer: frames whose wait is over render first
        pair_s += time.thread_time() - t0
        out(ready)
        t0 = time.thread_time()
        if topic == "frame":
            comp.add_frame(msg, now)
        elif topic == "partner":
            comp.add_partner(msg, now)
        elif topic == "camera_info":
            comp.set_camera(camera_from_info(msg), msg.seq, msg.undecided_from)
        elif topic in STATS:
            comp.add_stats(msg)
        else:
            comp.add_side(topic, msg)
        ready = comp.ready(now)
        pair_s += time.thread_time() - t0
        out(ready)
    out(comp.ready(msgs[-1][1] + 1.0, flush=True))
    if writer is not None:
        writer.close()
    return {
        "frames": len(render_s),
        "render_ms": 1e3 * float(np.mean(render_s)),
        "render_ms_p95": 1e3 * float(np.percentile(render_s, 95)),
        "render_ms_new_partner": 1e3 * float(np.median(np.array(render_s)[new_partner])) if any(new_partner) else 0.0,
        "new_partners": int(sum(new_partner)),
        "video_ms": 1e3 * float(np.mean(video_s)),
        "pair_ms": 1e3 * pair_s / max(len(render_s), 1),
        "partner_drawn": comp.counts["partner_drawn"],
        "digest": digest.hexdigest()[:16],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bag", type=Path, help="the recorded inputs (with --record: where to write them)")
    ap.add_argument("--record", type=Path, metavar="CLIP", help="record the inputs from demo.yaml on this clip first")
    ap.add_argument("--frames", type=int, default=300, help="frames to record (the clip looped)")
    ap.add_argument("--repeats", type=int, default=3, help="timed replays; figures are their medians")
    ap.add_argument("--profile", action="store_true", help="print cProfile's top functions of one more replay")
    ap.add_argument("--save", type=Path, help="write the rendered frames (N, H, W, 3) uint8 to this .npy")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    if args.bag is None:
        if args.record is None:
            ap.error("give --bag, --record or both")
        args.bag = Path(tempfile.mkdtemp(prefix="bench-renderer-")) / "inputs.mcap"
    if args.record is not None:
        record(args.record, args.frames, args.bag)
    msgs = load(args.bag)
    work = Path(tempfile.mkdtemp(prefix="bench-renderer-"))
    keep: list[np.ndarray] | None = [] if args.save else None
    runs = [replay(msgs, work / f"replay{i}.avi", keep if i == 0 else None) for i in range(args.repeats)]
    if keep is not None:
        np.save(args.save, np.stack(keep))
    if len({r["digest"] for r in runs}) != 1:
        raise RuntimeError(f"replays of the same bag rendered different frames: {[r['digest'] for r in runs]}")
    if args.profile:
        prof = cProfile.Profile()
        prof.enable()
        replay(msgs, work / "profile.avi", None)
        prof.disable()
        s = io.StringIO()
        pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(30)
        print(s.getvalue(), file=sys.stderr)
    res = {
        "bag": str(args.bag),
        "frames": runs[0]["frames"],
        "partner_drawn": runs[0]["partner_drawn"],
        "new_partners": runs[0]["new_partners"],
        "digest": runs[0]["digest"],
        **{
            k: round(float(np.median([r[k] for r in runs])), 3)
            for k in ("render_ms", "render_ms_p95", "render_ms_new_partner", "video_ms", "pair_ms")
        },
        "render_ms_runs": [round(r["render_ms"], 3) for r in runs],
    }
    print(json.dumps(res))


if __name__ == "__main__":
    main()
