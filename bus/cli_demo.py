"""``counterpart demo``: the whole graph end to end on the built-in scene (or your video, or a camera).

1. builds the default models if they are not cached yet (progress on stderr);
2. launches ``launch/demo.yaml`` (the camera replaying the simulator's handshake in real time
   through all six nodes), or ``launch/live.yaml`` with ``--live``, or the demo graph on ``--input``;
3. writes ``OUT/demo.mp4`` (or ``.avi`` where OpenCV cannot write H.264) and
   ``OUT/demo_contact_sheet.png``, and prints where they are and the per-node statistics.
"""
from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

#: the responder's models offered on the live page, built before the graph starts
RESPONDER_MODELS = ("dual-hmm", "joint-shape", "listener", "emotion")


def add_arguments(p: argparse.ArgumentParser) -> None:
    src = p.add_mutually_exclusive_group()
    src.add_argument("--input", metavar="FILE", help="run on your own video file instead of the built-in scene")
    src.add_argument("--live", action="store_true", help="use the V4L2 camera (launch/live.yaml)")
    p.add_argument("--device", default="/dev/video0", help="camera device for --live")
    p.add_argument("--serve", action="store_true",
                   help="serve the live page (http://127.0.0.1:PORT); the scene or file loops until Ctrl-C")
    p.add_argument("--port", type=int, default=8080, help="port of the live page")
    p.add_argument("--out", default="out", help="output folder (default: out)")
    p.add_argument("--scenario", default="handshake", help="built-in scene when no --input/--live")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--frames", type=int, default=0, help="stop after this many frames (0: the whole scene or file)")
    p.add_argument("--set", action="append", metavar="NODE.PARAM=VALUE", help="override a node parameter")


def ensure_models() -> None:
    """Build the default model files the graph loads, when they are not cached yet."""
    from nodes.responder.models import load_default
    from nodes.tracker.prior import default_prior_path, load_default_prior

    if not default_prior_path().exists():
        print("  tracker motion prior (once)...", file=sys.stderr)
    load_default_prior(progress=True)
    for name in RESPONDER_MODELS:
        load_default(name, progress=lambda m, name=name: print(f"  responder {name}: {m}", file=sys.stderr))


def contact_sheet(video: Path, out: Path, n: int = 12, cols: int = 4) -> bool:
    """A grid of ``n`` frames spread over ``video``, each stamped with its frame number."""
    import cv2
    import numpy as np

    cap = cv2.VideoCapture(str(video))
    frames = []
    ok, img = cap.read()
    while ok:
        frames.append(img)
        ok, img = cap.read()
    cap.release()
    if not frames:
        return False
    idx = np.linspace(0, len(frames) - 1, min(n, len(frames))).round().astype(int)
    tiles = []
    for i in idx:
        tile = frames[i].copy()
        cv2.putText(tile, f"#{i}", (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
        tiles.append(tile)
    while len(tiles) % cols:
        tiles.append(np.zeros_like(tiles[0]))
    rows = [np.hstack(tiles[r:r + cols]) for r in range(0, len(tiles), cols)]
    return bool(cv2.imwrite(str(out), np.vstack(rows)))


def main(args: argparse.Namespace) -> int:
    from .launchfile import LaunchError
    from .cli_launch import load_checked
    from .params import ParamError
    from .runner import setup_logging
    from .stats_watch import StatsWatcher, stats_json, stats_table
    from .supervisor import Launcher, prune_run_dirs

    setup_logging("demo")
    log = logging.getLogger("demo")
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    print("counterpart demo: preparing the default models (cached after the first run)", file=sys.stderr)
    ensure_models()
    video = out / "demo.mp4"
    sets = [f"renderer.video={video}", f"renderer.serve={'true' if args.serve else 'false'}",
            f"renderer.port={args.port}"]
    if args.live:
        file = "live.yaml"
        sets.append(f"camera.source={args.device}")
    else:
        file = "demo.yaml"
        if args.input:
            if not Path(args.input).is_file():
                print(f"counterpart demo: --input {args.input}: no such file", file=sys.stderr)
                return 2
            sets.append(f"camera.source={Path(args.input).resolve()}")
        else:
            sets.append(f"camera.source=sim:{args.scenario}?seed={args.seed}")
    if args.frames:
        sets.append(f"camera.max_frames={args.frames}")
    if args.serve and not args.live:
        sets.append("camera.loop=true")  # keep the page alive until Ctrl-C
    sets += args.set or []
    try:
        graph = load_checked(file, sets, None)
    except (LaunchError, ParamError) as exc:
        print(f"counterpart demo: {exc}", file=sys.stderr)
        return 2
    prune_run_dirs()
    launcher = Launcher(graph)
    watcher = StatsWatcher(launcher.run_dir)
    watcher.start()
    log.info("running %s (Ctrl-C to stop)%s", graph.file,
             (f"; live page on http://127.0.0.1:{args.port}" if args.port else "; the renderer logs the page's address")
             if args.serve else "")
    code = launcher.run()
    watcher.stop()
    launcher.cleanup()
    written = sorted(out.glob("demo.*"))
    videos = [p for p in written if p.suffix in (".mp4", ".avi")]
    sheet = out / "demo_contact_sheet.png"
    if videos and contact_sheet(videos[0], sheet):
        print(f"video:         {videos[0]}")
        print(f"contact sheet: {sheet}")
    else:
        print("counterpart demo: no video was written", file=sys.stderr)
        code = code or 1
    if watcher.latest:
        (out / "demo_stats.json").write_text(json.dumps(stats_json(watcher.latest), indent=1))
        print(f"per-node statistics ({out / 'demo_stats.json'}):")
        print(stats_table(watcher.latest))
    return code
